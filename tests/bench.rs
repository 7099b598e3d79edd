//! `lacuna bench` end to end on a tiny config: every output exists and is
//! consistent (the JSON holds every data set x structure), every exact
//! structure matches naive, the hard-case suite passes, bad input fails.

use lacuna::bench::{BenchConfig, ErrorPoint, Record};
use std::path::Path;
use std::process::Command;

fn lacuna(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_lacuna")).args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

const TINY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/tiny-bench.toml");

#[test]
fn tiny_bench_writes_consistent_tables_json_csv_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let (code, stdout, stderr) = lacuna(&[
        "bench",
        TINY,
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--validate",
        "--frames-out",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    for needle in [
        "Table 2",
        "Table 1",
        "Image error against naive",
        "skipped optional data set /no/such/volume.nii.gz",
    ] {
        assert!(stdout.contains(needle), "'{needle}' missing:\n{stdout}");
    }
    let config = BenchConfig::load(Path::new(TINY)).unwrap();
    let records: Vec<Record> =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let datasets = ["nbody:32", "menger:27"];
    assert_eq!(records.len(), datasets.len() * config.structures.len());
    for d in datasets {
        for s in &config.structures {
            let r = records
                .iter()
                .find(|r| r.dataset == d && r.structure == s.label)
                .unwrap_or_else(|| panic!("{d} x {} missing", s.label));
            assert_eq!((r.setup.width, r.setup.height, r.setup.frames), (32, 32, 2));
            assert!(!r.setup.device.is_empty() && !r.setup.driver.is_empty());
            assert!(
                r.fps > 0.0 && r.frame.min_ms <= r.frame.median_ms && r.frame.median_ms <= r.frame.max_ms,
                "{d} {}: {:?}",
                s.label,
                r.frame
            );
            assert!(r.visible_percent > 0.0 && r.active_brick_percent > 0.0);
            if s.accel == "naive" {
                assert_eq!(r.nodes, 0);
            } else {
                assert!(
                    r.build_ms > 0.0 && r.nodes > 0 && r.tree_height > 0 && !r.build_phases_ms.is_empty(),
                    "{d} {}",
                    s.label
                );
            }
            if !s.label.contains("paper") {
                assert_eq!(r.error_vs_naive.differing, 0, "{d} {} differs from naive", s.label);
            }
        }
    }
    assert_eq!(
        records.iter().find(|r| r.dataset == "menger:27").unwrap().tf,
        "ramp:0.3:1:0.3"
    );
    // CSV: a header and a row per record.
    assert_eq!(
        std::fs::read_to_string(out.join("results.csv"))
            .unwrap()
            .lines()
            .count(),
        records.len() + 1
    );
    // Speed against error: 2 steps x 2 thresholds, errors shrink with the step.
    let points: Vec<ErrorPoint> =
        serde_json::from_str(&std::fs::read_to_string(out.join("error.json")).unwrap()).unwrap();
    assert_eq!(points.len(), 4);
    let rmse = |step: f32| {
        points
            .iter()
            .find(|p| p.sweep_step == step && p.ert.is_none())
            .unwrap()
            .error
            .rmse
    };
    assert!(rmse(0.25) < rmse(1.0), "a finer step should be closer to the reference");
    for f in [
        "table1.md",
        "table2.md",
        "exactness.md",
        "error.md",
        "error.csv",
        "notes.txt",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    for f in ["fig3-fps", "fig4-build-rate", "error"] {
        let svg = std::fs::read_to_string(out.join(format!("{f}.svg"))).unwrap();
        assert!(svg.starts_with("<svg") || svg.contains("<svg"), "{f}.svg");
        let png = std::fs::read(out.join(format!("{f}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG", "{f}.png");
    }
    let frames = std::fs::read_dir(out.join("frames")).unwrap().count();
    assert_eq!(frames, records.len());
}

#[test]
fn the_hard_case_suite_passes_for_every_structure() {
    let (code, stdout, stderr) = lacuna(&["bench", "--suite", "hard", "--quiet"]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("| hard case | lbvh | grid |"), "{stdout}");
    assert!(!stdout.contains("FAIL"), "{stdout}");
    let runs = lacuna::bench::hard::cases().unwrap().len() * lacuna::bench::hard::structures().len();
    assert!(
        stdout.contains(&format!("hard cases: {runs} of {runs} structure runs passed")),
        "{stdout}"
    );
}

#[test]
fn built_in_configs_parse_and_cover_every_structure() {
    for (text, name) in [
        (lacuna::bench::config::QUICK, "quick"),
        (lacuna::bench::config::PAPER, "paper"),
    ] {
        let c = BenchConfig::parse(text, name).unwrap();
        for accel in lacuna::accel::Accel::ALL {
            assert!(
                c.structures.iter().any(|s| s.accel == accel.name()),
                "{name} lacks {accel}"
            );
        }
        assert!(
            c.error.as_ref().unwrap().datasets.as_ref().unwrap().len() >= 3,
            "{name}: speed against error needs three data sets"
        );
    }
}

#[test]
fn bad_bench_input_is_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        "name = \"x\"\nsize = [8, 8]\nframes = 1\nwarmup = 0\nbuilds = 1\nstep = 0.5\nelevation = 0.0\nbogus = 1\n",
    )
    .unwrap();
    let dup = dir.path().join("dup.toml");
    std::fs::write(
        &dup,
        "name = \"x\"\nsize = [8, 8]\nframes = 1\nwarmup = 0\nbuilds = 1\nstep = 0.5\nelevation = 0.0\n[[dataset]]\nvolume = \"nbody:8\"\n[[structure]]\nlabel = \"a\"\naccel = \"lbvh\"\n[[structure]]\nlabel = \"a\"\naccel = \"grid\"\n",
    )
    .unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["bench"], "give exactly one of"),
        (vec!["bench", "--quick", "--paper"], "give exactly one of"),
        (vec!["bench", "--suite", "soft"], "expected hard"),
        (vec!["bench", "/no/such.toml"], "/no/such.toml"),
        (vec!["bench", bad.to_str().unwrap()], "unknown field"),
        (vec!["bench", dup.to_str().unwrap()], "appears twice"),
        (vec!["bench", "--quick", "--frames", "0"], "invalid frames"),
        (vec!["bench", "--quick", "--size", "0x4"], "width and height"),
    ];
    for (args, needle) in cases {
        let (code, _, stderr) = lacuna(&args);
        assert_ne!(code, 0, "{args:?}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
}
