//! Several channels on one grid: `+` joins files and generators, one
//! transfer function per channel (or one for all), densities mixed per
//! sample; every structure equals naive on every channel combination and
//! mode, the GPU equals the CPU reference, and bad channel input is a
//! one-line error.

use crate::common;
use crate::common::identity::{standard_views, Fixture, Kernels, DEFAULTS};
use crate::common::{fails, lacuna, max_abs};
use lacuna::accel::Accel;
use lacuna::frame::Frame;
use lacuna::render::{reference, FrameDesc, Mode};
use lacuna::volume::{BrickGrid, Filter, LoadOptions, Series, VoxelData, VoxelType, BRICK};
use lacuna::{TransferFunction, Volume};

fn load(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

fn tf(spec: &str) -> TransferFunction {
    TransferFunction::parse(spec).unwrap()
}

fn per_channel(specs: &[&str]) -> TransferFunction {
    TransferFunction::per_channel(specs.iter().map(|s| tf(s)).collect()).unwrap()
}

fn with_mode(views: &[FrameDesc], mode: Mode) -> Vec<FrameDesc> {
    views
        .iter()
        .map(|v| v.to_builder().mode(mode).build().unwrap())
        .collect()
}

fn shows(frames: &[Frame]) -> bool {
    frames.iter().any(|f| f.pixels.iter().any(|p| p[3] > 0.01))
}

/// A float32 channel on `like`'s grid: its values scaled into [-3, 40),
/// with a slab of NaN (no data) along x = 0..2.
fn float_channel(like: &Volume) -> Volume {
    let [w, h, _] = like.dims;
    let values: Vec<f32> = (0..like.data.len())
        .map(|i| match i as u32 % w < 3 {
            true => f32::NAN,
            false => -3.0 + 43.0 * like.channel(0).data.texel(i) * ((i as u32 / w) % h) as f32 / h as f32,
        })
        .collect();
    Volume::new("float", like.dims, like.spacing, VoxelType::F32, VoxelData::F32(values)).unwrap()
}

#[test]
fn joined_generators_are_one_volume_of_channels() {
    let v = load("vessels:32+nbody:32");
    assert_eq!(v.channel_count(), 2);
    assert_eq!(v.name, "vessels:32x32x32+nbody:32x32x32");
    assert_eq!(
        [v.channel_name(0), v.channel_name(1)],
        ["vessels:32x32x32", "nbody:32x32x32"]
    );
    let (a, b) = (load("vessels:32"), load("nbody:32"));
    assert_eq!(v.channel(0).data.texel(999), a.data.texel(999));
    assert_eq!(v.channel(1).data.texel(999), b.data.texel(999));
    // The union: a brick is active iff it is in either channel.
    let t = per_channel(&[a.default_tf.as_deref().unwrap(), b.default_tf.as_deref().unwrap()]);
    let union = BrickGrid::new(&v, BRICK, 1).active(&t);
    let ea = BrickGrid::new(&a, BRICK, 1).active(t.channel(0));
    let eb = BrickGrid::new(&b, BRICK, 1).active(t.channel(1));
    for (i, u) in union.iter().enumerate() {
        assert_eq!(*u, ea[i] || eb[i], "brick {i}");
    }
    assert!(union.iter().filter(|a| **a).count() > ea.iter().filter(|a| **a).count());
}

#[test]
fn every_structure_equals_naive_over_two_sparse_channels_in_every_mode() {
    let fx = Fixture::new();
    let v = load("vessels:32+nbody:32");
    let t = per_channel(&["ramp:0.3:1", "ramp:0.35:1"]);
    let views = &standard_views()[..4];
    for mode in [Mode::Composite, Mode::Mip, Mode::MinIp, Mode::Average] {
        let frames = fx.check_with(
            &format!("vessels+nbody {}", mode.name()),
            &v,
            &t,
            &with_mode(views, mode),
            &[DEFAULTS],
            Kernels::Reported,
        );
        // A ramp's minimum is transparent: minip shows nothing.
        if !matches!(mode, Mode::Average | Mode::MinIp) {
            assert!(shows(&frames), "{mode:?}: empty frames prove nothing");
        }
    }
}

#[test]
fn hard_cases_transparent_dense_and_mixed_type_channels() {
    let fx = Fixture::new();
    let views = &standard_views()[..3];
    // One channel transparent: the frame is the other channel's alone.
    let v = load("nbody:32+vessels:32");
    let t = per_channel(&["ramp:0.35:1", "ramp:0:1:0"]);
    let frames = fx.check("transparent second channel", &v, &t, views);
    assert!(shows(&frames));
    let alone = fx.check("nbody alone", &load("nbody:32"), &tf("ramp:0.35:1"), views);
    for (two, one) in frames.iter().zip(&alone) {
        assert!(
            max_abs(two, one) < 1e-6,
            "a transparent channel changed the frame: {}",
            max_abs(two, one)
        );
    }
    // One dense channel and one sparse.
    let v = load("menger:27+nbody:27");
    fx.check_with(
        "dense menger + sparse nbody",
        &v,
        &per_channel(&["ramp:0.5:1:0.2", "ramp:0.35:1"]),
        views,
        &[DEFAULTS],
        Kernels::Reported,
    );
    // u8 with float32 (other ranges, NaN voxels), in two modes; one TF for both.
    let nbody = load("nbody:32");
    let mixed = Volume::join(vec![nbody.clone(), float_channel(&nbody)]).unwrap();
    assert_eq!(lacuna::volume::common_kind(&mixed).constant(), 0, "stored as float");
    for mode in [Mode::Composite, Mode::Mip] {
        let frames = fx.check_with(
            &format!("u8 + f32 {}", mode.name()),
            &mixed,
            &tf("ramp:0.4:1"),
            &with_mode(views, mode),
            &[DEFAULTS],
            Kernels::Reported,
        );
        assert!(shows(&frames));
    }
}

#[test]
fn the_gpu_mix_equals_the_cpu_reference() {
    let ctx = common::gpu();
    let nbody = load("nbody:24");
    let cases = [
        (load("vessels:24+nbody:24"), per_channel(&["ramp:0.3:1", "ramp:0.35:1"])),
        (
            Volume::join(vec![nbody.clone(), float_channel(&nbody), load("shells:24")]).unwrap(),
            per_channel(&["ramp:0.35:1", "band:0.3:0.9:0.4", "ramp:0.5:1"]),
        ),
    ];
    for (v, t) in &cases {
        for mode in [Mode::Composite, Mode::Mip, Mode::MinIp, Mode::Average] {
            for view in &standard_views()[..2] {
                // The manual filter's weights are the reference's.
                let desc = view.to_builder().mode(mode).filter(Filter::Manual).build().unwrap();
                let gpu = common::render(&ctx, v, t, &desc, Accel::naive());
                let cpu = reference::render_frame(v, t, &desc).unwrap();
                let d = max_abs(&gpu, &cpu);
                assert!(d < 1e-4, "{} {}: GPU and CPU differ by {d}", v.name, mode.name());
                if !matches!(mode, Mode::Average | Mode::MinIp) {
                    assert!(shows(std::slice::from_ref(&gpu)), "{} {}", v.name, mode.name());
                }
            }
        }
    }
    common::assert_clean(&ctx);
}

#[test]
fn a_series_of_channels_steps_every_channel() {
    let series = Series::open("nbody:24+vessels:24", &LoadOptions::default()).unwrap();
    assert_eq!(series.steps(), lacuna::volume::procedural::STEPS);
    let step = series.load(5, None).unwrap();
    let nbody = Series::open("nbody:24", &LoadOptions::default())
        .unwrap()
        .load(5, None)
        .unwrap();
    let vessels = Series::open("vessels:24", &LoadOptions::default())
        .unwrap()
        .load(5, None)
        .unwrap();
    assert_eq!(step.channel_count(), 2);
    assert!((0..step.data.len()).all(|i| step.channel(0).data.texel(i) == nbody.data.texel(i)));
    assert!((0..step.data.len()).all(|i| step.channel(1).data.texel(i) == vessels.data.texel(i)));
}

#[test]
fn render_takes_a_tf_per_channel_and_equals_naive() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let spec = "vessels:32+nbody:32";
    let common = ["--size", "64x64", "--tf", "ramp:0.3:1", "--tf", "spike:0.6:0.2"];
    let mut frames = Vec::new();
    for accel in ["naive", "auto", "distance"] {
        let path = out(&format!("{accel}.exr"));
        let mut args = vec!["render", spec, "--accel", accel, "--out", &path, "--validate"];
        args.extend(common);
        let run = lacuna(&args, &[]);
        assert_eq!(run.code, 0, "{accel}: {}", run.stderr);
        assert!(run.stdout.contains("ramp:0.3:1 | spike:0.6:0.2"), "{}", run.stdout);
        frames.push(Frame::read_exr(std::path::Path::new(&path)).unwrap());
    }
    assert!(frames.iter().all(|f| max_abs(f, &frames[0]) == 0.0));
}

#[test]
fn bad_channel_input_is_one_error() {
    fails(&["render", "vessels:32+nbody:16"], &[], "channels share one grid");
    fails(
        &[
            "render",
            "vessels:16+nbody:16",
            "--tf",
            "ramp:0:1",
            "--tf",
            "ramp:0:1",
            "--tf",
            "ramp:0:1",
        ],
        &[],
        "3 transfer functions for a volume of 2 channels",
    );
    fails(
        &["render", "nbody:16", "--tf", "ramp:0:1", "--tf", "ramp:0:1"],
        &[],
        "2 transfer functions for a volume of 1 channel",
    );
    fails(
        &["render", "nbody:8+nbody:8+nbody:8+nbody:8+nbody:8"],
        &[],
        "1 to 4 channels",
    );
    fails(
        &["render", "nbody:16+vessels:16", "--shade", "on"],
        &[],
        "one channel's gradient",
    );
    fails(
        &["render", "nbody:16+vessels:16", "--mode", "iso", "--iso", "0.5"],
        &[],
        "one channel's gradient",
    );
    fails(&["render", "nbody:16+"], &[], "joined with '+'");
}

#[test]
fn nifti_components_and_nrrd_component_axes_are_channels() {
    let dir = tempfile::tempdir().unwrap();
    let n = 4 * 3 * 2;
    // NIfTI: x, y, z, 2 time steps, 2 components (dim[5]); channel c of
    // step t holds 10 c + t + i / 100 at voxel i, as float32.
    let value = |c: usize, t: usize, i: usize| 10.0 * c as f32 + t as f32 + i as f32 / 100.0;
    let mut data = Vec::new();
    for c in 0..2 {
        for t in 0..2 {
            for i in 0..n {
                data.extend_from_slice(&value(c, t, i).to_le_bytes());
            }
        }
    }
    let nii = dir.path().join("two.nii");
    std::fs::write(&nii, common::nifti_bytes(&[4, 3, 2, 2, 2], 16, 32, [1.0; 3], &data)).unwrap();
    let series = Series::open(nii.to_str().unwrap(), &LoadOptions::default()).unwrap();
    assert_eq!(series.steps(), 2);
    // Told by the header, before a voxel is read (bench's preflight).
    assert_eq!(series.channels_known(), Some(2));
    for t in 0..2 {
        let v = series.load(t as u32, None).unwrap();
        assert_eq!(v.channel_count(), 2);
        assert_eq!(v.channel_name(0), format!("{}[0]", nii.display()));
        for c in 0..2 {
            let ch = v.channel(c);
            let [lo, hi] = ch.value_range;
            for i in [0, 7, n - 1] {
                let source = lo + ch.data.texel(i) as f64 * (hi - lo);
                assert!(
                    (source - value(c, t, i) as f64).abs() < 1e-4,
                    "nifti c{c} t{t} i{i}: {source}"
                );
            }
        }
    }
    let too_many = dir.path().join("five.nii");
    std::fs::write(
        &too_many,
        common::nifti_bytes(&[2, 2, 2, 1, 5], 2, 8, [1.0; 3], &[0u8; 40]),
    )
    .unwrap();
    fails(&["info", too_many.to_str().unwrap()], &[], "1 to 4 channels");

    // NRRD: a component axis first, channels interleaved per voxel.
    let mut nrrd = b"NRRD0004\ntype: uint8\ndimension: 4\nsizes: 3 4 3 2\nkinds: RGB-color domain domain domain\nspacings: nan 1 1 2\nencoding: raw\n\n".to_vec();
    nrrd.extend((0..3 * n).map(|k| (k % 3 * 50 + k / 3) as u8));
    let path = dir.path().join("rgb.nrrd");
    std::fs::write(&path, &nrrd).unwrap();
    let v = load(path.to_str().unwrap());
    assert_eq!((v.channel_count(), v.dims, v.spacing), (3, [4, 3, 2], [1.0, 1.0, 2.0]));
    // Each component by its index, the first too (not the file's name).
    let p = path.display();
    let names: Vec<String> = (0..3).map(|c| v.channel_name(c)).collect();
    assert_eq!(names, [format!("{p}[0]"), format!("{p}[1]"), format!("{p}[2]")]);
    for c in 0..3 {
        match &v.channel(c).data {
            VoxelData::U8(d) => assert_eq!(d[5], (c * 50 + 5) as u8),
            other => panic!("{other:?}"),
        }
    }
    // As Slicer and teem write a vector volume: `none` first in the space
    // directions, for the component axis.
    let slicer = String::from_utf8(nrrd.clone()).unwrap().replacen(
        "spacings: nan 1 1 2",
        "space: left-posterior-superior\nspace directions: none (1,0,0) (0, 0.5,0) (0,0,2)",
        1,
    );
    let path = dir.path().join("slicer.nrrd");
    std::fs::write(&path, slicer.as_bytes()).unwrap();
    let v = load(path.to_str().unwrap());
    assert_eq!((v.channel_count(), v.dims, v.spacing), (3, [4, 3, 2], [1.0, 0.5, 2.0]));
    // Told by the header, before a voxel is read (bench's preflight).
    let series = Series::open(path.to_str().unwrap(), &LoadOptions::default()).unwrap();
    assert_eq!(series.channels_known(), Some(3));
    // A time axis last is a series; anywhere else it is not contiguous.
    let mut timed =
        b"NRRD0004\ntype: uint8\ndimension: 4\nsizes: 4 3 2 3\nkinds: domain domain domain time\nencoding: raw\n\n"
            .to_vec();
    timed.extend((0..3 * n).map(|k| (k / n * 7 + k % n) as u8));
    let path = dir.path().join("timed.nrrd");
    std::fs::write(&path, &timed).unwrap();
    let series = Series::open(path.to_str().unwrap(), &LoadOptions::default()).unwrap();
    assert_eq!(series.steps(), 3);
    match &series.load(2, None).unwrap().data {
        VoxelData::U8(d) => assert_eq!(d[1], 15),
        other => panic!("{other:?}"),
    }
    let mut bad_bytes =
        b"NRRD0004\ntype: uint8\ndimension: 4\nsizes: 3 4 3 2\nkinds: time domain domain domain\nencoding: raw\n\n"
            .to_vec();
    bad_bytes.extend(std::iter::repeat_n(0u8, 3 * n));
    let path = dir.path().join("time_first.nrrd");
    std::fs::write(&path, &bad_bytes).unwrap();
    fails(&["info", path.to_str().unwrap()], &[], "time axis is not contiguous");
}

#[test]
fn info_describes_every_channel_and_counts_visible_voxels_over_all_of_them() {
    let line = |out: &str, key: &str| -> String {
        out.lines()
            .find(|l| l.trim_start().starts_with(key))
            .unwrap_or_else(|| panic!("no {key} in {out}"))
            .trim()
            .to_string()
    };
    let alone: Vec<String> = ["vessels:16", "nbody:16"]
        .iter()
        .map(|v| common::lacuna(&["info", v], &[]).stdout)
        .collect();
    let run = common::lacuna(&["info", "vessels:16+nbody:16", "--tf", "ramp:0.3:1"], &[]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let blocks: Vec<&str> = run.stdout.split("channel ").skip(1).collect();
    assert_eq!(blocks.len(), 2, "{}", run.stdout);
    let names = ["vessels:16x16x16", "nbody:16x16x16"];
    for (c, (block, alone)) in blocks.iter().zip(&alone).enumerate() {
        // Each channel by its own name, not channel 1 by the joined one.
        let head = format!("{} of 2: {}\n", c + 1, names[c]);
        assert!(block.starts_with(&head), "{block}");
        for key in ["type", "values", "[0.0,0.1)"] {
            assert_eq!(line(block, key), line(alone, key), "channel {}: {key}", c + 1);
        }
    }
    // Visible where either channel is: at least as many as each alone.
    let share = |out: &str| -> f64 { line(out, "visible").split_whitespace().nth(1).unwrap().parse().unwrap() };
    let each: Vec<f64> = ["vessels:16", "nbody:16"]
        .iter()
        .map(|v| share(&common::lacuna(&["info", v, "--tf", "ramp:0.3:1"], &[]).stdout))
        .collect();
    let both = share(&run.stdout);
    assert!(
        both >= each[0].max(each[1]) && both <= each[0] + each[1],
        "{both} against {each:?}"
    );
    assert!(
        both > each[0].max(each[1]),
        "nbody and vessels overlap entirely? {both} {each:?}"
    );
}
