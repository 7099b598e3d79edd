//! The GPU LBVH against the CPU reference (same topology and boxes), the
//! Karras emit with duplicate codes, classification modes, and empty/one/all
//! brick structures.

mod common;
use common::{assert_clean, gpu};
use lacuna::accel::lbvh::{cpu, Node};
use lacuna::accel::{BuildInput, BuildOptions, Builder, Classify, Stats};
use lacuna::volume::{BrickGrid, GpuVolume, VoxelData, VoxelType, BRICK};
use lacuna::{TransferFunction, Volume};

fn rng(seed: u64) -> impl FnMut() -> u32 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 33) as u32
    }
}

/// A volume whose bricks are bright or dark at random (probability p in 1/100).
fn random_bricks(dims: [u32; 3], p: u32, seed: u64) -> Volume {
    let mut r = rng(seed);
    let counts = dims.map(|d| d.div_ceil(BRICK));
    let lit: Vec<bool> = (0..counts.iter().product::<u32>()).map(|_| r() % 100 < p).collect();
    let mut data = vec![0u8; dims.iter().product::<u32>() as usize];
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let b = (x / BRICK) + counts[0] * ((y / BRICK) + counts[1] * (z / BRICK));
                if lit[b as usize] && (x + y + z) % 3 == 0 {
                    data[(x + dims[0] * (y + dims[1] * z)) as usize] = 200;
                }
            }
        }
    }
    Volume::new("random bricks", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap()
}

/// (dims, percent of bricks lit, seed) of the random-occupancy cases.
const OCCUPANCIES: [([u32; 3], u32, u64); 5] = [
    ([64, 64, 64], 30, 1),
    ([61, 35, 47], 10, 2),
    ([64, 64, 64], 100, 3),
    ([40, 8, 24], 3, 4),
    ([64, 64, 64], 1, 5),
];

/// The active bricks of `v` under `tf`, ascending (the CPU classification).
fn active_bricks(v: &Volume, tf: &TransferFunction) -> Vec<u32> {
    let grid = BrickGrid::new(v, BRICK, 1);
    (0..).zip(grid.active(tf)).filter(|(_, a)| *a).map(|(i, _)| i).collect()
}

fn gpu_lbvh(ctx: &lacuna::gpu::Context, v: &Volume, tf: &TransferFunction, classify: Classify) -> (Vec<Node>, u32) {
    let options = BuildOptions {
        classify,
        ..Default::default()
    };
    let (nodes, leaves, _) = gpu_lbvh_with(&Builder::new(ctx).unwrap(), v, tf, &options);
    (nodes, leaves)
}

/// The LBVH built with `options`: its nodes, its brick count and its statistics.
fn gpu_lbvh_with(
    builder: &Builder,
    v: &Volume,
    tf: &TransferFunction,
    options: &BuildOptions,
) -> (Vec<Node>, u32, Stats) {
    let ctx = builder.context();
    let gv = GpuVolume::upload(ctx, v).unwrap();
    let lut = tf.upload(ctx).unwrap();
    let (ranges, _) = builder.ranges(&gv, 16).unwrap();
    let scene = BuildInput {
        volume: v,
        gpu_volume: &gv,
        tf,
        gpu_tf: &lut,
    };
    let (s, t) = builder.build(common::accel("lbvh"), &scene, &ranges, options).unwrap();
    let l = s.tree().unwrap();
    for phase in ["classify", "compact", "morton", "sort", "emit", "refit"] {
        assert!(t.get(phase).is_some() || l.leaves == 0, "missing phase {phase}");
    }
    assert_eq!(t.get("collapse").is_some(), options.collapse && l.leaves > 0);
    (l.read_nodes().unwrap(), l.leaves, s.stats().unwrap().unwrap())
}

#[test]
fn gpu_lbvh_matches_the_cpu_reference_on_random_occupancy() {
    let ctx = gpu();
    let tf = TransferFunction::parse("band:0.5:1").unwrap();
    for (dims, p, seed) in OCCUPANCIES {
        let v = random_bricks(dims, p, seed);
        let active = active_bricks(&v, &tf);
        let want = cpu::build(&active, BrickGrid::new(&v, BRICK, 1).counts, dims, BRICK);
        let (got, leaves) = gpu_lbvh(&ctx, &v, &tf, Classify::Range);
        assert_eq!(leaves as usize, active.len(), "{dims:?} p={p}: active bricks");
        let first = got.iter().zip(&want).position(|(a, b)| a != b);
        assert!(
            first.is_none() && got.len() == want.len(),
            "{dims:?} p={p}: node {first:?} differs: {:?} vs {:?}",
            first.map(|i| got[i]),
            first.map(|i| want[i])
        );
    }
    assert_clean(&ctx);
}

#[test]
fn gpu_collapse_matches_the_cpu_reference_and_collapses() {
    let ctx = gpu();
    let builder = Builder::new(&ctx).unwrap();
    let model = builder.cost_model().unwrap();
    let tf = TransferFunction::parse("band:0.5:1").unwrap();
    let collapsed = BuildOptions {
        collapse: true,
        ..Default::default()
    };
    for (dims, p, seed) in OCCUPANCIES.into_iter().chain([([96, 96, 96], 60, 6)]) {
        let v = random_bricks(dims, p, seed);
        let active = active_bricks(&v, &tf);
        let mut want = cpu::build(&active, BrickGrid::new(&v, BRICK, 1).counts, dims, BRICK);
        cpu::collapse(&mut want, &model);
        let (got, _, stats) = gpu_lbvh_with(&builder, &v, &tf, &collapsed);
        let first = got.iter().zip(&want).position(|(a, b)| a != b);
        assert!(
            first.is_none() && got.len() == want.len(),
            "{dims:?} p={p}: node {first:?} differs: {:?} vs {:?} ({model:?})",
            first.map(|i| got[i]),
            first.map(|i| want[i])
        );
        let shape = lacuna::accel::tree::shape(&want);
        assert_eq!((stats.nodes, stats.leaves), (shape.nodes, shape.leaves));
        let (_, _, plain) = gpu_lbvh_with(&builder, &v, &tf, &BuildOptions::default());
        assert!(stats.nodes <= plain.nodes, "{dims:?} p={p}");
        if p == 100 {
            // Every brick active: the whole volume is one leaf.
            assert_eq!((stats.nodes, stats.leaves), (1, 1), "{dims:?}");
            assert_eq!(got[0].bounds(), ([0; 3], dims.map(|d| d as i32)));
        }
        if p == 1 {
            // Sparse: the empty space stays out of the leaves (one brick
            // in a 64^3 box costs 64x its samples as one leaf).
            assert!(stats.leaves > 1, "{dims:?}: {stats}");
        }
    }
    assert_clean(&ctx);
}

/// Every node reached exactly once from the root, each internal node with two children.
fn assert_valid_tree(links: &[[i32; 2]], n: usize) {
    let mut seen = vec![0u32; 2 * n - 1];
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        seen[i] += 1;
        if i < n - 1 {
            for c in links[i] {
                assert!(c > 0 && (c as usize) < 2 * n - 1, "node {i}: child {c} out of range");
                stack.push(c as usize);
            }
        }
    }
    assert!(
        seen.iter().all(|&s| s == 1),
        "some node is unreachable or reached twice"
    );
}

#[test]
fn karras_emit_matches_the_cpu_with_duplicate_codes() {
    let ctx = gpu();
    let builder = Builder::new(&ctx).unwrap();
    let mut r = rng(11);
    let mut cases: Vec<Vec<u32>> = vec![
        vec![5, 5],
        vec![7; 17],
        vec![0, 0, 1, 1, 1, 2, 9, 9, 9, 9, 1000, 1000],
        (0..1000).map(|_| r() % 50).collect(),
        (0..4097).map(|_| r() & 0x3FFF_FFFF).collect(),
        (0..300).collect(),
    ];
    for c in &mut cases {
        c.sort();
    }
    for codes in &cases {
        let n = codes.len();
        let got = builder
            .kernels::<lacuna::accel::lbvh::LbvhBuilder>()
            .unwrap()
            .emit_links(codes)
            .unwrap();
        let want: Vec<[i32; 2]> = cpu::emit(codes)[..n - 1]
            .iter()
            .map(|nd| [nd.lo[3], nd.hi[3]])
            .collect();
        assert_valid_tree(&want, n);
        let first_diff = got.iter().zip(&want).position(|(a, b)| a != b);
        assert!(first_diff.is_none(), "n={n}: internal node {first_diff:?} differs");
    }
    assert_clean(&ctx);
}
