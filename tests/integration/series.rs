//! Time series: generator animations, file patterns and NIfTI time axes
//! load step by step, normalised as step 0; every structure equals naive
//! on every step; and every bad series is a one-line error.

use crate::common;
use crate::common::identity::{cam, Fixture, DEFAULTS};
use crate::common::{fails, gzip, lacuna, nifti_bytes};
use lacuna::accel::auto::{self, Choice, KEEP_SHARE};
use lacuna::accel::{Accel, BuildInput, Params, Structure};
use lacuna::frame::{diff, Frame};
use lacuna::render::Octants;
use lacuna::render::{Filter, FrameDesc, Mode, Projection};
use lacuna::volume::{procedural, LoadOptions, Series, VoxelData, VoxelType};
use lacuna::{Error, TransferFunction, Volume};
use std::path::Path;

fn open(spec: &str) -> Series {
    Series::open(spec, &LoadOptions::default()).unwrap()
}

fn u8s(v: &Volume) -> &[u8] {
    match &v.data {
        VoxelData::U8(d) => d,
        other => panic!("{}: not u8: {other:?}", v.name),
    }
}

#[test]
fn generators_animate_from_their_still_volume() {
    for spec in ["menger:27", "nbody:32", "vessels:32", "turbulence:24", "shells:24"] {
        let series = open(spec);
        assert_eq!(series.steps(), procedural::STEPS, "{spec}");
        let still = Volume::load(spec, &LoadOptions::default()).unwrap();
        let step0 = series.load(0, None).unwrap();
        assert!(u8s(&step0) == u8s(&still), "{spec}: step 0 is the still volume");
        let later = series.load(9, None).unwrap();
        assert!(u8s(&later) != u8s(&step0), "{spec}: step 9 moved");
        // Every step is normalised as step 0.
        assert_eq!(later.norm, step0.norm, "{spec}");
        let err = series.load(procedural::STEPS, None).unwrap_err().to_string();
        assert!(err.contains("has 64 steps, 0 to 63"), "{err}");
    }
}

/// Writes `values` as raw u8 files numbered `numbers` in `dir`.
fn write_u8_steps(dir: &Path, numbers: &[u32], dims: [u32; 3], values: impl Fn(u32, usize) -> u8) {
    let n = dims.iter().product::<u32>() as usize;
    for &k in numbers {
        let name = format!("run_{k:03}_{}x{}x{}_uint8.raw", dims[0], dims[1], dims[2]);
        let bytes: Vec<u8> = (0..n).map(|i| values(k, i)).collect();
        std::fs::write(dir.join(name), bytes).unwrap();
    }
}

#[test]
fn a_pattern_of_files_is_a_series_in_number_order() {
    let dir = tempfile::tempdir().unwrap();
    // Steps 7, 8, 9 (and 10 and 100, which a %03d pattern does not print
    // as "10"/"0100"): each a ramp scaled by its number.
    write_u8_steps(dir.path(), &[9, 7, 8], [4, 3, 2], |k, i| (i as u32 * (k - 6)) as u8);
    std::fs::write(dir.path().join("run_0100_4x3x2_uint8.raw"), [0u8; 24]).unwrap();
    std::fs::write(dir.path().join("run_10_4x3x2_uint8.raw"), [0u8; 24]).unwrap();
    let spec = dir.path().join("run_%03d_4x3x2_uint8.raw");
    let series = open(spec.to_str().unwrap());
    assert_eq!(series.steps(), 3);
    assert!(
        series.step_name(1).ends_with("run_008_4x3x2_uint8.raw"),
        "{}",
        series.step_name(1)
    );
    let step0 = series.load(0, None).unwrap();
    let step2 = series.load(2, None).unwrap();
    assert_eq!(u8s(&step0)[5], 5);
    assert_eq!(u8s(&step2)[5], 15);
    // Step 0 spans 0..23; step 2's 69 maps past 1 and clamps, as the
    // sampler clamps.
    assert_eq!(step2.norm, step0.norm);
    assert_eq!(step2.normalize(step2.data.texel(23)), 1.0);
    assert!((step2.normalize(step2.data.texel(5)) - 15.0 / 23.0).abs() < 1e-6);
    let err = series.load(3, None).unwrap_err().to_string();
    assert!(err.contains("has 3 steps, 0 to 2"), "{err}");
}

#[test]
fn float_steps_are_mapped_onto_the_first_steps_range() {
    let dir = tempfile::tempdir().unwrap();
    // Step 0 spans -2..2, step 1 spans 0..4 (stored normalised to its own
    // range): its value 2 is step 0's maximum.
    for (k, offset) in [(0, -2.0f32), (1, 0.0)] {
        let values: Vec<u8> = (0..8)
            .flat_map(|i| (offset + i as f32 * 4.0 / 7.0).to_le_bytes())
            .collect();
        std::fs::write(dir.path().join(format!("f{k}_2x2x2_float32.raw")), values).unwrap();
    }
    let series = open(dir.path().join("f%d_2x2x2_float32.raw").to_str().unwrap());
    let [s0, s1] = [0, 1].map(|k| series.load(k, None).unwrap());
    let value = |v: &Volume, i: usize| v.normalize(v.data.texel(i));
    assert!((value(&s0, 7) - 1.0).abs() < 1e-6);
    assert!((value(&s1, 0) - 0.5).abs() < 1e-6, "{}", value(&s1, 0));
    assert!((value(&s1, 3) - (12.0 / 7.0 + 2.0) / 4.0).abs() < 1e-5);
    assert_eq!(value(&s1, 7), 1.0);
}

/// float64 steps whose range overflows f64's differences (-1e308 to
/// 1e308) or is subnormal map onto finite texels and norms, not NaN.
#[test]
fn float64_steps_at_the_ends_of_f64_normalise_to_finite_values() {
    let dir = tempfile::tempdir().unwrap();
    let wide: Vec<f64> = (0..8).map(|i| if i < 4 { 1e308 } else { -1e308 }).collect();
    let tiny: Vec<f64> = (0..8).map(|i| i as f64 * 1e-320).collect();
    for (k, values) in [(0, &wide), (1, &wide), (2, &tiny)] {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(dir.path().join(format!("e{k}_2x2x2_float64.raw")), bytes).unwrap();
    }
    let series = open(dir.path().join("e%d_2x2x2_float64.raw").to_str().unwrap());
    let value = |v: &Volume, i: usize| v.normalize(v.data.texel(i));
    for k in [0, 1] {
        let step = series.load(k, None).unwrap();
        assert!(step.norm.iter().all(|n| n.is_finite()), "step {k}: {:?}", step.norm);
        assert_eq!((step.no_data_total(), step.value_range), (0, [-1e308, 1e308]));
        assert_eq!([value(&step, 0), value(&step, 7)], [1.0, 0.0], "step {k}");
    }
    // A step spanning half of step 0's range maps onto its upper half.
    let half: Vec<u8> = (0..8)
        .flat_map(|i| (if i < 4 { 1e308f64 } else { 0.0 }).to_le_bytes())
        .collect();
    std::fs::write(dir.path().join("e1_2x2x2_float64.raw"), half).unwrap();
    let step = series.load(1, None).unwrap();
    assert_eq!([value(&step, 0), value(&step, 7)], [1.0, 0.5], "{:?}", step.norm);
    // A subnormal step in it would need an offset past f32: an error.
    let err = series.load(2, None).unwrap_err().to_string();
    assert!(
        err.contains("cannot be mapped onto step 0's range (-1e308 .. 1e308) in f32"),
        "{err}"
    );
    // A subnormal range alone normalises.
    let alone = Volume::load(
        dir.path().join("e2_2x2x2_float64.raw").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(
        (alone.no_data_total(), value(&alone, 0), value(&alone, 7)),
        (0, 0.0, 1.0)
    );
}

#[test]
fn bad_patterns_and_steps_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let none = dir.path().join("none_%04d_4x4x4_uint8.raw");
    let err = Series::open(none.to_str().unwrap(), &LoadOptions::default())
        .err()
        .unwrap();
    assert!(err.to_string().contains("the pattern matches no file"), "{err}");

    write_u8_steps(dir.path(), &[1, 2, 4], [4, 4, 4], |_, i| i as u8);
    let gap = dir.path().join("run_%03d_4x4x4_uint8.raw");
    let err = Series::open(gap.to_str().unwrap(), &LoadOptions::default())
        .err()
        .unwrap();
    assert!(
        err.to_string()
            .contains("run_003_4x4x4_uint8.raw is missing between 1 and 4"),
        "{err}"
    );

    // A step shorter than the layout given for every step.
    let other = dir.path().join("grid_%d.raw");
    std::fs::write(dir.path().join("grid_0.raw"), [0u8; 64]).unwrap();
    std::fs::write(dir.path().join("grid_1.raw"), [0u8; 8]).unwrap();
    let layout = LoadOptions {
        raw: Some(lacuna::volume::RawLayout {
            dims: [4, 4, 4],
            ty: lacuna::volume::VoxelType::U8,
        }),
        ..LoadOptions::default()
    };
    let series = Series::open(other.to_str().unwrap(), &layout).unwrap();
    assert_eq!(series.steps(), 2);
    let err = series.load(1, None).unwrap_err();
    assert!(matches!(err, Error::Format { .. }), "{err}");

    // A still volume has step 0 only.
    let err = open("nbody:16").load(64, None).unwrap_err().to_string();
    assert!(err.contains("has 64 steps"), "{err}");
    let still = dir.path().join("grid_0.raw");
    let err = Series::open(still.to_str().unwrap(), &layout)
        .unwrap()
        .load(1, None)
        .unwrap_err()
        .to_string();
    assert!(err.contains("is one volume, not a time series"), "{err}");
}

#[test]
fn steps_on_different_grids_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    // A NIfTI pattern carries its grid in each header.
    let a = nifti_bytes(&[4, 4, 4], 2, 8, [1.0; 3], &[1u8; 64]);
    let b = nifti_bytes(&[4, 4, 2], 2, 8, [1.0; 3], &[1u8; 32]);
    std::fs::write(dir.path().join("n0.nii"), a).unwrap();
    std::fs::write(dir.path().join("n1.nii"), b).unwrap();
    let series = open(dir.path().join("n%d.nii").to_str().unwrap());
    let err = series.load(1, None).unwrap_err().to_string();
    assert!(
        err.contains("n1.nii': is 4x4x2 uint8 in 1 channel(s), where step 0 is 4x4x4 uint8 in 1 channel(s)"),
        "{err}"
    );
    // A step with two channels (NIfTI's fifth axis) after one with one.
    let c = nifti_bytes(&[4, 4, 4, 1, 2], 2, 8, [1.0; 3], &[1u8; 128]);
    std::fs::write(
        dir.path().join("c0.nii"),
        nifti_bytes(&[4, 4, 4], 2, 8, [1.0; 3], &[1u8; 64]),
    )
    .unwrap();
    std::fs::write(dir.path().join("c1.nii"), c).unwrap();
    let err = open(dir.path().join("c%d.nii").to_str().unwrap())
        .load(1, None)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("c1.nii': is 4x4x4 uint8 in 2 channel(s), where step 0 is 4x4x4 uint8 in 1 channel(s): every step must share one grid, type and channel count"),
        "{err}"
    );
}

#[test]
fn integer_steps_share_step_0s_scaling_or_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<u8> = (0..64u8).map(|i| i * 3).collect();
    let scaled = |slope: f32, inter: f32| {
        let mut b = nifti_bytes(&[4, 4, 4], 2, 8, [1.0; 3], &data);
        b[112..116].copy_from_slice(&slope.to_le_bytes());
        b[116..120].copy_from_slice(&inter.to_le_bytes());
        b
    };
    let off = "a raw voxel's value is -1 off step 0's (a NIfTI's scl_inter";
    for (name, slope, inter, why) in [
        ("same", 2.0, 1.0, ""),
        (
            "half",
            0.5,
            0.0,
            "scale by 0.5 per raw unit (in magnitude) where step 0's scale by 2 ",
        ),
        (
            "negative",
            -1.0,
            0.0,
            "scale by 1 per raw unit (in magnitude) where step 0's scale by 2 ",
        ),
        ("intercept", 2.0, 0.0, off),
    ] {
        std::fs::write(dir.path().join(format!("{name}0.nii")), scaled(2.0, 1.0)).unwrap();
        std::fs::write(dir.path().join(format!("{name}1.nii")), scaled(slope, inter)).unwrap();
        let series = open(dir.path().join(format!("{name}%d.nii")).to_str().unwrap());
        let (step0, step1) = (series.load(0, None).unwrap(), series.load(1, None));
        match name {
            // The same values, the same normalised texels.
            "same" => {
                let step1 = step1.unwrap();
                let norm = |v: &Volume, i: usize| v.normalize(v.data.texel(i));
                assert!((0..64).all(|i| norm(&step1, i) == norm(&step0, i)), "{name}");
            }
            _ => {
                let err = step1.unwrap_err().to_string();
                assert!(err.contains(why) && err.contains("share one scaling"), "{name}: {err}");
            }
        }
    }
}

/// A step on another spacing is another grid, refused as channels on
/// different spacings are.
#[test]
fn steps_share_step_0s_spacing_or_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<u8> = (0..64u8).collect();
    for (k, spacing) in [[1.0, 1.0, 1.0], [1.0, 1.0, 2.0]].into_iter().enumerate() {
        let bytes = nifti_bytes(&[4, 4, 4], 2, 8, spacing, &data);
        std::fs::write(dir.path().join(format!("s{k}.nii")), bytes).unwrap();
    }
    // A pixdim rounded another way is the same grid.
    let bytes = nifti_bytes(&[4, 4, 4], 2, 8, [1.0, 1.0, 1.000_001], &data);
    std::fs::write(dir.path().join("r1.nii"), bytes).unwrap();
    std::fs::copy(dir.path().join("s0.nii"), dir.path().join("r0.nii")).unwrap();
    open(dir.path().join("r%d.nii").to_str().unwrap())
        .load(1, None)
        .unwrap();
    let series = open(dir.path().join("s%d.nii").to_str().unwrap());
    series.load(0, None).unwrap();
    let err = series.load(1, None).unwrap_err().to_string();
    assert!(
        err.contains("has spacing 1 x 1 x 2 where step 0 has 1 x 1 x 1: every step must share one grid"),
        "{err}"
    );
}

/// A step 0 of one value gives no range to normalise the series by: the
/// range chosen is named in a note, where before later steps saturated
/// without a word.
#[test]
fn a_constant_step_0_is_named_in_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let step = |k: u32| -> Vec<u8> { (0..64u32).flat_map(|i| ((i * k) as f32 * 10.0).to_le_bytes()).collect() };
    for k in 0..2 {
        std::fs::write(dir.path().join(format!("sim_{k}_4x4x4_float32.raw")), step(k)).unwrap();
    }
    let spec = dir.path().join("sim_%d_4x4x4_float32.raw");
    let run = lacuna(&["info", spec.to_str().unwrap(), "--time", "1"], &[]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    assert!(
        run.stderr
            .contains("step 0 holds one value (0) throughout, so every step is normalised over 0 .. 1"),
        "{}",
        run.stderr
    );
    // A step 0 with a range says nothing.
    std::fs::write(dir.path().join("sim_0_4x4x4_float32.raw"), step(2)).unwrap();
    let run = lacuna(&["info", spec.to_str().unwrap(), "--time", "1"], &[]);
    assert!(run.code == 0 && run.stderr.is_empty(), "{}", run.stderr);
}

/// A pattern's file with a time axis of its own would show its step 0
/// alone: refused, at open and where a later file has one.
#[test]
fn a_patterns_files_hold_one_step_each() {
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<u8> = (0..24u8).collect();
    let one = nifti_bytes(&[3, 2, 2], 2, 8, [1.0; 3], &data[..12]);
    let two = nifti_bytes(&[3, 2, 2, 2], 2, 8, [1.0; 3], &data);
    let why = "holds 2 time steps: the files of a printf pattern hold one step each";
    std::fs::write(dir.path().join("a0.nii"), &two).unwrap();
    std::fs::write(dir.path().join("a1.nii"), &two).unwrap();
    let spec = dir.path().join("a%d.nii");
    match Series::open(spec.to_str().unwrap(), &LoadOptions::default()) {
        Err(e) => assert!(e.to_string().contains(why), "{e}"),
        Ok(_) => panic!("a pattern of two-step files opened"),
    }
    std::fs::write(dir.path().join("b0.nii"), &one).unwrap();
    std::fs::write(dir.path().join("b1.nii"), &two).unwrap();
    let series = open(dir.path().join("b%d.nii").to_str().unwrap());
    series.load(0, None).unwrap();
    let err = series.load(1, None).unwrap_err().to_string();
    assert!(err.contains("b1.nii") && err.contains(why), "{err}");
}

#[test]
fn a_nifti_time_axis_loads_one_step_at_a_time() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [3u32, 2, 2];
    let data: Vec<u8> = (0..36).map(|i| (i * 7) as u8).collect();
    let bytes = nifti_bytes(&[3, 2, 2, 3], 2, 8, [1.0; 3], &data);
    for name in ["t.nii", "t.nii.gz"] {
        let p = dir.path().join(name);
        let written = if name.ends_with(".gz") {
            gzip(&bytes)
        } else {
            bytes.clone()
        };
        std::fs::write(&p, written).unwrap();
        let series = open(p.to_str().unwrap());
        assert_eq!(series.steps(), 3, "{name}");
        for k in 0..3u32 {
            let step = series.load(k, None).unwrap();
            assert_eq!(step.dims, dims);
            assert_eq!(
                u8s(&step),
                &data[12 * k as usize..12 * (k as usize + 1)],
                "{name} step {k}"
            );
        }
        let err = series.load(3, None).unwrap_err().to_string();
        assert!(err.contains("has 3 steps, 0 to 2"), "{err}");
        // Loading the file as one volume gives step 0.
        let still = Volume::load(p.to_str().unwrap(), &LoadOptions::default()).unwrap();
        assert_eq!(u8s(&still), &data[..12]);
    }
    // Beyond time and components (a 6th dimension) is refused, as is a
    // truncated step, when the file is opened (dim[5], components, are
    // channels: tests/integration/channels.rs).
    let p = dir.path().join("six.nii");
    std::fs::write(&p, nifti_bytes(&[3, 2, 2, 1, 1, 2], 2, 8, [1.0; 3], &[0u8; 24])).unwrap();
    let err = Series::open(p.to_str().unwrap(), &LoadOptions::default())
        .err()
        .unwrap();
    assert!(err.to_string().contains("beyond x, y, z, time and components"), "{err}");
    let p = dir.path().join("short.nii");
    std::fs::write(&p, nifti_bytes(&[3, 2, 2, 3], 2, 8, [1.0; 3], &data[..30])).unwrap();
    let err = Series::open(p.to_str().unwrap(), &LoadOptions::default())
        .err()
        .unwrap();
    assert!(matches!(err, Error::Format { .. }), "{err}");
    assert!(
        err.to_string().contains("holds 382 bytes, but the 3 time steps"),
        "{err}"
    );
    // A .nii.gz is checked when the step is read: the missing step is named.
    let p = dir.path().join("short.nii.gz");
    std::fs::write(&p, gzip(&nifti_bytes(&[3, 2, 2, 3], 2, 8, [1.0; 3], &data[..30]))).unwrap();
    let series = open(p.to_str().unwrap());
    assert_eq!(u8s(&series.load(1, None).unwrap()), &data[12..24]);
    let err = series.load(2, None).unwrap_err().to_string();
    assert!(
        err.ends_with(
            "ends before time step 2 (0 to 2) of channel 1 of 1: it holds 6 of that block's 12 bytes (3x2x2 uint8)"
        ),
        "{err}"
    );
}

/// Every structure equals naive on steps where the visible set moved.
#[test]
fn every_structure_equals_naive_on_every_step() {
    let fx = Fixture::new();
    let views = [
        cam(40, 30.0, 20.0, Projection::Orthographic, 0.5),
        cam(40, 200.0, -15.0, Projection::Orthographic, 0.37),
    ];
    // The sponge is dense: a tree may be one leaf (marched naively, saying so).
    for (spec, steps, dense) in [("nbody:40", [0u32, 31, 63], false), ("menger:27", [0, 4, 13], true)] {
        let series = open(spec);
        let mut previous: Option<Frame> = None;
        for k in steps {
            let v = series.load(k, None).unwrap();
            let tf = TransferFunction::parse(v.default_tf.as_deref().unwrap()).unwrap();
            let what = format!("{spec} step {k}");
            let frames = match dense {
                true => fx.check_dense(&what, &v, &tf, &views),
                false => fx.check(&what, &v, &tf, &views),
            };
            if let Some(p) = &previous {
                assert!(common::max_abs(p, &frames[0]) > 0.01, "{spec} step {k} looks as before");
            }
            previous = Some(frames[0].clone());
        }
    }
}

/// A new step with auto keeps the structure auto chose on an earlier step
/// (built alone from the new step's data) while its share of active
/// regions stays within `KEEP_SHARE` of the share at the choice, and its
/// frames equal naive's; a share moved further, or a step with nothing
/// visible, is priced anew. Other structures build as on a first step.
#[test]
fn auto_keeps_its_choice_across_steps_while_the_active_share_holds() {
    let fx = Fixture::new();
    let series = open("nbody:40");
    let view = cam(40, 30.0, 20.0, Projection::Orthographic, 0.5);
    let auto = common::accel("auto");
    // Priced by the test's given constants alone: no timing moves the choice.
    let params = auto.params(&[("trial", "off")]).unwrap();
    // Step `v` built by `accel` with `last`, for frames like `view`: the
    // build and naive's frame, which its frame equals.
    let build = |v: &Volume, accel: Accel, params: &Params, last: Option<&Choice>, view: &FrameDesc| {
        let tf = TransferFunction::parse(v.default_tf.as_deref().unwrap()).unwrap();
        let p = fx.prepare(v, &tf, DEFAULTS);
        let input = BuildInput {
            volume: v,
            gpu_volume: &p.gv,
            tf: &tf,
            gpu_tf: &p.lut,
            mode: *view.mode(),
            frames: std::slice::from_ref(view),
            octants: Octants::ALL,
        };
        let step = fx.builder.build_step(accel, params, last, &input).unwrap();
        let naive = fx.frame(&Structure::naive(), &p, view, Filter::Manual);
        let frame = fx.frame(&step.structure, &p, view, Filter::Manual);
        let d = diff(&naive, &frame).unwrap();
        assert_eq!(d.differing, 0, "{}: {d}", step.structure.marched_as());
        (step, naive)
    };
    // As `build`, with auto, and its choice.
    let step_of = |v: &Volume, last: Option<&Choice>, view: &FrameDesc| {
        let (step, naive) = build(v, auto, &params, last, view);
        let choice = auto::choice_of(&step.structure).expect("auto's build").clone();
        (step, choice, naive)
    };
    let mut last: Option<Choice> = None;
    for k in 0..3 {
        let v = series.load(k, None).unwrap();
        let (step, choice, _) = step_of(&v, last.as_ref(), &view);
        assert_eq!(choice.kept, k, "step {k}: {}", choice.reason());
        assert_eq!(
            step.ranges.is_none(),
            k > 0,
            "a kept step computes only its structure's ranges"
        );
        assert!(
            !step.structure.marched_as().is_naive(),
            "nbody skips: {}",
            choice.reason()
        );
        if let Some(first) = &last {
            assert_eq!(choice.candidate.label, first.candidate.label);
            assert!(choice.reason().contains("kept for"), "{}", choice.reason());
            let (now, then) = (choice.share_now.unwrap(), choice.share.unwrap());
            assert!((now / then).max(then / now) <= KEEP_SHARE);
        }
        last = Some(choice);
    }
    let v = series.load(3, None).unwrap();
    // A share moved further than KEEP_SHARE: priced anew, the kept try's
    // build timed too.
    let mut moved = last.clone().unwrap();
    moved.share = moved.share.map(|s| s * KEEP_SHARE * 1.05);
    let (step, choice, _) = step_of(&v, Some(&moved), &view);
    assert_eq!(choice.kept, 0, "{}", choice.reason());
    assert!(step.ranges.is_some());
    assert!(step
        .build_timings
        .phases
        .iter()
        .any(|(name, _)| name.starts_with("kept ")));
    // Nothing visible on the new step: priced anew, transparent.
    let n = v.voxel_count() as usize;
    let mut empty = Volume::new("empty", v.dims, v.spacing, VoxelType::U8, VoxelData::U8(vec![0; n])).unwrap();
    empty.default_tf = v.default_tf.clone();
    empty.norm = v.norm;
    let (_, choice, naive) = step_of(&empty, last.as_ref(), &view);
    assert_eq!(choice.kept, 0, "{}", choice.reason());
    assert!(naive.pixels.iter().all(|p| *p == [0.0; 4]));
    // A MIP series keeps the choice of MIP frames (and a composite choice
    // does not carry over to them).
    let mip = cam(40, 30.0, 20.0, Projection::Orthographic, 0.5)
        .to_builder()
        .mode(Mode::Mip)
        .build()
        .unwrap();
    let mut mip_last: Option<Choice> = None;
    for k in 0..2 {
        let v = series.load(k, None).unwrap();
        let carried = if k == 0 { last.as_ref() } else { mip_last.as_ref() };
        let (step, choice, _) = step_of(&v, carried, &mip);
        assert_eq!(choice.kept, k, "MIP step {k}: {}", choice.reason());
        assert!(!step.structure.marched_as().is_naive(), "{}", choice.reason());
        mip_last = Some(choice);
    }
    // Another structure builds as on a first step, whatever auto chose.
    let grid = common::accel("grid");
    let (step, _) = build(&v, grid, &grid.defaults(), last.as_ref(), &view);
    assert!(step.ranges.is_some() && auto::choice_of(&step.structure).is_none());
    common::assert_clean(&fx.ctx);
}

#[test]
fn render_takes_a_time_step() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.exr");
    let o = out.to_str().unwrap();
    let r = lacuna(
        &[
            "render",
            "vessels:24",
            "--time",
            "12",
            "--size",
            "32x24",
            "--out",
            o,
            "--validate",
        ],
        &[],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(
        r.stdout.contains("time    step 12 of 64 (vessels:24 step 12)"),
        "{}",
        r.stdout
    );
    let frame = Frame::read_exr(&out).unwrap();
    assert_eq!(frame.metadata["time"], "12");
    fails(
        &["render", "vessels:24", "--time", "64"],
        &[],
        "error: invalid time '64': vessels:24 has 64 steps, 0 to 63",
    );
}
