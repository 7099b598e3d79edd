//! `lacuna bench` end to end on a tiny config: every output exists and is
//! consistent (the JSON holds every data set x structure), every exact
//! structure matches naive, the hard-case suite's command runs the cases
//! and looks it is asked for, the whole suite passes (run in this process),
//! bad input fails.

use crate::common;
use lacuna::bench::{BenchConfig, ErrorPoint, Record};
use std::path::Path;
use std::process::Command;

fn lacuna(args: &[&str]) -> (i32, String, String) {
    // auto's kernel constants in the tests' shared cache (tests/common).
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("xdg-cache");
    let out = Command::new(env!("CARGO_BIN_EXE_lacuna"))
        .args(args)
        .env("XDG_CACHE_HOME", cache)
        .output()
        .unwrap();
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
        "Time to the first exact frame of a new time step",
    ] {
        assert!(stdout.contains(needle), "'{needle}' missing:\n{stdout}");
    }
    let config = BenchConfig::load(Path::new(TINY)).unwrap();
    let records: Vec<Record> =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    // The series' new steps: every structure, each step exact (but the
    // paper's classification, which need not be).
    let steps: Vec<lacuna::bench::series::StepRecord> =
        serde_json::from_str(&std::fs::read_to_string(out.join("steps.json")).unwrap()).unwrap();
    assert_eq!(steps.len(), config.structures.len());
    for r in &steps {
        assert_eq!(
            (r.dataset.as_str(), r.steps.as_slice()),
            ("nbody:32 [time 2..4]", &[3, 4][..]),
            "{r:?}"
        );
        if !r.structure.contains("paper classification") {
            assert_eq!(r.differing_pixels, 0, "{r:?}");
        }
        let parts = r.upload_ms + r.ranges_ms + r.build_ms + r.frame_ms;
        assert!(r.new_step_ms > 0.0 && r.load_ms > 0.0 && r.next_frame_ms > 0.0, "{r:?}");
        // Medians of sums are not sums of medians, but they bound each other.
        assert!(r.new_step_ms <= 4.0 * parts && parts <= 4.0 * r.new_step_ms, "{r:?}");
    }
    let datasets = ["nbody:32 [time 2..4]", "menger:27"];
    // Each kept frame says how to make it again, as `render`'s does: the
    // series' frames are its step FIRST's.
    let kept = lacuna::frame::Frame::read_exr(&out.join("frames/nbody_32__time_2..4_-grid_8.exr")).unwrap();
    for (key, value) in [
        ("volume", "nbody:32x32x32"),
        ("accel", "grid"),
        ("cell", "8"),
        ("time", "2"),
        ("step", "0.5"),
    ] {
        assert_eq!(
            kept.metadata.get(key).map(String::as_str),
            Some(value),
            "{key}: {:?}",
            kept.metadata
        );
    }
    assert!(
        kept.metadata.contains_key("device") && kept.metadata.contains_key("camera"),
        "{:?}",
        kept.metadata
    );
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
            // Every view timed in every round; warm-up within its bounds.
            assert_eq!(r.setup.rounds, 2);
            assert_eq!(r.frame.samples, r.setup.frames * r.setup.rounds, "{d} {}", s.label);
            assert!(
                (2..=config.warmup_cap).contains(&r.warmed_up.frames)
                    && (2..=config.warmup_cap).contains(&r.warmed_up.builds),
                "{d} {}: {:?}",
                s.label,
                r.warmed_up
            );
            assert!(
                r.build_min_ms <= r.build_ms && r.build_ms <= r.build_max_ms,
                "{d} {}",
                s.label
            );
            // The noise flag follows the spreads it is defined by.
            assert!(r.frame_spread >= 1.0 && r.build_spread >= 1.0);
            assert_eq!(
                r.unstable,
                r.frame_spread > 1.5 || r.build_spread > 1.5,
                "{d} {}",
                s.label
            );
            assert!(
                r.frame_spread <= r.frame.max_ms / r.frame.min_ms + 1e-9,
                "a view's spread cannot exceed the record's"
            );
            // Speed-up over naive from the same rounds: naive's own is 1.
            assert!(r.speedup.is_finite() && r.speedup > 0.0, "{d} {}", s.label);
            if s.accel == "naive" {
                assert_eq!(r.speedup, 1.0);
            } else {
                // The median of paired ratios lies between the extreme ratios.
                let naive = records.iter().find(|n| n.dataset == d && n.accel == "naive").unwrap();
                assert!(
                    r.speedup <= naive.frame.max_ms / r.frame.min_ms + 1e-9
                        && r.speedup >= naive.frame.min_ms / r.frame.max_ms - 1e-9,
                    "{d} {}: speed-up {} outside what the times allow",
                    s.label,
                    r.speedup
                );
            }
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
    // CSV: a header and a row per record, with the speed-up and the flag.
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert_eq!(csv.lines().count(), records.len() + 1);
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    for column in [
        "frame_min_ms",
        "frame_median_ms",
        "frame_max_ms",
        "speedup",
        "unstable",
        "warmup_capped",
        "driver",
        "camera",
        "filter",
        "chosen",
    ] {
        assert!(header.contains(&column), "CSV lacks {column}");
    }
    // Tables: speed-ups in Table 2 and the frame table; a dagger exactly
    // when a record is unstable.
    let table2 = std::fs::read_to_string(out.join("table2.md")).unwrap();
    let frames_md = std::fs::read_to_string(out.join("frames.md")).unwrap();
    assert!(table2.contains("(1.00x)"), "{table2}");
    assert!(frames_md.contains(" 1.00x"), "{frames_md}");
    let marked = |t: &str| {
        t.lines()
            .filter(|l| l.starts_with('|'))
            .map(|l| l.matches(" †").count())
            .sum::<usize>()
    };
    let unstable = records.iter().filter(|r| r.unstable).count();
    assert_eq!(marked(&table2), unstable, "{table2}");
    assert_eq!(marked(&frames_md), unstable, "{frames_md}");
    // The legend only where a record is marked.
    let legend = |t: &str| t.contains("† unstable: ");
    assert_eq!(
        (legend(&table2), legend(&frames_md)),
        (unstable > 0, unstable > 0),
        "{table2}"
    );
    let mut steady = records.clone();
    steady.iter_mut().for_each(|r| r.unstable = false);
    assert!(!legend(&lacuna::bench::tables::table2_md(&steady)));
    assert!(stdout.contains("fastest on nbody:32 [time 2..4]: "), "{stdout}");
    // Only an exact structure can be the fastest: a faster one whose image
    // differs from naive's (the paper's classification can) is passed over.
    let mut fast = records.clone();
    fast[1].frame.median_ms = 1e-6;
    let fastest = |rs: &[Record]| -> Vec<(String, String)> {
        let pick = lacuna::bench::tables::fastest(rs);
        pick.iter().map(|r| (r.dataset.clone(), r.structure.clone())).collect()
    };
    let it = (fast[1].dataset.clone(), fast[1].structure.clone());
    assert!(fastest(&fast).contains(&it));
    fast[1].error_vs_naive.differing = 3;
    assert!(!fastest(&fast).contains(&it));

    // The run compared with itself passes; with one median doubled it fails.
    let results = out.join("results.json");
    let (code, stdout, stderr) = lacuna(&[
        "bench",
        "--compare",
        results.to_str().unwrap(),
        results.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(stdout.contains("largest change of a median 0.0 %"), "{stdout}");
    let mut slower = records.clone();
    let last = slower.len() - 1;
    slower[last].frame.median_ms *= 2.0;
    let slower_path = dir.path().join("slower.json");
    std::fs::write(&slower_path, serde_json::to_string(&slower).unwrap()).unwrap();
    let (code, stdout, _) = lacuna(&[
        "bench",
        "--compare",
        results.to_str().unwrap(),
        slower_path.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{stdout}");
    assert!(
        stdout.contains("largest change of a median 100.0 %") && stdout.contains("FAIL"),
        "{stdout}"
    );
    // A record B lost fails, named; so does one B gained.
    let lost = records[..last].to_vec();
    let lost_path = dir.path().join("lost.json");
    std::fs::write(&lost_path, serde_json::to_string(&lost).unwrap()).unwrap();
    let gone = format!("{} / {}", records[last].dataset, records[last].structure);
    for (a, b, side) in [
        (&results, &lost_path, "in A only: "),
        (&lost_path, &results, "in B only: "),
    ] {
        let (code, stdout, _) = lacuna(&["bench", "--compare", a.to_str().unwrap(), b.to_str().unwrap()]);
        assert_eq!(code, 1, "{stdout}");
        assert!(
            stdout.contains(&format!("{side}{gone}")) && stdout.contains("FAIL"),
            "{stdout}"
        );
    }
    // Another device is named and compared; another frame size (or
    // filter, step, ...) is not the same work: one error line, no verdict.
    // There the default filter may be the other one: a note too.
    let mut elsewhere = records.clone();
    for r in &mut elsewhere {
        r.setup.device = "another GPU".into();
        r.filter = "hardware".into();
    }
    let mut smaller = records.clone();
    smaller[0].setup.width /= 2;
    smaller[0].filter = "hardware".into();
    for (name, other, code, needle) in [
        (
            "elsewhere.json",
            &elsewhere,
            0,
            "note: the runs differ in sample filter: A manual, B hardware",
        ),
        ("smaller.json", &smaller, 2, "the runs rendered different frames: "),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, serde_json::to_string(other).unwrap()).unwrap();
        let (got, stdout, stderr) = lacuna(&["bench", "--compare", results.to_str().unwrap(), path.to_str().unwrap()]);
        assert_eq!(got, code, "{name}: {stdout}\n{stderr}");
        assert!(
            stdout.contains(needle) || stderr.contains(needle),
            "{name}: {stdout}\n{stderr}"
        );
        if code == 2 {
            assert!(
                stderr.trim().lines().count() == 1
                    && stderr.contains("filter manual against hardware")
                    && !stdout.contains("PASS"),
                "{stderr}"
            );
        }
    }
    // Records no run writes are refused, not compared as NaN: a time of
    // zero or less, and a data set x structure twice.
    let mut zero = records.clone();
    zero[0].frame.median_ms = 0.0;
    let twice = [records.clone(), records.clone()].concat();
    for (name, bad, needle) in [
        ("zero.json", &zero, "median_ms 0 is not a positive time"),
        ("twice.json", &twice, "appears twice"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, serde_json::to_string(bad).unwrap()).unwrap();
        let (code, _, stderr) = lacuna(&["bench", "--compare", path.to_str().unwrap(), results.to_str().unwrap()]);
        assert_eq!(code, 2, "{name}: {stderr}");
        assert!(
            stderr.trim().lines().count() == 1 && stderr.contains(needle),
            "{name}: {stderr}"
        );
    }
    // Speed against error: 2 filters x 2 steps x 2 thresholds, errors shrink
    // with the step under each filter.
    let points: Vec<ErrorPoint> =
        serde_json::from_str(&std::fs::read_to_string(out.join("error.json")).unwrap()).unwrap();
    assert_eq!(points.len(), 8);
    for filter in ["manual", "hardware"] {
        let rmse = |step: f32| {
            points
                .iter()
                .find(|p| p.sweep_step == step && p.ert.is_none() && p.filter == filter)
                .unwrap()
                .error
                .rmse
        };
        assert!(
            rmse(0.25) < rmse(1.0),
            "{filter}: a finer step should be closer to the reference"
        );
    }
    // The timed frames use the device's faster filter for 8-bit volumes:
    // manual from the cells copy on a CPU device, else hardware.
    let cpu = common::gpu().info().device_type == lacuna::gpu::vk::PhysicalDeviceType::CPU;
    let faster = if cpu { "manual" } else { "hardware" };
    assert!(
        records.iter().all(|r| r.filter == faster),
        "timed filter is not {faster}"
    );
    for f in [
        "table1.md",
        "table2.md",
        "exactness.md",
        "frames.md",
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

/// Runs the hard-case suite in `looks` on a pooled context (the kernels it
/// makes serve later tests; a `lacuna bench` process would make them for
/// itself alone); asserts every run passed, and every case and structure
/// ran in each look under at least the manual filter.
fn hard_suite_passes(looks: &[&str]) {
    use lacuna::bench::hard::{self, Selection};
    let gpu = common::gpu();
    let only = Selection {
        looks: looks.iter().map(|l| l.to_string()).collect(),
        cases: Vec::new(),
    };
    let outcomes = hard::run(&gpu, &only, |_| {}).unwrap();
    let failed: Vec<String> = outcomes
        .iter()
        .filter(|o| !o.passed())
        .map(|o| format!("{} / {} / {} / {}: {}", o.case, o.look, o.filter, o.structure, o.detail))
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
    let cases = hard::cases().unwrap();
    let structures = hard::structures().unwrap();
    assert!(cases.iter().any(|c| c.volume.channel_count() > 1));
    // Several channels are not rendered lit (README, "Channels").
    let lit = |look: &str| look.starts_with("shaded") || look.starts_with("iso");
    for case in &cases {
        for look in looks.iter().filter(|l| case.volume.channel_count() == 1 || !lit(l)) {
            for (label, _, _) in &structures {
                assert!(
                    outcomes.iter().any(|o| o.case == case.name
                        && o.look == *look
                        && o.filter == lacuna::render::Filter::Manual
                        && o.structure == *label),
                    "{} / {look} / {label} did not run",
                    case.name
                );
            }
        }
    }
    // Average is marched naively by every structure; the others skip.
    for o in &outcomes {
        assert_eq!(
            o.mode_fallback,
            o.look == "average",
            "{} / {} / {}: marched naively",
            o.case,
            o.look,
            o.structure
        );
    }
}

// The suite in three parts, which the test harness runs side by side.
#[test]
fn the_hard_case_suite_passes_in_composite_and_shaded() {
    hard_suite_passes(&["composite", "shaded, jittered"]);
}

#[test]
fn the_hard_case_suite_passes_in_mip_and_minip() {
    hard_suite_passes(&["mip", "minip"]);
}

#[test]
fn the_hard_case_suite_passes_in_average_and_iso() {
    hard_suite_passes(&["average", "iso, jittered"]);
}

/// `lacuna bench --suite hard` end to end on two cases in two looks: the
/// table's rows and the summary count what ran.
#[test]
fn the_hard_suite_command_runs_the_cases_and_looks_named() {
    let cases = ["a single active voxel", "two channels, one transparent"];
    let looks = ["shaded, jittered", "average"];
    let mut args = vec!["bench", "--suite", "hard", "--quiet"];
    for c in cases {
        args.extend(["--case", c]);
    }
    for l in looks {
        args.extend(["--look", l]);
    }
    let (code, stdout, stderr) = lacuna(&args);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    assert!(
        stdout.contains("| hard case | look | filter | lbvh | lbvh collapsed | grid |"),
        "{stdout}"
    );
    assert!(!stdout.contains("FAIL"), "{stdout}");
    // Two channels are not lit: three case-look pairs, each under the
    // manual filter at least.
    for row in [
        "| a single active voxel | shaded, jittered | manual |",
        "| a single active voxel | average | manual |",
        "| two channels, one transparent | average | manual |",
    ] {
        assert!(stdout.contains(row), "{row}\n{stdout}");
    }
    assert!(!stdout.contains("| two channels, one transparent | shaded"), "{stdout}");
    assert!(!stdout.contains("grazing rays"), "{stdout}");
    let rows = stdout
        .lines()
        .filter(|l| l.starts_with("| a ") || l.starts_with("| two "))
        .count();
    assert_eq!(rows, 3, "{stdout}");
    let structures = lacuna::bench::hard::structures().unwrap().len();
    let line = stdout.lines().find(|l| l.starts_with("hard cases: ")).unwrap();
    let numbers: Vec<usize> = line
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|w| w.parse().ok())
        .collect();
    // passed, of total, marched naively (every structure in average).
    assert_eq!(numbers[0], numbers[1], "{line}");
    assert_eq!(numbers[1], rows * structures, "{line}");
    let average_rows = stdout.lines().filter(|l| l.contains("| average |")).count();
    assert_eq!(numbers[2], average_rows * structures, "{line}");
}

#[test]
fn an_unknown_hard_suite_case_is_refused() {
    let (code, _, stderr) = lacuna(&["bench", "--suite", "hard", "--case", "rays of light"]);
    assert_ne!(code, 0);
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("invalid case 'rays of light': expected one of: rays parallel to an axis;"),
        "{stderr}"
    );
    // A case named only in looks it does not run in runs nothing: an
    // error, not an empty pass.
    let (code, stdout, stderr) = lacuna(&[
        "bench",
        "--suite",
        "hard",
        "--case",
        "two channels, one transparent",
        "--look",
        "shaded, jittered",
    ]);
    assert_ne!(code, 0, "{stdout}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("runs in none of the looks named"), "{stderr}");
}

#[test]
fn an_unknown_hard_suite_look_is_refused() {
    let (code, _, stderr) = lacuna(&["bench", "--suite", "hard", "--look", "glow"]);
    assert_ne!(code, 0);
    assert!(
        stderr.contains("invalid look 'glow': expected one of: composite;"),
        "{stderr}"
    );
}

#[test]
fn built_in_configs_parse_and_cover_every_structure() {
    for (text, name) in [
        (lacuna::bench::config::QUICK, "quick"),
        (lacuna::bench::config::PAPER, "paper"),
    ] {
        let c = BenchConfig::parse(text, name).unwrap();
        for accel in lacuna::accel::TABLE {
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
fn protocol_fields_have_documented_defaults_and_data_sets_their_own_ert() {
    // Only data sets and structures: every protocol field takes its default
    // (README, "Benchmark"), and the file's stem names the run.
    let c = BenchConfig::parse(
        "[[dataset]]\nvolume = \"nbody:8\"\n[[dataset]]\nvolume = \"nbody:8\"\nert = 0.99\n\
         [[structure]]\nlabel = \"n\"\naccel = \"naive\"\n",
        "/some/where/mine.toml",
    )
    .unwrap();
    assert_eq!(c.name, "mine");
    assert_eq!(c.size, [512, 512]);
    assert_eq!((c.frames, c.warmup, c.builds, c.rounds, c.warmup_cap), (6, 2, 3, 3, 30));
    assert_eq!((c.step, c.elevation, c.ert, c.stable), (0.5, 20.0, None, 0.05));
    assert_eq!(c.datasets[1].ert, Some(0.99));
    assert_eq!(c.datasets[1].label(&c).unwrap(), "nbody:8 [ert 0.99]");
    assert_eq!(c.datasets[0].label(&c).unwrap(), "nbody:8");
    let ranged = BenchConfig::parse(
        "[[dataset]]\nvolume = \"nbody:8\"\nvalue_range = [0.0, 500.0]\n[[structure]]\nlabel = \"n\"\naccel = \"naive\"\n",
        "range.toml",
    )
    .unwrap();
    assert_eq!(ranged.datasets[0].label(&ranged).unwrap(), "nbody:8 [range 0..500]");
    assert_eq!(ranged.datasets[0].options().unwrap().value_range, Some([0.0, 500.0]));
    // An iso value as a TOML number is the same as its text; a time range
    // is in the label.
    let iso = |value: &str| {
        let c = BenchConfig::parse(
            &format!(
                "[[dataset]]\nvolume = \"nbody:8\"\ntime = [1, 3]\nlook = {{ mode = \"iso\", iso = {value} }}\n\
                 [[structure]]\nlabel = \"n\"\naccel = \"naive\"\n"
            ),
            "iso.toml",
        );
        c.and_then(|c| c.datasets[0].label(&c)).map_err(|e| e.to_string())
    };
    assert_eq!(iso("0.3"), iso("\"0.3\""));
    assert_eq!(iso("0.3").unwrap(), "nbody:8 [mode iso; iso 0.3; shade; time 1..3]");
    assert!(
        iso("true").unwrap_err().contains("a number or a string of numbers"),
        "{:?}",
        iso("true")
    );
    // The built-in auto suite times every data set with ERT off and on.
    let auto = BenchConfig::parse(lacuna::bench::config::AUTO, "auto").unwrap();
    let on = auto.datasets.iter().filter(|d| d.ert.is_some()).count();
    assert_eq!(2 * on, auto.datasets.len());
    assert!(auto.structures.iter().any(|s| s.accel == "auto"));
}

/// A data set's `value_range` maps every step it times, and each new
/// step's frame stays naive's.
#[test]
fn a_data_sets_value_range_is_timed_exact_over_its_steps() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = dir.path().join("range.toml");
    std::fs::write(
        &cfg,
        "size = [16, 16]\nframes = 1\nwarmup = 0\nbuilds = 1\nrounds = 2\n\
         [[dataset]]\nvolume = \"nbody:16\"\ntime = [0, 1]\nvalue_range = [0.0, 400.0]\ntf = \"ramp:0.2:1\"\n\
         [[structure]]\nlabel = \"g\"\naccel = \"grid\"\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    let (code, stdout, stderr) = lacuna(&[
        "bench",
        cfg.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--validate",
    ]);
    assert_eq!(code, 0, "{stdout}\n{stderr}");
    let steps: Vec<lacuna::bench::series::StepRecord> =
        serde_json::from_str(&std::fs::read_to_string(out.join("steps.json")).unwrap()).unwrap();
    assert!(!steps.is_empty());
    for r in &steps {
        assert_eq!(r.dataset, "nbody:16 [time 0..1; range 0..400]", "{r:?}");
        assert_eq!(r.differing_pixels, 0, "{r:?}");
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
    let filter = dir.path().join("filter.toml");
    std::fs::write(
        &filter,
        "name = \"x\"\nsize = [8, 8]\nframes = 1\nwarmup = 0\nbuilds = 1\nstep = 0.5\nelevation = 0.0\n[[dataset]]\nvolume = \"nbody:8\"\n[[structure]]\nlabel = \"a\"\naccel = \"grid\"\n[error]\nsteps = [1.0]\nert = [0.0]\nfilters = [\"manual\", \"linear\"]\nreference_step = 0.5\nframes = 1\naccel = \"grid\"\n",
    )
    .unwrap();
    // Variations of a valid config with an error sweep, each with one fault.
    let base = "name = \"x\"\nsize = [8, 8]\nframes = 1\nwarmup = 0\nbuilds = 1\nstep = 0.5\nelevation = 0.0\n[[dataset]]\nvolume = \"nbody:8\"\n[[structure]]\nlabel = \"a\"\naccel = \"grid\"\n[error]\nsteps = [1.0]\nert = [0.0]\nreference_step = 0.5\nframes = 1\naccel = \"grid\"\n";
    let faults = [
        (
            "elevation",
            ("elevation = 0.0", "elevation = inf"),
            "elevation must be in [-90, 90] degrees, not inf",
        ),
        (
            "tf",
            ("volume = \"nbody:8\"", "volume = \"nbody:8\"\ntf = \"ramp:1:0\""),
            "data set 'nbody:8': invalid transfer function 'ramp:1:0'",
        ),
        (
            "storage",
            ("volume = \"nbody:8\"", "volume = \"nbody:8\"\nstorage = \"bricks:0\""),
            "data set 'nbody:8': invalid storage 'bricks:0'",
        ),
        (
            "escape",
            ("name = \"x\"", "name = \"../../escape\""),
            "must be a plain folder name",
        ),
        (
            "size3",
            ("size = [8, 8]", "size = [8, 8, 8]"),
            "size must be [width, height], not 3 numbers",
        ),
        (
            "range",
            ("volume = \"nbody:8\"", "volume = \"nbody:8\"\nvalue_range = [5.0, 1.0]"),
            "data set 'nbody:8 [range 5..1]': invalid value range '5:1': must be two finite values",
        ),
        (
            "time3",
            ("volume = \"nbody:8\"", "volume = \"nbody:8\"\ntime = [0, 3, 9]"),
            "time must be [FIRST, LAST], not 3 numbers",
        ),
        (
            "noframes",
            ("frames = 1\naccel", "frames = 0\naccel"),
            "error sweep frames must be in 1..=100000, not 0",
        ),
        (
            "manyframes",
            ("frames = 1\naccel", "frames = 4000000000\naccel"),
            "error sweep frames must be in 1..=100000, not 4000000000",
        ),
        (
            "twodatasets",
            (
                "volume = \"nbody:8\"\n",
                "volume = \"nbody:8\"\n[[dataset]]\nvolume = \"nbody:8\"\ntf = \"ramp:0.5:1\"\n",
            ),
            "data set 'nbody:8' appears twice",
        ),
        (
            "refstep",
            ("reference_step = 0.5", "reference_step = -1"),
            "reference_step -1 must be > 0",
        ),
        (
            "nothere",
            ("[error]\n", "[error]\ndatasets = [\"nothere:9\"]\n"),
            "error sweep data set 'nothere:9' is none of the [[dataset]] labels: nbody:8",
        ),
        (
            "unclosed",
            ("size = [8, 8]", "size = [8, 8"),
            "invalid array: expected `]`",
        ),
        // What a data set's spec and headers tell is checked before any
        // data set runs, naming the file and the data set.
        (
            "missingraw",
            ("volume = \"nbody:8\"", "volume = \"/no/such/v_8x8x8_uint8.raw\""),
            "missingraw.toml: data set '/no/such/v_8x8x8_uint8.raw': /no/such/v_8x8x8_uint8.raw: No such file",
        ),
        (
            "timepast",
            ("volume = \"nbody:8\"", "volume = \"nbody:8\"\ntime = [70, 80]"),
            "timepast.toml: data set 'nbody:8 [time 70..80]': invalid time '80': nbody:8 has 64 steps",
        ),
        (
            "timeback",
            ("volume = \"nbody:8\"", "volume = \"nbody:8\"\ntime = [3, 1]"),
            "timeback.toml: data set 'nbody:8 [time 3..1]': invalid time '[3, 1]'",
        ),
        (
            "tfcount",
            (
                "volume = \"nbody:8\"",
                "volume = \"nbody:8\"\ntf = \"ramp:0.3:1|ramp:0.2:1\"",
            ),
            "tfcount.toml: data set 'nbody:8': invalid transfer function",
        ),
        (
            "brickshardware",
            (
                "elevation = 0.0\n[[dataset]]\nvolume = \"nbody:8\"",
                "elevation = 0.0\nfilter = \"hardware\"\n[[dataset]]\nvolume = \"nbody:8\"\nstorage = \"bricks:8\"",
            ),
            "data set 'nbody:8 [storage bricks:8]': invalid filter 'hardware': bricked storage",
        ),
        (
            "shadechannels",
            (
                "volume = \"nbody:8\"",
                "volume = \"nbody:8+vessels:8\"\nlook = { shade = true }",
            ),
            "shadechannels.toml: data set 'nbody:8+vessels:8 [shade]': the volume has 2 channels",
        ),
        // The run adds naive under that label: two records of one name.
        (
            "naivelabel",
            ("label = \"a\"", "label = \"naive\""),
            "structure label 'naive' is the naive march's (every run times it), not grid's",
        ),
    ];
    let mut fault_cases = Vec::new();
    for (name, (from, to), needle) in faults {
        assert!(base.contains(from), "{name}");
        let path = dir.path().join(format!("{name}.toml"));
        std::fs::write(&path, base.replacen(from, to, 1)).unwrap();
        fault_cases.push((path, needle));
    }
    let mut cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["bench", filter.to_str().unwrap()], "expected manual or hardware"),
        (
            vec!["bench", "--quick", "--filter", "linear"],
            "expected manual or hardware",
        ),
        (vec!["bench"], "give exactly one of"),
        (vec!["bench", "--quick", "--paper"], "give exactly one of"),
        (vec!["bench", "--suite", "soft"], "expected hard or auto"),
        (vec!["bench", "/no/such.toml"], "/no/such.toml"),
        (
            vec!["bench", bad.to_str().unwrap()],
            "invalid bench config at line 8, column 1: unknown field `bogus`",
        ),
        (vec!["bench", dup.to_str().unwrap()], "appears twice"),
        (
            vec!["bench", "--quick", "--frames", "0"],
            "frames and builds must be at least 1",
        ),
        (vec!["bench", "--quick", "--rounds", "1"], "rounds must be at least 2"),
        (vec!["bench", "--quick", "--ert", "1.5"], "ert must be in (0, 1]"),
        (vec!["bench", "--compare", "/no/a.json", "/no/b.json"], "/no/a.json"),
        // Input files are checked before they are read: a device never ends.
        (vec!["bench", "/dev/zero"], "/dev/zero: is not a regular file"),
        (
            vec!["bench", "--compare", "/dev/zero", "/dev/zero"],
            "/dev/zero: is not a regular file",
        ),
        (vec!["bench", "--quick", "--compare", "a", "b"], "give exactly one of"),
        // Options the source does not read.
        (
            vec!["bench", "--compare", "a", "b", "--frames", "3"],
            "invalid option '--frames': --compare reads two results.json and runs nothing",
        ),
        (
            vec!["bench", "--suite", "hard", "--rounds", "3"],
            "invalid option '--rounds': the hard suite's cases fix their own frames",
        ),
        (
            vec!["bench", "--suite", "hard", "--recalibrate"],
            "invalid option '--recalibrate': the hard suite's cases fix their own frames, price auto with nominal constants",
        ),
        (
            vec!["bench", "--suite", "auto", "--look", "mip"],
            "invalid option '--look': it chooses among the hard suite's looks and cases",
        ),
        (vec!["bench", "--quick", "--size", "0x4"], "width and height"),
        (vec!["bench", "--quick", "--size", "100000x100000"], "1..=16384 pixels"),
    ];
    let file = dir.path().join("a-file");
    std::fs::write(&file, "").unwrap();
    let under_file = file.join("run");
    cases.push((
        vec!["bench", "--quick", "--out", under_file.to_str().unwrap()],
        "a-file: exists and is not a folder",
    ));
    // Two labels one frame file: refused before anything runs.
    let one_file = dir.path().join("one-file.toml");
    std::fs::write(
        &one_file,
        base.replacen(
            "accel = \"grid\"\n[error]",
            "accel = \"grid\"\n[[structure]]\nlabel = \"x y\"\naccel = \"lbvh\"\n[[structure]]\nlabel = \"x_y\"\naccel = \"kd-cpu\"\n[error]",
            1,
        ),
    )
    .unwrap();
    cases.push((
        vec!["bench", one_file.to_str().unwrap(), "--frames-out"],
        "--frames-out would write 'nbody:8 / x y' and 'nbody:8 / x_y' to one file, frames/nbody_8-x_y.exr",
    ));
    // `--rounds 2` mends a file's `rounds = 1`: the run gets past the
    // protocol's checks to the output folder.
    let one_round = dir.path().join("one-round.toml");
    std::fs::write(&one_round, format!("rounds = 1\n{base}")).unwrap();
    cases.push((
        vec!["bench", one_round.to_str().unwrap()],
        "one-round.toml: rounds must be at least 2",
    ));
    cases.push((
        vec![
            "bench",
            one_round.to_str().unwrap(),
            "--rounds",
            "2",
            "--out",
            under_file.to_str().unwrap(),
        ],
        "a-file: exists and is not a folder",
    ));
    cases.push((
        vec!["bench", "--quick", "--rounds", "1"],
        "bench/quick.toml (built in) with the command line's overrides: rounds must be at least 2",
    ));
    // `optional` skips a missing volume, not a missing transfer function.
    let tf_missing = dir.path().join("tf-missing.toml");
    std::fs::write(
        &tf_missing,
        base.replacen(
            "volume = \"nbody:8\"",
            "volume = \"nbody:8\"\noptional = true\ntf = \"/no/such/tf.json\"",
            1,
        ),
    )
    .unwrap();
    let tf_out = dir.path().join("tf-out");
    let (code, _, stderr) = lacuna(&[
        "bench",
        tf_missing.to_str().unwrap(),
        "--quiet",
        "--out",
        tf_out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("invalid transfer function '/no/such/tf.json'"),
        "{stderr}"
    );
    // Nothing measured is no result: every data set optional and missing.
    let none = dir.path().join("none.toml");
    std::fs::write(
        &none,
        base.split("[error]").next().unwrap().replacen(
            "volume = \"nbody:8\"",
            "volume = \"/no/such/v.nii\"\noptional = true\ntf = \"/no/such/tf.json\"",
            1,
        ),
    )
    .unwrap();
    let none_out = dir.path().join("none-out");
    for (path, needle) in &fault_cases {
        cases.push((vec!["bench", path.to_str().unwrap()], needle));
    }
    for (args, needle) in cases {
        let (code, _, stderr) = lacuna(&args);
        assert_ne!(code, 0, "{args:?}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
    }
    // The skipped data set's note, then one error.
    let (code, _, stderr) = lacuna(&["bench", none.to_str().unwrap(), "--out", none_out.to_str().unwrap()]);
    let last = stderr.trim().lines().last().unwrap_or_default();
    assert_eq!(code, 2, "{stderr}");
    assert!(
        last.starts_with("error: ") && last.contains("none.toml: every data set was skipped"),
        "{stderr}"
    );
    assert!(
        !none_out.join("results.json").exists(),
        "results of nothing were written"
    );
}

#[test]
fn interleaving_visits_every_structure_in_every_round_naive_first() {
    let (views, rounds, structures) = (3, 4, 5);
    let slots: Vec<_> = lacuna::bench::schedule(views, rounds, structures).collect();
    assert_eq!(slots.len(), (views * rounds) as usize * structures);
    for (i, chunk) in slots.chunks(structures).enumerate() {
        // One round: the same view and round, every structure once, in order.
        let (view, round) = (chunk[0].view, chunk[0].round);
        assert_eq!((view, round), (i as u32 / rounds, i as u32 % rounds));
        let order: Vec<usize> = chunk.iter().map(|s| s.structure).collect();
        assert_eq!(order, (0..structures).collect::<Vec<_>>());
        assert!(chunk.iter().all(|s| s.view == view && s.round == round));
    }
}

#[test]
fn warm_up_runs_until_two_consecutive_times_agree_and_reports_the_cap() {
    use lacuna::bench::{warm_up, WarmedUp};
    let run = |times: &[f64], least, cap| {
        let mut seen = 0;
        let w = warm_up(least, cap, 0.05, |i| {
            seen += 1;
            Ok(times[i as usize % times.len()])
        })
        .unwrap();
        assert_eq!(seen, w.runs, "one call per run");
        w
    };
    // A cold cache: slow first frames, then stable.
    let cold = [120.0, 90.0, 40.0, 33.0, 32.0, 32.5];
    assert_eq!(run(&cold, 1, 30), WarmedUp { runs: 5, capped: false });
    // Never two alike: stops at the cap and says so.
    assert_eq!(run(&[10.0, 20.0], 1, 7), WarmedUp { runs: 7, capped: true });
    // Stable at once still runs the least number asked for (never fewer than 2).
    assert_eq!(run(&[5.0], 0, 30), WarmedUp { runs: 2, capped: false });
    assert_eq!(run(&[5.0], 4, 30), WarmedUp { runs: 4, capped: false });
    // An error in a run stops the warm-up with it.
    assert!(warm_up(1, 5, 0.05, |_| Err(lacuna::Error::invalid("x", "y", "z"))).is_err());
}

/// A run's files are written all or none: where one cannot be placed (a
/// folder stands where table1.md goes), the last run's results.json is
/// left as it was, no new file appears and no staging folder is left. An
/// output folder under a file is refused before the run.
#[test]
fn bench_outputs_are_all_or_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("one.toml");
    std::fs::write(
        &config,
        "name = \"x\"\nsize = [8, 8]\nframes = 1\nrounds = 2\nwarmup = 0\nbuilds = 1\n[[dataset]]\nvolume = \"nbody:8\"\n[[structure]]\nlabel = \"grid\"\naccel = \"grid\"\n",
    )
    .unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("table1.md")).unwrap();
    std::fs::write(out.join("results.json"), "old").unwrap();
    let (code, stdout, stderr) = lacuna(&[
        "bench",
        config.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--validate",
    ]);
    assert_eq!(code, 2, "{stdout}{stderr}");
    assert!(
        stderr.starts_with("error: ") && stderr.contains("table1.md: exists and is not a regular file"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(out.join("results.json")).unwrap(), "old");
    let mut names: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    names.sort();
    assert_eq!(names, ["results.json", "table1.md"]);
    // Once the folder is gone the same run writes the whole set, and an
    // earlier run's outputs it does not write (a sweep, steps, frames of
    // other labels) go; the user's own files stay.
    std::fs::remove_dir(out.join("table1.md")).unwrap();
    std::fs::create_dir_all(out.join("frames")).unwrap();
    for stale in ["steps.md", "error.json", "notes.txt", "frames/other-naive.exr"] {
        std::fs::write(out.join(stale), "an earlier run's").unwrap();
    }
    std::fs::write(out.join("mine.txt"), "the user's").unwrap();
    let (code, stdout, stderr) = lacuna(&[
        "bench",
        config.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--validate",
        "--frames-out",
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    assert!(std::fs::read_to_string(out.join("results.json"))
        .unwrap()
        .starts_with('['));
    assert!(out.join("table1.md").is_file() && out.join("fig3-fps.png").is_file());
    for stale in ["steps.md", "error.json", "notes.txt", "frames/other-naive.exr"] {
        // Gone, or this run's own (its notes).
        let old = std::fs::read_to_string(out.join(stale)).is_ok_and(|t| t == "an earlier run's");
        assert!(!old, "{stale} stayed");
    }
    assert!(out.join("mine.txt").is_file() && out.join("frames/nbody_8-grid.exr").is_file());
    // A folder no run wrote before (no results.json) loses nothing.
    let plain = dir.path().join("plain");
    std::fs::create_dir_all(&plain).unwrap();
    std::fs::write(plain.join("error.md"), "the user's").unwrap();
    let (code, stdout, stderr) = lacuna(&[
        "bench",
        config.to_str().unwrap(),
        "--out",
        plain.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    assert_eq!(std::fs::read_to_string(plain.join("error.md")).unwrap(), "the user's");
    let under_file = out.join("results.json").join("deeper");
    let (code, _, stderr) = lacuna(&["bench", config.to_str().unwrap(), "--out", under_file.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(stderr.contains("exists and is not a folder"), "{stderr}");
}
