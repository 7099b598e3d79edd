//! `cargo xtask`: a fresh machine's set-up, then cargo.
//!
//! - `cargo xtask run [ARGS]`: the Vulkan driver and loader, then
//!   `cargo run --release -- ARGS` (the main job: `cargo xtask run -- bench --quick`);
//! - `cargo xtask test [ARGS]`: those, the validation layer, the ch2 MRI,
//!   and a virtual X server with the libraries the viewer's window needs,
//!   then `cargo test ARGS`;
//! - `cargo xtask setup [test]`: only the packages.
//!
//! Packages (Debian's names) that `dpkg-query` does not list as installed
//! are installed with `apt-get` when this runs as root (or with `sudo -n`
//! when that asks no password); otherwise it stops at once with the exact
//! command to run, before the build takes minutes. On a machine without
//! dpkg it says which packages to find and goes on.

use std::process::{Command, ExitCode, Stdio};

/// What `lacuna` needs to render: Mesa's Vulkan drivers (lavapipe without a
/// GPU) and the Vulkan loader.
const RUN: &[&str] = &["mesa-vulkan-drivers", "libvulkan1"];

/// What `cargo test` needs besides: the validation layer (every GPU test
/// runs under it), the ch2 MRI one test renders, and Xvfb with the X
/// libraries winit loads for the viewer's window test.
const TEST: &[&str] = &[
    "vulkan-validationlayers",
    "mricron-data",
    "xvfb",
    "xauth",
    "libx11-6",
    "libxcursor1",
    "libxrandr2",
    "libxi6",
    "libxkbcommon-x11-0",
];

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (task, rest) = match args.split_first() {
        Some((t, rest)) => (t.as_str(), rest),
        None => ("help", &args[..]),
    };
    let result = match task {
        "run" => setup(RUN).and_then(|()| cargo(&["run", "--release", "--"], strip_dashes(rest))),
        "test" => setup(&[RUN, TEST].concat()).and_then(|()| cargo(&["test"], rest)),
        "setup" if rest.first().map(String::as_str) == Some("test") => setup(&[RUN, TEST].concat()),
        "setup" => setup(RUN),
        _ => {
            eprintln!("usage: cargo xtask run [-- LACUNA ARGS] | test [CARGO TEST ARGS] | setup [test]");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => ExitCode::from(code),
    }
}

/// `cargo xtask run -- bench --quick` and `cargo xtask run bench --quick` alike.
fn strip_dashes(args: &[String]) -> &[String] {
    match args.first().map(String::as_str) {
        Some("--") => &args[1..],
        _ => args,
    }
}

/// Installs what of `packages` is missing, or stops with the command to run.
fn setup(packages: &[&str]) -> Result<(), u8> {
    let Some(missing) = missing(packages) else {
        eprintln!(
            "note: no dpkg here; lacuna needs a Vulkan 1.3 driver and loader (Debian: {}) and, for its tests, \
             the Khronos validation layer, Xvfb and the ch2 MRI (Debian: {})",
            RUN.join(" "),
            TEST.join(" ")
        );
        return Ok(());
    };
    if missing.is_empty() {
        return Ok(());
    }
    let list = missing.join(" ");
    let sudo = if is_root() {
        None
    } else if quiet_ok("sudo", &["-n", "true"]) {
        Some("sudo")
    } else {
        eprintln!(
            "error: missing system packages: {list}; install them with: sudo apt-get update && sudo apt-get install -y --no-install-recommends {list}"
        );
        return Err(1);
    };
    eprintln!("installing missing system packages: {list}");
    let apt = |args: &[&str]| -> bool {
        let mut cmd = Command::new(sudo.unwrap_or("apt-get"));
        if sudo.is_some() {
            cmd.args(["-n", "apt-get"]);
        }
        cmd.args(args)
            .env("DEBIAN_FRONTEND", "noninteractive")
            .stdout(Stdio::null())
            .status()
            .is_ok_and(|s| s.success())
    };
    let mut install = vec!["install", "-y", "-qq", "--no-install-recommends"];
    install.extend(missing.iter().map(String::as_str));
    if !(apt(&["update", "-qq"]) && apt(&install)) {
        eprintln!("error: apt-get could not install: {list}");
        return Err(1);
    }
    Ok(())
}

/// The packages of `packages` dpkg does not list as installed; None
/// without dpkg.
fn missing(packages: &[&str]) -> Option<Vec<String>> {
    let mut out = Vec::new();
    for p in packages {
        let status = Command::new("dpkg-query")
            .args(["-W", "-f=${Status}", p])
            .stderr(Stdio::null())
            .output()
            .ok()?;
        if !String::from_utf8_lossy(&status.stdout).contains("install ok installed") {
            out.push(p.to_string());
        }
    }
    Some(out)
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

fn quiet_ok(program: &str, args: &[&str]) -> bool {
    Command::new(program)
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Runs cargo (the one that runs this) with `fixed` then `args`; its exit
/// code is ours.
fn cargo(fixed: &[&str], args: &[String]) -> Result<(), u8> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo).args(fixed).args(args).status();
    match status {
        Ok(s) if s.success() => Ok(()),
        Ok(s) => Err(s.code().and_then(|c| u8::try_from(c).ok()).unwrap_or(1)),
        Err(e) => {
            eprintln!("error: cannot run cargo: {e}");
            Err(1)
        }
    }
}
