//! Loaders (raw, NRRD, NIfTI) on files the tests write, the real ch2 MRI,
//! procedural generators, brick ranges, and every bad-input error.

use crate::common;
use crate::common::{encode, gzip};
use lacuna::volume::{BrickGrid, GpuVolume, LoadOptions, RawLayout, VoxelData, VoxelType};
use lacuna::{Error, TransferFunction, Volume};
use std::path::{Path, PathBuf};

fn load(path: &Path) -> lacuna::Result<Volume> {
    Volume::load(path.to_str().unwrap(), &LoadOptions::default())
}

/// A small volume's values in a recognisable pattern.
fn pattern(dims: [u32; 3]) -> Vec<f64> {
    (0..dims.iter().product::<u32>())
        .map(|i| ((i * 29) % 200) as f64)
        .collect()
}

fn write(path: &Path, bytes: &[u8]) {
    std::fs::write(path, bytes).unwrap();
}

/// Every voxel's normalised value equals the pattern normalised over its range.
fn assert_pattern(v: &Volume, dims: [u32; 3]) {
    assert_eq!(v.dims, dims);
    let p = pattern(dims);
    let (lo, hi) = (
        p.iter().cloned().fold(f64::MAX, f64::min),
        p.iter().cloned().fold(f64::MIN, f64::max),
    );
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let i = (x + dims[0] * (y + dims[1] * z)) as usize;
                let want = (p[i] - lo) / (hi - lo);
                let got = v.value(x, y, z) as f64;
                assert!(
                    (got - want).abs() < 1e-5,
                    "{}: voxel ({x},{y},{z}) = {got}, want {want}",
                    v.name
                );
            }
        }
    }
}

const TYPES: [(VoxelType, &str); 8] = [
    (VoxelType::U8, "uint8"),
    (VoxelType::I8, "int8"),
    (VoxelType::U16, "uint16"),
    (VoxelType::I16, "int16"),
    (VoxelType::U32, "uint32"),
    (VoxelType::I32, "int32"),
    (VoxelType::F32, "float32"),
    (VoxelType::F64, "float64"),
];

#[test]
fn raw_files_named_the_open_scivis_way_load_every_type() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [5, 4, 3];
    for (ty, name) in TYPES {
        let path = dir.path().join(format!("pattern_5x4x3_{name}.raw"));
        write(&path, &encode(&pattern(dims), ty, true));
        let v = load(&path).unwrap();
        assert_eq!(v.source_type, ty);
        assert_pattern(&v, dims);
        // u8 and u16 (and the signed ones shifted) stay native.
        match ty {
            VoxelType::U8 | VoxelType::I8 => assert!(matches!(v.data, VoxelData::U8(_))),
            VoxelType::U16 | VoxelType::I16 => assert!(matches!(v.data, VoxelData::U16(_))),
            _ => assert!(matches!(v.data, VoxelData::F32(_))),
        }
    }
    // Source-unit ranges: int16 keeps its sign.
    let v = load(&dir.path().join("pattern_5x4x3_int16.raw")).unwrap();
    let top = pattern(dims).into_iter().fold(0.0, f64::max);
    assert_eq!(v.value_range, [-30000.0, (top - 100.0) * 300.0]);
}

#[test]
fn raw_files_with_explicit_layout() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("anything.bin");
    let dims = [3, 7, 2];
    write(&path, &encode(&pattern(dims), VoxelType::U16, true));
    let opts = LoadOptions {
        raw: Some(RawLayout {
            dims,
            ty: VoxelType::U16,
        }),
        ..LoadOptions::default()
    };
    let v = Volume::load(path.to_str().unwrap(), &opts).unwrap();
    assert_pattern(&v, dims);
}

fn expect_format(result: lacuna::Result<Volume>, needle: &str) {
    match result {
        Err(e @ Error::Format { .. }) => {
            assert!(e.to_string().contains(needle), "'{e}' lacks '{needle}'")
        }
        Err(e) => panic!("wrong error class: {e:?}"),
        Ok(v) => panic!("loaded {} but expected an error containing '{needle}'", v.name),
    }
}

#[test]
fn raw_errors_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let short = dir.path().join("short_4x4x4_uint8.raw");
    write(&short, &[0u8; 63]);
    expect_format(load(&short), "holds 63 bytes of voxel data but 4x4x4 uint8 needs 64");
    let typ = dir.path().join("odd_4x4x4_uint7.raw");
    write(&typ, &[0u8; 64]);
    expect_format(load(&typ), "unknown voxel type 'uint7'");
    let noname = dir.path().join("nodims.raw");
    write(&noname, &[0u8; 64]);
    expect_format(load(&noname), "give --dims");
    let zero = dir.path().join("zero_4x0x4_uint8.raw");
    write(&zero, &[]);
    let err = load(&zero).unwrap_err();
    assert!(
        err.to_string().contains("zero dimension") || err.to_string().contains("WxHxD"),
        "{err}"
    );
    let missing = dir.path().join("missing_4x4x4_uint8.raw");
    assert!(matches!(load(&missing), Err(Error::Io { .. })));
    // A float volume with a NaN loads it as no data, normalising only the
    // finite values (tests/integration/nan.rs renders such volumes).
    let nan = dir.path().join("nan_3x1x1_float32.raw");
    let mut bytes = 1.0f32.to_le_bytes().to_vec();
    bytes.extend(f32::NAN.to_le_bytes());
    bytes.extend(3.0f32.to_le_bytes());
    write(&nan, &bytes);
    let v = load(&nan).unwrap();
    assert_eq!(v.no_data.nan, 1);
    assert_eq!([v.value(0, 0, 0), v.value(2, 0, 0)], [0.0, 1.0]);
    assert!(v.value(1, 0, 0).is_nan());
}

fn nrrd_header(ty: &str, dims: [u32; 3], encoding: &str, extra: &str) -> String {
    format!(
        "NRRD0004\n# written by a test\ntype: {ty}\ndimension: 3\nsizes: {} {} {}\nendian: little\nencoding: {encoding}\n{extra}",
        dims[0], dims[1], dims[2]
    )
}

#[test]
fn nrrd_attached_detached_raw_and_gzip_with_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [6, 5, 4];
    let data = encode(&pattern(dims), VoxelType::I16, true);
    // Attached, raw, spacings.
    let p = dir.path().join("a.nrrd");
    let mut bytes = nrrd_header("short", dims, "raw", "spacings: 0.5 0.75 2\nkey:=value\n\n").into_bytes();
    bytes.extend(&data);
    write(&p, &bytes);
    let v = load(&p).unwrap();
    assert_pattern(&v, dims);
    assert_eq!(v.spacing, [0.5, 0.75, 2.0]);
    // Attached, gzip, space directions.
    let p = dir.path().join("b.nrrd");
    let mut bytes = nrrd_header(
        "int16",
        dims,
        "gzip",
        "space: left-posterior-superior\nspace directions: (0.9,0,0) (0,1.2,0) (0,0,3)\n\n",
    )
    .into_bytes();
    bytes.extend(gzip(&data));
    write(&p, &bytes);
    let v = load(&p).unwrap();
    assert_pattern(&v, dims);
    assert!((v.spacing[0] - 0.9).abs() < 1e-6 && (v.spacing[1] - 1.2).abs() < 1e-6 && v.spacing[2] == 3.0);
    // Spacings of nan beside space directions say nothing: the directions hold.
    let p = dir.path().join("nan.nrrd");
    let extra = "spacings: nan nan nan\nspace directions: (0.9,0,0) (0,1.2,0) (0,0,3)\n\n";
    let mut bytes = nrrd_header("int16", dims, "raw", extra).into_bytes();
    bytes.extend(&data);
    write(&p, &bytes);
    assert_eq!(load(&p).unwrap().spacing[2], 3.0);
    // Per axis: a time axis's spacing beside the spatial axes' directions
    // (`unu join -sp`) is the format's own way.
    let p = dir.path().join("time.nrrd");
    let header = format!(
        "NRRD0004\ntype: int16\ndimension: 4\nsizes: {} {} {} 2\nendian: little\nencoding: raw\nkinds: domain domain domain time\nspacings: nan nan nan 0.5\nspace directions: (0.9,0,0) (0,1.2,0) (0,0,3) none\n\n",
        dims[0], dims[1], dims[2]
    );
    write(&p, &[header.into_bytes(), data.clone(), data.clone()].concat());
    let series = lacuna::volume::Series::open(p.to_str().unwrap(), &Default::default()).unwrap();
    assert_eq!(series.steps(), 2);
    let v = series.load(1, None).unwrap();
    assert_eq!(v.spacing[2], 3.0);
    assert_pattern(&v, dims);
    // Detached header, raw and gzip data files.
    write(&dir.path().join("c.raw"), &data);
    write(
        &dir.path().join("c.nhdr"),
        nrrd_header("short", dims, "raw", "data file: c.raw\n").as_bytes(),
    );
    assert_pattern(&load(&dir.path().join("c.nhdr")).unwrap(), dims);
    write(&dir.path().join("d.raw.gz"), &gzip(&data));
    write(
        &dir.path().join("d.nhdr"),
        nrrd_header("short", dims, "gzip", "datafile: d.raw.gz\n").as_bytes(),
    );
    assert_pattern(&load(&dir.path().join("d.nhdr")).unwrap(), dims);
    // Big-endian floats.
    let p = dir.path().join("e.nrrd");
    let mut bytes = nrrd_header("float", dims, "raw", "\n")
        .replace("endian: little", "endian: big")
        .into_bytes();
    bytes.extend(encode(&pattern(dims), VoxelType::F32, false));
    write(&p, &bytes);
    assert_pattern(&load(&p).unwrap(), dims);
}

/// A slice or a row is a volume one voxel thick, as a 2-D NIfTI is; its
/// spacings and space directions give the axes it has.
#[test]
fn a_2d_or_1d_nrrd_is_a_volume_one_voxel_thick() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [6, 5, 1];
    let data = encode(&pattern(dims), VoxelType::I16, true);
    for (name, fields) in [
        ("slice.nrrd", "dimension: 2\nsizes: 6 5\nspacings: 0.5 2\n"),
        (
            "dirs.nrrd",
            "dimension: 2\nsizes: 6 5\nspace dimension: 2\nspace directions: (0.5,0) (0,2)\n",
        ),
    ] {
        let p = dir.path().join(name);
        let header = format!("NRRD0004\ntype: short\n{fields}endian: little\nencoding: raw\n\n");
        write(&p, &[header.into_bytes(), data.clone()].concat());
        let v = load(&p).unwrap();
        assert_eq!(v.spacing, [0.5, 2.0, 1.0], "{name}");
        assert_pattern(&v, dims);
    }
    let p = dir.path().join("row.nrrd");
    let header = "NRRD0004\ntype: short\ndimension: 1\nsizes: 30\nendian: little\nencoding: raw\n\n";
    write(&p, &[header.as_bytes(), &data].concat());
    let v = load(&p).unwrap();
    assert_eq!((v.dims, v.spacing), ([30, 1, 1], [1.0; 3]));
    assert_pattern(&v, [30, 1, 1]);
}

#[test]
fn nrrd_errors_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [4, 4, 4];
    let p = dir.path().join("corrupt.nrrd");
    let mut bytes = nrrd_header("uchar", dims, "gzip", "\n").into_bytes();
    bytes.extend(b"\x1f\x8b\x08\x00garbage that is not deflate");
    write(&p, &bytes);
    expect_format(load(&p), "corrupt gzip");
    let p = dir.path().join("short.nrrd");
    let mut bytes = nrrd_header("uchar", dims, "raw", "\n").into_bytes();
    bytes.extend([0u8; 10]);
    write(&p, &bytes);
    expect_format(load(&p), "holds 10 bytes");
    let p = dir.path().join("type.nrrd");
    write(&p, nrrd_header("complex", dims, "raw", "\n").as_bytes());
    expect_format(load(&p), "NRRD type 'complex' is not supported");
    let p = dir.path().join("magic.nrrd");
    write(&p, b"hello");
    expect_format(load(&p), "not a NRRD file");
    let p = dir.path().join("missing.nhdr");
    write(
        &p,
        nrrd_header("uchar", dims, "raw", "data file: nowhere.raw\n").as_bytes(),
    );
    assert!(matches!(load(&p), Err(Error::Io { .. })));
    // A field given twice (in either spelling) is refused, not the last
    // one taken; so are the skips lacuna would otherwise misread.
    for (extra, message) in [
        ("sizes: 4 4 4\n\n", "gives the field 'sizes' twice"),
        ("byte skip: 0\nbyteskip: 0\n\n", "gives the field 'byteskip' twice"),
        ("line skip: 2\n\n", "'line skip' is not supported"),
        ("byte skip: -1\n\n", "'byte skip: -1'"),
        ("byte skip: -7\n\n", "must be >= 0, not '-7'"),
        (
            "spacings: 1 1 1\nspace directions: (2,0,0) (0,2,0) (0,0,2)\n\n",
            "NRRD axis 0 has both a spacing (1) and a space direction, which the format does not allow",
        ),
    ] {
        let p = dir.path().join("fields.nrrd");
        let mut bytes = nrrd_header("uchar", dims, "raw", extra).into_bytes();
        bytes.extend([0u8; 64]);
        write(&p, &bytes);
        expect_format(load(&p), message);
    }
}

#[test]
fn nrrd_field_names_read_in_every_spelling() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [6, 5, 4];
    let data = encode(&pattern(dims), VoxelType::I16, true);
    // "byteskip" and "Byte Skip" are "byte skip": three bytes before the data.
    for field in ["byteskip: 3", "Byte Skip: 3", "byte  skip: 3"] {
        let p = dir.path().join("skip.nrrd");
        // Comments and key:=value pairs may repeat: they are no fields.
        let extra = format!("{field}\nline skip: 0\n# a\n# a\nk:=1\nk:=1\n\n");
        let mut bytes = nrrd_header("short", dims, "raw", &extra).into_bytes();
        bytes.extend([9u8; 3]);
        bytes.extend(&data);
        write(&p, &bytes);
        assert_pattern(&load(&p).unwrap(), dims);
    }
}

fn nifti_bytes(dims: [u32; 3], datatype: i16, bitpix: i16, pixdim: [f32; 3], data: &[u8]) -> Vec<u8> {
    common::nifti_bytes(&dims, datatype, bitpix, pixdim, data)
}

#[test]
fn nifti_single_file_and_gzip_with_pixdim() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [7, 3, 5];
    for (ty, code, bits) in [
        (VoxelType::U8, 2, 8),
        (VoxelType::I16, 4, 16),
        (VoxelType::F32, 16, 32),
        (VoxelType::U16, 512, 16),
    ] {
        let bytes = nifti_bytes(dims, code, bits, [0.8, 1.0, 2.5], &encode(&pattern(dims), ty, true));
        let p = dir.path().join(format!("v{code}.nii"));
        write(&p, &bytes);
        let v = load(&p).unwrap();
        assert_eq!(v.source_type, ty);
        assert_eq!(v.spacing, [0.8, 1.0, 2.5]);
        assert_pattern(&v, dims);
        let p = dir.path().join(format!("v{code}.nii.gz"));
        write(&p, &gzip(&bytes));
        assert_pattern(&load(&p).unwrap(), dims);
    }
}

#[test]
fn nifti_errors_name_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let dims = [2, 2, 2];
    // RGB24 (128) is not a scalar type lacuna renders.
    let p = dir.path().join("rgb.nii");
    write(&p, &nifti_bytes(dims, 128, 24, [1.0; 3], &[0u8; 24]));
    expect_format(load(&p), "datatype");
    // Corrupt gzip.
    let p = dir.path().join("bad.nii.gz");
    let mut gz = gzip(&nifti_bytes(dims, 2, 8, [1.0; 3], &[1u8; 8]));
    let n = gz.len();
    gz.truncate(n / 2);
    write(&p, &gz);
    expect_format(load(&p), "NIfTI");
    // Zero dimension.
    let p = dir.path().join("zero.nii");
    write(&p, &nifti_bytes([2, 0, 2], 2, 8, [1.0; 3], &[]));
    let err = load(&p).unwrap_err();
    assert!(err.to_string().contains("zero dimension"), "{err}");
    // A header of another size is no NIfTI-1 header.
    let p = dir.path().join("size.nii");
    let mut bytes = nifti_bytes(dims, 2, 8, [1.0; 3], &[1u8; 8]);
    bytes[..4].copy_from_slice(&100i32.to_le_bytes());
    write(&p, &bytes);
    expect_format(load(&p), "not a NIfTI-1 header: its sizeof_hdr is 100, not 348");
    // NIfTI-2 (sizeof_hdr 540), either byte order, is named as such.
    for size in [540i32.to_le_bytes(), 540i32.to_be_bytes()] {
        let p = dir.path().join("two.nii");
        let mut bytes = vec![0u8; 560];
        bytes[..4].copy_from_slice(&size);
        write(&p, &bytes);
        let err = load(&p).unwrap_err();
        assert!(
            matches!(err, Error::Format { .. }) && err.to_string().contains("is NIfTI-2 (sizeof_hdr 540)"),
            "{err}"
        );
    }
    assert!(matches!(load(&dir.path().join("none.nii")), Err(Error::Io { .. })));
}

const CH2: &str = "/usr/share/mricron/templates/ch2.nii.gz";

#[test]
fn the_real_ch2_mri_loads_and_renders() {
    // .ci/run installs mricron-data; a missing file is a setup error, not a skip.
    assert!(Path::new(CH2).exists(), "{CH2} missing: apt install mricron-data");
    let v = load(Path::new(CH2)).unwrap();
    assert_eq!(v.dims, [181, 217, 181]);
    assert_eq!(v.spacing, [1.0, 1.0, 1.0]);
    assert_eq!(v.source_type, VoxelType::U8);
    assert!(v.value_range[1] > v.value_range[0]);
    // Render a small frame of it on the GPU against the CPU reference.
    let tf = TransferFunction::parse("ramp:0.3:0.9:0.2").unwrap();
    let s = lacuna::render::FrameDesc::builder(48, 48)
        .step(2.0)
        .filter(lacuna::render::Filter::Manual)
        .build()
        .unwrap();
    let ctx = common::gpu();
    let frame = common::render(&ctx, &v, &tf, &s, lacuna::accel::Accel::naive());
    let cpu = lacuna::render::reference::render(&v, &tf, &s.params_for(v.dims, v.spacing, v.norm).unwrap());
    assert!(common::max_abs(&frame, &cpu) <= 1e-4);
    assert!(
        frame.pixels.iter().filter(|p| p[3] > 0.1).count() > 200,
        "the head should cover the frame"
    );
}

#[test]
fn procedural_volumes_are_deterministic_at_any_size() {
    for g in lacuna::volume::procedural::Generator::ALL {
        for dims in ["1x1x5", "7x3x2", "33"] {
            let spec = format!("{}:{dims}", g.name());
            let a = Volume::load(&spec, &LoadOptions::default()).unwrap();
            let b = Volume::load(&spec, &LoadOptions::default()).unwrap();
            let (VoxelData::U8(x), VoxelData::U8(y)) = (&a.data, &b.data) else {
                panic!()
            };
            assert_eq!(x, y, "{spec} is not deterministic");
            assert!(a.default_tf.is_some());
        }
    }
    // Seeds change the volume.
    let (a, b) = (
        Volume::load("nbody:32:1", &LoadOptions::default()).unwrap(),
        Volume::load("nbody:32:2", &LoadOptions::default()).unwrap(),
    );
    let (VoxelData::U8(x), VoxelData::U8(y)) = (&a.data, &b.data) else {
        panic!()
    };
    assert_ne!(x, y);
}

fn visible_percent(spec: &str) -> f64 {
    let v = Volume::load(spec, &LoadOptions::default()).unwrap();
    let tf = TransferFunction::parse(v.default_tf.as_ref().unwrap()).unwrap();
    let n = v.data.len();
    100.0
        * (0..n)
            .filter(|&i| tf.lookup(v.normalize(v.data.texel(i)))[3] > 0.0)
            .count() as f64
        / n as f64
}

#[test]
fn generator_occupancy_under_default_transfer_functions() {
    // Level-3 Menger sponge: (20/27)^3 = 40.6 % solid.
    let m = visible_percent("menger:54");
    assert!((m - 40.6).abs() < 1.0, "menger {m}");
    let t = visible_percent("turbulence:64");
    assert!((40.0..60.0).contains(&t), "turbulence {t}");
    let n = visible_percent("nbody:64");
    assert!((0.05..0.5).contains(&n), "nbody {n}");
    let s = visible_percent("shells:64");
    assert!((1.0..20.0).contains(&s), "shells {s}");
    let v = visible_percent("vessels:64");
    assert!((0.3..8.0).contains(&v), "vessels {v}");
}

#[test]
fn volume_spec_errors() {
    let o = LoadOptions::default();
    for (spec, needle) in [
        ("blob:64", "not a generator"),
        ("menger:abc", "SIZE"),
        ("menger:0", "zero dimension"),
        ("menger:8:2.5", "Menger level"),
        // Finer than a voxel: every centre of a 9^3 grid lies in a level-3 hole.
        ("menger:9:3", "9x9x9 resolves levels up to 2"),
        ("menger:81:9", "needs at least 3^9 = 19683 voxels a side"),
        ("menger:81x81x8:2", "resolves levels up to 1"),
        ("menger:8:x", "not a number"),
        ("nbody:8:-1", "seed"),
        ("nbody:8:1e20", "the seed must be an integer from 0 to 2^53"),
        // Echoed as the number read, not a rounded integer like the one given.
        ("nbody:8:18446744073709551615", "'nbody:1.8446744073709552e19'"),
        ("", "is empty"),
        ("no/such/file.raw", "No such file"),
        ("volume.xyz", "No such file"),
    ] {
        let err = Volume::load(spec, &o).unwrap_err().to_string();
        assert!(err.contains(needle), "{spec}: '{err}' lacks '{needle}'");
        assert!(!err.contains('\n'), "multi-line error for {spec}");
    }
    let dir = tempfile::tempdir().unwrap();
    let p: PathBuf = dir.path().join("volume.xyz");
    write(&p, b"x");
    let err = load(&p).unwrap_err().to_string();
    assert!(err.contains("unknown volume format"), "{err}");
}

#[test]
fn a_volume_over_the_3d_image_limit_is_refused_dense_and_bricked_by_auto() {
    let ctx = common::gpu();
    let max = ctx.info().max_image_dimension_3d;
    let v = Volume::new(
        "long",
        [max + 1, 1, 1],
        [1.0; 3],
        VoxelType::U8,
        VoxelData::U8(vec![1; max as usize + 1]),
    )
    .unwrap();
    let err = GpuVolume::upload_as(&ctx, &v, lacuna::volume::Storage::Dense)
        .err()
        .unwrap();
    assert!(
        matches!(
            err,
            Error::DeviceLimit {
                limit: "maxImageDimension3D",
                ..
            }
        ),
        "{err}"
    );
    assert!(err.to_string().contains(&max.to_string()));
    // Auto storage takes bricks where the dense image does not fit.
    let gv = GpuVolume::upload(&ctx, &v).unwrap();
    assert_eq!(gv.pool().map(|p| p.edge), Some(lacuna::volume::POOL_BRICK));
    common::assert_clean(&ctx);
}

#[test]
fn brick_ranges_cover_a_one_voxel_apron() {
    // One bright voxel at x = 8 (first voxel of brick 1); the apron puts it
    // into brick 0's range too, since samples in brick 0 interpolate it.
    let dims = [24, 8, 8];
    let mut data = vec![0u8; 24 * 8 * 8];
    data[8] = 255;
    let v = Volume::new("dot", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let with = BrickGrid::new(&v, 8, 1);
    let without = BrickGrid::new(&v, 8, 0);
    assert_eq!(with.counts, [3, 1, 1]);
    assert_eq!(with.ranges, vec![[0.0, 1.0], [0.0, 1.0], [0.0, 0.0]]);
    assert_eq!(without.ranges, vec![[0.0, 0.0], [0.0, 1.0], [0.0, 0.0]]);
    let tf = TransferFunction::parse("band:0.5:1").unwrap();
    assert_eq!(with.active(&tf), vec![true, true, false]);
}
