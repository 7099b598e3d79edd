//! Streamed loading into bricks (`volume::PoolStream`): the pool a
//! generator's slabs or a raw file's layers stream into is the pool planned
//! from the dense volume, byte for byte (table, slots, images); every voxel
//! reads back through it; a kept region stores only its bricks and still
//! normalises by the whole volume; every structure renders a streamed
//! volume as naive does, and as the dense volume renders; bad streams are
//! errors.

use crate::common;
use crate::common::identity::{standard_views, Fixture};
use crate::common::{fails, lacuna};
use lacuna::frame::diff;
use lacuna::volume::{
    cells_words, GpuVolume, LoadOptions, PoolLayout, PoolLimits, PoolStream, RawLayout, Series, Storage, StreamTo,
    VoxelData, VoxelType,
};
use lacuna::{TransferFunction, Volume};

fn limits(max_image_bytes: u64) -> PoolLimits {
    PoolLimits {
        max_image_dim: 4096,
        max_image_bytes,
        max_table_entries: i32::MAX as u64,
    }
}

fn dense(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

/// `spec` streamed into bricks of `edge`, keeping `keep`.
fn streamed(spec: &str, edge: u32, l: PoolLimits, keep: Option<[[u32; 3]; 2]>) -> Volume {
    let series = Series::open(spec, &LoadOptions::default()).unwrap();
    series.load_bricks(0, &StreamTo::new(edge, l).keep(keep)).unwrap()
}

fn host(v: &Volume) -> &lacuna::volume::HostPool {
    match &v.data {
        VoxelData::Bricks(p) => p,
        _ => panic!("{} was not streamed", v.name),
    }
}

#[test]
fn a_streamed_pool_is_the_planned_pool_byte_for_byte() {
    // Odd dims; an edge that divides nothing, the default, and a pool split
    // over several images.
    for (spec, edge, max_bytes) in [
        ("nbody:37x29x45", 4, u64::MAX),
        ("nbody:37x29x45", 16, u64::MAX),
        ("nbody:48", 8, 100_000),
    ] {
        let d = dense(spec);
        let s = streamed(spec, edge, limits(max_bytes), None);
        let planned = PoolLayout::of_volume(&d, edge, limits(max_bytes)).unwrap();
        let p = host(&s);
        assert_eq!(p.layout.table, planned.table, "{spec}/{edge}");
        assert_eq!(p.layout.stored, planned.stored);
        assert_eq!(p.layout.values, planned.values);
        assert_eq!(p.layout.images, planned.images);
        assert!(planned.images.len() > 1 || max_bytes == u64::MAX);
        let VoxelData::U8(bytes) = &d.data else {
            panic!("nbody is u8")
        };
        for k in 0..planned.images.len() {
            let mut want = vec![0u8; planned.image_bytes(k) as usize];
            planned.fill(k, bytes, &mut want);
            let mut got = vec![0u8; want.len()];
            p.fill(k, 0, &mut got);
            assert!(got == want, "{spec}/{edge}: image {k} differs");
        }
        // Every voxel through the table, and the volume's own fields.
        assert!((0..d.data.len()).all(|i| s.data.texel(i) == d.data.texel(i)));
        assert_eq!((s.dims, s.value_range, s.norm), (d.dims, d.value_range, d.norm));
        assert_eq!(
            (s.name.as_str(), s.default_tf.as_deref()),
            (d.name.as_str(), d.default_tf.as_deref())
        );
    }
}

#[test]
fn every_generator_streams_its_layers_as_it_generates_them() {
    // Odd dims, a step of each animation, bricks of 4 and 16; whole, and a
    // rank's layers only (normalised by the agreed range).
    for spec in [
        "menger:37x29x45:2",
        "vessels:37x29x45",
        "turbulence:37x29x45",
        "shells:37x29x45",
    ] {
        for (time, edge) in [(0, 4), (5, 16)] {
            let series = Series::open(spec, &LoadOptions::default()).unwrap();
            let d = series.load(time, None).unwrap();
            let s = Series::open(spec, &LoadOptions::default())
                .unwrap()
                .load_bricks(time, &StreamTo::new(edge, limits(u64::MAX)))
                .unwrap();
            let planned = PoolLayout::of_volume(&d, edge, limits(u64::MAX)).unwrap();
            assert_eq!(host(&s).layout.table, planned.table, "{spec} step {time}");
            assert!(
                (0..d.data.len()).all(|i| s.data.texel(i) == d.data.texel(i)),
                "{spec} step {time}"
            );
            assert_eq!((s.value_range, s.norm, &s.name), (d.value_range, d.norm, &d.name));
        }
        let d = dense(spec);
        let whole = (d.value_range[0], d.value_range[1]);
        let heard = std::sync::Arc::new(std::sync::Mutex::new(0u32));
        let seen = heard.clone();
        let keep = [[0, 0, 1], [3, 2, 2]];
        let to = StreamTo::new(16, limits(u64::MAX))
            .keep(Some(keep))
            .across(std::sync::Arc::new(move |_| Ok(whole)))
            .progress(std::sync::Arc::new(move |_, total| *seen.lock().unwrap() = total));
        let s = Series::open(spec, &LoadOptions::default())
            .unwrap()
            .load_bricks(0, &to)
            .unwrap();
        // Layers 16 to 32, and the border layer after them.
        assert_eq!(*heard.lock().unwrap(), 17, "{spec}: layers made");
        assert_eq!((s.value_range, s.norm), (d.value_range, d.norm), "{spec}");
        for z in 16..32 {
            for y in 0..29 {
                for x in 0..37 {
                    let i = d.index(x, y, z);
                    assert_eq!(s.data.texel(i), d.data.texel(i), "{spec}: voxel {x},{y},{z}");
                }
            }
        }
    }
}

#[test]
fn a_raw_file_streams_as_it_loads() {
    let dir = tempfile::tempdir().unwrap();
    let (path, bytes) = raw_u16(dir.path());
    let dims = [23u32, 17, 29];
    let spec = path.to_str().unwrap();
    let d = dense(spec);
    let s = streamed(spec, 4, limits(u64::MAX), None);
    let planned = PoolLayout::of_volume(&d, 4, limits(u64::MAX)).unwrap();
    assert_eq!(host(&s).layout.table, planned.table);
    assert!(planned.constant_bricks > 0);
    assert!((0..d.data.len()).all(|i| s.data.texel(i) == d.data.texel(i)));
    assert_eq!(
        (s.value_range, s.norm, s.source_type),
        (d.value_range, d.norm, VoxelType::U16)
    );
    // A file shorter than its dims is refused before any layer is read.
    let short = dir.path().join("short_23x17x29_uint16.raw");
    std::fs::write(&short, &bytes[..bytes.len() - 2]).unwrap();
    let series = Series::open(short.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let e = series
        .load_bricks(0, &StreamTo::new(16, limits(u64::MAX)))
        .unwrap_err()
        .to_string();
    assert!(e.contains("needs 22678"), "{e}");
    // --dims and --type name a file's layout as its name does.
    let options = LoadOptions {
        raw: Some(RawLayout {
            dims,
            ty: VoxelType::U16,
        }),
        ..LoadOptions::default()
    };
    let plain = dir.path().join("plain.bin");
    std::fs::write(&plain, &bytes).unwrap();
    let series = Series::open(plain.to_str().unwrap(), &options).unwrap();
    assert_eq!(series.streamed_layout(), Some((dims, VoxelType::U16)));
    let v = series.load_bricks(0, &StreamTo::new(4, limits(u64::MAX))).unwrap();
    assert_eq!(host(&v).layout.table, planned.table);
}

/// Every brick `p` stores lies in `keep`.
fn assert_stores_only(p: &lacuna::volume::HostPool, keep: [[u32; 3]; 2], spec: &str) {
    let counts = p.layout.counts;
    for &b in &p.layout.stored {
        let c = [b % counts[0], b / counts[0] % counts[1], b / (counts[0] * counts[1])];
        assert!(
            (0..3).all(|a| c[a] >= keep[0][a] && c[a] < keep[1][a]),
            "{spec}: brick {c:?} stored"
        );
    }
}

#[test]
fn a_kept_region_stores_only_its_bricks_and_normalises_by_the_whole() {
    let d = dense("nbody:64");
    let keep = [[1, 0, 0], [3, 4, 2]];
    let s = streamed("nbody:64", 16, limits(u64::MAX), Some(keep));
    let p = host(&s);
    assert_stores_only(p, keep, "nbody:64");
    let whole = PoolLayout::of_volume(&d, 16, limits(u64::MAX)).unwrap();
    assert!(p.layout.stored.len() < whole.stored.len());
    // Inside the kept bricks every voxel is the volume's.
    for z in 0..32 {
        for y in 0..64 {
            for x in 16..48 {
                let i = d.index(x, y, z);
                assert_eq!(s.data.texel(i), d.data.texel(i));
            }
        }
    }
    assert_eq!((s.value_range, s.norm), (d.value_range, d.norm));
}

/// A uint16 raw file of odd dims with a constant slab (x < 9) and a
/// varying rest, named for its layout; its bytes.
fn raw_u16(dir: &std::path::Path) -> (std::path::PathBuf, Vec<u8>) {
    let dims = [23u32, 17, 29];
    let mut bytes = Vec::new();
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let v: u16 = if x < 9 { 7 } else { (x * 31 + y * 7 + z * 1013) as u16 };
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    let path = dir.join("slabs_23x17x29_uint16.raw");
    std::fs::write(&path, &bytes).unwrap();
    (path, bytes)
}

/// The least and greatest stored value of layers `z` of a dense volume.
fn layers_range(v: &Volume, z: std::ops::Range<u32>) -> (f64, f64) {
    let [w, h, _] = v.dims;
    let stored = |i: usize| -> f64 {
        match &v.data {
            VoxelData::U8(b) => b[i] as f64,
            VoxelData::U16(b) => b[i] as f64,
            _ => panic!("{} is not an integer volume", v.name),
        }
    };
    let n = (w * h) as usize;
    (z.start as usize * n..z.end as usize * n)
        .map(stored)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)))
}

#[test]
fn a_rank_streams_only_its_layers_and_normalises_by_the_agreed_range() {
    let dir = tempfile::tempdir().unwrap();
    let (raw, _) = raw_u16(dir.path());
    // Blocks in the middle, at either end, and one brick row thick.
    for (spec, edge, keep) in [
        ("nbody:37x29x45", 8, [[0, 1, 2], [3, 4, 4]]),
        ("nbody:37x29x45", 8, [[2, 0, 0], [5, 4, 1]]),
        ("nbody:37x29x45", 16, [[0, 0, 1], [3, 2, 3]]),
        (raw.to_str().unwrap(), 4, [[1, 1, 3], [6, 5, 5]]),
        (raw.to_str().unwrap(), 4, [[0, 0, 7], [6, 5, 8]]),
    ] {
        let d = dense(spec);
        let whole = layers_range(&d, 0..d.dims[2]);
        // The layers the kept bricks' slots hold: their rows and one more.
        let layers = keep[0][2] * edge..(keep[1][2] * edge + 1).min(d.dims[2]);
        assert!(layers.len() < d.dims[2] as usize);
        let (heard, progress) = (
            std::sync::Arc::new(std::sync::Mutex::new(Vec::new())),
            std::sync::Arc::new(std::sync::Mutex::new(0)),
        );
        let (log, seen) = (heard.clone(), progress.clone());
        let to = StreamTo::new(edge, limits(u64::MAX))
            .keep(Some(keep))
            .across(std::sync::Arc::new(move |mine| {
                log.lock().unwrap().push(mine);
                Ok(whole)
            }))
            .progress(std::sync::Arc::new(move |_, total| *seen.lock().unwrap() = total));
        let series = Series::open(spec, &LoadOptions::default()).unwrap();
        let s = series.load_bricks(0, &to).unwrap();
        // Asked once, with the range of its own layers; told the whole's.
        assert_eq!(
            *heard.lock().unwrap(),
            vec![Some(layers_range(&d, layers.clone()))],
            "{spec}"
        );
        assert_eq!(
            *progress.lock().unwrap(),
            layers.len() as u32,
            "{spec}: layers streamed"
        );
        assert_eq!((s.value_range, s.norm), (d.value_range, d.norm), "{spec}");
        // Only kept bricks stored, and every voxel of their slots is the
        // volume's.
        let p = host(&s);
        assert_stores_only(p, keep, spec);
        let [lo, hi] = keep.map(|k| [0, 1, 2].map(|a| (k[a] * edge).min(d.dims[a])));
        for z in lo[2]..hi[2] {
            for y in lo[1]..hi[1] {
                for x in lo[0]..hi[0] {
                    let i = d.index(x, y, z);
                    assert_eq!(s.data.texel(i), d.data.texel(i), "{spec}: voxel {x},{y},{z}");
                }
            }
        }
        // The slots, border layers included, are those of the whole stream.
        let all_layers = streamed(spec, edge, limits(u64::MAX), Some(keep));
        let q = host(&all_layers);
        assert_eq!(
            (&p.layout.stored, &p.layout.images),
            (&q.layout.stored, &q.layout.images)
        );
        assert!((0..p.layout.stored.len()).all(|k| p.slot(k) == q.slot(k)), "{spec}");
        // A brick row not streamed holds one value of the volume.
        let values: std::collections::HashSet<_> = (0..d.data.len()).map(|i| d.data.texel(i).to_bits()).collect();
        assert!(
            (0..s.data.len()).all(|i| values.contains(&s.data.texel(i).to_bits())),
            "{spec}"
        );
    }
}

#[test]
fn a_failed_stream_still_agrees_and_reports_its_own_error() {
    let heard = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let log = heard.clone();
    let to = StreamTo::new(4, limits(u64::MAX))
        .keep(Some([[0, 0, 1], [2, 2, 2]]))
        .across(std::sync::Arc::new(move |mine| {
            log.lock().unwrap().push(mine);
            Err(lacuna::Error::Elsewhere("streaming the volume".into()))
        }));
    // This process's feed fails: it still takes part, with no range, and
    // its own error is what it reports.
    let e = to
        .run([8, 8, 8], 1, |_, layers| {
            assert_eq!(layers, 4..8);
            Err(lacuna::Error::invalid("layer", "4", "unreadable"))
        })
        .unwrap_err();
    assert!(e.to_string().starts_with("invalid layer '4'"), "{e}");
    // Its feed succeeds but another's failed: the agreement's error.
    let e = to
        .run([8, 8, 8], 1, |stream, layers| {
            stream.push(&vec![3u8; 64 * layers.len()])
        })
        .unwrap_err();
    assert!(matches!(e, lacuna::Error::Elsewhere(_)), "{e}");
    assert_eq!(*heard.lock().unwrap(), vec![None, Some((3.0, 3.0))]);
}

#[test]
fn every_structure_renders_a_streamed_volume_as_the_dense_one() {
    let tf = TransferFunction::parse("ramp:0.35:1").unwrap();
    // Three of the standard views: oblique, axis-aligned, perspective inside.
    let views: Vec<_> = standard_views()
        .into_iter()
        .enumerate()
        .filter(|(i, _)| [0, 2, 6].contains(i))
        .map(|(_, v)| v)
        .collect();
    let d = dense("nbody:37x29x45");
    let from_dense = Fixture::new().check("nbody dense", &d, &tf, &views);
    let s = streamed("nbody:37x29x45", 16, PoolLimits::of(common::gpu().info()), None);
    let from_stream = Fixture::with_bricks(16).check("nbody streamed", &s, &tf, &views);
    for (i, (a, b)) in from_dense.iter().zip(&from_stream).enumerate() {
        let st = diff(a, b).unwrap();
        assert_eq!(st.differing, 0, "view {i}: {st:?}");
    }
}

#[test]
fn render_streams_what_does_not_fit_and_says_so() {
    // Auto streams where the dense image passes the device's 3D limit.
    let ctx = common::gpu();
    let too_long = format!("nbody:{}x3x2", ctx.info().max_image_dimension_3d + 1);
    drop(ctx);
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.exr");
    let r = lacuna(
        &[
            "render",
            &too_long,
            "--size",
            "32x32",
            "--validate",
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("storage bricks of 16^3"), "{}", r.stdout);
    assert!(r.stdout.contains("streamed into bricks"), "{}", r.stdout);
    assert!(r.stdout.contains("host peak"), "{}", r.stdout);
    // An explicit dense store of it is refused by that limit.
    fails(
        &["render", &too_long, "--size", "32x32", "--storage", "dense"],
        &[],
        "maxImageDimension3D",
    );
    // Bricks asked for a small volume stream too, and say so.
    let r = lacuna(
        &[
            "render",
            "nbody:40",
            "--size",
            "32x32",
            "--storage",
            "bricks",
            "--validate",
        ],
        &[],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("streamed into bricks"), "{}", r.stdout);
    let r = lacuna(&["render", "nbody:40", "--size", "32x32", "--validate"], &[]);
    assert!(
        r.stdout.contains("storage dense") && !r.stdout.contains("streamed"),
        "{}",
        r.stdout
    );
}

#[test]
fn a_broken_stream_is_an_error() {
    let l = limits(u64::MAX);
    let mut s = PoolStream::new([8, 8, 8], 1, 4, l, None).unwrap();
    let e = s.push(&[0u8; 65]).unwrap_err().to_string();
    assert!(e.contains("whole layers of 64 bytes"), "{e}");
    s.push(&[0u8; 64 * 3]).unwrap();
    let e = s.finish(l).unwrap_err().to_string();
    assert!(e.contains("3 of 8 layers"), "{e}");
    let mut s = PoolStream::new([8, 8, 8], 1, 4, l, None).unwrap();
    let e = s.push(&[0u8; 64 * 9]).unwrap_err().to_string();
    assert!(e.contains("up to layer 8"), "{e}");
    assert!(PoolStream::new([8, 8, 8], 1, 0, l, None).is_err());
}

#[test]
fn progress_hears_every_brick_row_in_order() {
    let heard = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let log = heard.clone();
    let to = StreamTo::new(16, limits(u64::MAX)).progress(std::sync::Arc::new(move |done, total| {
        log.lock().unwrap().push((done, total));
    }));
    let series = Series::open("nbody:40x30x50", &LoadOptions::default()).unwrap();
    series.load_bricks(0, &to).unwrap();
    let heard = heard.lock().unwrap();
    // Rows of 16 layers, each heard once its next row's first layer is in.
    assert_eq!(*heard, vec![(17, 50), (33, 50), (49, 50), (50, 50)]);
}

/// A streamed volume uploaded dense (a library caller may) gets the dense
/// volume's cells copy, word for word, packed from the pool block by block.
#[test]
fn a_streamed_volume_uploaded_dense_has_the_dense_cells_copy() {
    let ctx = common::gpu();
    let d = dense("nbody:37x29x45");
    let s = streamed("nbody:37x29x45", 16, PoolLimits::of(ctx.info()), None);
    let want: Vec<u8> = bytemuck::cast_slice(&cells_words(&d)).to_vec();
    let mut gv = GpuVolume::upload_as(&ctx, &s, Storage::Dense).unwrap();
    gv.add_cells(&s).unwrap();
    let got = gv.cells().unwrap().buffer().download(0, want.len() as u64).unwrap();
    assert!(
        got == want,
        "the streamed volume's cells copy differs from the dense one's"
    );
    common::assert_clean(&ctx);
}
