//! `lacuna view` end to end: a real window (on $DISPLAY, else a virtual X
//! server through `xvfb-run`), the viewer's own Vulkan host adopting its
//! device into lacuna, validation on, and its screenshot equal to `lacuna
//! render`'s frame bit for bit. Bad input fails before any window opens.

use crate::common::{lacuna, Run};
use lacuna::frame::Frame;
use std::process::Command;
use std::sync::Mutex;

/// One window at a time: concurrent `xvfb-run -a` can pick the same display number.
static ONE_WINDOW: Mutex<()> = Mutex::new(());

/// `lacuna ARGS` where a window can open: on $DISPLAY when it is set, else
/// under `xvfb-run -a`. Neither is a failure, not a skip.
fn windowed(args: &[&str]) -> Command {
    let exe = env!("CARGO_BIN_EXE_lacuna");
    let display = std::env::var("DISPLAY").is_ok_and(|d| !d.is_empty());
    let mut cmd = if display {
        Command::new(exe)
    } else {
        let mut c = Command::new("xvfb-run");
        // 24-bit colour: the default 8-bit screen has no visual Vulkan presents to.
        c.args(["-a", "-s", "-screen 0 640x480x24", exe]);
        c
    };
    cmd.args(args);
    cmd
}

const NO_XVFB: &str = "DISPLAY is not set and xvfb-run cannot run: install the Debian package xvfb (.ci/run does)";

fn lacuna_windowed(args: &[&str]) -> Run {
    let _one = ONE_WINDOW.lock().unwrap_or_else(|p| p.into_inner());
    let out = windowed(args).output().unwrap_or_else(|e| panic!("{NO_XVFB} ({e})"));
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into(),
        stderr: String::from_utf8_lossy(&out.stderr).into(),
    }
}

fn ok(r: &Run, what: &str) {
    assert_eq!(r.code, 0, "{what}\nstdout: {}\nstderr: {}", r.stdout, r.stderr);
    // --validate prints every validation message to stderr.
    assert!(r.stderr.is_empty(), "{what}: {}", r.stderr);
}

#[test]
fn the_viewers_screenshot_is_renders_frame_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [&[&str]; 2] = [
        // The Must-show case: defaults (auto, the generator's TF, orbit 30,20).
        &["nbody:64"],
        // Another structure, TF, camera, projection and step.
        &[
            "menger:27",
            "--accel",
            "lbvh",
            "--tf",
            "ramp:0.2:1:0.3",
            "--camera",
            "-40,25",
            "--perspective",
            "35",
            "--step",
            "0.75",
        ],
    ];
    for (i, case) in cases.iter().enumerate() {
        let a = dir.path().join(format!("view{i}.exr"));
        let b = dir.path().join(format!("render{i}.exr"));
        let (a_str, b_str) = (a.to_str().unwrap(), b.to_str().unwrap());
        let size = ["--size", "96x80", "--validate"];
        let view = [&["view"], *case, &size, &["--frames", "5", "--screenshot", a_str]].concat();
        let r = lacuna_windowed(&view);
        ok(&r, &format!("{view:?}"));
        assert!(r.stdout.contains(&format!("wrote {a_str}")), "{}", r.stdout);
        // The title's figures, printed once at the end: GPU-timed march and rebuild.
        let summary = r
            .stdout
            .lines()
            .find(|l| l.starts_with("frames 5: "))
            .unwrap_or_else(|| panic!("{}", r.stdout));
        assert!(
            summary.contains(" fps, march ") && summary.contains(" ms, rebuild "),
            "{summary}"
        );
        let render = [&["render"], *case, &size, &["--out", b_str]].concat();
        ok(&lacuna(&render, &[]), &format!("{render:?}"));

        let frame = Frame::read_exr(&a).unwrap();
        assert_eq!((frame.width, frame.height), (96, 80), "the window's frame size");
        assert!(
            frame.pixels.iter().any(|p| p[3] > 0.05),
            "case {i}: an empty frame proves nothing"
        );
        assert_eq!(
            frame.metadata["volume"],
            Frame::read_exr(&b).unwrap().metadata["volume"]
        );
        let diff = lacuna(&["diff", a_str, b_str, "--max-abs", "0"], &[]);
        assert_eq!(diff.code, 0, "case {i}: {}{}", diff.stdout, diff.stderr);
        assert!(diff.stdout.contains("differing 0 of 7680"), "{}", diff.stdout);
    }
}

#[test]
fn keys_rebuild_for_the_new_tf_and_structure_and_match_render() {
    // T: the next preset (ramp:0.3:1 after the generator's TF); Right: move it
    // by 0.02; Tab twice: two structures down the table from naive; E: ERT on.
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("keys.exr"), dir.path().join("render.exr"));
    let (a_str, b_str) = (a.to_str().unwrap(), b.to_str().unwrap());
    let common = ["menger:27", "--size", "64x48", "--camera", "10,30", "--validate"];
    let keys = "t,ArrowRight,Tab,Tab,e";
    let view = [
        &["view"],
        &common[..],
        &[
            "--accel",
            "naive",
            "--keys",
            keys,
            "--frames",
            "2",
            "--screenshot",
            a_str,
        ],
    ]
    .concat();
    let r = lacuna_windowed(&view);
    ok(&r, &format!("{view:?}"));
    let accel = lacuna::accel::TABLE[2].name();
    let summary = r
        .stdout
        .lines()
        .find(|l| l.starts_with("frames 2: "))
        .unwrap_or_default();
    // A generator is a time series: the summary ends with the step shown.
    assert!(
        summary.contains(&format!("({accel}), time step 0 of 64")),
        "{}",
        r.stdout
    );
    let frame = Frame::read_exr(&a).unwrap();
    assert_eq!(frame.metadata["tf"], "ramp:0.32:1.02");
    assert_eq!(frame.metadata["accel"], accel);
    assert_eq!(frame.metadata["ert"], "0.99");
    let render = [
        &["render"],
        &common[..],
        &[
            "--tf",
            "ramp:0.32:1.02",
            "--accel",
            accel,
            "--ert",
            "0.99",
            "--out",
            b_str,
        ],
    ]
    .concat();
    ok(&lacuna(&render, &[]), &format!("{render:?}"));
    let diff = lacuna(&["diff", a_str, b_str, "--max-abs", "0"], &[]);
    assert_eq!(diff.code, 0, "{}{}", diff.stdout, diff.stderr);
}

#[test]
fn look_keys_and_flags_match_render() {
    // Starts shaded; M four times: mip, minip, average, iso 0.5; '.': iso
    // 0.52; C: a clip plane facing the camera, PageUp moves it; X: jitter.
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("look.exr"), dir.path().join("render.exr"));
    let (a_str, b_str) = (a.to_str().unwrap(), b.to_str().unwrap());
    let common = [
        "shells:32",
        "--size",
        "64x48",
        "--camera",
        "20,15",
        "--accel",
        "grid",
        "--validate",
    ];
    let view = [
        &["view"],
        &common[..],
        &[
            "--shade",
            "on",
            "--keys",
            "m,m,m,m,>,c,PageUp,x",
            "--frames",
            "2",
            "--screenshot",
            a_str,
        ],
    ]
    .concat();
    let r = lacuna_windowed(&view);
    ok(&r, &format!("{view:?}"));
    let frame = Frame::read_exr(&a).unwrap();
    assert_eq!(frame.metadata["mode"], "iso");
    assert_eq!(frame.metadata["iso"], "0.52");
    assert_eq!(frame.metadata["jitter"], "on");
    assert!(frame.depth.is_none(), "the viewer presents colour only");
    let clip = &frame.metadata["clip0"];
    let render = [
        &["render"],
        &common[..],
        &[
            "--mode", "iso", "--iso", "0.52", "--clip", clip, "--jitter", "on", "--out", b_str,
        ],
    ]
    .concat();
    ok(&lacuna(&render, &[]), &format!("{render:?}"));
    let diff = lacuna(&["diff", a_str, b_str, "--max-abs", "0"], &[]);
    assert_eq!(diff.code, 0, "{}{}", diff.stdout, diff.stderr);
    assert!(Frame::read_exr(&b).unwrap().pixels.iter().any(|p| p[3] > 0.5));
}

/// On two channels, the keys that would shade (L) or reach iso (the mode
/// key's fourth press) skip that look with a note, not end the session:
/// M five times goes mip, minip, average, (iso skipped) composite, mip.
/// A frame too large for the device is refused before its canvas.
#[test]
fn keys_skip_looks_the_volume_cannot_show() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("two.exr");
    let args = [
        "view",
        "menger:16+nbody:16",
        "--size",
        "32x32",
        "--validate",
        "--keys",
        "l,m,m,m,m,m",
        "--frames",
        "2",
        "--screenshot",
        shot.to_str().unwrap(),
    ];
    let r = lacuna_windowed(&args);
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    let notes: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(notes.len(), 2, "{}", r.stderr);
    for (note, look) in notes.iter().zip(["'composite · shaded'", "'iso 0.5'"]) {
        assert!(
            note.starts_with(&format!(
                "note: look skipped: invalid look {look}: shaded and iso frames take one channel"
            )),
            "{note}"
        );
    }
    assert_eq!(Frame::read_exr(&shot).unwrap().metadata["mode"], "mip");
    let big = lacuna_windowed(&[
        "view",
        "menger:16",
        "--size",
        "16384x16384",
        "--frames",
        "1",
        "--validate",
    ]);
    assert_eq!(big.code, 2, "{}", big.stderr);
    assert!(
        big.stderr
            .starts_with("error: frame 16384x16384 (4294967296 bytes) exceeds the device limit maxStorageBufferRange"),
        "{}",
        big.stderr
    );
}

/// Scripted Esc or Q ends the session where it is pressed; Shift+Tab is
/// the previous structure; each S press writes a numbered pair, apart from
/// the --screenshot file.
#[test]
fn scripted_quit_shift_tab_and_numbered_screenshots() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("v.exr");
    let r = lacuna_windowed(&[
        "view",
        "nbody:16",
        "--size",
        "32x32",
        "--validate",
        "--accel",
        "grid",
        "--keys",
        "Tab,Shift+Tab,s,frame,s",
        "--frames",
        "2",
        "--screenshot",
        shot.to_str().unwrap(),
    ]);
    ok(&r, "view with S twice");
    assert!(
        r.stdout.contains("frames 2:") && r.stdout.contains("(grid)"),
        "{}",
        r.stdout
    );
    for name in ["v.exr", "v-1.exr", "v-1.png", "v-2.exr", "v-2.png"] {
        assert!(
            dir.path().join(name).is_file(),
            "{name}: {:?}",
            std::fs::read_dir(dir.path()).unwrap().collect::<Vec<_>>()
        );
    }
    let last = dir.path().join("v-2.exr");
    let diff = crate::common::lacuna(
        &["diff", shot.to_str().unwrap(), last.to_str().unwrap(), "--max-abs", "0"],
        &[],
    );
    assert_eq!(
        diff.code, 0,
        "the last S press is the last frame: {}{}",
        diff.stdout, diff.stderr
    );
    // Q after the second frame ends the session before --frames' fifth.
    let q = lacuna_windowed(&[
        "view",
        "nbody:16",
        "--size",
        "32x32",
        "--validate",
        "--keys",
        "frame,frame,q",
        "--frames",
        "5",
    ]);
    ok(&q, "view --keys frame,frame,q");
    assert!(q.stdout.starts_with("frames 2:"), "{}", q.stdout);
}

#[test]
fn bad_view_input_is_one_line_before_any_window() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.tiff");
    let missing = dir.path().join("no/such/dir/shot.exr");
    let json = dir.path().join("missing.json");
    let cases: [(Vec<&str>, &str); 11] = [
        (
            vec!["view", "nbody:16", "--keys", "t,Teleport"],
            "invalid key 'Teleport': expected one of:",
        ),
        (
            vec![
                "view",
                "nbody:16",
                "--frames",
                "1",
                "--screenshot",
                shot.to_str().unwrap(),
            ],
            "invalid frame output",
        ),
        (
            vec!["view", "nbody:16", "--screenshot", missing.to_str().unwrap()],
            "no/such/dir",
        ),
        (vec!["view", "nbody:16", "--frames", "0"], "invalid frames '0'"),
        (
            vec!["view", "nbody:16", "--keys", "q,m"],
            "invalid keys 'q,m': the keys after q are never pressed",
        ),
        (
            vec!["view", "nbody:16", "--keys", "s,q"],
            "invalid keys 's,q': S asks for the next frame, which q ends the session before",
        ),
        // Keys that would never show.
        (
            vec!["view", "nbody:16", "--keys", "frame,m", "--frames", "1"],
            "invalid keys 'frame,m': its last keys show from frame 2, but --frames 1 ends the session first",
        ),
        (
            vec![
                "view",
                "nbody:16",
                "--keys",
                "q",
                "--frames",
                "1",
                "--screenshot",
                "x.exr",
            ],
            "invalid keys 'q': q and Escape end the session before --frames' last frame",
        ),
        (
            vec!["view", "nbody:16", "--json", json.to_str().unwrap()],
            "missing.json",
        ),
        (
            vec!["view", "/no/such/volume_8x8x8_uint8.raw"],
            "/no/such/volume_8x8x8_uint8.raw",
        ),
        // Good input, no display: said so, with no build path in it.
        (vec!["view", "nbody:8"], "set DISPLAY, or run under xvfb-run"),
    ];
    for (args, message) in cases {
        // No display at all: the input is refused before a window is tried.
        let r = lacuna(&args, &[("DISPLAY", ""), ("WAYLAND_DISPLAY", "")]);
        assert_eq!(r.code, 2, "{args:?}: {}{}", r.stdout, r.stderr);
        let lines: Vec<&str> = r.stderr.lines().collect();
        assert_eq!(lines.len(), 1, "{args:?}: {}", r.stderr);
        assert!(
            lines[0].starts_with("error: ") && lines[0].contains(message),
            "{args:?}: {}",
            lines[0]
        );
        assert!(
            !lines[0].contains(".cargo") && !lines[0].contains(".rs:"),
            "{args:?}: a build path: {}",
            lines[0]
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn without_a_display_the_viewer_says_so_in_one_line() {
    let r = lacuna(
        &["view", "nbody:16", "--frames", "1"],
        &[("DISPLAY", ""), ("WAYLAND_DISPLAY", "")],
    );
    assert_eq!(r.code, 2, "{}{}", r.stdout, r.stderr);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{}", r.stderr);
    assert!(lines[0].starts_with("error: cannot open a window"), "{}", lines[0]);
}

/// A series in the viewer: `.` steps forward, `,` back, Space plays (a new step each
/// frame, the next loading while this one renders); the screenshot equals
/// `render --time` of the step shown. Dense steps go into the last step's
/// memory; bricked ones are uploaded anew, the last step freed first.
#[test]
fn the_viewer_steps_and_plays_a_series_and_matches_render() {
    let dir = tempfile::tempdir().unwrap();
    for (keys, frames, step, storage) in [
        // `Comma` names ',' (one step back) in the comma-separated list.
        (".,.,.,Comma", "2", "2", "dense"),
        ("Space", "4", "3", "dense"),
        ("Space", "3", "2", "bricks:8"),
    ] {
        let size = ["--size", "64x48", "--validate", "--storage", storage];
        let a = dir.path().join(format!("view-{frames}-{storage}.exr"));
        let b = dir.path().join(format!("render-{frames}-{storage}.exr"));
        let (a_str, b_str) = (a.to_str().unwrap(), b.to_str().unwrap());
        let view = [
            &[
                "view",
                "vessels:32",
                "--keys",
                keys,
                "--frames",
                frames,
                "--screenshot",
                a_str,
            ][..],
            &size,
        ]
        .concat();
        let r = lacuna_windowed(&view);
        ok(&r, &format!("{view:?}"));
        let summary = r.stdout.lines().find(|l| l.starts_with("frames ")).unwrap_or_default();
        assert!(
            summary.contains(&format!("time step {step} of 64 (load ")) && summary.contains(" ms, upload "),
            "{view:?}: {summary}"
        );
        let render = [&["render", "vessels:32", "--time", step, "--out", b_str][..], &size].concat();
        ok(&lacuna(&render, &[]), &format!("{render:?}"));
        let diff = lacuna(&["diff", a_str, b_str, "--max-abs", "0"], &[]);
        assert_eq!(diff.code, 0, "{keys}: {}{}", diff.stdout, diff.stderr);
        assert!(diff.stdout.contains("differing 0 of 3072"), "{}", diff.stdout);
        // The screenshot says which step it shows, as render's frame does.
        let shot = Frame::read_exr(&a).unwrap();
        assert_eq!(shot.metadata.get("time").map(String::as_str), Some(step), "{keys}");
    }
}

/// A step of a series that does not load (a file cut short) is named in a
/// note and the step shown kept; the session goes on to the next keys.
#[test]
fn a_step_that_does_not_load_is_a_note_not_the_end_of_the_session() {
    let dir = tempfile::tempdir().unwrap();
    for k in 0..3 {
        let file = dir.path().join(format!("run_{k:04}_16x16x16_uint8.raw"));
        let time = k.to_string();
        let export = ["export", "vessels:16", file.to_str().unwrap(), "--time", &time];
        ok(&lacuna(&export, &[]), &format!("{export:?}"));
    }
    let cut = dir.path().join("run_0001_16x16x16_uint8.raw");
    std::fs::File::options()
        .write(true)
        .open(&cut)
        .unwrap()
        .set_len(100)
        .unwrap();
    let pattern = dir.path().join("run_%04d_16x16x16_uint8.raw");
    let pattern = pattern.to_str().unwrap();
    let (a, b) = (dir.path().join("view.exr"), dir.path().join("render.exr"));
    let size = ["--size", "32x32", "--validate"];
    // `.` asks for the cut step 1; after a frame, `,` goes back from 0 to 2.
    let view = [
        &[
            "view",
            pattern,
            "--keys",
            ".,frame,Comma",
            "--frames",
            "2",
            "--screenshot",
            a.to_str().unwrap(),
        ][..],
        &size,
    ]
    .concat();
    let r = lacuna_windowed(&view);
    assert_eq!(r.code, 0, "{view:?}: {}{}", r.stdout, r.stderr);
    // That note and nothing else (--validate prints any message).
    assert!(
        r.stderr.lines().count() == 1
            && r.stderr.starts_with("note: time step 1 not shown: ")
            && r.stderr.contains("run_0001_16x16x16_uint8.raw: holds 100 bytes"),
        "{}",
        r.stderr
    );
    let render = [
        &["render", pattern, "--time", "2", "--out", b.to_str().unwrap()][..],
        &size,
    ]
    .concat();
    ok(&lacuna(&render, &[]), &format!("{render:?}"));
    let diff = lacuna(
        &["diff", a.to_str().unwrap(), b.to_str().unwrap(), "--max-abs", "0"],
        &[],
    );
    assert_eq!(diff.code, 0, "{}{}", diff.stdout, diff.stderr);
    assert_eq!(Frame::read_exr(&a).unwrap().metadata["time"], "2");
}

/// A frame lavapipe's loop cap cut short (the LBVH on vessels:32 at the
/// least step naive marching fits: `modes::at_the_loop_pass_limit_...`)
/// says so in the title and the `--frames` summary and is not written as a
/// screenshot; naive's frame at the same step is whole and says nothing.
#[test]
fn a_frame_the_loop_cap_cut_short_says_it_is_not_exact() {
    // One frame of vessels:32 at naive's least step, with `accel` and `extra`.
    let view = |accel: &str, extra: &[&str]| {
        let common = [
            "view",
            "vessels:32",
            "--accel",
            accel,
            "--size",
            "16x16",
            "--step",
            "0.00086",
            "--frames",
            "1",
        ];
        lacuna_windowed(&[&common[..], extra].concat())
    };
    let summary = |accel: &str| {
        let r = view(accel, &["--validate"]);
        ok(&r, accel);
        r.stdout
            .lines()
            .find(|l| l.starts_with("frames 1: "))
            .unwrap_or_default()
            .to_string()
    };
    let capped = crate::common::gpu().info().loop_pass_limit.is_some();
    let lbvh = summary("lbvh");
    assert_eq!(lbvh.contains("NOT EXACT: the device's loop cap cut"), capped, "{lbvh}");
    let naive = summary("naive");
    assert!(
        naive.starts_with("frames 1: ") && !naive.contains("NOT EXACT"),
        "{naive}"
    );
    if capped {
        // Such a frame is not written as a screenshot: one error line, no file.
        let dir = tempfile::tempdir().unwrap();
        let shot = dir.path().join("shot.exr");
        let r = view("lbvh", &["--screenshot", shot.to_str().unwrap()]);
        assert_ne!(r.code, 0, "{}", r.stdout);
        let lines: Vec<&str> = r.stderr.trim().lines().collect();
        assert!(
            lines.len() == 1 && lines[0].starts_with("error: ") && lines[0].contains("may not be the exact one"),
            "{}",
            r.stderr
        );
        assert!(!shot.exists(), "a cut frame was written");
    }
}

/// An octant map holds the ray directions of the frames it served: the
/// orthographic first frame's one octant, then after that frame P
/// (perspective from outside): the viewer adds the new frame's octants
/// before drawing it, and the frame equals `render`'s, which builds that
/// frame's own.
#[test]
fn an_octant_map_grows_with_the_frames_directions() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("view.exr"), dir.path().join("render.exr"));
    let (a_str, b_str) = (a.to_str().unwrap(), b.to_str().unwrap());
    let common = [
        "nbody:48",
        "--size",
        "64x48",
        "--accel",
        "distance-octant",
        "--camera",
        "10,30",
    ];
    let summary = |r: &Run| {
        r.stdout
            .lines()
            .find(|l| l.starts_with("frames "))
            .unwrap_or_default()
            .to_string()
    };
    let one = [&["view"][..], &common, &["--frames", "1", "--validate"]].concat();
    let r = lacuna_windowed(&one);
    ok(&r, &format!("{one:?}"));
    assert!(
        summary(&r).contains("(distance-octant, 1 of 8 octants)"),
        "{}",
        r.stdout
    );
    let grown = [
        &["view"][..],
        &common,
        &[
            "--keys",
            "frame,p",
            "--frames",
            "2",
            "--validate",
            "--screenshot",
            a_str,
        ],
    ]
    .concat();
    let r = lacuna_windowed(&grown);
    ok(&r, &format!("{grown:?}"));
    let line = summary(&r);
    let held: u32 = line
        .split("distance-octant, ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no octant count: {line}"));
    assert!(held > 1, "the perspective frame's rays span more octants: {line}");
    let render = [&["render"][..], &common, &["--perspective", "40", "--out", b_str]].concat();
    let rendered = lacuna(&render, &[]);
    ok(&rendered, &format!("{render:?}"));
    let diff = lacuna(&["diff", a_str, b_str, "--max-abs", "0"], &[]);
    assert!(
        diff.code == 0 && diff.stdout.contains("differing 0 of 3072"),
        "{}{}",
        diff.stdout,
        diff.stderr
    );
}

/// On two channels with a TF each, the arrows move both windows, and the
/// frame is render's with the moved TFs.
#[test]
fn arrows_move_every_channels_window() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("view.exr"), dir.path().join("render.exr"));
    let common = ["vessels:16+nbody:16", "--size", "32x32", "--validate"];
    let view = [
        &["view"],
        &common[..],
        &[
            "--keys",
            "ArrowRight",
            "--frames",
            "1",
            "--screenshot",
            a.to_str().unwrap(),
        ],
    ]
    .concat();
    ok(&lacuna_windowed(&view), "view with ArrowRight on two channels");
    let render = [
        &["render"],
        &common[..],
        &[
            "--tf",
            "ramp:0.32:1.02",
            "--tf",
            "ramp:0.37:1.02",
            "--out",
            b.to_str().unwrap(),
        ],
    ]
    .concat();
    ok(&crate::common::lacuna(&render, &[]), "render");
    let diff = crate::common::lacuna(
        &["diff", a.to_str().unwrap(), b.to_str().unwrap(), "--max-abs", "0"],
        &[],
    );
    assert_eq!(diff.code, 0, "{}{}", diff.stdout, diff.stderr);
}

/// The lacuna process `child` runs: itself, or xvfb-run's child.
fn viewer_pid(child: &std::process::Child) -> Option<i32> {
    let named_lacuna =
        |pid: &str| std::fs::read_to_string(format!("/proc/{pid}/comm")).is_ok_and(|c| c.trim() == "lacuna");
    let id = child.id().to_string();
    if named_lacuna(&id) {
        return id.parse().ok();
    }
    let children = std::fs::read_to_string(format!("/proc/{id}/task/{id}/children")).ok()?;
    let found = children.split_whitespace().find(|pid| named_lacuna(pid));
    found.and_then(|pid| pid.parse().ok())
}

/// An unchanged window is not redrawn: the frames an idle session draws
/// are those its keys asked for, where it used to redraw without end (two
/// cores busy). Ctrl-C ends the session as Q does: exit 0, the title's
/// figures printed, validation clean.
#[test]
fn an_idle_window_draws_nothing_and_ctrl_c_ends_the_session() {
    let dir = tempfile::tempdir().unwrap();
    let stem = dir.path().join("idle.png");
    let _one = ONE_WINDOW.lock().unwrap_or_else(|p| p.into_inner());
    let mut child = windowed(&[
        "view",
        "nbody:32",
        "--size",
        "48x48",
        "--validate",
        "--keys",
        "frame,s",
        "--screenshot",
        stem.to_str().unwrap(),
    ])
    .stdout(std::process::Stdio::piped())
    .stderr(std::process::Stdio::piped())
    .spawn()
    .unwrap_or_else(|e| panic!("{NO_XVFB} ({e})"));
    // S, pressed after the first frame, is written with the second.
    let shot = dir.path().join("idle-1.png");
    while !shot.is_file() {
        if let Some(status) = child.try_wait().unwrap() {
            let out = child.wait_with_output().unwrap();
            panic!(
                "the viewer ended before its screenshot ({status}): {}{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // Time for a viewer that redraws without end to draw many more frames.
    std::thread::sleep(std::time::Duration::from_secs(2));
    let pid = viewer_pid(&child).expect("the lacuna process under the window");
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0, "SIGINT to {pid}");
    let out = child.wait_with_output().unwrap();
    let r = Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into(),
        stderr: String::from_utf8_lossy(&out.stderr).into(),
    };
    ok(&r, "Ctrl-C ends the session");
    assert!(r.stdout.contains(&format!("wrote {}", shot.display())), "{}", r.stdout);
    // The two frames asked for; the window system's expose may add one.
    let frames = r
        .stdout
        .lines()
        .find_map(|l| l.strip_prefix("frames ")?.split(':').next()?.parse::<u32>().ok())
        .unwrap_or_else(|| panic!("no summary: {}", r.stdout));
    assert!(
        (2..=3).contains(&frames),
        "an idle window drew {frames} frames: {}",
        r.stdout
    );
}
