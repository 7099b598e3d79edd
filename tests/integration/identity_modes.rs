//! Every skipping structure equals naive marching bit for bit in every
//! frame mode, with gradient shading, clip planes, a crop box and jitter
//! (DESIGN invariant 3 beyond the plain composite): each structure built
//! for the frame's mode, under each sample filter.

use crate::common::identity::{cam, lattice_views, standard_views, Fixture, Kernels, DEFAULTS};
use lacuna::frame::Frame;
use lacuna::render::{Clip, FrameDesc, Iso, Light, Mode, Projection, Shading};
use lacuna::volume::{LoadOptions, VoxelData, VoxelType};
use lacuna::{TransferFunction, Volume};

fn load(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

fn tf(spec: &str) -> TransferFunction {
    TransferFunction::parse(spec).unwrap()
}

/// `views` with `f` applied to each.
fn with(
    views: &[FrameDesc],
    f: impl Fn(lacuna::render::FrameBuilder) -> lacuna::render::FrameBuilder,
) -> Vec<FrameDesc> {
    views.iter().map(|v| f(v.to_builder()).build().unwrap()).collect()
}

fn iso(values: &[f32]) -> Mode {
    Mode::Iso(Iso::new(values).unwrap())
}

fn shows(frames: &[Frame]) -> bool {
    frames.iter().any(|f| f.pixels.iter().any(|p| p[3] > 0.01))
}

#[test]
fn every_mode_on_sparse_and_thin_data() {
    let fx = Fixture::new();
    let views = &standard_views()[..5];
    for spec in ["nbody:48", "vessels:44", "shells:40"] {
        let v = load(spec);
        let t = tf(v.default_tf.as_ref().unwrap());
        for mode in [
            Mode::Mip,
            Mode::MinIp,
            Mode::Average,
            iso(&[0.5]),
            iso(&[0.2, 0.45, 0.8]),
        ] {
            let frames = fx.check_with(
                &format!("{spec} {}", mode.name()),
                &v,
                &t,
                &with(views, |b| b.mode(mode)),
                &[DEFAULTS],
                Kernels::Reported,
            );
            if !matches!(mode, Mode::MinIp | Mode::Average) {
                assert!(shows(&frames), "{spec} {mode:?}: empty frames prove nothing");
            }
        }
    }
}

#[test]
fn shading_and_gradient_opacity_on_every_structure() {
    let fx = Fixture::new();
    let views = &standard_views();
    let fixed = Shading {
        light: Light::Fixed {
            azimuth_deg: 120.0,
            elevation_deg: 40.0,
        },
        gradient_opacity: Some([0.01, 0.08]),
        ..Shading::default()
    };
    for (spec, kernels) in [("vessels:44", Kernels::Own), ("menger:27", Kernels::Reported)] {
        let v = load(spec);
        let t = tf(v.default_tf.as_ref().unwrap());
        for shading in [Shading::default(), fixed] {
            let frames = fx.check_with(
                spec,
                &v,
                &t,
                &with(views, |b| b.shading(Some(shading))),
                &[DEFAULTS],
                kernels,
            );
            assert!(shows(&frames));
        }
    }
    let v = load("nbody:48");
    let t = tf(v.default_tf.as_ref().unwrap());
    let frames = fx.check(
        "shaded iso",
        &v,
        &t,
        &with(views, |b| b.mode(iso(&[0.3])).shading(Some(fixed))),
    );
    assert!(shows(&frames));
}

#[test]
fn clip_planes_crop_boxes_and_their_hard_cases() {
    let fx = Fixture::new();
    let v = load("shells:40");
    let t = tf(v.default_tf.as_ref().unwrap());
    let persp = Projection::Perspective {
        fov_deg: 60.0,
        distance: Some(0.6),
    };
    let clips = [
        // Oblique planes, the crop box cutting bricks mid-way.
        Clip::default()
            .plane([1.0, 0.3, -0.2, -17.0])
            .unwrap()
            .crop([3.5, 5.0, 2.0], [37.0, 30.25, 35.0])
            .unwrap(),
        // A plane parallel to the axis-aligned views' rays, on a brick face.
        Clip::default().plane([1.0, 0.0, 0.0, -16.0]).unwrap(),
        // A plane through the near perspective eye (inside the box).
        Clip::default().plane([0.2, 0.1, 1.0, -20.0]).unwrap(),
        // A crop box of zero thickness, and a plane that removes everything.
        Clip::default().crop([0.0, 0.0, 20.0], [40.0, 40.0, 20.0]).unwrap(),
        Clip::default().plane([0.0, 1.0, 0.0, -41.0]).unwrap(),
    ];
    let mut views = standard_views()[..4].to_vec();
    views.push(cam(40, 20.0, 10.0, persp, 0.5));
    for (i, clip) in clips.iter().enumerate() {
        for mode in [Mode::Composite, Mode::Mip, iso(&[0.6])] {
            let frames = fx.check_with(
                &format!("clip {i} {}", mode.name()),
                &v,
                &t,
                &with(&views, |b| b.clip(*clip).mode(mode)),
                &[DEFAULTS],
                Kernels::Reported,
            );
            assert_eq!(shows(&frames), i < 3, "clip {i}: what it keeps");
        }
    }
}

#[test]
fn jitter_with_every_mode_and_lattice_rays() {
    let fx = Fixture::new();
    let v = load("vessels:44");
    let t = tf(v.default_tf.as_ref().unwrap());
    for mode in [Mode::Composite, Mode::Mip, iso(&[0.45])] {
        fx.check_with(
            &format!("jitter {}", mode.name()),
            &v,
            &t,
            &with(&standard_views(), |b| b.jitter(true).mode(mode)),
            &[DEFAULTS],
            Kernels::Reported,
        );
    }
    // Rays through brick faces and corners, jittered and shaded.
    let all = lattice_views();
    let views = [all[0], all[2]];
    let mut turb = load("turbulence:32");
    turb.default_tf = None;
    fx.check_dense(
        "jittered shaded lattice rays",
        &turb,
        &tf("band:0.8:1"),
        &with(&views, |b| b.jitter(true).shading(Some(Shading::default()))),
    );
    fx.check_with(
        "jittered iso lattice rays",
        &turb,
        &tf("band:0.8:1"),
        &with(&views, |b| b.jitter(true).mode(iso(&[0.8]))),
        &[DEFAULTS],
        Kernels::Reported,
    );
}

#[test]
fn an_isosurface_between_two_voxel_values_and_at_a_single_voxel() {
    let fx = Fixture::new();
    // Two values (0 and 1): the surface at 0.5 lies between voxels, where
    // only interpolation reaches it.
    let data: Vec<u8> = (0..24 * 24 * 24).map(|i| if (i % 24) < 12 { 0 } else { 255 }).collect();
    let halves = Volume::new("halves", [24; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let views = [
        cam(24, 90.0, 0.0, Projection::Orthographic, 0.5),
        cam(24, 80.0, 10.0, Projection::Orthographic, 0.25),
    ];
    let frames = fx.check_with(
        "iso between values",
        &halves,
        &tf("ramp:0:1"),
        &with(&views, |b| b.mode(iso(&[0.5]))),
        &[DEFAULTS],
        Kernels::Reported,
    );
    assert!(frames[0].pixels.iter().all(|p| p[3] == 1.0), "every ray crosses x = 12");
    // One bright voxel: its isosurface is a small blob in one brick corner.
    let mut data = vec![0u8; 40 * 40 * 40];
    data[16 + 40 * (16 + 40 * 16)] = 255;
    let dot = Volume::new("dot", [40; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let frames = fx.check(
        "iso single voxel",
        &dot,
        &tf("ramp:0:1"),
        &with(&standard_views(), |b| b.mode(iso(&[0.3]))),
    );
    assert!(shows(&frames));
}
