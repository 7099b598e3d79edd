//! `mpirun -np N lacuna render` (feature `mpi`; `cargo xtask test` installs
//! OpenMPI and IceT and runs these): with 2 and 3 ranks the IceT-composited
//! frame equals the one-process frame within 1e-5 (MIP, MinIP and iso
//! frames bit for bit), and bad requests, or one rank failing while the
//! others stream, end every rank with one `error:` line and no file.
#![cfg(feature = "mpi")]

use crate::common;
use lacuna::frame::{diff, Frame};
use std::path::Path;
use std::process::Command;

/// `mpirun -np ranks lacuna ARGS` (as root too, more ranks than cores).
fn mpirun(ranks: u32, args: &[&str]) -> common::Run {
    let mut program = vec![env!("CARGO_BIN_EXE_lacuna")];
    program.extend_from_slice(args);
    mpirun_program(ranks, &program)
}

/// `mpirun -np ranks PROGRAM...`.
fn mpirun_program(ranks: u32, program: &[&str]) -> common::Run {
    let out = Command::new("mpirun")
        .args(["--oversubscribe", "-np", &ranks.to_string()])
        .args(program)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env(
            "XDG_CACHE_HOME",
            Path::new(env!("CARGO_TARGET_TMPDIR")).join("xdg-cache"),
        )
        .output()
        .expect("mpirun (Debian: openmpi-bin; `cargo xtask setup mpi`)");
    common::Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into(),
        stderr: String::from_utf8_lossy(&out.stderr).into(),
    }
}

#[test]
fn ranks_composite_to_the_one_process_frame() {
    let dir = tempfile::tempdir().unwrap();
    // A float32 file each rank reads only its layers of (odd dims, values
    // that vary along z so that no rank's layers hold the whole range, and
    // NaN): the ranks agree on its source range, then its stored range.
    let raw = dir.path().join("ramp_37x29x45_float32.raw");
    let bytes: Vec<u8> = (0..37 * 29 * 45u32)
        .flat_map(|i| {
            let (x, y, z) = (i % 37, i / 37 % 29, i / (37 * 29));
            let v = match (x + y) % 5 {
                0 => 0.9 * z as f32 + 0.04 * x as f32 - 3.0,
                1 if z % 7 == 0 => f32::NAN,
                _ => -3.0,
            };
            v.to_le_bytes()
        })
        .collect();
    std::fs::write(&raw, bytes).unwrap();
    let cases: [&[&str]; 6] = [
        &["nbody:64", "--accel", "auto"],
        // Iso keeps each pixel's nearest surface: bit for bit.
        &[
            "turbulence:37x29x45",
            "--mode",
            "iso",
            "--iso",
            "0.45,0.6",
            "--perspective",
            "40",
            "--camera",
            "200,-30",
            "--accel",
            "grid",
        ],
        // MIP and MinIP keep each pixel's extreme ray value: bit for bit.
        &["nbody:64", "--mode", "mip", "--tf", "ramp:0.1:1", "--accel", "auto"],
        &[
            "turbulence:37x29x45",
            "--mode",
            "minip",
            "--tf",
            "band:0.05:0.45",
            "--camera",
            "90,10",
            "--accel",
            "distance",
        ],
        &[raw.to_str().unwrap(), "--tf", "ramp:0.2:1", "--accel", "grid"],
        &[
            "turbulence:37x29x45",
            "--tf",
            "ramp:0.3:0.9",
            "--perspective",
            "40",
            "--camera",
            "200,-30",
            "--shade",
            "on",
            "--accel",
            "distance",
        ],
    ];
    for (i, case) in cases.iter().enumerate() {
        let one = dir.path().join(format!("one{i}.exr"));
        let mut args = vec!["render"];
        args.extend_from_slice(case);
        args.extend(["--size", "96x80", "--validate"]);
        let r = common::lacuna(
            &[&args, &["--filter", "manual", "--out", one.to_str().unwrap()][..]].concat(),
            &[],
        );
        assert_eq!(r.code, 0, "{}", r.stderr);
        let one = Frame::read_exr(&one).unwrap();
        assert!(
            one.pixels.iter().filter(|p| p[3] > 0.001).count() > 20,
            "{case:?} shows the volume"
        );
        // The modes that pick by value: three ranks (cut across z and y).
        let rank_counts: &[u32] = if case.contains(&"--mode") { &[3] } else { &[2, 3] };
        for &ranks in rank_counts {
            let out = dir.path().join(format!("ranks{i}_{ranks}.exr"));
            let mut all = args.clone();
            all.extend(["--out", out.to_str().unwrap()]);
            let r = mpirun(ranks, &all);
            assert_eq!(r.code, 0, "{ranks} ranks {case:?}:\n{}\n{}", r.stdout, r.stderr);
            assert!(
                r.stdout.contains("composite") && r.stdout.contains(&format!("rank {}:", ranks - 1)),
                "{}",
                r.stdout
            );
            // Rank 0 alone reports and writes.
            assert_eq!(r.stdout.matches("wrote ").count(), 1, "{}", r.stdout);
            let frame = Frame::read_exr(&out).unwrap();
            assert_eq!(
                frame.metadata.get("ranks").map(String::as_str),
                Some(&*ranks.to_string())
            );
            let d = diff(&one, &frame).unwrap();
            match case.contains(&"--mode") {
                true => assert_eq!(d.differing, 0, "{ranks} ranks {case:?}: {d:?}"),
                false => assert!(d.max_abs < 1e-5, "{ranks} ranks {case:?}: {d:?}"),
            }
        }
    }
}

/// Every rank ends non-zero, one `error:` line in all, naming `needle`,
/// and no file is written.
fn fails_on_ranks(ranks: u32, args: &[&str], needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    all.extend(["--size", "32x32", "--validate", "--out", out.to_str().unwrap()]);
    let r = mpirun(ranks, &all);
    assert_ne!(r.code, 0, "{all:?} succeeded: {}", r.stdout);
    let errors: Vec<&str> = r.stderr.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{all:?}: expected one error line, got:\n{}", r.stderr);
    assert!(errors[0].contains(needle), "'{}' lacks '{needle}'", errors[0]);
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "{all:?} left a file behind"
    );
}

#[test]
fn bad_requests_across_ranks_are_one_error() {
    // One brick of 16^3, two ranks.
    fails_on_ranks(2, &["nbody:16"], "invalid rank count '2'");
    fails_on_ranks(3, &["nbody:32", "--mode", "average"], "does not composite across ranks");
    fails_on_ranks(
        2,
        &["nbody:32", "--mode", "iso", "--iso", "0.5", "--step", "15"],
        "iso across ranks reads the sample one step before a block",
    );
    fails_on_ranks(
        2,
        &["nbody:32", "--storage", "dense"],
        "ranks store their blocks in bricks",
    );
    fails_on_ranks(
        2,
        &["no-such-file.raw", "--dims", "64x64x64", "--type", "uint8"],
        "no-such-file.raw",
    );
    // A file shorter than its dims, found before any rank renders.
    let data = tempfile::tempdir().unwrap();
    let short = data.path().join("short.raw");
    std::fs::write(&short, vec![0u8; 100]).unwrap();
    let short = short.to_str().unwrap();
    fails_on_ranks(
        2,
        &[short, "--dims", "64x64x64", "--type", "uint8"],
        "holds 100 bytes of voxel data but 64x64x64 uint8 needs 262144",
    );
}

#[test]
fn a_rank_that_fails_before_the_others_stream_ends_every_rank_with_its_error() {
    // Rank 1 finds no device and fails before its load, while the others
    // stream their layers and wait on the ranks' agreement on the range:
    // they must stop, not hang, and rank 1 alone reports.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let script = format!(
        "if [ \"$OMPI_COMM_WORLD_RANK\" = 1 ]; then export LACUNA_DEVICE=no-such-device; fi; exec {} render nbody:64 --size 32x32 --validate --out {}",
        env!("CARGO_BIN_EXE_lacuna"),
        out.display()
    );
    for ranks in [2, 3] {
        let r = mpirun_program(ranks, &["sh", "-c", &script]);
        assert_ne!(r.code, 0, "{}", r.stdout);
        let errors: Vec<&str> = r.stderr.lines().filter(|l| l.starts_with("error:")).collect();
        assert_eq!(errors.len(), 1, "expected one error line, got:\n{}", r.stderr);
        assert!(
            errors[0].contains("no-such-device") && errors[0].contains(&format!("(rank 1 of {ranks})")),
            "{}",
            errors[0]
        );
        assert!(!out.exists(), "a file was written");
    }
}
