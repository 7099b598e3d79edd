//! Files of every type streamed into bricks (`volume::slabs`): raw files of
//! each voxel type, NRRDs (attached and detached, raw and gzip, either
//! endianness, a time axis) and NIfTI files (`.nii`, `.nii.gz`, a time axis) stream slab by slab into the pool their dense
//! load plans, every voxel bit for bit with the same range, normalisation
//! and no-data counts; a rank's float file agrees on its source range
//! before its stored range; a file shorter than its header says is one
//! error before rendering.

use crate::common;
use crate::common::{encode, gzip};
use lacuna::volume::{LoadOptions, PoolLayout, PoolLimits, Series, StreamTo, VoxelData, VoxelType};
use lacuna::Volume;
use std::path::Path;
use std::sync::{Arc, Mutex};

fn limits() -> PoolLimits {
    PoolLimits {
        max_image_dim: 4096,
        max_image_bytes: u64::MAX,
        max_table_entries: i32::MAX as u64,
    }
}

const DIMS: [u32; 3] = [23, 17, 29];

/// Values over DIMS: a constant slab (x < 9), a varying rest, and for float
/// types NaN and both infinities in a few voxels.
fn values(float: bool) -> Vec<f64> {
    let [w, h, d] = DIMS;
    (0..w * h * d)
        .map(|i| {
            let (x, y, z) = (i % w, i / w % h, i / (w * h));
            match i % 97 {
                5 if float => f64::NAN,
                11 if float => f64::INFINITY,
                13 if float => f64::NEG_INFINITY,
                _ if x < 9 => 40.0,
                _ => ((x * 31 + y * 7 + z * 13) % 200) as f64,
            }
        })
        .collect()
}

fn is_float(ty: VoxelType) -> bool {
    matches!(ty, VoxelType::F32 | VoxelType::F64)
}

/// Step `k` of `spec` loaded dense and streamed into bricks of `edge`.
fn dense_and_streamed(spec: &Path, k: u32, edge: u32) -> (Volume, Volume) {
    let series = Series::open(spec.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let dense = series.load(k, None).unwrap();
    let series = Series::open(spec.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let streamed = series.load_bricks(k, &StreamTo::new(edge, limits())).unwrap();
    (dense, streamed)
}

/// The streamed volume is the dense one: every voxel's bits, the range,
/// normalisation, no-data counts, type and spacing, and the pool planned
/// from the dense volume.
fn assert_same(what: &str, d: &Volume, s: &Volume, edge: u32) {
    let VoxelData::Bricks(pool) = &s.data else {
        panic!("{what} was not streamed")
    };
    assert!(
        (0..d.data.len()).all(|i| s.data.texel(i).to_bits() == d.data.texel(i).to_bits()),
        "{what}: voxels"
    );
    assert_eq!(
        (s.value_range, s.norm, s.no_data, s.source_type, s.spacing, &s.name),
        (d.value_range, d.norm, d.no_data, d.source_type, d.spacing, &d.name),
        "{what}"
    );
    let planned = PoolLayout::of_volume(d, edge, limits()).unwrap();
    assert_eq!(pool.layout.table, planned.table, "{what}: table");
    assert!(planned.constant_bricks > 0, "{what}: some bricks are constant");
}

#[test]
fn every_raw_type_streams_as_it_loads_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    for ty in [
        VoxelType::I8,
        VoxelType::I16,
        VoxelType::U32,
        VoxelType::I32,
        VoxelType::F32,
        VoxelType::F64,
    ] {
        let path = dir.path().join(format!("v_23x17x29_{ty}.raw"));
        std::fs::write(&path, encode(&values(is_float(ty)), ty, true)).unwrap();
        let (d, s) = dense_and_streamed(&path, 0, 4);
        if is_float(ty) {
            assert!(d.no_data.nan > 0 && d.no_data.pos_inf > 0 && d.no_data.neg_inf > 0);
        }
        assert_same(&ty.to_string(), &d, &s, 4);
    }
    // A constant float file and one of NaN only: nothing to normalise by.
    for (name, v) in [("constant", 2.5f32), ("nothing", f32::NAN)] {
        let path = dir.path().join(format!("{name}_23x17x29_float32.raw"));
        std::fs::write(&path, v.to_le_bytes().repeat(23 * 17 * 29)).unwrap();
        let (d, s) = dense_and_streamed(&path, 0, 4);
        assert_same(name, &d, &s, 4);
        let VoxelData::Bricks(pool) = &s.data else {
            panic!("{name} was not streamed")
        };
        assert_eq!(pool.layout.stored.len(), 0, "{name}: every brick is one value");
    }
}

#[test]
fn a_rank_agrees_on_a_float_file_s_source_range_then_its_stored_range() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("v_23x17x29_float32.raw");
    std::fs::write(&path, encode(&values(true), VoxelType::F32, true)).unwrap();
    let spec = path.to_str().unwrap();
    let d = Volume::load(spec, &LoadOptions::default()).unwrap();
    let VoxelData::F32(stored) = &d.data else {
        panic!("a float file stores f32")
    };
    let finite = |v: &[f64]| {
        v.iter()
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            })
    };
    let stored: Vec<f64> = stored.iter().map(|&v| v as f64).collect();
    let whole = [(d.value_range[0], d.value_range[1]), finite(&stored)];
    // Bricks of 4: z rows 2 to 4 kept, layers 8 to 20 read (their border too).
    let keep = [[0, 1, 2], [6, 4, 5]];
    let heard = Arc::new(Mutex::new(Vec::new()));
    let log = heard.clone();
    let to = StreamTo::new(4, limits())
        .keep(Some(keep))
        .across(Arc::new(move |mine| {
            let mut log = log.lock().unwrap();
            log.push(mine);
            Ok(whole[log.len() - 1])
        }));
    let s = Series::open(spec, &LoadOptions::default())
        .unwrap()
        .load_bricks(0, &to)
        .unwrap();
    // The source range of its own layers, then their stored range.
    let own: Vec<f64> = values(true)[8 * 23 * 17..21 * 23 * 17]
        .iter()
        .map(|&v| (v as f32 * 0.25 - 3.0) as f64)
        .collect();
    let heard = heard.lock().unwrap();
    assert_eq!(heard.len(), 2);
    assert_eq!(heard[0], Some(finite(&own)));
    let (lo, hi) = heard[1].unwrap();
    assert!(lo >= whole[1].0 && hi <= whole[1].1 && lo < hi);
    assert_eq!((s.value_range, s.norm), (d.value_range, d.norm));
    for z in 8..20 {
        for y in 4..16 {
            for x in 0..23 {
                let i = d.index(x, y, z);
                assert_eq!(
                    s.data.texel(i).to_bits(),
                    d.data.texel(i).to_bits(),
                    "voxel {x},{y},{z}"
                );
            }
        }
    }
}

fn nrrd_header(ty: &str, sizes: &str, encoding: &str, endian: &str, extra: &str) -> String {
    let dimension = sizes.split_whitespace().count();
    format!(
        "NRRD0004\ntype: {ty}\ndimension: {dimension}\nsizes: {sizes}\nendian: {endian}\nencoding: {encoding}\n{extra}"
    )
}

#[test]
fn nrrds_stream_as_they_load_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let sizes = "23 17 29";
    let i16_le = encode(&values(false), VoxelType::I16, true);
    let f32_be = encode(&values(true), VoxelType::F32, false);
    let u16_le = encode(&values(false), VoxelType::U16, true);
    // Attached raw, with spacings.
    let attached = dir.path().join("a.nrrd");
    let mut bytes = nrrd_header("short", sizes, "raw", "little", "spacings: 0.5 0.75 2\n\n").into_bytes();
    bytes.extend(&i16_le);
    std::fs::write(&attached, bytes).unwrap();
    // Attached gzip, big-endian floats with NaN and infinities.
    let gz = dir.path().join("b.nrrd");
    let mut bytes = nrrd_header("float", sizes, "gzip", "big", "\n").into_bytes();
    bytes.extend(gzip(&f32_be));
    std::fs::write(&gz, bytes).unwrap();
    // Detached raw with a byte skip, and detached gzip.
    let detached = dir.path().join("c.nhdr");
    std::fs::write(
        &detached,
        nrrd_header("ushort", sizes, "raw", "little", "byte skip: 7\ndata file: c.raw\n"),
    )
    .unwrap();
    std::fs::write(dir.path().join("c.raw"), [&[9u8; 7][..], &u16_le].concat()).unwrap();
    let detached_gz = dir.path().join("d.nhdr");
    std::fs::write(
        &detached_gz,
        nrrd_header("ushort", sizes, "gzip", "little", "data file: d.raw.gz\n"),
    )
    .unwrap();
    std::fs::write(dir.path().join("d.raw.gz"), gzip(&u16_le)).unwrap();
    // Signed bytes and unsigned 32-bit words, big-endian.
    let i8_nrrd = dir.path().join("e.nrrd");
    let mut bytes = nrrd_header("int8", sizes, "raw", "little", "\n").into_bytes();
    bytes.extend(encode(&values(false), VoxelType::I8, true));
    std::fs::write(&i8_nrrd, bytes).unwrap();
    let u32_nrrd = dir.path().join("f.nrrd");
    let mut bytes = nrrd_header("uint", sizes, "gzip", "big", "\n").into_bytes();
    bytes.extend(gzip(&encode(&values(false), VoxelType::U32, false)));
    std::fs::write(&u32_nrrd, bytes).unwrap();
    for (path, edge) in [
        (&attached, 4),
        (&gz, 8),
        (&detached, 8),
        (&detached_gz, 4),
        (&i8_nrrd, 4),
        (&u32_nrrd, 4),
    ] {
        let (d, s) = dense_and_streamed(path, 0, edge);
        assert_same(&path.display().to_string(), &d, &s, edge);
    }
    // A time axis: step 2 streams (normalised as step 0, streamed too).
    let series = dir.path().join("t.nrrd");
    let steps: Vec<u8> = (0..3)
        .flat_map(|k| {
            encode(
                &values(false).iter().map(|v| v + k as f64).collect::<Vec<_>>(),
                VoxelType::I16,
                true,
            )
        })
        .collect();
    let mut bytes = nrrd_header(
        "short",
        "23 17 29 3",
        "gzip",
        "little",
        "kinds: domain domain domain time\n\n",
    )
    .into_bytes();
    bytes.extend(gzip(&steps));
    std::fs::write(&series, bytes).unwrap();
    let (d, s) = dense_and_streamed(&series, 2, 4);
    assert_same("step 2 of t.nrrd", &d, &s, 4);
}

#[test]
fn nifti_files_stream_as_they_load_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let dims = DIMS.to_vec();
    let nii = dir.path().join("a.nii");
    let i16_le = encode(&values(false), VoxelType::I16, true);
    std::fs::write(&nii, common::nifti_bytes(&dims, 4, 16, [0.5, 0.75, 2.0], &i16_le)).unwrap();
    let gz = dir.path().join("b.nii.gz");
    let f32_le = encode(&values(true), VoxelType::F32, true);
    std::fs::write(&gz, gzip(&common::nifti_bytes(&dims, 16, 32, [1.0; 3], &f32_le))).unwrap();
    // A time axis: step 2 of 3.
    let series = dir.path().join("t.nii.gz");
    let steps: Vec<u8> = (0..3)
        .flat_map(|k| {
            let shifted: Vec<f64> = values(false).iter().map(|v| v + 3.0 * k as f64).collect();
            encode(&shifted, VoxelType::U16, true)
        })
        .collect();
    let with_time = [&dims[..], &[3]].concat();
    std::fs::write(
        &series,
        gzip(&common::nifti_bytes(&with_time, 512, 16, [1.0; 3], &steps)),
    )
    .unwrap();
    for (path, k, edge) in [(&nii, 0, 4), (&gz, 0, 8), (&series, 2, 4)] {
        let (d, s) = dense_and_streamed(path, k, edge);
        assert_same(&format!("step {k} of {}", path.display()), &d, &s, edge);
    }
}

#[test]
fn a_file_shorter_or_longer_than_its_header_says_is_one_error() {
    let dir = tempfile::tempdir().unwrap();
    let sizes = "23 17 29";
    let data = encode(&values(false), VoxelType::I16, true);
    let short = &data[..data.len() - 2];
    let raw = dir.path().join("a.nrrd");
    let mut bytes = nrrd_header("short", sizes, "raw", "little", "\n").into_bytes();
    bytes.extend(short);
    std::fs::write(&raw, bytes).unwrap();
    let gz = dir.path().join("b.nrrd");
    let mut bytes = nrrd_header("short", sizes, "gzip", "little", "\n").into_bytes();
    bytes.extend(gzip(short));
    std::fs::write(&gz, bytes).unwrap();
    // Gzip data longer than the header says: the dense load refuses it,
    // and so does a stream that reaches the last layer.
    let long = dir.path().join("long.nrrd");
    let mut bytes = nrrd_header("short", sizes, "gzip", "little", "\n").into_bytes();
    bytes.extend(gzip(&[&data[..], &[1, 2, 3, 4]].concat()));
    std::fs::write(&long, bytes).unwrap();
    let float = dir.path().join("f_23x17x29_float32.raw");
    std::fs::write(&float, &encode(&values(true), VoxelType::F32, true)[4..]).unwrap();
    let nii = dir.path().join("c.nii");
    std::fs::write(&nii, common::nifti_bytes(&DIMS, 4, 16, [1.0; 3], short)).unwrap();
    let nii_gz = dir.path().join("d.nii.gz");
    std::fs::write(&nii_gz, gzip(&common::nifti_bytes(&DIMS, 4, 16, [1.0; 3], short))).unwrap();
    for (path, needle) in [
        (
            &raw,
            "holds 22676 bytes of voxel data but 23x17x29 int16 (1 channels, 1 steps) needs 22678",
        ),
        (&gz, "ends before layer 29 of its 29 voxel layers"),
        (
            &long,
            "holds 22679 bytes of voxel data but 23x17x29 int16 (1 channels, 1 steps) needs 22678",
        ),
        (
            &float,
            "holds 45352 bytes of voxel data but 23x17x29 float32 needs 45356",
        ),
        (
            &nii,
            "holds 23028 bytes, but step 0 of its 23x17x29 int16 voxels ends at byte 23030",
        ),
        (&nii_gz, "ends before layer 29 of its 29 voxel layers"),
    ] {
        let series = Series::open(path.to_str().unwrap(), &LoadOptions::default()).unwrap();
        let e = series
            .load_bricks(0, &StreamTo::new(4, limits()))
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "{}: {e}", path.display());
    }
}

#[test]
fn a_nii_gz_whose_crc_does_not_match_is_refused_dense_and_streamed() {
    let dir = tempfile::tempdir().unwrap();
    let data = encode(&values(false), VoxelType::I16, true);
    let mut bytes = gzip(&common::nifti_bytes(DIMS.as_ref(), 4, 16, [1.0; 3], &data));
    // The trailer: CRC-32 of the inflated bytes, then their length.
    let crc = bytes.len() - 8;
    bytes[crc] ^= 0x5a;
    let bad = dir.path().join("bad.nii.gz");
    std::fs::write(&bad, &bytes).unwrap();
    let series = Series::open(bad.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let dense = series.load(0, None).unwrap_err().to_string();
    let streamed = series
        .load_bricks(0, &StreamTo::new(4, limits()))
        .unwrap_err()
        .to_string();
    for e in [dense, streamed] {
        assert!(e.contains("cannot read NIfTI data") && e.contains("checksum"), "{e}");
    }
    // The same file with its CRC intact loads, also with zero padding
    // after its gzip member (past the voxels, as in a .nii).
    bytes[crc] ^= 0x5a;
    std::fs::write(&bad, &bytes).unwrap();
    let (d, s) = dense_and_streamed(&bad, 0, 4);
    assert_same("intact", &d, &s, 4);
    for pad in [3, 512] {
        let padded = [&bytes[..], &vec![0u8; pad]].concat();
        std::fs::write(&bad, &padded).unwrap();
        let (d, s) = dense_and_streamed(&bad, 0, 4);
        assert_same(&format!("padded with {pad} zeros"), &d, &s, 4);
    }
    // Two gzip members (as pigz or a concatenation writes): one volume.
    let file = common::nifti_bytes(DIMS.as_ref(), 4, 16, [1.0; 3], &data);
    let split = file.len() / 3;
    std::fs::write(&bad, [gzip(&file[..split]), gzip(&file[split..])].concat()).unwrap();
    let (d, s) = dense_and_streamed(&bad, 0, 4);
    assert_same("two members", &d, &s, 4);
    // A corrupt second member is found as the first's was.
    let mut two = [gzip(&file[..split]), gzip(&file[split..])].concat();
    let end = two.len() - 8;
    two[end] ^= 0x5a;
    std::fs::write(&bad, two).unwrap();
    let e = Series::open(bad.to_str().unwrap(), &LoadOptions::default())
        .unwrap()
        .load(0, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("checksum"), "{e}");
}
