//! `--value-range LO:HI` (`LoadOptions::value_range`, `StepNorm::over`):
//! the source values a transfer function's 0 and 1 stand for, in every
//! step and channel, whatever each step's own range; every structure
//! equals naive under it; bad ranges are one-line errors.

use crate::common::{fails, lacuna, nifti_bytes};
use lacuna::volume::{LoadOptions, Series};
use std::path::Path;

fn series(spec: &Path, range: [f64; 2]) -> Series {
    let options = LoadOptions {
        value_range: Some(range),
        ..LoadOptions::default()
    };
    Series::open(spec.to_str().unwrap(), &options).unwrap()
}

/// Step `k` of a float series: voxel i holds (i x k) x 10.
fn float_step(k: u32) -> Vec<u8> {
    (0..64u32).flat_map(|i| ((i * k) as f32 * 10.0).to_le_bytes()).collect()
}

#[test]
fn every_step_maps_its_values_over_the_range_given() {
    let dir = tempfile::tempdir().unwrap();
    // A float series whose step 0 is empty, as a simulation's t = 0 is.
    for k in 0..3 {
        std::fs::write(dir.path().join(format!("sim_{k}_4x4x4_float32.raw")), float_step(k)).unwrap();
    }
    let floats = series(&dir.path().join("sim_%d_4x4x4_float32.raw"), [-100.0, 5000.0]);
    for k in 0..3u32 {
        let v = floats.load(k, None).unwrap();
        for i in [0usize, 1, 37, 63] {
            let want = ((i as u32 * k) as f64 * 10.0 + 100.0) / 5100.0;
            let got = v.normalize(v.data.texel(i)) as f64;
            assert!(
                (got - want.min(1.0)).abs() < 1e-6,
                "step {k} voxel {i}: {got} against {want}"
            );
        }
    }
    assert_eq!(floats.norm_note(), None, "a range given is no constant step 0's");

    // Integers, scaled by a NIfTI's slope: the range is in scaled units.
    let data: Vec<u8> = (0..64u8).collect();
    let mut bytes = nifti_bytes(&[4, 4, 4], 2, 8, [1.0; 3], &data);
    bytes[112..116].copy_from_slice(&2.0f32.to_le_bytes());
    bytes[116..120].copy_from_slice(&(-10.0f32).to_le_bytes());
    let nii = dir.path().join("scaled.nii");
    std::fs::write(&nii, bytes).unwrap();
    let v = series(&nii, [-50.0, 250.0]).load(0, None).unwrap();
    for i in [0usize, 5, 63] {
        let want = ((2.0 * i as f64 - 10.0) + 50.0) / 300.0;
        let got = v.normalize(v.data.texel(i)) as f64;
        assert!((got - want).abs() < 1e-6, "scaled voxel {i}: {got} against {want}");
    }
    // A scaled series whose step 0 is one value has no slope to tell:
    // each later step maps by its own.
    for (k, raw) in [vec![0u8; 64], data.clone()].into_iter().enumerate() {
        let mut bytes = nifti_bytes(&[4, 4, 4], 2, 8, [1.0; 3], &raw);
        bytes[112..116].copy_from_slice(&2.0f32.to_le_bytes());
        std::fs::write(dir.path().join(format!("t{k}.nii")), bytes).unwrap();
    }
    let steps = series(&dir.path().join("t%d.nii"), [0.0, 126.0]);
    assert_eq!(steps.load(0, None).unwrap().normalize(0.0), 0.0);
    let v = steps.load(1, None).unwrap();
    for i in [0usize, 20, 63] {
        let want = 2.0 * i as f64 / 126.0;
        let got = v.normalize(v.data.texel(i)) as f64;
        assert!((got - want).abs() < 1e-6, "step 1 voxel {i}: {got} against {want}");
    }
}

#[test]
fn every_structure_equals_naive_under_a_range_and_bad_ranges_are_one_line() {
    let dir = tempfile::tempdir().unwrap();
    for k in 0..3 {
        std::fs::write(dir.path().join(format!("sim_{k}_16x16x16_float32.raw")), {
            let v: Vec<u8> = (0..4096u32)
                .flat_map(|i| ((i % 97) as f32 * (i / 256) as f32 * k as f32).to_le_bytes())
                .collect();
            v
        })
        .unwrap();
    }
    let spec = dir.path().join("sim_%d_16x16x16_float32.raw");
    let spec = spec.to_str().unwrap();
    let frame = |accel: &str| {
        let out = dir.path().join(format!("{accel}.exr"));
        let args = [
            "render",
            spec,
            "--time",
            "2",
            "--value-range",
            "0:3000",
            "--tf",
            "ramp:0.4:1",
            "--size",
            "40x40",
            "--accel",
            accel,
            "--validate",
            "--out",
        ];
        let r = lacuna(&[&args[..], &[out.to_str().unwrap()]].concat(), &[]);
        assert_eq!(r.code, 0, "{accel}: {}", r.stderr);
        out
    };
    let naive = frame("naive");
    let seen = lacuna::frame::Frame::read_exr(&naive).unwrap();
    assert!(seen.pixels.iter().any(|p| p[3] > 0.05), "an empty frame proves nothing");
    for accel in ["auto", "grid", "distance-octant", "lbvh"] {
        let other = frame(accel);
        let d = lacuna(
            &[
                "diff",
                naive.to_str().unwrap(),
                other.to_str().unwrap(),
                "--max-abs",
                "0",
            ],
            &[],
        );
        assert_eq!(d.code, 0, "{accel} against naive: {}{}", d.stdout, d.stderr);
    }
    for range in ["5:1", "1:1", "nan:1", "0:inf", "3", "a:b", "0:1e-37"] {
        fails(
            &["info", "menger:9", "--value-range", range],
            &[],
            "invalid value range",
        );
    }
    // One range for a file of several channels would be channel 1's only.
    let nii = dir.path().join("two.nii");
    std::fs::write(&nii, nifti_bytes(&[2, 2, 2, 1, 2], 2, 8, [1.0; 3], &[7u8; 16])).unwrap();
    fails(
        &["info", nii.to_str().unwrap(), "--value-range", "0:10"],
        &[],
        "applies to one channel: join one-channel volumes with +",
    );
}
