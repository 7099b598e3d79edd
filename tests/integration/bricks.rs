//! Bricked storage: the pool holds every voxel the dense image holds (the
//! table walked on the CPU as the shaders walk it), constant bricks are left
//! out, every structure in every mode renders the dense volume's frames bit
//! for bit from it (odd dims, a brick edge that divides nothing, and the
//! default one; u16 texels, NaN-masked floats, two channels and a pool over
//! four images with every structure where the ranges decide and naive in
//! every mode), and bad storage requests are one-line errors.

use crate::common::identity::{every_look, standard_views, Fixture, Kernels, DEFAULTS};
use crate::common::{assert_clean, fails, gpu, lacuna, masked};
use lacuna::accel::Structure;
use lacuna::frame::{diff, Frame};
use lacuna::render::{Filter, FrameDesc, Mode};
use lacuna::volume::{GpuVolume, LoadOptions, PoolLayout, PoolLimits, Storage, VoxelData, VoxelType, POOL_BRICK};
use lacuna::{TransferFunction, Volume};

/// Limits of `max_image_dim` texels a side and `max_image_bytes` an image.
fn limits(max_image_dim: u32, max_image_bytes: u64) -> PoolLimits {
    PoolLimits {
        max_image_dim,
        max_image_bytes,
        max_table_entries: i32::MAX as u64,
    }
}

fn load(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

fn tf_of(v: &Volume) -> TransferFunction {
    TransferFunction::parse(v.default_tf.as_deref().unwrap_or("ramp:0.2:1")).unwrap()
}

/// u16 texels on odd dims: zero in x < 9, the value 7 in the slab
/// 9 <= x < 14, and a varying pattern beyond.
fn slabs() -> (Vec<u8>, [u32; 3]) {
    let dims = [23, 17, 29];
    let mut texels = Vec::new();
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let v: u16 = match x {
                    0..=8 => 0,
                    9..=13 => 7,
                    _ => (x * 31 + y * 7 + z * 1013) as u16,
                };
                texels.extend_from_slice(&v.to_le_bytes());
            }
        }
    }
    (texels, dims)
}

/// `v` as u16 texels spread over the range (a wider texel than u8).
fn wide(v: &Volume) -> Volume {
    let VoxelData::U8(bytes) = &v.data else {
        panic!("a u8 generator")
    };
    let data = bytes.iter().map(|&b| b as u16 * 251).collect();
    let mut w = Volume::new("wide", v.dims, v.spacing, VoxelType::U16, VoxelData::U16(data)).unwrap();
    w.default_tf = v.default_tf.clone();
    w
}

/// The pool texel of voxel v as `brick_texel` in glsl/common/bricks.glsl
/// finds it: (texel, step, image).
fn brick_texel(p: &PoolLayout, v: [i64; 3]) -> ([i64; 3], i64, usize) {
    let e = p.edge as i64;
    let b = v.map(|c| c / e);
    let n = p.counts.map(|c| c as i64);
    let [w0, w1] = p.table[(b[0] + n[0] * (b[1] + n[1] * b[2])) as usize];
    let step = 1 - (w1 >> 31) as i64;
    let origin = [(w0 & 0xffff) as i64, (w0 >> 16) as i64, (w1 & 0xffff) as i64];
    let image = ((w1 >> 16) & 0x7fff) as usize;
    ([0, 1, 2].map(|a| origin[a] + (v[a] - b[a] * e) * step), step, image)
}

#[test]
fn every_cell_read_through_the_table_is_the_dense_cell() {
    let (texels, dims) = slabs();
    // Edges from 1 to the longest side; 4 also split over images of at most
    // 50 slots of 5^3 u16 texels.
    let cases = [
        (1, u64::MAX),
        (4, u64::MAX),
        (4, 50 * 250),
        (5, u64::MAX),
        (8, u64::MAX),
        (29, u64::MAX),
    ];
    for (edge, max_bytes) in cases {
        let p = PoolLayout::plan(&texels, dims, 2, edge, limits(4096, max_bytes)).unwrap();
        assert_eq!(
            p.images.len() > 1,
            max_bytes < u64::MAX,
            "edge {edge}: {} images",
            p.images.len()
        );
        let pools: Vec<Vec<u8>> = (0..p.images.len())
            .map(|k| {
                assert!(p.image_bytes(k) <= max_bytes);
                let mut pool = vec![0u8; p.image_bytes(k) as usize];
                p.fill(k, &texels, &mut pool);
                pool
            })
            .collect();
        let texel_at = |bytes: &[u8], i: i64| u16::from_le_bytes([bytes[2 * i as usize], bytes[2 * i as usize + 1]]);
        let hi = dims.map(|d| d as i64 - 1);
        // Every cell whose low corner is -1 .. hi (the clamped apron the
        // samples read), each of its eight voxels, as cell_pool_texels.
        for z in -1..=hi[2] {
            for y in -1..=hi[1] {
                for x in -1..=hi[0] {
                    let i = [x, y, z];
                    let lo = [0, 1, 2].map(|a| i[a].clamp(0, hi[a]));
                    let up = [0, 1, 2].map(|a| (i[a] + 1).clamp(0, hi[a]));
                    let (at, step, image) = brick_texel(&p, lo);
                    let ext = p.extent(image).map(|e| e as i64);
                    for b in 0..8 {
                        let corner = [b & 1, (b >> 1) & 1, (b >> 2) & 1];
                        let t = [0, 1, 2].map(|a| at[a] + (up[a] - lo[a]) * step * corner[a]);
                        assert!(
                            (0..3).all(|a| t[a] < ext[a]),
                            "edge {edge}: texel {t:?} outside the pool"
                        );
                        let pooled = texel_at(&pools[image], t[0] + ext[0] * (t[1] + ext[1] * t[2]));
                        let v = [0, 1, 2].map(|a| if corner[a] == 1 { up[a] } else { lo[a] });
                        let dense = texel_at(&texels, v[0] + dims[0] as i64 * (v[1] + dims[1] as i64 * v[2]));
                        assert_eq!(pooled, dense, "edge {edge}, cell {i:?}, corner {b}");
                    }
                }
            }
        }
        // The two constant slabs are left out where a whole slot is one of
        // them, each value stored once.
        let total = p.counts.iter().product::<u32>() as u64;
        assert_eq!(p.stored.len() as u64 + p.constant_bricks, total);
        if edge <= 4 {
            // (Edge 1 also leaves out single voxels at the far corner.)
            assert!(p.constant_bricks > 0, "edge {edge}: {:?}", p.stats());
            // The 7 slab is 5 voxels wide: slots of 2 voxels fit inside it.
            let kept: &[[u8; 2]] = if edge == 1 { &[[0, 0], [7, 0]] } else { &[[0, 0]] };
            for v in kept {
                assert_eq!(
                    p.values.iter().filter(|x| *x == v).count(),
                    1,
                    "edge {edge}: {v:?} once"
                );
            }
        }
    }
}

#[test]
fn a_pool_past_the_device_limits_is_an_error_naming_the_limit() {
    let (texels, dims) = slabs();
    // 3-texel slots: 12-texel sides hold 4^3 slots an image, and four
    // images hold fewer than the ~1500 needed.
    let e = PoolLayout::plan(&texels, dims, 2, 2, limits(12, u64::MAX))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("12 texels a side (maxImageDimension3D)") && e.contains("brick pool"),
        "{e}"
    );
    let e = PoolLayout::plan(&texels, dims, 2, 2, limits(4096, 5400))
        .unwrap_err()
        .to_string();
    assert!(e.contains("of at most 5400 bytes (maxMemoryAllocationSize"), "{e}");
    let e = PoolLayout::plan(&texels, dims, 2, 0, limits(4096, u64::MAX))
        .unwrap_err()
        .to_string();
    assert!(e.contains("invalid brick edge '0'"), "{e}");
    let e = PoolLayout::plan(&texels, dims, 2, 30, limits(4096, u64::MAX))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("is longer than the volume's longest side (29 voxels; `bricks` alone means bricks:16): take bricks:EDGE with EDGE at most 29, or dense"),
        "{e}"
    );
    let few = PoolLimits {
        max_table_entries: 100,
        ..limits(4096, u64::MAX)
    };
    let e = PoolLayout::plan(&texels, dims, 2, 4, few).unwrap_err().to_string();
    assert!(
        e.contains("of 240 bricks of 4^3") && e.contains("maxTexelBufferElements"),
        "{e}"
    );
    let e = PoolLayout::plan(&texels[1..], dims, 2, 4, limits(4096, u64::MAX))
        .unwrap_err()
        .to_string();
    assert!(e.contains("brick pool"), "{e}");
    assert_eq!(Storage::parse("bricks").unwrap(), Storage::BRICKS);
    assert_eq!(Storage::parse("bricks:9").unwrap(), Storage::Bricks { edge: 9 });
    for bad in ["brick", "bricks:0", "bricks:x", "dense:4", ""] {
        let e = Storage::parse(bad).unwrap_err().to_string();
        assert!(e.starts_with(&format!("invalid storage '{bad}'")), "{e}");
    }
}

/// The naive frames of `views` of `v` on `fx` (in bricks where `fx.bricks`
/// says), with the manual filter.
fn naive_frames(fx: &Fixture, v: &Volume, tf: &TransferFunction, views: &[FrameDesc]) -> Vec<Frame> {
    let p = fx.prepare(v, tf, DEFAULTS);
    views
        .iter()
        .map(|view| fx.frame(&Structure::naive(), &p, view, Filter::Manual))
        .collect()
}

/// As `naive_frames`, uploaded dense.
fn dense_naive(fx: &mut Fixture, v: &Volume, tf: &TransferFunction, views: &[FrameDesc]) -> Vec<Frame> {
    let bricks = fx.bricks.take();
    let frames = naive_frames(fx, v, tf, views);
    fx.bricks = bricks;
    frames
}

fn assert_same(what: &str, a: &[Frame], b: &[Frame]) {
    for (i, (a, b)) in a.iter().zip(b).enumerate() {
        let d = diff(a, b).unwrap();
        assert_eq!(d.differing, 0, "{what}, view {i}: bricks vs dense: {d}");
    }
}

/// Which looks every structure is checked in over bricks (naive is checked
/// in all of them).
type Looks = fn(&Mode, bool) -> bool;

/// Every look.
fn all_looks(_: &Mode, _: bool) -> bool {
    true
}

/// Naive over bricks of each edge equals naive over the dense image in
/// every look; every structure over bricks equals naive over bricks in the
/// looks `structures_in` picks (given the mode and whether it is shaded).
fn check_every_look(what: &str, v: &Volume, edges: &[u32], structures_in: Looks) {
    let t = tf_of(v);
    let views = &standard_views()[..3];
    // One context for every look and edge, so the kernels every look shares
    // (ranges, builds, the LUT) are created once.
    let mut fx = Fixture::new();
    let limits = PoolLimits::of(fx.ctx.info());
    for (mode, shading) in every_look() {
        // Lit looks read one channel (tests/integration/channels.rs).
        if (shading.is_some() || matches!(mode, Mode::Iso(_))) && v.channel_count() > 1 {
            continue;
        }
        let views: Vec<FrameDesc> = views
            .iter()
            .map(|d| d.to_builder().mode(mode).shading(shading).build().unwrap())
            .collect();
        let dense = dense_naive(&mut fx, v, &t, &views);
        for &edge in edges {
            fx.bricks = Some((edge, limits));
            let what = format!("{what} {} bricks of {edge}", mode.name());
            let bricked = match structures_in(&mode, shading.is_some()) {
                true => fx.check_with(&what, v, &t, &views, &[DEFAULTS], Kernels::Reported),
                false => naive_frames(&fx, v, &t, &views),
            };
            assert_same(&what, &dense, &bricked);
        }
    }
    fx.bricks = None;
    assert_clean(&fx.ctx);
}

#[test]
fn every_structure_on_bricks_equals_dense_naive_in_every_look() {
    // Odd dims; 5 divides none of them, 32 leaves partial bricks.
    check_every_look("vessels", &load("vessels:45x37x51"), &[5, POOL_BRICK], all_looks);
}

/// Every structure in the looks whose skipping reads the ranges by a rule of
/// its own: composite (the transfer function's opacity), MIP (the running
/// maximum) and iso (a value between the extremes). Shaded composite
/// classifies as composite does (docs/structures.md), MinIP mirrors MIP's
/// rule, and average is marched naively by every structure: naive checks
/// those looks' samples over bricks. (`every_structure_on_bricks_...`
/// keeps every structure in every look.)
fn ranges_rules(mode: &Mode, shaded: bool) -> bool {
    !shaded && matches!(mode, Mode::Composite | Mode::Mip | Mode::Iso(_))
}

#[test]
fn a_pool_split_over_four_images_equals_dense() {
    // Slots of 6^3 u8 texels, at most 64 an image: vessels varies in about
    // 200 bricks of 5^3, so every one of the four images holds some.
    let v = load("vessels:30x27x33");
    let t = tf_of(&v);
    let mut fx = Fixture::new();
    let gv = GpuVolume::upload_bricks_within(&fx.ctx, &v, 5, limits(4096, 64 * 216)).unwrap();
    assert_eq!(gv.pool_image_count(), 4, "{:?}", gv.pool());
    let views = &standard_views()[..3];
    let bricked = Fixture::with_bricks_within(5, limits(4096, 64 * 216));
    for (mode, shading) in every_look() {
        let views: Vec<FrameDesc> = views
            .iter()
            .map(|d| d.to_builder().mode(mode).shading(shading).build().unwrap())
            .collect();
        let what = format!("four images {}", mode.name());
        let frames = match ranges_rules(&mode, shading.is_some()) {
            true => bricked.check_with(&what, &v, &t, &views, &[DEFAULTS], Kernels::Reported),
            false => naive_frames(&bricked, &v, &t, &views),
        };
        assert_same(&what, &dense_naive(&mut fx, &v, &t, &views), &frames);
    }
    assert_clean(&bricked.ctx);
    assert_clean(&fx.ctx);
}

#[test]
fn bricks_of_wide_texels_nan_and_channels_equal_dense() {
    check_every_look("nbody u16", &wide(&load("nbody:33x41x27")), &[7], ranges_rules);
    check_every_look("masked float", &masked("shells:36"), &[6], ranges_rules);
    check_every_look(
        "two channels",
        &load("vessels:31x29x35+nbody:31x29x35"),
        &[5],
        ranges_rules,
    );
}

#[test]
fn bricked_storage_refuses_the_hardware_filter_and_dense_copies() {
    let ctx = gpu();
    let v = load("vessels:40");
    let mut gv = GpuVolume::upload_as(&ctx, &v, Storage::Bricks { edge: 8 }).unwrap();
    let pool = gv.pool().expect("bricked");
    assert_eq!((pool.edge, pool.stored + pool.constant), (8, 125));
    assert!(pool.constant > 0, "vessels has empty bricks: {pool}");
    assert_eq!(gv.default_filter(), Filter::Manual);
    let e = gv.sampler_for(Filter::Hardware).unwrap_err().to_string();
    assert!(e.contains("manual filter only"), "{e}");
    let e = gv.add_cells(&v).unwrap_err().to_string();
    assert!(e.contains("bricked storage"), "{e}");
    // Auto is dense where the dense image fits.
    let auto = GpuVolume::upload(&ctx, &v).unwrap();
    assert!(auto.pool().is_none());
    assert_clean(&ctx);
}

#[test]
fn render_and_info_report_the_pool_and_match_dense() {
    let dir = tempfile::tempdir().unwrap();
    let mut frames = Vec::new();
    for storage in ["dense", "bricks:8"] {
        let out = dir.path().join(format!("{storage}.exr").replace(':', "_"));
        let r = lacuna(
            &[
                "render",
                "nbody:40x36x44",
                "--size",
                "48x40",
                "--filter",
                "manual",
                "--storage",
                storage,
                "--validate",
                "--out",
                out.to_str().unwrap(),
            ],
            &[],
        );
        assert_eq!(r.code, 0, "{}", r.stderr);
        let line = r
            .stdout
            .lines()
            .find(|l| l.starts_with("storage "))
            .unwrap()
            .to_string();
        if storage == "dense" {
            assert!(line.starts_with("storage dense ("), "{line}");
        } else {
            assert!(line.contains("bricks of 8^3: ") && line.contains("x dense"), "{line}");
        }
        frames.push(Frame::read_exr(&out).unwrap());
    }
    assert_same("render --storage", &frames[..1], &frames[1..]);
    let r = lacuna(&["info", "vessels:48", "--storage", "bricks:16"], &[]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("storage  bricks of 16^3: "), "{}", r.stdout);
    assert!(r.stdout.contains(" constant; pool "), "{}", r.stdout);
    // Without --storage: what auto resolves to, and what bricks would keep;
    // a volume shorter than the default brick is dense, with no complaint.
    let r = lacuna(&["info", "vessels:48"], &[]);
    assert!(r.stdout.contains("storage  dense (--storage auto, on "), "{}", r.stdout);
    assert!(r.stdout.contains("         bricks of 16^3: 27 stored"), "{}", r.stdout);
    assert!(r.stdout.contains("(with --storage bricks)\n"), "{}", r.stdout);
    // Dense asked for is checked against the device too.
    let dir = tempfile::tempdir().unwrap();
    let long = dir.path().join("long_5000x1x1_uint8.raw");
    std::fs::write(&long, [1u8; 5000]).unwrap();
    let r = lacuna(&["info", long.to_str().unwrap(), "--storage", "dense"], &[]);
    assert!(
        r.stdout.contains("storage  --storage dense does not fit ") && r.stdout.contains("maxImageDimension3D"),
        "{}",
        r.stdout
    );
    let r = lacuna(&["info", "menger:9"], &[]);
    assert!(
        r.stdout.contains("storage  dense (--storage auto") && !r.stdout.contains("does not fit"),
        "{}",
        r.stdout
    );
    fails(
        &["render", "vessels:32", "--storage", "sparse"],
        &[],
        "invalid storage 'sparse'",
    );
    fails(
        &["render", "vessels:32", "--storage", "bricks", "--filter", "hardware"],
        &[],
        "manual filter only",
    );
}

#[test]
fn a_volume_of_one_value_is_one_texel() {
    let ctx = gpu();
    let v = Volume::new(
        "flat",
        [19, 20, 21],
        [1.0; 3],
        VoxelType::U8,
        VoxelData::U8(vec![200; 19 * 20 * 21]),
    )
    .unwrap();
    let gv = GpuVolume::upload_as(&ctx, &v, Storage::Bricks { edge: 4 }).unwrap();
    let pool = gv.pool().unwrap();
    assert_eq!((pool.stored, pool.constant), (0, 5 * 5 * 6));
    assert_eq!(pool.pool_bytes, 125, "one slot of 5^3 texels holds the one value");
    // One value normalises to 0.
    let t = TransferFunction::parse("band:0:0.5:0.5").unwrap();
    let views = &standard_views()[..3];
    let mut fx = Fixture::with_bricks(4);
    let p = fx.prepare(&v, &t, DEFAULTS);
    let bricked: Vec<Frame> = views
        .iter()
        .map(|view| fx.frame(&Structure::naive(), &p, view, Filter::Manual))
        .collect();
    assert!(
        bricked.iter().all(|f| f.pixels.iter().any(|p| p[3] > 0.5)),
        "the value shows"
    );
    assert_same("flat", &dense_naive(&mut fx, &v, &t, views), &bricked);
    assert_clean(&ctx);
    assert_clean(&fx.ctx);
}

#[test]
fn a_recorded_bricked_upload_submits_nothing_and_renders_as_the_uploaded_one() {
    let ctx = gpu();
    let v = load("vessels:40");
    let tf = tf_of(&v);
    let storage = Storage::Bricks { edge: 8 };
    let uploaded = GpuVolume::upload_as(&ctx, &v, storage).unwrap();
    // One submission, this test's: the recorded upload (pool images and
    // brick table) adds none of its own.
    let before = ctx.submissions();
    let (recorded, staging) = ctx
        .submit_and_wait(|cmd| GpuVolume::record_upload_as(cmd, &v, storage))
        .unwrap();
    drop(staging);
    assert_eq!(ctx.submissions(), before + 1);
    assert!(recorded.pool().is_some(), "recorded in bricks");
    let renderer = lacuna::render::Renderer::new(&ctx).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    for az in [30.0, 200.0] {
        let desc = FrameDesc::builder(48, 48)
            .orbit(az, 20.0, lacuna::render::Projection::Orthographic)
            .filter(Filter::Manual)
            .build()
            .unwrap();
        let naive = Structure::naive();
        let a = crate::common::frame(&renderer, &naive, &uploaded, &lut, &desc);
        let b = crate::common::frame(&renderer, &naive, &recorded, &lut, &desc);
        assert!(a.pixels.iter().any(|p| p[3] > 0.1), "the frame shows the volume");
        assert_same("recorded bricks", &[a], &[b]);
    }
    assert_clean(&ctx);
}
