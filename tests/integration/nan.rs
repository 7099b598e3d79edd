//! Float volumes with NaN and infinities ("no data"): loaded, counted,
//! rendered like the CPU reference in every mode (a sample that reads a NaN
//! voxel is transparent), every structure bit-identical to naive, an
//! all-NaN volume transparent, and the hardware filter refused.

use crate::common::identity::{standard_views, Fixture, Kernels, DEFAULTS};
use crate::common::{gpu, lacuna, masked, max_abs, render};
use lacuna::accel::Accel;
use lacuna::render::{reference, Filter, FrameDesc, Projection};
use lacuna::volume::{GpuVolume, VoxelData, VoxelType};
use lacuna::{TransferFunction, Volume};

use crate::common::identity::every_look as modes;

#[test]
fn raw_float_files_with_nan_and_infinities_load_and_count_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("masked_4x4x2_float32.raw");
    let mut values = [0.5f32; 32];
    values[0] = f32::NAN;
    values[5] = f32::INFINITY;
    values[6] = f32::INFINITY;
    values[9] = f32::NEG_INFINITY;
    values[10] = 2.0;
    values[11] = -1.0;
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    std::fs::write(&path, bytes).unwrap();
    let v = Volume::load(path.to_str().unwrap(), &Default::default()).unwrap();
    assert_eq!((v.no_data.nan, v.no_data.pos_inf, v.no_data.neg_inf), (1, 2, 1));
    // The range is the finite values'; no-data voxels are stored as NaN.
    assert_eq!(v.value_range, [-1.0, 2.0]);
    let VoxelData::F32(stored) = &v.data else {
        panic!("float32 stays float")
    };
    assert_eq!(stored.iter().filter(|x| x.is_nan()).count(), 4);
    assert_eq!(v.value(2, 2, 0), 1.0);
    assert_eq!(v.value(3, 2, 0), 0.0);
    let r = lacuna(&["info", path.to_str().unwrap()], &[]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stdout.contains("no data  4 voxels (12.500 %): 1 NaN, 2 +inf, 1 -inf"),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("values   -1 .. 2"), "{}", r.stdout);
    // A volume with no value at all says so, not "0 .. 0".
    let none = dir.path().join("none_2x2x2_float32.raw");
    std::fs::write(
        &none,
        [f32::NAN; 8].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>(),
    )
    .unwrap();
    let r = lacuna(&["info", none.to_str().unwrap()], &[]);
    assert!(
        r.stdout.contains("values   none (every voxel is no data)\n"),
        "{}",
        r.stdout
    );
    // Rendering it works; the hardware filter is refused with a reason.
    let out = dir.path().join("f.exr");
    let ok = lacuna(
        &[
            "render",
            path.to_str().unwrap(),
            "--size",
            "16x16",
            "--validate",
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(ok.code, 0, "{}", ok.stderr);
    assert!(ok.stdout.contains("filter manual (device default)"), "{}", ok.stdout);
    let hw = lacuna(&["render", path.to_str().unwrap(), "--filter", "hardware"], &[]);
    assert_ne!(hw.code, 0);
    assert!(hw.stderr.contains("without data (NaN)"), "{}", hw.stderr);
}

#[test]
fn every_mode_matches_the_cpu_reference_on_masked_data() {
    let ctx = gpu();
    for spec in ["turbulence:32", "shells:36"] {
        let v = masked(spec);
        assert!(v.no_data.nan > 0 && v.no_data.pos_inf > 0 && v.no_data.neg_inf > 0);
        let gv = GpuVolume::upload(&ctx, &v).unwrap();
        assert!(gv.has_nan());
        assert!(gv.sampler_for(Filter::Hardware).is_err());
        let tf = TransferFunction::parse(v.default_tf.as_ref().unwrap()).unwrap();
        for (mode, shading) in modes() {
            for proj in [
                Projection::Orthographic,
                Projection::Perspective {
                    fov_deg: 40.0,
                    distance: None,
                },
            ] {
                let desc = FrameDesc::builder(40, 40)
                    .orbit(25.0, 15.0, proj)
                    .mode(mode)
                    .shading(shading)
                    .build()
                    .unwrap();
                let cpu = reference::render_frame(&v, &tf, &desc).unwrap();
                let f = render(&ctx, &v, &tf, &desc, Accel::naive());
                let err = max_abs(&f, &cpu);
                assert!(err <= 1e-4, "{spec} {mode:?}: GPU vs CPU {err}");
                assert!(f.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())));
            }
        }
    }
}

#[test]
fn the_mask_is_transparent_and_the_unmasked_data_still_shows() {
    // The same volume with and without its NaN ball: a ray through the
    // ball's centre only, head on, loses what the ball held.
    let ctx = gpu();
    let v = masked("shells:36");
    let plain = Volume::load("shells:36", &Default::default()).unwrap();
    let tf = TransferFunction::parse(v.default_tf.as_ref().unwrap()).unwrap();
    let desc = FrameDesc::builder(36, 36)
        .orbit(0.0, 0.0, Projection::Orthographic)
        .filter(Filter::Manual)
        .build()
        .unwrap();
    let a = render(&ctx, &v, &tf, &desc, Accel::naive());
    let b = render(&ctx, &plain, &tf, &desc, Accel::naive());
    assert!(a.pixels.iter().any(|p| p[3] > 0.01), "the rest still shows");
    assert!(max_abs(&a, &b) > 0.01, "the ball hid something");
}

#[test]
fn every_structure_equals_naive_on_masked_data_in_every_mode() {
    let fx = Fixture::new();
    let views = &standard_views()[..4];
    let v = masked("vessels:40");
    let tf = TransferFunction::parse(v.default_tf.as_ref().unwrap()).unwrap();
    for (mode, shading) in modes() {
        let views: Vec<FrameDesc> = views
            .iter()
            .map(|d| d.to_builder().mode(mode).shading(shading).build().unwrap())
            .collect();
        fx.check_with(
            &format!("masked {}", mode.name()),
            &v,
            &tf,
            &views,
            &[DEFAULTS],
            Kernels::Reported,
        );
    }
}

#[test]
fn an_all_nan_volume_renders_transparent_with_every_structure() {
    let fx = Fixture::new();
    let v = Volume::new(
        "all nan",
        [24, 20, 16],
        [1.0; 3],
        VoxelType::F32,
        VoxelData::F32(vec![f32::NAN; 24 * 20 * 16]),
    )
    .unwrap();
    assert_eq!(v.no_data.nan, 24 * 20 * 16);
    assert_eq!(v.value_range, [0.0, 0.0]);
    let tf = TransferFunction::parse("ramp:0:1:1").unwrap();
    for (mode, shading) in modes() {
        let views: Vec<FrameDesc> = standard_views()[..2]
            .iter()
            .map(|d| d.to_builder().mode(mode).shading(shading).build().unwrap())
            .collect();
        let frames = fx.check_with(
            &format!("all nan {}", mode.name()),
            &v,
            &tf,
            &views,
            &[DEFAULTS],
            Kernels::Reported,
        );
        assert!(frames.iter().all(|f| f.pixels.iter().all(|p| *p == [0.0; 4])));
    }
}

#[test]
fn exports_keep_no_data_as_nan_in_float32_only() {
    let dir = tempfile::tempdir().unwrap();
    let v = masked("nbody:16");
    let path = dir.path().join("m");
    let src = dir.path().join("masked_16x16x16_float32.raw");
    let bytes: Vec<u8> = match &v.data {
        VoxelData::F32(d) => d.iter().flat_map(|x| x.to_le_bytes()).collect(),
        _ => unreachable!(),
    };
    std::fs::write(&src, bytes).unwrap();
    let out = lacuna(&["export", src.to_str().unwrap(), path.to_str().unwrap()], &[]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let back = Volume::load(
        dir.path().join("m_16x16x16_float32.raw").to_str().unwrap(),
        &Default::default(),
    )
    .unwrap();
    assert_eq!(back.no_data.nan, v.no_data.total());
    let bad = lacuna(
        &[
            "export",
            src.to_str().unwrap(),
            path.to_str().unwrap(),
            "--type",
            "uint8",
        ],
        &[],
    );
    assert_ne!(bad.code, 0);
    assert!(bad.stderr.contains("without data (NaN)"), "{}", bad.stderr);
}
