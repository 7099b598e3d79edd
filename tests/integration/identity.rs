//! Every skipping structure renders exactly the naive image (DESIGN invariant
//! 3): bit for bit, under each sample filter (naive with the same filter),
//! over generators, the ch2 MRI, every TF kind, orthographic and perspective
//! cameras, and the DESIGN hard cases.

use crate::common;
use crate::common::assert_clean;
use crate::common::identity::{cam, lattice_views, standard_views, Fixture, Given, Kernels, DEFAULTS};
use lacuna::accel::{Params, Structure};
use lacuna::frame::diff;
use lacuna::render::{Filter, FrameDesc, Octants, Projection};
use lacuna::volume::{LoadOptions, VoxelData, VoxelType};
use lacuna::{TransferFunction, Volume};

fn load(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

fn tf(spec: &str) -> TransferFunction {
    TransferFunction::parse(spec).unwrap()
}

#[test]
fn generators_with_their_default_tfs() {
    let fx = Fixture::new();
    for spec in ["menger:27", "nbody:48", "vessels:44", "turbulence:32", "shells:40"] {
        let v = load(spec);
        let t = tf(v.default_tf.as_ref().unwrap());
        // The sponge and the turbulence fill their box: a k-d tree's tight
        // box is all of it, and no split shrinks it.
        let frames = if spec.starts_with("menger") || spec.starts_with("turbulence") {
            fx.check_dense(spec, &v, &t, &standard_views())
        } else {
            fx.check(spec, &v, &t, &standard_views())
        };
        assert!(
            frames[0].pixels.iter().any(|p| p[3] > 0.01),
            "{spec}: empty image proves nothing"
        );
    }
}

#[test]
fn every_tf_kind_including_a_spike_seen_only_through_interpolation() {
    let fx = Fixture::new();
    let v = load("turbulence:37x29x41");
    for spec in [
        "ramp:0.6:0.9:0.5",
        "band:0.45:0.5:0.8",
        "spike:0.7:0.002",
        "band:0.3105:0.3107",
    ] {
        fx.check(spec, &v, &tf(spec), &standard_views()[..4]);
    }
    // Two voxel values (0 and 1); the spike at 0.5 lies between them.
    let data: Vec<u8> = (0..24 * 24 * 24).map(|i| if (i % 24) < 12 { 0 } else { 255 }).collect();
    let halves = Volume::new("halves", [24; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let frames = fx.check(
        "spike between values",
        &halves,
        &tf("spike:0.5:0.0005"),
        &[
            cam(24, 90.0, 0.0, Projection::Orthographic, 0.5),
            cam(24, 80.0, 10.0, Projection::Orthographic, 0.25),
        ],
    );
    assert!(
        frames[0].pixels.iter().all(|p| p[3] > 0.0),
        "every ray crosses x = 12 exactly and sees the spike"
    );
    // A ParaView JSON colormap.
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("tf.json");
    std::fs::write(
        &json,
        r#"[{"RGBPoints":[0,0,0,1, 1,1,1,0],"Points":[0,0,0.5,0, 0.55,0,0.5,0, 1,0.9,0.5,0]}]"#,
    )
    .unwrap();
    fx.check("json", &v, &tf(json.to_str().unwrap()), &standard_views()[..2]);
}

#[test]
fn the_ch2_mri() {
    let fx = Fixture::new();
    let v = Volume::load("/usr/share/mricron/templates/ch2.nii.gz", &LoadOptions::default())
        .expect("apt install mricron-data");
    let views = [
        cam(64, 30.0, 20.0, Projection::Orthographic, 1.0),
        cam(
            48,
            120.0,
            -10.0,
            Projection::Perspective {
                fov_deg: 40.0,
                distance: None,
            },
            1.5,
        ),
    ];
    fx.check("ch2", &v, &tf("ramp:0.3:0.8:0.15"), &views);
}

#[test]
fn transparent_opaque_and_single_voxel_cases() {
    let fx = Fixture::new();
    let v = load("vessels:40");
    // Zero active bricks: empty structures and a transparent image.
    let frames = fx.check("transparent", &v, &tf("band:0:1:0"), &standard_views()[..2]);
    assert!(frames.iter().all(|f| f.pixels.iter().all(|p| *p == [0.0; 4])));
    let clear = tf("band:0:1:0");
    let p = fx.prepare(&v, &clear, DEFAULTS);
    for accel in [
        common::accel("lbvh"),
        common::accel("kd-cpu"),
        common::accel("kd-gpu"),
        common::accel("hybrid"),
    ] {
        assert_eq!(
            fx.build(&p, accel, &accel.defaults()).stats().unwrap().unwrap().leaves,
            0,
            "{accel}"
        );
    }
    assert_eq!(
        fx.build(&p, common::accel("grid"), &common::accel("grid").defaults())
            .stats()
            .unwrap()
            .unwrap()
            .active_bricks,
        0
    );
    // All active.
    let opaque = tf("band:0:1:0.05");
    let p = fx.prepare(&v, &opaque, DEFAULTS);
    assert_eq!(
        fx.build(&p, common::accel("lbvh"), &common::accel("lbvh").defaults())
            .stats()
            .unwrap()
            .unwrap()
            .active_bricks,
        125
    );
    assert_eq!(
        fx.build(&p, common::accel("kd-cpu"), &common::accel("kd-cpu").defaults())
            .stats()
            .unwrap()
            .unwrap()
            .active_bricks,
        40 * 40 * 40
    );
    // Every cell active: a k-d tree is one leaf covering the volume, marched naively.
    fx.check_with("opaque", &v, &opaque, &standard_views(), &[DEFAULTS], Kernels::Reported);
    let ert = FrameDesc::builder(32, 32).ert(Some(0.95)).build().unwrap();
    fx.check_with(
        "opaque with ERT",
        &v,
        &tf("band:0:1:1"),
        &[ert],
        &[DEFAULTS],
        Kernels::Reported,
    );
    // One bright voxel: its neighbours' footprints read it too.
    let mut data = vec![0u8; 40 * 40 * 40];
    data[16 + 40 * (16 + 40 * 16)] = 255;
    let dot = Volume::new("dot", [40; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let dot_tf = tf("band:0.02:1:1");
    let frames = fx.check("single voxel", &dot, &dot_tf, &standard_views());
    assert!(frames[1].pixels.iter().any(|p| p[3] > 0.0));
    let p = fx.prepare(&dot, &dot_tf, DEFAULTS);
    assert_eq!(
        fx.build(&p, common::accel("lbvh"), &common::accel("lbvh").defaults())
            .stats()
            .unwrap()
            .unwrap()
            .leaves,
        8,
        "voxel 16 sits on the corner of 8 bricks' aprons"
    );
    let kd = fx.build(&p, common::accel("kd-cpu"), &common::accel("kd-cpu").defaults());
    assert_eq!(
        kd.stats().unwrap().unwrap().active_bricks,
        27,
        "the 3^3 footprints around the voxel"
    );
    assert_eq!(kd.stats().unwrap().unwrap().leaves, 1);
}

#[test]
fn odd_and_degenerate_dimensions() {
    let fx = Fixture::new();
    for spec in [
        "nbody:13x37x21",
        "shells:1x1x40",
        "turbulence:1x9x1",
        "menger:9x9x1",
        "vessels:3x50x7",
    ] {
        let v = load(spec);
        fx.check_dense(spec, &v, &tf("ramp:0.2:1:0.6"), &standard_views());
    }
}

#[test]
fn rays_exactly_through_brick_faces_edges_and_corners_and_grazing() {
    let fx = Fixture::new();
    let mut v = load("turbulence:32");
    let views = lattice_views();
    v.default_tf = None;
    fx.check_dense("lattice rays", &v, &tf("ramp:0.55:1:0.5"), &views);
    fx.check_dense("lattice rays, sparse", &v, &tf("band:0.8:1"), &views);
}

#[test]
fn camera_inside_the_volume_and_inside_an_empty_region() {
    let fx = Fixture::new();
    // The centre of concentric shells is empty.
    let v = load("shells:48");
    let inside = Projection::Perspective {
        fov_deg: 90.0,
        distance: Some(0.0),
    };
    let near = Projection::Perspective {
        fov_deg: 60.0,
        distance: Some(0.5),
    };
    let views = vec![
        cam(40, 0.0, 0.0, inside, 0.5),
        cam(40, 33.0, 12.0, inside, 0.3),
        cam(40, 90.0, 45.0, near, 0.5),
    ];
    let frames = fx.check("inside shells", &v, &tf(v.default_tf.as_ref().unwrap()), &views);
    assert!(
        frames[0].pixels.iter().all(|p| p[3] > 0.0),
        "every ray from the centre meets the shells"
    );
}

#[test]
fn steps_that_do_not_divide_the_box_and_a_long_volume_with_large_t() {
    let fx = Fixture::new();
    let v = load("nbody:40");
    let t = tf("ramp:0.3:1");
    let views: Vec<FrameDesc> = [0.3f32, 0.77, 1.9, 3.3]
        .iter()
        .map(|&s| cam(40, 17.0, 23.0, Projection::Orthographic, s))
        .collect();
    fx.check("odd steps", &v, &t, &views);
    // 4 x 4 x 3000: t runs to thousands of voxels, where float spacing of t
    // is coarse; the lattice and the margins must still agree with naive.
    let n = 4 * 4 * 3000;
    let data: Vec<u8> = (0..n).map(|i| if (i / 16) % 97 < 3 { 255 } else { 0 }).collect();
    let long = Volume::new("long", [4, 4, 3000], [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let views = vec![
        cam(16, 0.0, 0.0, Projection::Orthographic, 0.5),
        cam(16, 0.3, 0.2, Projection::Orthographic, 0.7),
        cam(
            16,
            180.0,
            0.0,
            Projection::Perspective {
                fov_deg: 1.0,
                distance: Some(1.2),
            },
            0.5,
        ),
    ];
    fx.check("long volume", &long, &tf("band:0.5:1:0.01"), &views);
}

#[test]
fn voxel_classification_with_apron_equals_range_and_without_it_loses_samples() {
    let fx = Fixture::new();
    let lbvh = common::accel("lbvh");
    let voxel = lbvh.params(&[("classify", "voxel")]).unwrap();
    for spec in ["vessels:40", "nbody:48", "turbulence:37x29x41"] {
        let v = load(spec);
        let t = tf(v.default_tf.as_ref().unwrap());
        let p = fx.prepare(&v, &t, DEFAULTS);
        let nodes = |params: &Params| fx.build(&p, lbvh, params).tree().unwrap().read_nodes().unwrap();
        assert_eq!(
            nodes(&lbvh.defaults()),
            nodes(&voxel),
            "{spec}: same active bricks, same tree"
        );
    }
    // The paper's per-voxel voting drops a brick whose own voxels are clear
    // but whose samples interpolate a neighbour's.
    let data: Vec<u8> = (0..24 * 24 * 24).map(|i| if (i % 24) < 8 { 255 } else { 0 }).collect();
    let v = Volume::new("edge", [24; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let t = tf("spike:0.5:0.01");
    let p = fx.prepare(&v, &t, DEFAULTS);
    let view = cam(24, 90.0, 0.0, Projection::Orthographic, 0.5);
    let naive = fx.frame(&Structure::naive(), &p, &view, Filter::Manual);
    let paper = fx.build(
        &p,
        lbvh,
        &lbvh.params(&[("classify", "voxel"), ("apron", "off")]).unwrap(),
    );
    assert!(
        diff(&naive, &fx.frame(&paper, &p, &view, Filter::Manual))
            .unwrap()
            .max_abs
            > 0.0,
        "the paper's classification should lose the interpolated spike here"
    );
    let exact = fx.build(&p, lbvh, &voxel);
    assert_eq!(
        diff(&naive, &fx.frame(&exact, &p, &view, Filter::Manual))
            .unwrap()
            .differing,
        0
    );
    assert_clean(&fx.ctx);
}

#[test]
fn every_structure_parameter_set_the_paper_compares() {
    let fx = Fixture::new();
    let sets: [Given; 4] = [
        &[("kd", "shallow"), ("max-leaf", "32"), ("bins", "4"), ("cell", "16")],
        &[("kd", "deep"), ("max-leaf", "128"), ("bins", "4"), ("cell", "8")],
        &[("kd", "deep"), ("max-leaf", "32"), ("bins", "2"), ("cell", "32")],
        &[("kd", "deep"), ("max-leaf", "8"), ("bins", "7"), ("cell", "4")],
    ];
    for (spec, t, kernels) in [
        ("vessels:44", "ramp:0.3:1", Kernels::Own),
        ("menger:27", "ramp:0.3:1:0.2", Kernels::Reported),
    ] {
        let v = load(spec);
        fx.check_with(spec, &v, &tf(t), &standard_views()[..3], &sets, kernels);
    }
}

#[test]
fn an_octant_map_of_one_view_renders_every_direction_exactly() {
    // Built for the first view's ray octant alone (as `render` builds it):
    // views of every other octant read distance 1 there and walk cell by
    // cell, and still equal naive.
    let fx = Fixture::new();
    let v = load("nbody:48");
    let t = tf(v.default_tf.as_ref().unwrap());
    let inside = Projection::Perspective {
        fov_deg: 80.0,
        distance: Some(0.3),
    };
    let mut views: Vec<FrameDesc> = [25.0, -25.0]
        .into_iter()
        .flat_map(|el| [30.0, 120.0, 210.0, 300.0].map(|az| cam(40, az, el, Projection::Orthographic, 0.5)))
        .collect();
    views.push(cam(40, 75.0, 10.0, inside, 0.5));
    let p = fx.prepare(&v, &t, DEFAULTS);
    let first = views[0].octants(v.dims, v.spacing).unwrap();
    assert_eq!(first.len(), 1, "an orthographic view has one octant");
    let all = FrameDesc::octants_of(&views, v.dims, v.spacing).unwrap();
    assert_eq!(all, Octants::ALL, "the views cover every octant");
    let accel = common::accel("distance-octant");
    let params = Params::resolve(accel.method().params(), &[("cell", "4")]).unwrap();
    let partial = fx.build_for(&p, accel, &params, first);
    assert_eq!(partial.octants(), first);
    let naive = Structure::naive();
    for (i, view) in views.iter().enumerate() {
        let want = fx.frame(&naive, &p, view, Filter::Manual);
        assert!(
            want.pixels.iter().any(|px| px[3] > 0.01),
            "view {i}: empty image proves nothing"
        );
        let got = fx.frame(&partial, &p, view, Filter::Manual);
        let d = diff(&want, &got).unwrap();
        assert_eq!(
            d.differing,
            0,
            "view {i} ({}): {d:?}",
            view.octants(v.dims, v.spacing).unwrap()
        );
    }
    assert_clean(&fx.ctx);
}
