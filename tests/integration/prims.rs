//! GPU primitives against CPU references: scan, compaction, radix sort (keys
//! and payloads, stability) and brick min/max (from the volume, and coarser
//! from finer), at the sizes and key patterns that break naive
//! implementations.

use crate::common::{assert_clean, gpu};
use lacuna::accel::builder::RangeKind;
use lacuna::accel::Builder;
use lacuna::gpu::{vk, Buffer, Context};
use lacuna::prims::brick_minmax::coarsens_exactly;
use lacuna::prims::{BlockLayout, BrickMinMax, Compact, RadixSort, Scan};
use lacuna::volume::{BrickGrid, GpuVolume, LoadOptions, VoxelData, VoxelType};
use lacuna::Volume;

const SIZES: [usize; 9] = [0, 1, 2, 255, 256, 257, 4097, 100_000, 1 << 20];

fn rng(seed: u64) -> impl FnMut() -> u32 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 32) as u32
    }
}

fn buffer(ctx: &Context, data: &[u32]) -> Buffer {
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    if data.is_empty() {
        return Buffer::new(ctx, "test", 4, usage, lacuna::gpu::MemoryLocation::GpuOnly).unwrap();
    }
    Buffer::with_data(ctx, "test", bytemuck::cast_slice(data), usage).unwrap()
}

fn read(b: &Buffer, n: usize) -> Vec<u32> {
    if n == 0 {
        return Vec::new();
    }
    bytemuck::pod_collect_to_vec(&b.download(0, n as u64 * 4).unwrap())
}

fn patterns(n: usize, seed: u64) -> Vec<(&'static str, Vec<u32>)> {
    let mut r = rng(seed);
    let random: Vec<u32> = (0..n).map(|_| r()).collect();
    let mut sorted = random.clone();
    sorted.sort();
    let reversed: Vec<u32> = sorted.iter().rev().cloned().collect();
    vec![
        ("random", random.clone()),
        ("sorted", sorted),
        ("reversed", reversed),
        ("all-equal", vec![0xDEAD_BEEF; n]),
        (
            "few-distinct",
            random.iter().map(|v| [3, 0, u32::MAX, 7][(*v % 4) as usize]).collect(),
        ),
        ("max-value", vec![u32::MAX; n]),
    ]
}

/// The device's layout, then the other layouts the kernels support.
fn layouts(ctx: &Context) -> Vec<BlockLayout> {
    let mine = BlockLayout::for_device(ctx.info());
    let mut all = vec![mine];
    for (width, items) in [(256, 4), (64, 16), (32, 32), (16, 64)] {
        let l = BlockLayout { width, items };
        if l != mine {
            all.push(l);
        }
    }
    all
}

#[test]
fn exclusive_scan_matches_the_cpu() {
    let ctx = gpu();
    for (li, layout) in layouts(&ctx).into_iter().enumerate() {
        let scan = Scan::with_layout(&ctx, layout).unwrap();
        // Other layouts: every size but the largest.
        let sizes = if li == 0 { &SIZES[..] } else { &SIZES[..8] };
        for &n in sizes {
            let scratch = scan.scratch(n as u64).unwrap();
            for (name, data) in patterns(n, n as u64) {
                // Small values as well as wrapping ones.
                let data: Vec<u32> = if name == "random" {
                    data.iter().map(|v| v % 1000).collect()
                } else {
                    data
                };
                let buf = buffer(&ctx, &data);
                ctx.submit_and_wait(|cmd| scan.record(cmd, &buf, n as u64, &scratch))
                    .unwrap();
                let mut acc = 0u32;
                let want: Vec<u32> = data
                    .iter()
                    .map(|v| {
                        let e = acc;
                        acc = acc.wrapping_add(*v);
                        e
                    })
                    .collect();
                assert_eq!(read(&buf, n), want, "scan of {n} {name} ({layout:?})");
            }
        }
    }
    assert_clean(&ctx);
}

#[test]
fn compaction_keeps_flagged_indices_in_order() {
    let ctx = gpu();
    let compact = Compact::new(&ctx).unwrap();
    for n in SIZES {
        let scratch = compact.scratch(n as u64).unwrap();
        let mut r = rng(7 + n as u64);
        for (name, flags) in [
            (
                "random",
                (0..n).map(|_| r().is_multiple_of(3) as u32).collect::<Vec<_>>(),
            ),
            ("none", vec![0; n]),
            ("all", vec![1; n]),
            ("sparse", (0..n).map(|i| (i % 977 == 5) as u32).collect()),
        ] {
            let f = buffer(&ctx, &flags);
            let out = buffer(&ctx, &vec![0xFFFF_FFFF; n.max(1)]);
            let count = buffer(&ctx, &[12345]);
            ctx.submit_and_wait(|cmd| compact.record(cmd, &f, n as u64, &out, &count, &scratch))
                .unwrap();
            let want: Vec<u32> = (0..n as u32).filter(|&i| flags[i as usize] != 0).collect();
            assert_eq!(read(&count, 1)[0] as usize, want.len(), "count of {n} {name}");
            assert_eq!(read(&out, want.len()), want, "indices of {n} {name}");
        }
    }
    assert_clean(&ctx);
}

fn check_sort(ctx: &Context, sort: &RadixSort, keys: &[u32], bits: u32, what: &str) {
    let n = keys.len();
    let scratch = sort.scratch(n as u64).unwrap();
    let vals: Vec<u32> = (0..n as u32).collect();
    let (kb, vb) = (buffer(ctx, keys), buffer(ctx, &vals));
    ctx.submit_and_wait(|cmd| sort.record(cmd, &kb, &vb, n as u64, bits, &scratch))
        .unwrap();
    let mask = if bits == 32 { u32::MAX } else { (1u32 << bits) - 1 };
    // Stable CPU sort by the low `bits` bits; payload = original index.
    let mut want: Vec<(u32, u32)> = keys.iter().cloned().zip(vals).collect();
    want.sort_by_key(|(k, _)| k & mask);
    let (got_k, got_v) = (read(&kb, n), read(&vb, n));
    assert!(
        got_k == want.iter().map(|w| w.0).collect::<Vec<_>>(),
        "{what}: keys differ"
    );
    assert!(
        got_v == want.iter().map(|w| w.1).collect::<Vec<_>>(),
        "{what}: payloads differ (not stable)"
    );
}

#[test]
fn radix_sort_is_stable_and_matches_the_cpu() {
    let ctx = gpu();
    for (li, layout) in layouts(&ctx).into_iter().enumerate() {
        let sort = RadixSort::with_layout(&ctx, layout).unwrap();
        let sizes = if li == 0 { &SIZES[..] } else { &SIZES[..7] };
        for &n in sizes {
            for (name, keys) in patterns(n, 99 + n as u64) {
                check_sort(&ctx, &sort, &keys, 32, &format!("{n} {name} keys, 32 bits, {layout:?}"));
            }
        }
    }
    let sort = RadixSort::new(&ctx).unwrap();
    // Fewer key bits: 30-bit codes (even passes) and 13 bits (odd passes,
    // high bits ignored, so equal low bits keep input order).
    let mut r = rng(5);
    let codes: Vec<u32> = (0..100_000).map(|_| r() & ((1 << 30) - 1)).collect();
    check_sort(&ctx, &sort, &codes, 30, "30-bit codes");
    let mixed: Vec<u32> = (0..4097).map(|_| r()).collect();
    check_sort(&ctx, &sort, &mixed, 13, "13 of 32 bits");
    assert_clean(&ctx);
}

#[test]
fn block_layouts_are_checked() {
    let ctx = gpu();
    for (w, i) in [(128, 4), (8, 128), (48, 21)] {
        let err = Scan::with_layout(&ctx, BlockLayout { width: w, items: i })
            .err()
            .unwrap();
        assert!(err.to_string().contains("block layout"), "{err}");
    }
}

#[test]
fn primitives_refuse_more_elements_than_their_scratch_or_buffers_hold() {
    let ctx = gpu();
    let (sort, scan, compact) = (
        RadixSort::new(&ctx).unwrap(),
        Scan::new(&ctx).unwrap(),
        Compact::new(&ctx).unwrap(),
    );
    let (sort_scratch, scan_scratch, compact_scratch) = (
        sort.scratch(8).unwrap(),
        scan.scratch(8).unwrap(),
        compact.scratch(8).unwrap(),
    );
    let four = buffer(&ctx, &[1, 2, 3, 4]);
    let eight = buffer(&ctx, &[0; 8]);
    let count = buffer(&ctx, &[0]);
    // Past the scratch (a panic before), and past a buffer.
    for (n, buffer) in [(9, "scratch holds 8"), (5, "buffer 'test' holds 16 bytes")] {
        let errs = [
            ctx.submit_and_wait(|cmd| sort.record(cmd, &four, &eight, n, 32, &sort_scratch)),
            ctx.submit_and_wait(|cmd| scan.record(cmd, &four, n, &scan_scratch)),
            ctx.submit_and_wait(|cmd| compact.record(cmd, &four, n, &eight, &count, &compact_scratch)),
        ];
        for err in errs {
            let err = err.unwrap_err();
            assert!(err.to_string().contains(buffer), "{n}: {err}");
        }
    }
    assert_clean(&ctx);
}

#[test]
fn radix_sort_rejects_bad_key_bits() {
    let ctx = gpu();
    let sort = RadixSort::new(&ctx).unwrap();
    let scratch = sort.scratch(4).unwrap();
    let b = buffer(&ctx, &[1, 2, 3, 4]);
    let err = ctx
        .submit_and_wait(|cmd| sort.record(cmd, &b, &b, 4, 33, &scratch))
        .unwrap_err();
    assert!(err.to_string().contains("key bits '33'"), "{err}");
}

#[test]
fn brick_minmax_matches_the_cpu_brick_grid() {
    let ctx = gpu();
    let mm = BrickMinMax::new(&ctx).unwrap();
    // Dense, and bricks of 5 and 16 (runs of a row per brick, constant
    // bricks read once).
    let cases = [
        ("turbulence:37x29x41", 0),
        ("vessels:40", 0),
        ("nbody:9x20x3", 0),
        ("vessels:40", 5),
        ("nbody:45x38x41", 16),
        ("turbulence:37x29x41", 5),
    ];
    for (spec, edge) in cases {
        let v = Volume::load(spec, &LoadOptions::default()).unwrap();
        let gv = match edge {
            0 => GpuVolume::upload(&ctx, &v).unwrap(),
            e => GpuVolume::upload_bricks(&ctx, &v, e).unwrap(),
        };
        if let (Some(pool), "vessels:40") = (gv.pool(), spec) {
            assert!(pool.constant > 0, "the constant-brick path runs: {pool}");
        }
        for apron in [0, 1] {
            let cpu = BrickGrid::new(&v, 8, apron);
            let out = buffer(&ctx, &vec![0; cpu.len() * 2]);
            ctx.submit_and_wait(|cmd| mm.record(cmd, &gv, 8, apron, &out)).unwrap();
            let got: Vec<f32> = bytemuck::cast_slice(&read(&out, cpu.len() * 2)).to_vec();
            for (i, r) in cpu.ranges.iter().enumerate() {
                assert!(
                    (got[2 * i] - r[0]).abs() < 1e-6 && (got[2 * i + 1] - r[1]).abs() < 1e-6,
                    "{spec} bricks {edge} apron {apron} brick {i}: {:?} vs {r:?}",
                    &got[2 * i..2 * i + 2]
                );
            }
        }
    }
    assert_clean(&ctx);
}

/// Coarser ranges made from finer ones (`Builder::ranges` makes cells of 8,
/// 16 and 32 from those of 4) are the ranges computed from the volume, bit
/// for bit: odd dims, floats with NaN-only bricks, two channels, bricked
/// storage.
#[test]
fn coarser_ranges_from_finer_ones_are_the_direct_ranges_bit_for_bit() {
    let ctx = gpu();
    let builder = Builder::new(&ctx).unwrap();
    let mm = BrickMinMax::new(&ctx).unwrap();
    let dims = [37u32, 29, 41];
    let n = (dims[0] * dims[1] * dims[2]) as usize;
    let floats: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y, z) = (i % 37, i / 37 % 29, i / (37 * 29));
            // A block of no data over whole 4^3 and 8^3 cells, and holes.
            if (x < 17 && y < 9 && z < 9) || i % 97 == 0 {
                f32::NAN
            } else {
                ((x * 3 + y * 7 + z * 5) % 23) as f32 * 0.7 - 4.0
            }
        })
        .collect();
    let float = Volume::new("floats", dims, [1.0; 3], VoxelType::F32, VoxelData::F32(floats)).unwrap();
    let load = |s: &str| Volume::load(s, &LoadOptions::default()).unwrap();
    let two = Volume::join(vec![load("vessels:37x29x41"), load("nbody:37x29x41")]).unwrap();
    let cases = [
        (load("turbulence:37x29x41"), 0),
        (float.clone(), 0),
        (two, 0),
        (load("nbody:45x38x41"), 16),
        (float, 5),
    ];
    for (v, edge) in cases {
        let gv = match edge {
            0 => GpuVolume::upload(&ctx, &v).unwrap(),
            e => GpuVolume::upload_bricks(&ctx, &v, e).unwrap(),
        };
        assert!(coarsens_exactly(&gv), "{}: its normalisation keeps order", v.name);
        let all = [4, 8, 16, 32].map(RangeKind::Cells);
        let (coarsened, _) = builder.ranges(&all, &gv).unwrap();
        // The kernel itself, cells of 16 from cells of 4, against the
        // builder's direct ranges (so the comparison below is not of two
        // direct computations).
        let (direct16, _) = builder.ranges(&[RangeKind::Cells(16)], &gv).unwrap();
        let want = &direct16.cells(16).unwrap().ranges();
        let out = buffer(&ctx, &vec![0; want.size() as usize / 4]);
        let fine = &coarsened.cells(4).unwrap().ranges();
        ctx.submit_and_wait(|cmd| mm.record_coarsen(cmd, &gv, (fine, 4), 16, &out))
            .unwrap();
        assert!(
            read(&out, want.size() as usize / 4) == read(want, want.size() as usize / 4),
            "{} (bricks {edge}): cells of 16 coarsened from 4 differ",
            v.name
        );
        for cell in [8, 16, 32] {
            let (direct, _) = builder.ranges(&[RangeKind::Cells(cell)], &gv).unwrap();
            let bytes = |r: &lacuna::accel::builder::Ranges| {
                let b = &r.cells(cell).unwrap().ranges();
                b.download(0, b.size()).unwrap()
            };
            assert!(
                bytes(&coarsened) == bytes(&direct),
                "{} (bricks {edge}): cell {cell} ranges differ",
                v.name
            );
        }
    }
    assert_clean(&ctx);
}

/// Ranges read from the volume's cells copy (a 2x2x2 block of voxels a
/// fetch) are the ranges read from its image, bit for bit: every texel
/// kind (each unorm value once), NaN floats, odd dims, a one-voxel axis,
/// edges from 1 (whose one-voxel boxes keep the image) to 8, aprons 0 to 2.
#[test]
fn ranges_from_the_cells_copy_are_the_images_bit_for_bit() {
    let ctx = gpu();
    let mm = BrickMinMax::new(&ctx).unwrap();
    let load = |s: &str| Volume::load(s, &LoadOptions::default()).unwrap();
    let ramp8 = VoxelData::U8((0..=255u8).rev().collect());
    let ramp16 = VoxelData::U16((0..=65535u16).map(|v| v.wrapping_mul(40503)).collect());
    let dims = [11u32, 7, 5];
    let floats = (0..385)
        .map(|i| {
            if i % 13 == 0 || i < 30 {
                f32::NAN
            } else {
                (i % 29) as f32 * 0.37 - 2.0
            }
        })
        .collect();
    let volumes = [
        load("nbody:19x11x9"),
        load("turbulence:9x1x7"),
        Volume::new("u8 ramp", [16, 4, 4], [1.0; 3], VoxelType::U8, ramp8).unwrap(),
        Volume::new("u16 ramp", [64, 32, 32], [1.0; 3], VoxelType::U16, ramp16).unwrap(),
        Volume::new("floats", dims, [1.0; 3], VoxelType::F32, VoxelData::F32(floats)).unwrap(),
    ];
    for v in volumes {
        let mut gv = GpuVolume::upload(&ctx, &v).unwrap();
        let cases: Vec<(u32, u32)> = [1, 2, 3, 4, 5, 8]
            .iter()
            .flat_map(|&b| [(b, 0), (b, 1), (b, 2)])
            .collect();
        let ranges = |gv: &GpuVolume| -> Vec<Vec<u32>> {
            cases
                .iter()
                .map(|&(brick, apron)| {
                    let n = lacuna::prims::brick_minmax::brick_counts(v.dims, brick)
                        .iter()
                        .product::<u32>();
                    let out = buffer(&ctx, &vec![0; 2 * n as usize]);
                    ctx.submit_and_wait(|cmd| mm.record(cmd, gv, brick, apron, &out))
                        .unwrap();
                    read(&out, 2 * n as usize)
                })
                .collect()
        };
        let from_image = ranges(&gv);
        gv.add_cells(&v).unwrap();
        let from_cells = ranges(&gv);
        for ((brick, apron), (a, b)) in cases.iter().zip(from_image.iter().zip(&from_cells)) {
            assert!(a == b, "{} brick {brick} apron {apron}: ranges differ", v.name);
        }
    }
    assert_clean(&ctx);
}
