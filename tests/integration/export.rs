//! `lacuna export` and `volume::write_raw`: volumes written as Open SciVis
//! raw files and read back with lacuna's raw loader (same dims, same voxels,
//! the same image), the default type per source type, and every bad input as
//! one line, exit code 2 and nothing left on disk.

use crate::common::lacuna;
use lacuna::volume::{write_raw, LoadOptions, SourceValues, VoxelData, VoxelType};
use lacuna::Volume;
use std::path::{Path, PathBuf};

fn load(path: &Path) -> Volume {
    Volume::load(path.to_str().unwrap(), &LoadOptions::default()).unwrap()
}

/// The file names in `dir`, sorted (temporaries start with a dot and show).
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn u8s(v: &Volume) -> &[u8] {
    match &v.data {
        VoxelData::U8(d) => d,
        other => panic!("{}: expected uint8 data, got {other:?}", v.name),
    }
}

/// The file's values, little-endian, as f64.
fn file_values(path: &Path, ty: VoxelType) -> Vec<f64> {
    let bytes = std::fs::read(path).unwrap();
    match ty {
        VoxelType::U8 => bytes.iter().map(|&b| b as f64).collect(),
        VoxelType::U16 => bytes
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]) as f64)
            .collect(),
        VoxelType::F32 => bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
            .collect(),
        other => panic!("not an export type: {other}"),
    }
}

/// Every voxel's normalised value (what the GPU samples) of `a` and `b`
/// within `tol`.
fn assert_same_values(a: &Volume, b: &Volume, tol: f32) {
    assert_eq!(a.dims, b.dims);
    let [w, h, d] = a.dims;
    for z in 0..d {
        for y in 0..h {
            for x in 0..w {
                let (va, vb) = (a.value(x, y, z), b.value(x, y, z));
                assert!(
                    (va - vb).abs() <= tol,
                    "{} vs {}: voxel ({x},{y},{z}) {va} vs {vb}",
                    a.name,
                    b.name
                );
            }
        }
    }
}

#[test]
fn a_generated_volume_round_trips_through_the_library_in_every_type() {
    let dir = tempfile::tempdir().unwrap();
    let volume = Volume::load("nbody:24x20x16", &LoadOptions::default()).unwrap();
    let source = SourceValues::new(&volume);

    // Default: the source type, uint8; the texels come back bit for bit.
    let written = write_raw(&volume, &dir.path().join("nbody"), None).unwrap();
    assert_eq!(written.ty, VoxelType::U8);
    assert_eq!(written.path, dir.path().join("nbody_24x20x16_uint8.raw"));
    assert_eq!(written.bytes, 24 * 20 * 16);
    let back = load(&written.path);
    assert_eq!((back.dims, back.source_type), (volume.dims, VoxelType::U8));
    assert_eq!(u8s(&back), u8s(&volume));
    assert_eq!(back.value_range, volume.value_range);
    assert_eq!(back.norm, volume.norm);

    // uint16 and float32 hold the same source values (the uint8 integers,
    // exactly: both types hold every integer 0..=255). The normalised values
    // agree only to f32 rounding: the loader normalises uint16 texels by
    // 65535 and float32 values over their range in f64 then rounds to f32,
    // where uint8 texels are normalised by 255, so the same value can differ
    // in the last bits (~6e-8 relative), far below any TF's resolution.
    for (ty, name) in [(VoxelType::U16, "uint16"), (VoxelType::F32, "float32")] {
        let path = dir.path().join(format!("nbody_24x20x16_{name}.raw"));
        let written = write_raw(&volume, &path, Some(ty)).unwrap();
        assert_eq!((written.ty, &written.path), (ty, &path));
        let values = file_values(&path, ty);
        assert_eq!(values.len(), source.len());
        for (i, (&got, &want)) in values.iter().zip(u8s(&volume)).enumerate() {
            assert_eq!(got, want as f64, "{name}: voxel {i}");
        }
        let back = load(&path);
        assert_eq!((back.dims, back.source_type), (volume.dims, ty));
        assert_eq!(back.value_range, volume.value_range);
        // Read back, uint16 stays integer and exact; float32 is stored
        // normalised as f32, so its source values are exact to 2^-25 of
        // the range (the bound as in `the_default_type_is_the_smallest_that_holds_every_value`).
        let again = SourceValues::new(&back);
        let tol = match ty {
            VoxelType::U16 => 0.0,
            _ => (back.value_range[1] - back.value_range[0]) * 2f64.powi(-24),
        };
        assert!(
            (0..source.len()).all(|i| (again.get(i) - source.get(i)).abs() <= tol),
            "{name}"
        );
        assert_same_values(&volume, &back, 1e-6);
    }
    // Only the three files: no temporaries.
    assert_eq!(listing(dir.path()).len(), 3);
}

/// Writes `values` as an Open SciVis raw file of `ty` in `dir`.
fn write_source(dir: &Path, name: &str, dims: [u32; 3], ty: VoxelType, values: &[f64]) -> PathBuf {
    let path = dir.join(format!("{name}_{}x{}x{}_{}.raw", dims[0], dims[1], dims[2], ty.name()));
    let mut bytes = Vec::new();
    for &v in values {
        match ty {
            VoxelType::U8 => bytes.push(v as u8),
            VoxelType::I8 => bytes.push(v as i8 as u8),
            VoxelType::U16 => bytes.extend((v as u16).to_le_bytes()),
            VoxelType::I16 => bytes.extend((v as i16).to_le_bytes()),
            VoxelType::U32 => bytes.extend((v as u32).to_le_bytes()),
            VoxelType::I32 => bytes.extend((v as i32).to_le_bytes()),
            VoxelType::F32 => bytes.extend((v as f32).to_le_bytes()),
            VoxelType::F64 => bytes.extend(v.to_le_bytes()),
        }
    }
    std::fs::write(&path, bytes).unwrap();
    path
}

const DIMS: [u32; 3] = [7, 5, 3];

/// 105 values from `lo` in steps of `step`, shuffled.
fn values(lo: f64, step: f64) -> Vec<f64> {
    (0..105u32).map(|i| lo + ((i * 47) % 105) as f64 * step).collect()
}

#[test]
fn loaded_int16_and_float_files_round_trip_in_source_units() {
    let input = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();

    // int16 with negative values: float32 by default, the integers exactly
    // (int16 is stored offset into uint16, so nothing was lost).
    let signed = values(-1200.0, 31.0);
    let v = load(&write_source(input.path(), "signed", DIMS, VoxelType::I16, &signed));
    let w = write_raw(&v, &out.path().join("signed"), None).unwrap();
    assert_eq!(w.ty, VoxelType::F32);
    assert_eq!(file_values(&w.path, VoxelType::F32), signed);
    let back = load(&w.path);
    assert_eq!(back.value_range, [-1200.0, -1200.0 + 104.0 * 31.0]);
    // Normalised over the same range in f64, then rounded to f32 (the
    // int16 path divides in f32): equal to f32 rounding.
    assert_same_values(&v, &back, 1e-6);

    // int16 with non-negative values: uint16 by default, exactly.
    let unsigned = values(3.0, 300.0);
    let v = load(&write_source(input.path(), "unsigned", DIMS, VoxelType::I16, &unsigned));
    let w = write_raw(&v, &out.path().join("unsigned"), None).unwrap();
    assert_eq!(w.ty, VoxelType::U16);
    assert_eq!(file_values(&w.path, VoxelType::U16), unsigned);
    assert_same_values(&v, &load(&w.path), 1e-6);

    // float32: lacuna stores (v - lo) / (hi - lo) as f32, so a value comes
    // back within half an f32 ulp of [0, 1] times the range (2^-25 x 20):
    // min and max exactly, the rest to ~6e-7.
    let floats: Vec<f64> = values(-3.0, 0.19).into_iter().map(|v| (v as f32) as f64).collect();
    let v = load(&write_source(input.path(), "floats", DIMS, VoxelType::F32, &floats));
    let w = write_raw(&v, &out.path().join("floats"), None).unwrap();
    assert_eq!(w.ty, VoxelType::F32);
    let got = file_values(&w.path, VoxelType::F32);
    let range = v.value_range[1] - v.value_range[0];
    for (i, (g, f)) in got.iter().zip(&floats).enumerate() {
        assert!((g - f).abs() <= range * 2f64.powi(-24), "voxel {i}: {g} vs {f}");
    }
    let back = load(&w.path);
    assert_eq!(back.value_range, v.value_range);
    assert_same_values(&v, &back, 1e-6);
    assert_eq!(listing(out.path()).len(), 3);
}

#[test]
fn the_default_type_is_the_smallest_that_holds_every_value() {
    let input = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    for (ty, vals, want) in [
        (VoxelType::U8, values(0.0, 2.0), VoxelType::U8),
        (VoxelType::U16, values(0.0, 1.0), VoxelType::U16),
        (VoxelType::F32, values(0.0, 1.0), VoxelType::F32),
        (VoxelType::I8, values(0.0, 1.0), VoxelType::U8),
        (VoxelType::I8, values(-5.0, 1.0), VoxelType::F32),
        (VoxelType::I16, values(0.0, 2.0), VoxelType::U8),
        (VoxelType::U32, values(0.0, 600.0), VoxelType::U16),
        (VoxelType::U32, values(0.0, 700.0), VoxelType::F32),
        (VoxelType::I32, values(-70000.0, 1.0), VoxelType::F32),
        (VoxelType::F64, values(2.0, 2.0), VoxelType::U8),
        (VoxelType::F64, values(2.0, 0.5), VoxelType::F32),
    ] {
        let name = format!("{ty}-{}", vals[1]);
        let v = load(&write_source(input.path(), &name, DIMS, ty, &vals));
        let w = write_raw(&v, &out.path().join(&name), None).unwrap();
        assert_eq!(w.ty, want, "{name}");
        // Integer sources and integer exports come back exactly. A float
        // source is stored as (v - lo) / (hi - lo) in f32: its float32
        // export is within half an ulp of [0, 1] times the range, plus the
        // final rounding to f32 (one ulp of the value).
        let got = file_values(&w.path, want);
        let float = matches!(ty, VoxelType::F32 | VoxelType::F64) && want == VoxelType::F32;
        for (i, (g, v)) in got.iter().zip(&vals).enumerate() {
            let tol = if float {
                104.0 * 2f64.powi(-25) + v.abs() * 2f64.powi(-23)
            } else {
                0.0
            };
            assert!((g - v).abs() <= tol, "{name}: voxel {i} is {g}, want {v}");
        }
    }
}

#[test]
fn export_time_writes_that_step_of_a_series() {
    let dir = tempfile::tempdir().unwrap();
    let series = lacuna::volume::Series::open("nbody:20", &LoadOptions::default()).unwrap();
    let steps = [0u32, 3].map(|k| series.load(k, None).unwrap());
    assert_ne!(
        u8s(&steps[0]),
        u8s(&steps[1]),
        "steps 0 and 3 are alike: the test shows nothing"
    );
    for (k, step) in [0u32, 3].iter().zip(&steps) {
        let stem = dir.path().join(format!("step{k}"));
        let r = lacuna(
            &["export", "nbody:20", stem.to_str().unwrap(), "--time", &k.to_string()],
            &[],
        );
        assert_eq!(r.code, 0, "{}", r.stderr);
        let back = load(&dir.path().join(format!("step{k}_20x20x20_uint8.raw")));
        assert_eq!(u8s(&back), u8s(step), "step {k}");
    }
    // A file pattern's steps, step 0 by default as `--time 0`.
    let files = tempfile::tempdir().unwrap();
    for k in 0..2u8 {
        std::fs::write(
            files.path().join(format!("run_{k:04}_4x2x2_uint8.raw")),
            [k * 10 + 1; 16],
        )
        .unwrap();
    }
    let pattern = files.path().join("run_%04d_4x2x2_uint8.raw");
    for (k, time) in [(0u8, None), (0, Some("0")), (1, Some("1"))] {
        let stem = dir.path().join(format!("file{k}"));
        let mut args = vec!["export", pattern.to_str().unwrap(), stem.to_str().unwrap()];
        args.extend(time.map(|t| ["--time", t]).into_iter().flatten());
        let r = lacuna(&args, &[]);
        assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
        let back = load(&dir.path().join(format!("file{k}_4x2x2_uint8.raw")));
        assert_eq!(u8s(&back), [k * 10 + 1; 16], "{args:?}");
    }
}

#[test]
fn export_from_the_cli_reads_back_and_renders_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let stem = dir.path().join("menger");
    let r = lacuna(&["export", "menger:27", stem.to_str().unwrap()], &[]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let path = dir.path().join("menger_27x27x27_uint8.raw");
    assert_eq!(r.stdout, format!("{}\n", path.display()));
    assert!(r.stderr.is_empty(), "{}", r.stderr);
    let generated = Volume::load("menger:27", &LoadOptions::default()).unwrap();
    let back = load(&path);
    assert_eq!(back.dims, [27, 27, 27]);
    assert_eq!(u8s(&back), u8s(&generated));

    // The same image: the generator's TF given explicitly (a raw file has none).
    let (a, b) = (dir.path().join("gen.exr"), dir.path().join("raw.exr"));
    for (spec, out) in [("menger:27", &a), (path.to_str().unwrap(), &b)] {
        let args = [
            "render",
            spec,
            "--tf",
            "ramp:0.3:1:0.2",
            "--size",
            "32x32",
            "--validate",
        ];
        let r = lacuna(&[&args[..], &["--out", out.to_str().unwrap()]].concat(), &[]);
        assert_eq!(r.code, 0, "{spec}: {}", r.stderr);
    }
    let d = lacuna(
        &["diff", a.to_str().unwrap(), b.to_str().unwrap(), "--max-abs", "0"],
        &[],
    );
    assert_eq!(d.code, 0, "{}", d.stdout);

    // An Open SciVis name and a type; float32 holds the same source values.
    let named = dir.path().join("sponge_27x27x27_float32.raw");
    let r = lacuna(
        &["export", "menger:27", named.to_str().unwrap(), "--type", "float32"],
        &[],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(r.stdout.trim(), named.to_str().unwrap());
    let values = file_values(&named, VoxelType::F32);
    assert!(values.iter().zip(u8s(&generated)).all(|(&f, &u)| f == u as f64));
    assert_same_values(&generated, &load(&named), 1e-6);
}

#[test]
fn cli_loader_options_and_the_spacing_note() {
    let dir = tempfile::tempdir().unwrap();
    // A raw file without an Open SciVis name: --dims and --source-type.
    let vals = values(-40.0, 1.0);
    let src = write_source(dir.path(), "x", DIMS, VoxelType::I16, &vals);
    let bare = dir.path().join("input.bin");
    std::fs::rename(&src, &bare).unwrap();
    let stem = dir.path().join("out");
    let r = lacuna(
        &[
            "export",
            bare.to_str().unwrap(),
            stem.to_str().unwrap(),
            "--dims",
            "7x5x3",
            "--source-type",
            "int16",
        ],
        &[],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    let out = dir.path().join("out_7x5x3_float32.raw");
    assert_eq!(r.stdout.trim(), out.to_str().unwrap());
    assert_eq!(file_values(&out, VoxelType::F32), vals);

    // An NRRD with spacing: one note line says it is not kept.
    let nrrd = dir.path().join("spaced.nrrd");
    let mut bytes =
        b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\nspacings: 0.5 0.5 2\n\n"
            .to_vec();
    bytes.extend([0u8, 1, 2, 3, 4, 5, 6, 7]);
    std::fs::write(&nrrd, bytes).unwrap();
    let r = lacuna(
        &[
            "export",
            nrrd.to_str().unwrap(),
            dir.path().join("spaced").to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(r.stdout.lines().count(), 1, "{}", r.stdout);
    let notes: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(notes.len(), 1, "{}", r.stderr);
    assert!(
        notes[0].starts_with("note: the spacing 0.5 x 0.5 x 2 is not stored"),
        "{}",
        notes[0]
    );
    let back = load(&dir.path().join("spaced_2x2x2_uint8.raw"));
    assert_eq!(u8s(&back), &[0, 1, 2, 3, 4, 5, 6, 7]);

    // float32 kept normalised: a note gives the bound, and every value
    // keeps to it; small values in a wide range lose their digits.
    let floats: Vec<f64> = values(0.0, 1.0).iter().map(|v| v * 9523.8 - 1000.0).collect();
    let src = write_source(dir.path(), "wide", DIMS, VoxelType::F32, &floats);
    let r = lacuna(&["export", src.to_str().unwrap(), stem.to_str().unwrap()], &[]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let (lo, hi) = (-1000.0f64, 104.0 * 9523.8 - 1000.0);
    let within = (hi as f32 as f64 - lo) * (-24f64).exp2();
    let note = format!(
        "note: float32 voxels are kept normalised to 0 .. 1 in float32 over their range (-1000 .. {}), so each exported value is within {within:.3e} of the file's",
        hi as f32 as f64
    );
    assert!(r.stderr.starts_with(&note), "{}\nwanted {note}", r.stderr);
    let out = file_values(&dir.path().join("out_7x5x3_float32.raw"), VoxelType::F32);
    for (i, (got, want)) in out.iter().zip(&floats).enumerate() {
        let want = *want as f32 as f64;
        assert!((got - want).abs() <= within, "voxel {i}: {got} against {want}");
    }
    // Integers exported exactly say nothing.
    let r = lacuna(&["export", "menger:9", stem.to_str().unwrap()], &[]);
    assert!(r.code == 0 && r.stderr.is_empty(), "{}", r.stderr);
}

/// Runs `lacuna export ARGS` with `{in}` and `{out}` replaced by the input
/// and (empty) output folders; asserts exit code 2, one `error:` line
/// containing `needle`, and an output folder as it was (no file, no
/// temporary).
fn fails(input: &Path, args: &[&str], needle: &str) {
    let out = tempfile::tempdir().unwrap();
    std::fs::create_dir(out.path().join("existing")).unwrap();
    let before = listing(out.path());
    let fill = |a: &&str| {
        a.replace("{in}", input.to_str().unwrap())
            .replace("{out}", out.path().to_str().unwrap())
    };
    let args: Vec<String> = std::iter::once("export".to_string())
        .chain(args.iter().map(fill))
        .collect();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let r = lacuna(&args, &[]);
    assert_eq!(r.code, 2, "{args:?}: {}{}", r.stdout, r.stderr);
    assert!(r.stdout.is_empty(), "{args:?}: {}", r.stdout);
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(lines.len(), 1, "{args:?}: expected one line:\n{}", r.stderr);
    assert!(lines[0].starts_with("error: "), "{}", lines[0]);
    assert!(lines[0].contains(needle), "{args:?}: '{}' lacks '{needle}'", lines[0]);
    assert_eq!(listing(out.path()), before, "{args:?} left a file behind");
    assert!(listing(&out.path().join("existing")).is_empty(), "{args:?}");
}

#[test]
fn bad_export_input_is_one_line_exit_2_and_leaves_nothing() {
    let input = tempfile::tempdir().unwrap();
    write_source(input.path(), "big", DIMS, VoxelType::U16, &values(0.0, 3.0));
    write_source(input.path(), "neg", DIMS, VoxelType::I16, &values(-2.0, 1.0));
    write_source(input.path(), "frac", DIMS, VoxelType::F32, &values(0.0, 0.5));
    write_source(input.path(), "huge", DIMS, VoxelType::F64, &values(0.0, 1e300));
    // A range past f64's differences: the values are rebuilt finite.
    write_source(input.path(), "wide", DIMS, VoxelType::F64, &values(-1e308, 1.9e306));
    // 105 values 0, 3, .., 312, shuffled: the first above 255 in x-fastest
    // order is named.
    let first = (0..105u32).find(|i| (i * 47 % 105) * 3 > 255).unwrap();
    let (x, y, z) = (first % 7, first / 7 % 5, first / 35);
    let too_big = format!(
        "invalid export type 'uint8': voxel ({x}, {y}, {z}) is {}, outside uint8's range 0 to 255; \
         uint16 holds every value",
        (first * 47 % 105) * 3
    );
    let cases: [(&[&str], &str); 22] = [
        (
            &["nbody:9", "{out}/v", "--time", "64"],
            "invalid time '64': nbody:9 has 64 steps, 0 to 63",
        ),
        (
            &["{in}/big_7x5x3_uint16.raw", "{out}/v", "--time", "1"],
            "big_7x5x3_uint16.raw is one volume, not a time series",
        ),
        (&["menger:9", "{out}/existing"], "is a folder"),
        (&["menger:9", "{out}/"], "is a folder"),
        (&["menger:9", "{out}/missing/v"], "its folder does not exist"),
        (
            &["menger:9", "{out}/missing/v_9x9x9_uint8.raw"],
            "its folder does not exist",
        ),
        (&["{in}/big_7x5x3_uint16.raw", "{out}/v", "--type", "uint8"], &too_big),
        (
            &["{in}/neg_7x5x3_int16.raw", "{out}/v", "--type", "uint16"],
            "is -2, outside uint16's range 0 to 65535; float32 holds every value",
        ),
        (
            &["{in}/frac_7x5x3_float32.raw", "{out}/v", "--type", "uint8"],
            "voxel (1, 0, 0) is 23.5, not an integer; float32 holds every value",
        ),
        (
            &["{in}/huge_7x5x3_float64.raw", "{out}/v"],
            "beyond float32's largest magnitude 3.4028235e38; a raw file cannot hold it",
        ),
        (
            &["{in}/wide_7x5x3_float64.raw", "{out}/v"],
            "invalid voxel '(0, 0, 0)': -1e308, beyond float32's largest magnitude",
        ),
        (&["menger:9", "{out}/sponge.raw"], "must be sponge_9x9x9_uint8.raw"),
        (
            &["menger:9", "{out}/sponge_9x9x9_uint8.raw.raw"],
            "must be sponge_9x9x9_uint8.raw (",
        ),
        (&["menger:9", "{out}/sponge.nrrd"], "export writes raw files, not .nrrd"),
        (
            &["menger:9", "{out}/sponge.NII.GZ"],
            "export writes raw files, not .nii.gz",
        ),
        (
            &["menger:9", "{out}/sponge_9x9x9_float32.raw"],
            "must be sponge_9x9x9_uint8.raw",
        ),
        (
            &["menger:9", "{out}/sponge_9x9x9_uint8.raw", "--type", "uint16"],
            "must be sponge_9x9x9_uint16.raw",
        ),
        (
            &["menger:9", "{out}/v", "--type", "int16"],
            "expected uint8, uint16 or float32",
        ),
        (&["menger:9", "{out}/v", "--type", "uint9"], "uint9"),
        (&["menger:9", "{out}/v", "--dims", "9x9x9"], "--source-type"),
        (&["nosuch:9", "{out}/v"], "not a generator"),
        (
            &["menger:9+nbody:9", "{out}/v"],
            "has 2 channels and a raw file holds one",
        ),
    ];
    for (args, needle) in cases {
        fails(input.path(), args, needle);
    }
}

/// Little-endian bytes of `values` as `ty` (a NIfTI's voxels).
fn raw_bytes(ty: VoxelType, values: &[f64]) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    std::fs::read(write_source(dir.path(), "v", DIMS, ty, values)).unwrap()
}

#[test]
fn scaled_nifti_voxels_load_render_and_export_as_slope_times_raw_plus_intercept() {
    let dir = tempfile::tempdir().unwrap();
    let floats: Vec<f64> = values(-3.0, 0.19).into_iter().map(|v| (v as f32) as f64).collect();
    // (type, NIfTI datatype, raw values, slope, intercept, default export type)
    for (k, (ty, datatype, raw, slope, inter, want)) in [
        (VoxelType::U8, 2i16, values(0.0, 2.0), 10.0f32, 0.0f32, VoxelType::U16),
        (VoxelType::U8, 2, values(0.0, 2.0), -1.0, 0.0, VoxelType::F32),
        (VoxelType::U8, 2, values(0.0, 2.0), -1.0, 250.0, VoxelType::U8),
        (VoxelType::U8, 2, values(0.0, 1.0), 0.5, 0.0, VoxelType::F32),
        (VoxelType::I16, 4, values(-1200.0, 31.0), -2.0, 5.0, VoxelType::F32),
        (VoxelType::F32, 16, floats.clone(), -0.5, 1.0, VoxelType::F32),
        // Stored normalised as f32: halves over an even range are still halves.
        (VoxelType::I32, 8, values(-100.0, 1.0), 0.5, 0.0, VoxelType::F32),
        (VoxelType::U32, 768, values(0.0, 1.0), 0.5, 0.0, VoxelType::F32),
    ]
    .into_iter()
    .enumerate()
    {
        let name = format!("{ty} x {slope} + {inter}");
        let mut bytes =
            crate::common::nifti_bytes(&DIMS, datatype, 8 * ty.bytes() as i16, [1.0; 3], &raw_bytes(ty, &raw));
        bytes[112..116].copy_from_slice(&slope.to_le_bytes());
        bytes[116..120].copy_from_slice(&inter.to_le_bytes());
        let nii = dir.path().join(format!("scaled{k}.nii"));
        std::fs::write(&nii, bytes).unwrap();
        let scaled: Vec<f64> = raw.iter().map(|r| r * slope as f64 + inter as f64).collect();
        let v = load(&nii);
        let (lo, hi) = scaled
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        let span = hi - lo;
        assert!(
            (v.value_range[0] - lo).abs() <= span * 1e-6 && (v.value_range[1] - hi).abs() <= span * 1e-6,
            "{name}: range {:?}, want [{lo}, {hi}]",
            v.value_range
        );
        // What the GPU samples: the scaled values normalised over their
        // range, as a file holding them does.
        let reference = load(&write_source(
            dir.path(),
            &format!("ref{k}"),
            DIMS,
            VoxelType::F64,
            &scaled,
        ));
        assert_same_values(&v, &reference, 1e-6);
        let w = write_raw(&v, &dir.path().join(format!("out{k}")), None).unwrap();
        assert_eq!(w.ty, want, "{name}");
        for (i, (g, s)) in file_values(&w.path, want).iter().zip(&scaled).enumerate() {
            let tol = match ty {
                VoxelType::F32 | VoxelType::I32 | VoxelType::U32 => span * 2f64.powi(-24) + s.abs() * 2f64.powi(-23),
                _ => 0.0,
            };
            assert!((g - s).abs() <= tol, "{name}: voxel {i} exported {g}, want {s}");
        }
    }
    // A non-finite intercept is 0 and the slope still applies, as
    // nifti_clib reads it.
    let raw = values(0.0, 1.0);
    let mut bytes = crate::common::nifti_bytes(&DIMS, 4, 16, [1.0; 3], &raw_bytes(VoxelType::I16, &raw));
    bytes[112..116].copy_from_slice(&2.0f32.to_le_bytes());
    bytes[116..120].copy_from_slice(&f32::NAN.to_le_bytes());
    let nan_inter = dir.path().join("nan-inter.nii");
    std::fs::write(&nan_inter, bytes).unwrap();
    let hi = 2.0 * raw.iter().fold(0.0f64, |a, &b| a.max(b));
    assert_eq!(load(&nan_inter).value_range, [0.0, hi], "slope 2, intercept NaN");
    // A wide int32 range (f32 storage cannot tell integers there): the
    // scaled least value keeps its half, not rounded to an integer.
    let raw = values(1.0, 330_000.0);
    let mut bytes = crate::common::nifti_bytes(&DIMS, 8, 32, [1.0; 3], &raw_bytes(VoxelType::I32, &raw));
    bytes[112..116].copy_from_slice(&0.5f32.to_le_bytes());
    let wide = dir.path().join("wide.nii");
    std::fs::write(&wide, bytes).unwrap();
    let w = write_raw(&load(&wide), &dir.path().join("wide"), None).unwrap();
    assert_eq!((w.ty, file_values(&w.path, VoxelType::F32)[0]), (VoxelType::F32, 0.5));
    // Halves are not integers: uint8 cannot hold them, and says so.
    let halves = dir.path().join("scaled3.nii");
    let err = write_raw(&load(&halves), &dir.path().join("halves"), Some(VoxelType::U8)).unwrap_err();
    assert!(err.to_string().contains("not an integer"), "{err}");
}

#[test]
fn a_negatively_scaled_nifti_renders_streamed_into_bricks_as_its_scaled_values() {
    let dir = tempfile::tempdir().unwrap();
    let raw = values(0.0, 2.0);
    let mut bytes = crate::common::nifti_bytes(&DIMS, 2, 8, [1.0; 3], &raw_bytes(VoxelType::U8, &raw));
    bytes[112..116].copy_from_slice(&(-1.0f32).to_le_bytes());
    let nii = dir.path().join("negative.nii");
    std::fs::write(&nii, bytes).unwrap();
    let scaled: Vec<f64> = raw.iter().map(|r| -r).collect();
    let reference = write_source(dir.path(), "negated", DIMS, VoxelType::F64, &scaled);
    let mut frames = Vec::new();
    for (input, storage) in [(&nii, "bricks:4"), (&nii, "dense"), (&reference, "dense")] {
        let out = dir.path().join(format!("{storage}-{}.exr", frames.len()));
        let run = lacuna(
            &[
                "render",
                input.to_str().unwrap(),
                "--tf",
                "ramp:0.2:1",
                "--size",
                "32x32",
                "--storage",
                storage,
                "--out",
                out.to_str().unwrap(),
            ],
            &[],
        );
        assert_eq!(run.code, 0, "{}", run.stderr);
        frames.push(lacuna::frame::Frame::read_exr(&out).unwrap());
    }
    assert!(frames[2].pixels.iter().any(|p| p[3] > 0.01), "an empty frame");
    assert_eq!(frames[0].pixels, frames[1].pixels, "bricks against dense");
    let d = lacuna::frame::diff(&frames[1], &frames[2]).unwrap();
    assert!(d.max_abs <= 1e-5, "against the negated values: {}", d.max_abs);
}
