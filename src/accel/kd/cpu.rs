//! The k-d tree built on the multi-core CPU (rayon): occupancy and summed
//! volume tables per TF change, then a top-down build evaluating every
//! raster plane of the longest axis, children built in parallel.

use super::occupancy::Occupancy;
use super::{
    cheaper_as_leaf, choose, flatten, forced_plane, halves, longest_axis, raster_planes, volume, Candidate, IBox,
    KdNode, KdParams,
};
use super::{kd_variants, Depth, KD, MAX_LEAF};
use crate::accel::builder::{Builder, RangeKind, Ranges};
use crate::accel::cost::CostModel;
use crate::accel::method::{BuildInput, Built, March, Method};
use crate::accel::params::{Param, Params, COLLAPSE};
use crate::accel::stats::Stats;
use crate::accel::tree::{GpuTree, Node, TREE_MARCH};
use crate::error::Result;
use crate::gpu::{Context, Timings};
use crate::tf::TransferFunction;
use crate::volume::Volume;
use rayon::prelude::*;

/// Splits `b` (a tight box) recursively; with a cost model, a region
/// cheaper as one leaf stays one.
pub fn split(occ: &Occupancy, b: IBox, root_vol: i64, params: &KdParams, collapse: Option<&CostModel>) -> KdNode {
    if params.halts(volume(&b), root_vol) {
        return KdNode::Leaf(b);
    }
    let axis = longest_axis(&b);
    let planes = raster_planes(&b, axis);
    let candidates: Vec<Candidate> = planes
        .par_iter()
        .map(|&p| {
            let (l, r) = halves(&b, axis, p);
            (p, occ.tight(&l), occ.tight(&r))
        })
        .collect();
    let chosen = match choose(&b, &candidates) {
        Some(i) => Some(candidates[i]),
        None => forced_plane(&b, params).map(|(axis, p)| {
            let (l, r) = halves(&b, axis, p);
            (p, occ.tight(&l), occ.tight(&r))
        }),
    };
    match chosen {
        Some((_, Some(l), Some(r))) if !collapse.is_some_and(|m| cheaper_as_leaf(m, &b, &l, &r)) => {
            let (left, right) = rayon::join(
                || split(occ, l, root_vol, params, collapse),
                || split(occ, r, root_vol, params, collapse),
            );
            KdNode::Inner(b, Box::new(left), Box::new(right))
        }
        // A forced split with one empty side just tightens the box.
        Some((_, Some(only), None)) | Some((_, None, Some(only))) if only != b => {
            split(occ, only, root_vol, params, collapse)
        }
        _ => KdNode::Leaf(b),
    }
}

/// Builds the tree over `occ`'s active footprints (with cost-driven leaves
/// when a cost model is given).
pub fn build_nodes(occ: &Occupancy, params: &KdParams, collapse: Option<&CostModel>) -> Vec<Node> {
    let all: IBox = [[0; 3], occ.dims];
    let root = occ.tight(&all).map(|b| split(occ, b, volume(&b), params, collapse));
    flatten(root.as_ref())
}

/// Occupancy ("svt"), the tree ("tree") and its upload ("upload"), all wall
/// time on the host.
pub fn build(
    ctx: &Context,
    volume: &Volume,
    tf: &TransferFunction,
    params: &KdParams,
    collapse: Option<&CostModel>,
) -> Result<(GpuTree, Timings)> {
    let mut t = Timings::default();
    let occ = t.cpu("svt", || Occupancy::new(volume, tf));
    let nodes = t.cpu("tree", || build_nodes(&occ, params, collapse));
    let stats = Stats {
        unit: "voxel footprints",
        total_bricks: volume.voxel_count(),
        active_bricks: occ.active,
        ..Default::default()
    };
    let start = std::time::Instant::now();
    let tree = GpuTree::upload(ctx, &nodes, stats)?;
    t.push("upload", start.elapsed().as_secs_f64() * 1e3);
    Ok((tree, t))
}

/// `--accel kd-cpu`.
pub struct KdCpu;

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for KdCpu {
    fn name(&self) -> &'static str {
        "kd-cpu"
    }
    fn description(&self) -> &'static str {
        "k-d tree built on the multi-core CPU from summed volume tables (Zellmann et al. 2018)"
    }
    fn params(&self) -> &'static [Param] {
        &[KD, MAX_LEAF, COLLAPSE]
    }
    fn check(&self, p: &Params) -> Result<()> {
        KdParams::from_params(p).map(|_| ())
    }
    fn ranges(&self, _: &Params) -> Result<RangeKind> {
        Ok(RangeKind::None)
    }
    fn march(&self) -> March {
        TREE_MARCH
    }
    fn variants(&self) -> Result<Vec<(String, Params)>> {
        kd_variants(self, &[(Depth::Shallow, 32), (Depth::Deep, 32)])
    }
    /// Host-driven: built on the CPU from the host volume, then uploaded.
    fn recordable(&self) -> bool {
        false
    }
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        _: &Ranges,
        p: &Params,
    ) -> Result<(Box<dyn Built>, Timings)> {
        let collapse = p.switch("collapse")?;
        let model = collapse.then(|| builder.cost_model()).transpose()?;
        let kd = KdParams::from_params(p)?;
        let (mut tree, mut t) = build(builder.context(), input.volume, input.tf, &kd, model.as_ref())?;
        tree.check_whole_box(input.gpu_volume.dims, collapse, &mut t)?;
        Ok((Box::new(tree), t))
    }
}
