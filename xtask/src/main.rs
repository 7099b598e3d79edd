//! `cargo xtask`: a fresh machine's set-up, then cargo.
//!
//! - `cargo xtask run [ARGS]`: the Vulkan driver and loader, then
//!   `cargo run --release -- ARGS` (the main job: `cargo xtask run -- bench --quick`);
//! - `cargo xtask test [ARGS]`: those, the validation layer, the ch2 MRI,
//!   and a virtual X server with the libraries the viewer's window needs,
//!   then the library checked as engines build it (`library_builds`) and
//!   `cargo test ARGS` with lavapipe's shader optimisation off (see
//!   `test_env`);
//! - `cargo xtask setup [test|mpi]`: only the packages (mpi: MPI and IceT
//!   for the `mpi` feature; `test` includes them, and runs `cargo test
//!   --features mpi`).
//!
//! IceT comes with Debian's `paraview` package, which pulls in Qt and two
//! hundred other packages; its two small libraries need only libc and MPI.
//! So `setup mpi` downloads `paraview` and `paraview-dev` with `apt-get
//! download` (no root needed), unpacks them with `dpkg-deb -x` and keeps
//! IceT's headers and libraries in `target/icet`, where build.rs finds them.
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

/// What the `mpi` feature needs from packages: `mpirun` and `mpicc` with
/// `mpi.h` (OpenMPI).
const MPI: &[&str] = &["openmpi-bin", "libopenmpi-dev"];

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (task, rest) = match args.split_first() {
        Some((t, rest)) => (t.as_str(), rest),
        None => ("help", &args[..]),
    };
    let result = match task {
        "run" => setup(RUN).and_then(|()| cargo(&["run", "--release", "--"], strip_dashes(rest), &[])),
        // Without dpkg there is no IceT to unpack: the tests without MPI.
        "test" if !quiet_ok("dpkg-query", &["--version"]) => {
            eprintln!("note: no dpkg, so no IceT to unpack: the tests run without the `mpi` feature");
            setup(&[RUN, TEST].concat())
                .and_then(|()| library_builds())
                .and_then(|()| cargo(&["test"], rest, &test_env()))
        }
        "test" => setup(&[RUN, TEST, MPI].concat())
            .and_then(|()| icet())
            .and_then(|()| library_builds())
            .and_then(|()| cargo(&["test", "--features", "mpi"], rest, &test_env())),
        "setup" if rest.first().map(String::as_str) == Some("test") => {
            setup(&[RUN, TEST, MPI].concat()).and_then(|()| icet())
        }
        "setup" if rest.first().map(String::as_str) == Some("mpi") => setup(MPI).and_then(|()| icet()),
        "setup" => setup(RUN),
        _ => {
            eprintln!("usage: cargo xtask run [-- LACUNA ARGS] | test [CARGO TEST ARGS] | setup [test|mpi]");
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(code) => ExitCode::from(code),
    }
}

/// The library as an engine depends on it (README, "Library"): without
/// the command line's features, and with frame files only. `cargo test`
/// builds the default features, so code only these compile would go
/// unbuilt (a missing import there once broke an engine's build).
fn library_builds() -> Result<(), u8> {
    for features in [
        &["--no-default-features"][..],
        &["--no-default-features", "--features", "frames"],
    ] {
        let features: Vec<String> = features.iter().map(|f| f.to_string()).collect();
        cargo(&["check", "--lib"], &features, &[])?;
    }
    Ok(())
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

/// The tests' environment: lavapipe's LLVM optimisation passes off
/// (`GALLIVM_PERF=nopt`) unless the caller set `GALLIVM_PERF`. The suite
/// compiles about 1300 pipeline variants, and on a machine whose Mesa
/// shader cache is cold (a fresh CI machine) compiling them was most of
/// its time: the tests took 34 minutes on 2 cores, 20 with the passes off
/// (README, "Tests").
/// The tests check what kernels compute, which the passes do not change
/// (shaded, iso and hardware-filtered frames came out the same bit for bit
/// with and without them), only how fast, which no test asserts. Mesa keys its disk cache on
/// the flag, so these shaders never stand in for optimised ones. Other
/// drivers ignore it.
fn test_env() -> Vec<(&'static str, &'static str)> {
    match std::env::var_os("GALLIVM_PERF") {
        Some(_) => Vec::new(),
        None => vec![("GALLIVM_PERF", "nopt")],
    }
}

/// Runs cargo (the one that runs this) with `fixed` then `args`, and `env`
/// added to the environment; its exit code is ours.
fn cargo(fixed: &[&str], args: &[String], env: &[(&str, &str)]) -> Result<(), u8> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(cargo)
        .args(fixed)
        .args(args)
        .envs(env.iter().copied())
        .status();
    match status {
        Ok(s) if s.success() => Ok(()),
        Ok(s) => Err(s.code().and_then(|c| u8::try_from(c).ok()).unwrap_or(1)),
        Err(e) => {
            eprintln!("error: cannot run cargo: {e}");
            Err(1)
        }
    }
}

/// IceT's headers and libraries in `target/icet` (see the module comment),
/// unless they are there already or `paraview-dev` is installed.
fn icet() -> Result<(), u8> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = root.join("target").join("icet");
    if dir.join("include").join("IceT.h").is_file() || system_icet() {
        return Ok(());
    }
    let debs = root.join("target").join("icet-debs");
    let fail = |what: &str| {
        eprintln!("error: cannot fetch IceT ({what}); install paraview-dev, or set LACUNA_ICET_DIR");
        1
    };
    let _ = std::fs::remove_dir_all(&debs);
    std::fs::create_dir_all(&debs).map_err(|_| fail("cannot create target/icet-debs"))?;
    eprintln!("fetching IceT from Debian's paraview and paraview-dev packages into target/icet");
    let downloaded = Command::new("apt-get")
        .args(["download", "-qq", "paraview", "paraview-dev"])
        .current_dir(&debs)
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !downloaded {
        return Err(fail("apt-get download paraview paraview-dev failed"));
    }
    let unpacked = debs.join("root");
    for entry in std::fs::read_dir(&debs).map_err(|_| fail("no packages"))?.flatten() {
        let path = entry.path();
        if path.extension().is_some_and(|e| e == "deb")
            && !Command::new("dpkg-deb")
                .arg("-x")
                .arg(&path)
                .arg(&unpacked)
                .status()
                .is_ok_and(|s| s.success())
        {
            return Err(fail("dpkg-deb -x failed"));
        }
    }
    let mut found = (0, [false; 2]);
    let (include, lib) = (dir.join("include"), dir.join("lib"));
    std::fs::create_dir_all(&include)
        .and_then(|()| std::fs::create_dir_all(&lib))
        .map_err(|_| fail("cannot create target/icet"))?;
    let mut stack = vec![unpacked.clone()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).into_iter().flatten().flatten() {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_dir() {
                stack.push(path);
            } else if ["IceT.h", "IceTConfig.h", "IceTMPI.h"].contains(&name.as_str()) {
                std::fs::copy(&path, include.join(&name)).map_err(|_| fail("cannot copy a header"))?;
                found.0 += 1;
            } else if (name.starts_with("libvtkIceTCore") || name.starts_with("libvtkIceTMPI")) && name.contains(".so")
            {
                std::fs::copy(&path, lib.join(&name)).map_err(|_| fail("cannot copy a library"))?;
                found.1[name.starts_with("libvtkIceTMPI") as usize] = true;
            }
        }
    }
    let _ = std::fs::remove_dir_all(&debs);
    if found.0 < 3 || found.1 != [true; 2] {
        let _ = std::fs::remove_dir_all(&dir);
        return Err(fail("the packages hold no IceT headers or libraries"));
    }
    Ok(())
}

/// Whether `paraview-dev` put IceT's headers under /usr/include.
fn system_icet() -> bool {
    std::fs::read_dir("/usr/include")
        .into_iter()
        .flatten()
        .flatten()
        .any(|e| {
            e.file_name().to_string_lossy().starts_with("paraview-")
                && e.path().join("vtkicet/src/include/IceT.h").is_file()
        })
}
