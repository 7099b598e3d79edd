//! Each frame mode, shading, clip planes, the crop box and jitter: naive
//! marching on the GPU against the CPU reference (`render::reference`) of
//! the same frame, within 1e-4, on frames that show something.

use crate::common::{accel, fails, gpu, max_abs, render, try_render_with};
use lacuna::accel::Accel;
use lacuna::frame::Frame;
use lacuna::render::reference;
use lacuna::render::{Clip, Filter, FrameBuilder, FrameDesc, Iso, Light, Mode, Projection, Shading};
use lacuna::{TransferFunction, Volume};

const PERSP: Projection = Projection::Perspective {
    fov_deg: 40.0,
    distance: None,
};

fn base(size: u32, az: f64, el: f64, projection: Projection) -> FrameBuilder {
    FrameDesc::builder(size, size)
        .orbit(az, el, projection)
        .filter(Filter::Manual)
}

fn load(spec: &str) -> (Volume, TransferFunction) {
    let v = Volume::load(spec, &Default::default()).unwrap();
    let tf = TransferFunction::parse(v.default_tf.as_ref().unwrap()).unwrap();
    (v, tf)
}

/// Renders `s` with naive marching and on the CPU, asserts they agree, and
/// returns the GPU frame.
fn check(volume: &Volume, tf: &TransferFunction, s: FrameBuilder) -> Frame {
    let ctx = gpu();
    let desc = s.build().unwrap();
    let cpu = reference::render_frame(volume, tf, &desc).unwrap();
    let frame = render(&ctx, volume, tf, &desc, Accel::naive());
    let err = max_abs(&frame, &cpu);
    assert!(
        err <= 1e-4,
        "{} {} {}: GPU vs CPU max abs {err}",
        volume.name,
        desc.mode().name(),
        desc.camera().describe()
    );
    // Iso frames carry their surfaces' depth (distances here), others none.
    assert_eq!(frame.depth.is_some(), matches!(desc.mode(), Mode::Iso(_)));
    if let (Some(gpu), Some(cpu)) = (&frame.depth, &cpu.depth) {
        for (i, (g, c)) in gpu.iter().zip(cpu).enumerate() {
            let hit = frame.pixels[i][3] > 0.0;
            assert_eq!(
                g.is_finite(),
                hit,
                "pixel {i}: depth {g} but alpha {}",
                frame.pixels[i][3]
            );
            assert!(
                g == c || (g - c).abs() <= 1e-4 * c.abs().max(1.0),
                "pixel {i}: depth {g} vs {c}"
            );
        }
    }
    frame
}

fn visible(f: &Frame) -> usize {
    f.pixels.iter().filter(|p| p[3] > 0.01).count()
}

#[test]
fn blend_modes_match_the_cpu_reference() {
    for spec in ["nbody:48", "turbulence:32", "shells:36"] {
        let (v, tf) = load(spec);
        for mode in [Mode::Mip, Mode::MinIp, Mode::Average] {
            for (az, el, proj) in [(30.0, 20.0, Projection::Orthographic), (-115.0, 35.0, PERSP)] {
                let f = check(&v, &tf, base(40, az, el, proj).mode(mode));
                // The minimum and the mean of sparse data map to transparent.
                assert!(visible(&f) > 0 || mode != Mode::Mip, "{spec} {mode:?}: empty frame");
            }
        }
    }
}

#[test]
fn mip_is_the_brightest_sample_through_the_tf() {
    // A single bright voxel seen head on: the MIP pixel through it is the
    // TF's colour at the largest sample, however far behind the voxel lies.
    let (v, tf) = load("shells:36");
    let composite = check(&v, &tf, base(32, 0.0, 0.0, Projection::Orthographic));
    let mip = check(&v, &tf, base(32, 0.0, 0.0, Projection::Orthographic).mode(Mode::Mip));
    // MIP is not composite, and it shows at least the pixels composite does.
    assert!(max_abs(&composite, &mip) > 0.01);
    assert!(visible(&mip) >= visible(&composite) / 2);
}

#[test]
fn shaded_composite_matches_the_cpu_reference() {
    for spec in ["menger:27", "vessels:40", "turbulence:32"] {
        let (v, tf) = load(spec);
        let unshaded = check(&v, &tf, base(40, 30.0, 20.0, Projection::Orthographic));
        let lights = [
            Shading::default(),
            Shading {
                light: Light::Fixed {
                    azimuth_deg: 60.0,
                    elevation_deg: -30.0,
                },
                gradient_opacity: Some([0.0, 0.05]),
                ..Shading::default()
            },
            // Whole exponents are raised by repeated squaring, others by
            // pow: both as the reference does.
            Shading {
                specular: 1.0,
                shininess: 128.0,
                ..Shading::default()
            },
            Shading {
                specular: 1.0,
                shininess: 7.5,
                ..Shading::default()
            },
        ];
        for shading in lights {
            for (az, el, proj) in [(30.0, 20.0, Projection::Orthographic), (-115.0, 35.0, PERSP)] {
                let f = check(&v, &tf, base(40, az, el, proj).shading(Some(shading)));
                assert!(visible(&f) > 0, "{spec}: empty shaded frame");
            }
        }
        let shaded = check(
            &v,
            &tf,
            base(40, 30.0, 20.0, Projection::Orthographic).shading(Some(Shading::default())),
        );
        assert!(max_abs(&shaded, &unshaded) > 0.01, "{spec}: shading changed nothing");
    }
}

#[test]
fn shading_reads_gradients_across_brick_faces_and_anisotropic_spacing() {
    // Odd dims (bricks of 8 end mid-volume), anisotropic spacing, and axis
    // views whose samples lie on voxel faces: the gradient's ±1 voxel reads
    // cross brick faces and the clamped volume edge.
    let mut v = Volume::load("turbulence:37x29x41", &Default::default()).unwrap();
    v.spacing = [1.0, 1.5, 0.75];
    let tf = TransferFunction::parse("ramp:0.4:1:0.3").unwrap();
    for (az, el) in [(0.0, 0.0), (90.0, 0.0), (0.0, 90.0), (45.0, 30.0)] {
        check(
            &v,
            &tf,
            base(37, az, el, Projection::Orthographic).shading(Some(Shading::default())),
        );
    }
}

#[test]
fn isosurfaces_match_the_cpu_reference() {
    for spec in ["shells:36", "turbulence:32", "nbody:48"] {
        let (v, tf) = load(spec);
        for values in [&[0.5][..], &[0.3, 0.7]] {
            let iso = Iso::new(values).unwrap();
            for (az, el, proj) in [(30.0, 20.0, Projection::Orthographic), (-115.0, 35.0, PERSP)] {
                let f = check(&v, &tf, base(40, az, el, proj).mode(Mode::Iso(iso)));
                assert!(visible(&f) > 0, "{spec} iso {values:?}: no surface");
                // Iso pixels are opaque or empty.
                assert!(f.pixels.iter().all(|p| p[3] == 0.0 || p[3] == 1.0));
            }
        }
        let colored = Iso::new(&[0.5]).unwrap().with_color([1.0, 0.5, 0.0]).unwrap();
        check(
            &v,
            &tf,
            base(40, 30.0, 20.0, Projection::Orthographic).mode(Mode::Iso(colored)),
        );
    }
}

#[test]
fn an_iso_value_outside_the_data_is_transparent() {
    let (v, tf) = load("shells:36");
    let f = check(
        &v,
        &tf,
        base(32, 30.0, 20.0, Projection::Orthographic).mode(Mode::Iso(Iso::new(&[1.5]).unwrap())),
    );
    assert_eq!(visible(&f), 0);
}

#[test]
fn clip_planes_and_crop_boxes_match_the_cpu_reference() {
    let (v, tf) = load("turbulence:32");
    let full = check(&v, &tf, base(40, 30.0, 20.0, Projection::Orthographic));
    let cases = [
        Clip::default().plane([1.0, 0.0, 0.0, -16.0]).unwrap(),
        Clip::default()
            .plane([1.0, 1.0, 0.0, -20.0])
            .unwrap()
            .plane([0.0, -1.0, 0.5, 20.0])
            .unwrap(),
        Clip::default().crop([4.0, 8.0, 0.0], [28.0, 20.0, 30.0]).unwrap(),
        Clip::default()
            .crop([0.0, 0.0, 0.0], [32.0, 32.0, 32.0])
            .unwrap()
            .plane([0.0, 0.0, 1.0, -10.5])
            .unwrap(),
    ];
    for clip in cases {
        for (az, el, proj) in [(30.0, 20.0, Projection::Orthographic), (-115.0, 35.0, PERSP)] {
            let f = check(&v, &tf, base(40, az, el, proj).clip(clip));
            assert!(visible(&f) > 0, "{clip:?}: nothing kept");
        }
        let f = check(&v, &tf, base(40, 30.0, 20.0, Projection::Orthographic).clip(clip));
        assert!(max_abs(&f, &full) > 0.01, "{clip:?}: cut nothing");
    }
}

#[test]
fn clipping_hard_cases_match_the_cpu_reference() {
    let (v, tf) = load("shells:36");
    // A plane through the perspective eye, a plane parallel to axis-aligned
    // rays, a crop box of zero thickness, a plane that removes everything.
    let eye_plane = Clip::default().plane([0.3, 0.2, 1.0, -18.0]).unwrap();
    let f = check(&v, &tf, base(32, 0.0, 0.0, PERSP).clip(eye_plane));
    assert!(visible(&f) > 0);
    let parallel = Clip::default().plane([1.0, 0.0, 0.0, -18.0]).unwrap();
    let f = check(&v, &tf, base(32, 0.0, 0.0, Projection::Orthographic).clip(parallel));
    let visible_half = visible(&f);
    assert!(visible_half > 0);
    let thin = Clip::default().crop([0.0, 0.0, 18.0], [36.0, 36.0, 18.0]).unwrap();
    let f = check(&v, &tf, base(32, 0.0, 0.0, Projection::Orthographic).clip(thin));
    assert_eq!(visible(&f), 0, "a zero-thickness crop keeps no sample");
    let none = Clip::default().plane([0.0, 1.0, 0.0, -100.0]).unwrap();
    let f = check(&v, &tf, base(32, 30.0, 20.0, PERSP).clip(none));
    assert_eq!(visible(&f), 0, "a plane that keeps nothing");
    // Every mode honours the clip.
    for mode in [Mode::Mip, Mode::Average, Mode::Iso(Iso::new(&[0.5]).unwrap())] {
        check(&v, &tf, base(32, 30.0, 20.0, PERSP).clip(parallel).mode(mode));
    }
}

#[test]
fn jitter_matches_the_cpu_reference_and_is_fixed_per_pixel() {
    let (v, tf) = load("turbulence:32");
    let plain = check(&v, &tf, base(40, 30.0, 20.0, Projection::Orthographic).step(2.0));
    let s = base(40, 30.0, 20.0, Projection::Orthographic).step(2.0).jitter(true);
    let a = check(&v, &tf, s);
    let b = check(&v, &tf, s);
    assert_eq!(a.pixels, b.pixels, "jitter is stable across runs");
    assert!(max_abs(&a, &plain) > 1e-3, "jitter moved no sample");
    for mode in [Mode::Mip, Mode::Iso(Iso::new(&[0.5]).unwrap())] {
        check(&v, &tf, s.mode(mode));
    }
    // The hash is a fixed function of the pixel.
    assert_eq!(reference::pixel_jitter(0, 0), reference::pixel_jitter(0, 0));
    assert_ne!(reference::pixel_jitter(0, 0), reference::pixel_jitter(1, 0));
    assert!((0..64).all(|x| (0.0..1.0).contains(&reference::pixel_jitter(x, 7))));
}

#[test]
fn shaded_isosurfaces_and_clips_combine() {
    let (v, tf) = load("vessels:40");
    let iso = Mode::Iso(Iso::new(&[0.4]).unwrap());
    let clip = Clip::default()
        .plane([0.0, 1.0, 0.0, -12.0])
        .unwrap()
        .crop([2.0, 2.0, 2.0], [38.0, 38.0, 30.0])
        .unwrap();
    check(&v, &tf, base(40, 60.0, 10.0, PERSP).mode(iso).clip(clip).jitter(true));
    let lit = Shading {
        light: Light::Fixed {
            azimuth_deg: -40.0,
            elevation_deg: 50.0,
        },
        ..Shading::default()
    };
    check(&v, &tf, base(40, 60.0, 10.0, PERSP).mode(iso).shading(Some(lit)));
    check(
        &v,
        &tf,
        base(40, 60.0, 10.0, PERSP).shading(Some(lit)).clip(clip).jitter(true),
    );
}

/// At the least step naive marching fits (unlit, on vessels:32), lavapipe's
/// loop cap cuts several structures' marches short: a group of lanes
/// whose spans differ runs more passes than any one ray has samples
/// (the grid and the octree there differed from naive in 8 and 15 of 256
/// pixels before the march checked the cap). Every structure, auto
/// included, either equals naive there or refuses the frame with
/// `Error::LoopCap`; none returns a different frame (auto, built here
/// without the frame, probes another one, so its choice may be refused). On
/// lavapipe (8-lane groups) some structure is refused, so the check decides. From
/// the command line, auto's frame there is naive's: auto chose naive (its
/// counting frames left cut candidates out), or a structure that ran
/// whole, or one cut on tiles it did not probe, which gives way to naive
/// with a note (which depends on auto's timing of this machine).
#[test]
fn at_the_loop_pass_limit_every_structure_equals_naive_or_is_refused() {
    let ctx = gpu();
    let (v, tf) = load("vessels:32");
    let limit = ctx.info().loop_pass_limit;
    // samples 64452 + 8 x 56 + 256 = 65156 passes: within lavapipe's 65535.
    let step = if limit.is_some() { 0.00086 } else { 0.001 };
    let desc = base(16, 30.0, 20.0, Projection::Orthographic)
        .step(step)
        .build()
        .unwrap();
    let naive = render(&ctx, &v, &tf, &desc, Accel::naive());
    assert!(visible(&naive) > 10, "an empty frame proves nothing");
    let mut refused = Vec::new();
    for a in Accel::skipping() {
        match try_render_with(&ctx, &v, &tf, &desc, a, &a.defaults()) {
            Ok(frame) => assert_eq!(max_abs(&frame, &naive), 0.0, "{a}'s frame differs from naive's"),
            Err(e @ lacuna::Error::LoopCap { .. }) => {
                assert!(e.to_string().contains("may not be the exact one"), "{e}");
                refused.push(a.to_string());
            }
            Err(e) => panic!("{a}: {e}"),
        }
    }
    assert_eq!(
        limit.is_some(),
        !refused.is_empty(),
        "refused on a device with a loop cap, and only there: {refused:?}"
    );
    // vessels:64 at its naive bound: auto either chooses naive or gives way
    // to it; either way the frame is naive's and the run succeeds.
    let dir = tempfile::tempdir().unwrap();
    let step = if limit.is_some() { "0.001722" } else { "0.002" };
    let out = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let run = |accel: &str, file: &str| {
        crate::common::lacuna(
            &[
                "render",
                "vessels:64",
                "--size",
                "16x16",
                "--step",
                step,
                "--accel",
                accel,
                "--out",
                file,
                "--validate",
            ],
            &[],
        )
    };
    let (auto_out, naive_out) = (out("auto.exr"), out("naive.exr"));
    let auto_run = run("auto", &auto_out);
    assert_eq!(auto_run.code, 0, "{}\n{}", auto_run.stdout, auto_run.stderr);
    assert_eq!(run("naive", &naive_out).code, 0);
    let read = |f: &str| Frame::read_exr(std::path::Path::new(f)).unwrap();
    let (a, n) = (read(&auto_out), read(&naive_out));
    assert_eq!(
        max_abs(&a, &n),
        0.0,
        "auto's frame differs from naive's:\n{}",
        auto_run.stdout
    );
    if let Some(note) = auto_run.stdout.lines().find(|l| l.starts_with("note: auto's choice")) {
        assert!(note.ends_with("so this frame was marched naively"), "{note}");
    }
}

/// lavapipe ends every loop of a SIMD group once they have run 65535 passes
/// between them (a march past it stopped short: vessels:32 unlit at step
/// 0.0005 differed from step 0.002 by up to 0.34). A lit march at the least
/// step `limits::check_loop_passes` allows there runs whole: naive equals
/// the CPU reference, and a grid of 2-voxel cells equals naive or is
/// refused. A finer step is one error, in the library and from the command
/// line.
#[test]
fn a_march_at_the_loop_pass_limit_is_whole_and_a_finer_one_is_refused() {
    let ctx = gpu();
    let (v, tf) = load("vessels:32");
    assert_eq!(v.dims, [32, 32, 32]);
    let limit = ctx.info().loop_pass_limit;
    // On a 32^3 box a lit frame needs 0.00171 on lavapipe (limits.rs).
    let least = if limit.is_some() { 0.00171 } else { 0.001 };
    let lit = |step: f32| {
        base(10, 30.0, 20.0, Projection::Orthographic)
            .step(step)
            .shading(Some(Shading::default()))
    };
    let naive = check(&v, &tf, lit(least));
    assert!(visible(&naive) > 10, "an empty frame proves nothing");
    let grid = accel("grid");
    let cells = grid.params(&[("cell", "2")]).unwrap();
    // A structure's group may pass more often than naive's (see the test
    // above): its frame is naive's or refused.
    match try_render_with(&ctx, &v, &tf, &lit(least).build().unwrap(), grid, &cells) {
        Ok(gridded) => assert_eq!(max_abs(&gridded, &naive), 0.0, "the grid's frame differs from naive's"),
        Err(e) => assert!(matches!(e, lacuna::Error::LoopCap { .. }), "{e}"),
    }
    if limit.is_none() {
        return;
    }
    let finer = lit(0.0015).build().unwrap();
    let naive_accel = Accel::naive();
    let Err(e) = try_render_with(&ctx, &v, &tf, &finer, naive_accel, &naive_accel.defaults()) else {
        panic!("a march past the limit rendered");
    };
    assert!(
        e.to_string().contains("ends a SIMD group's loops after 65535 passes")
            && e.to_string().contains("a step of at least 0.00171"),
        "{e}"
    );
    fails(
        &[
            "render",
            "vessels:32",
            "--accel",
            "naive",
            "--size",
            "8x8",
            "--step",
            "0.0005",
        ],
        &[],
        "a step of at least 0.000855",
    );
    // auto (the default) refuses it the same way before it builds or
    // probes anything: its counting frames once ran into the cap and
    // reported a naive march nobody asked for.
    for (step, shade, least) in [("0.0005", "off", "0.000855"), ("0.0015", "on", "0.00171")] {
        fails(
            &[
                "render",
                "vessels:32",
                "--size",
                "8x8",
                "--step",
                step,
                "--shade",
                shade,
            ],
            &[],
            &format!("a step of at least {least}"),
        );
    }
}
