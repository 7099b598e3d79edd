//! `render` with a frame's look (`--mode`, `--iso`, shading, clip planes,
//! the crop box, jitter): the frame equals the library's CPU reference of
//! the same description, the EXR metadata records the look in the flags'
//! syntax, and every bad combination is a one-line error with no file.

use crate::common::{fails, render_ok};
use lacuna::frame::{diff, Frame};
use lacuna::render::{reference, Clip, Filter, FrameDesc, Iso, Light, Mode, Projection, Shading};
use lacuna::{TransferFunction, Volume};

/// Renders with `--filter manual` (the reference's filter) and compares
/// with the CPU reference of `desc`.
fn matches_reference(spec: &str, flags: &[&str], desc: FrameDesc) -> Frame {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frame.exr");
    let mut all = vec!["--filter", "manual", "--camera", "30,20", "--accel", "grid"];
    all.extend_from_slice(flags);
    render_ok(spec, &out, &all);
    let frame = Frame::read_exr(&out).unwrap();
    let volume = Volume::load(spec, &Default::default()).unwrap();
    let tf = TransferFunction::parse(volume.default_tf.as_ref().unwrap()).unwrap();
    let cpu = reference::render_frame(&volume, &tf, &desc).unwrap();
    let d = diff(&frame, &cpu).unwrap();
    assert!(d.max_abs <= 1e-4, "{flags:?}: {d}");
    // An iso frame's EXR has a Z channel: each surface's distance.
    assert_eq!(frame.depth.is_some(), cpu.depth.is_some(), "{flags:?}");
    if let (Some(z), Some(want)) = (&frame.depth, &cpu.depth) {
        assert!(z.iter().any(|d| d.is_finite()) && z.iter().any(|d| d.is_infinite()));
        for (g, w) in z.iter().zip(want) {
            assert!(g == w || (g - w).abs() <= 1e-4 * w.abs(), "Z {g} vs {w}");
        }
    }
    assert!(frame.pixels.iter().any(|p| p[3] > 0.01), "{flags:?}: empty frame");
    frame
}

fn desc() -> lacuna::render::FrameBuilder {
    FrameDesc::builder(40, 32)
        .orbit(30.0, 20.0, Projection::Orthographic)
        .filter(Filter::Manual)
}

#[test]
fn modes_shading_clip_and_jitter_from_the_command_line() {
    let f = matches_reference("nbody:32", &["--mode", "mip"], desc().mode(Mode::Mip).build().unwrap());
    assert_eq!(f.metadata["mode"], "mip");
    let iso = Iso::new(&[0.3, 0.6]).unwrap().with_color([1.0, 0.5, 0.25]).unwrap();
    let f = matches_reference(
        "shells:32",
        &[
            "--mode",
            "iso",
            "--iso",
            "0.3,0.6",
            "--iso-color",
            "1,0.5,0.25",
            "--light",
            "-40,30",
        ],
        desc()
            .mode(Mode::Iso(iso))
            .shading(Some(Shading {
                light: Light::Fixed {
                    azimuth_deg: -40.0,
                    elevation_deg: 30.0,
                },
                ..Shading::default()
            }))
            .build()
            .unwrap(),
    );
    assert_eq!(f.metadata["iso"], "0.3,0.6");
    assert_eq!(f.metadata["iso_color"], "1,0.5,0.25");
    assert_eq!(f.metadata["shade"], "light -40,30, phong 0.1,0.7,0.2,10");
    let clip = Clip::default()
        .plane([1.0, 0.0, -0.5, -4.0])
        .unwrap()
        .plane([0.0, -1.0, 0.0, 28.0])
        .unwrap()
        .crop([2.0, 0.0, 1.0], [30.0, 32.0, 31.5])
        .unwrap();
    let shading = Shading {
        gradient_opacity: Some([0.0, 0.1]),
        ..Shading::default()
    }
    .parse_phong("0.2,0.6,0.4,20")
    .unwrap();
    let f = matches_reference(
        "vessels:32",
        &[
            "--shade",
            "on",
            "--phong",
            "0.2,0.6,0.4,20",
            "--gradient-opacity",
            "0:0.1",
            "--clip",
            "1,0,-0.5,-4",
            "--clip",
            "0,-1,0,28",
            "--crop",
            "2:30,0:32,1:31.5",
            "--jitter",
            "on",
        ],
        desc().shading(Some(shading)).clip(clip).jitter(true).build().unwrap(),
    );
    assert_eq!(f.metadata["clip0"], "1,0,-0.5,-4");
    assert_eq!(f.metadata["crop"], "2:30,0:32,1:31.5");
    assert_eq!(f.metadata["jitter"], "on");
}

#[test]
fn an_iso_value_outside_the_data_renders_transparent_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frame.exr");
    let r = render_ok("nbody:24", &out, &["--mode", "iso", "--iso", "1.5"]);
    assert!(r.stdout.contains("note: iso value 1.5 lies outside"), "{}", r.stdout);
    let f = Frame::read_exr(&out).unwrap();
    assert!(f.pixels.iter().all(|p| *p == [0.0; 4]));
    let r = render_ok("nbody:24", &out, &["--mode", "average", "--accel", "grid"]);
    assert!(r.stdout.contains("no structure skips"), "{}", r.stdout);
    assert!(r.stdout.contains("grid -> naive"), "{}", r.stdout);
}

#[test]
fn bad_look_input_is_one_line_and_leaves_no_file() {
    let r = |extra: &[&str], needle: &str| {
        let mut args = vec!["render", "nbody:16", "--size", "16x16"];
        args.extend_from_slice(extra);
        fails(&args, &[], needle);
    };
    r(&["--mode", "glow"], "expected composite, mip, minip, average or iso");
    r(&["--mode", "iso"], "needs --iso");
    r(&["--mode", "iso", "--iso", "nan"], "finite");
    r(&["--mode", "iso", "--iso", ""], "expected V[,V2,...]");
    r(&["--mode", "iso", "--iso", "0.1,0.2,0.3,0.4,0.5"], "1 to 4 values");
    r(&["--iso", "0.5"], "need --mode iso");
    r(
        &["--mode", "mip", "--iso", "0.5"],
        "invalid iso '0.5': iso values need --mode iso, not --mode mip",
    );
    r(&["--iso-color", "1,0,0"], "needs --mode iso");
    r(&["--mode", "iso", "--iso", "0.5", "--iso-color", "2,0,0"], "[0, 1]");
    r(&["--mode", "mip", "--shade", "on"], "not mip");
    r(&["--mode", "iso", "--iso", "0.5", "--shade", "off"], "always lit");
    r(&["--light", "10,20"], "needs --shade on");
    r(&["--shade", "on", "--light", "10"], "expected AZ,EL");
    r(&["--shade", "on", "--phong", "0.1,2,0.2,10"], "diffuse");
    r(&["--shade", "on", "--gradient-opacity", "0.5:0.1"], "0 <= LO < HI");
    r(
        &["--mode", "iso", "--iso", "0.5", "--gradient-opacity", "0:1"],
        "opaque",
    );
    r(&["--mode", "average", "--ert", "0.9"], "composite rays only");
    r(&["--clip", "0,0,0,1"], "normal (A, B, C) is zero");
    r(&["--clip", "1,0,0"], "expected A,B,C,D");
    r(&["--clip", "1,0,0,inf"], "finite");
    let seven: Vec<&str> = (0..7).flat_map(|_| ["--clip", "1,0,0,0"]).collect();
    r(&seven, "at most 6");
    r(&["--crop", "0:8,0:8"], "expected X0:X1,Y0:Y1,Z0:Z1");
    r(&["--crop", "9:3,0:8,0:8"], "inverted");
    r(&["--crop", "20:30,0:8,0:8"], "outside the volume");
    r(&["--crop", "-9:-1,0:8,0:8"], "outside the volume");
    r(&["--jitter", "yes"], "jitter");
}
