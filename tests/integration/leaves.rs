//! Cost-driven leaves: the measured cost model, and collapsed trees against
//! their CPU reference and their plain counterparts.

use crate::common::{assert_clean, gpu};
use lacuna::accel::cost::{self, CostModel, FLOOR_NS};
use lacuna::accel::{Accel, BuildInput, Builder, Params, Ranges, Stats};
use lacuna::render::FrameDesc;
use lacuna::render::Mode;
use lacuna::render::Octants;
use lacuna::volume::{GpuVolume, VoxelData, VoxelType};
use lacuna::{TransferFunction, Volume};

#[test]
fn the_cost_model_is_measured_once_with_positive_finite_constants() {
    let ctx = gpu();
    let builder = Builder::new(&ctx).unwrap();
    let m = builder.cost_model().unwrap();
    for (name, v) in [("sample", m.sample_ns), ("step", m.step_ns), ("entry", m.entry_ns)] {
        assert!(v.is_finite() && v >= FLOOR_NS, "{name}_ns = {v}");
    }
    // Kept per builder: the second call returns the same constants.
    assert_eq!(builder.cost_model().unwrap(), m);
    // A brick leaf marches several samples, so it costs more than one.
    let (brick, _) = m.leaf([0; 3], [8; 3]);
    assert!(brick as f64 > m.sample_ns, "{m:?}");
    assert_clean(&ctx);
}

#[test]
fn the_collapse_plans_for_the_renderers_default_step() {
    assert_eq!(FrameDesc::builder(1, 1).build().unwrap().step(), cost::STEP);
}

/// A cost model with samples, steps and leaf entries of plausible relative
/// cost (the measured ones move with the machine's load).
const FIXED: CostModel = CostModel {
    sample_ns: 1.0,
    step_ns: 2.0,
    entry_ns: 4.0,
};

/// Runs `f` with a builder, the volume and TF uploaded, and their ranges.
fn with_input<T>(
    ctx: &lacuna::gpu::Context,
    v: &Volume,
    tf: &TransferFunction,
    f: impl FnOnce(&Builder, &BuildInput, &Ranges) -> T,
) -> T {
    let builder = Builder::new(ctx).unwrap();
    // Fixed constants: collapse decisions must not follow the VM's load.
    builder.set_cost_model(FIXED);
    let gv = GpuVolume::upload(ctx, v).unwrap();
    let lut = tf.upload(ctx).unwrap();
    let kinds: Vec<_> = lacuna::accel::TABLE
        .iter()
        .flat_map(|a| a.method().ranges(&a.defaults()))
        .collect();
    let (ranges, _) = builder.ranges(&kinds, &gv).unwrap();
    let input = BuildInput {
        volume: v,
        gpu_volume: &gv,
        tf,
        gpu_tf: &lut,
        mode: Mode::Composite,
        frames: &[],
        octants: Octants::ALL,
    };
    f(&builder, &input, &ranges)
}

/// Every tree that reads `collapse`: its statistics with collapse on and
/// off, and whether the collapsed one is marched with the naive kernel.
fn collapsed_trees(ctx: &lacuna::gpu::Context, v: &Volume, tf: &TransferFunction) -> Vec<(Accel, Stats, Stats, bool)> {
    with_input(ctx, v, tf, |builder, input, ranges| {
        Accel::skipping()
            .filter(|a| a.method().params().iter().any(|p| p.name == "collapse"))
            .map(|a| {
                let build = |p: &Params| {
                    let structure = builder.build(a, input, ranges, p).unwrap().0;
                    let naively = structure.marched_as().is_naive();
                    // The naive kernel binds nothing of a structure.
                    assert_eq!(structure.built().bindings().is_empty(), naively, "{a}");
                    (structure.stats().unwrap().unwrap(), naively)
                };
                let (collapsed, naively) = build(&a.params(&[("collapse", "on")]).unwrap());
                (a, collapsed, build(&a.defaults()).0, naively)
            })
            .collect()
    })
}

#[test]
fn a_fully_active_volume_is_one_leaf_and_a_sparse_one_keeps_its_empty_space_out() {
    let ctx = gpu();
    let tf = TransferFunction::parse("band:0.5:1").unwrap();
    let dims = [72, 64, 56];
    let n = dims.iter().product::<u32>() as usize;
    // One dark voxel, so the stored range (which values are normalised by) is not empty.
    let mut data = vec![200u8; n];
    data[0] = 0;
    let full = Volume::new("full", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let trees = collapsed_trees(&ctx, &full, &tf);
    assert_eq!(trees.len(), 3, "lbvh, kd-cpu and kd-gpu read collapse");
    for (accel, on, off, naively) in trees {
        assert_eq!((on.nodes, on.leaves, on.height), (1, 1, 1), "{accel}: {on}");
        assert!(off.nodes >= on.nodes, "{accel}");
        // One leaf covering the volume: nothing to traverse.
        assert!(naively, "{accel}: a whole-box leaf is marched with the naive kernel");
    }
    // The hybrid's one-leaf tree still walks its grid inside the leaf.
    let hybrid = with_input(&ctx, &full, &tf, |builder, input, ranges| {
        let accel: Accel = "hybrid".parse().unwrap();
        builder.build(accel, input, ranges, &accel.defaults()).unwrap().0
    });
    assert!(hybrid.marched_as_reason().is_none() && hybrid.marched_as().name() == "hybrid");
    // Two bright 4^3 blobs in opposite corners: one leaf would march the
    // whole volume's diagonal for two small targets.
    let mut data = vec![0u8; n];
    for (x0, y0, z0) in [(2, 2, 2), (64, 56, 48)] {
        for z in z0..z0 + 4 {
            for y in y0..y0 + 4 {
                for x in x0..x0 + 4 {
                    data[x + dims[0] as usize * (y + dims[1] as usize * z)] = 200;
                }
            }
        }
    }
    let sparse = Volume::new("sparse", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    for (accel, on, _, naively) in collapsed_trees(&ctx, &sparse, &tf) {
        assert!(on.leaves >= 2, "{accel}: {on}");
        assert!(!naively, "{accel}: a tree with leaves to skip between is traversed");
    }
    assert_clean(&ctx);
}
