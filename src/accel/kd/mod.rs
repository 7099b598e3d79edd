//! k-d trees over the active voxel footprints (Zellmann et al.'s SVT trees):
//! split the longest axis at candidate planes on the 8-voxel raster, cost =
//! volume(tight left) + volume(tight right) (Vidal et al. 2008), reject a
//! plane that removes no more than 1/1000 of the node's volume, children get
//! tight boxes. Built on the CPU (`cpu`, every candidate plane, rayon) or with
//! GPU reductions (`gpu`, binned planes, one submission per tree level).
//! Both emit the shared tree node format, so the LBVH's march kernel renders
//! them.
//!
//! A footprint `[i, i+1]^3` is active iff the TF's max alpha over the 27
//! voxels its samples can read is > 0; every leaf is the tight box of the
//! active footprints in its region, and the leaves cover all of them.

pub mod cpu;
pub mod gpu;
pub mod occupancy;

use super::cost::CostModel;
use super::method::Method;
use super::params::{Param, Params};
use super::tree::Node;
use crate::error::Result;

/// A box of voxel footprints: `[lo, hi)` per axis.
pub type IBox = [[i32; 3]; 2];

/// Voxel footprints in box `b` (0 when it is empty).
pub fn volume(b: &IBox) -> i64 {
    (0..3).map(|a| (b[1][a] - b[0][a]).max(0) as i64).product()
}

/// Candidate planes lie on multiples of this (the paper's dl = 8).
pub const RASTER: i32 = 8;

/// Halting rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Depth {
    /// Leaf when the node's volume is below 10 % of the root's (Vidal's rule).
    Shallow,
    /// Leaf at 8^3 voxels or less; a leaf longer than `max_leaf` along its
    /// longest axis is split in the middle of that axis.
    Deep,
}

/// What shapes a k-d tree: halting rule, leaf size and the GPU builder's bins.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct KdParams {
    pub depth: Depth,
    /// Deep trees: the longest leaf extent in voxels (the paper: 32 or 128).
    pub max_leaf: u32,
    /// GPU builder: bins per node (the paper: 4).
    pub bins: u32,
}

impl Default for KdParams {
    fn default() -> Self {
        KdParams {
            depth: Depth::Deep,
            max_leaf: 32,
            bins: 4,
        }
    }
}

/// `--kd shallow|deep`: the halting rule.
pub const KD: Param = Param::choice(
    "kd",
    &["shallow", "deep"],
    "deep",
    "k-d trees: shallow (leaf below 10 % of the root volume) or deep (leaf at 8^3)",
);
/// `--max-leaf N`: deep trees split leaves longer than this in the middle.
pub const MAX_LEAF: Param = Param::int(
    "max-leaf",
    32,
    8,
    u32::MAX,
    "Deep k-d trees: split leaves longer than this many voxels in the middle",
);
/// `--bins N`: the GPU builder's candidate planes per node.
pub const BINS: Param = Param::int("bins", 4, 2, 64, "GPU k-d tree: candidate bins per node");

impl KdParams {
    /// From a structure's `kd`, `max-leaf` and (if it has one) `bins`
    /// parameters (their schemas checked the values).
    pub fn from_params(p: &Params) -> Result<Self> {
        let depth = match p.choice("kd")? {
            "shallow" => Depth::Shallow,
            _ => Depth::Deep,
        };
        let bins = if p.has("bins") {
            p.int("bins")?
        } else {
            KdParams::default().bins
        };
        Ok(KdParams {
            depth,
            max_leaf: p.int("max-leaf")?,
            bins,
        })
    }

    /// Whether a node of volume `vol` is a leaf whatever its splits.
    pub fn halts(&self, vol: i64, root_vol: i64) -> bool {
        match self.depth {
            Depth::Shallow => vol * 10 < root_vol,
            Depth::Deep => vol <= 512,
        }
    }
}

/// The axis along which box `b` is longest (the lowest on ties).
pub fn longest_axis(b: &IBox) -> usize {
    let e = [0, 1, 2].map(|a| b[1][a] - b[0][a]);
    if e[0] >= e[1] && e[0] >= e[2] {
        0
    } else if e[1] >= e[2] {
        1
    } else {
        2
    }
}

/// Every raster plane strictly inside the box along `axis` (the CPU builder).
pub fn raster_planes(b: &IBox, axis: usize) -> Vec<i32> {
    let first = (b[0][axis] / RASTER + 1) * RASTER;
    (0..)
        .map(|k| first + k * RASTER)
        .take_while(|&p| p < b[1][axis])
        .collect()
}

/// Binned planes (the GPU builder): bin width max(len / bins, 8) rounded
/// down to the raster; planes on the raster strictly inside the box.
pub fn binned_planes(b: &IBox, axis: usize, bins: u32) -> Vec<i32> {
    let len = b[1][axis] - b[0][axis];
    let width = ((len / bins as i32).max(RASTER) / RASTER) * RASTER;
    let mut planes: Vec<i32> = (1..bins as i32)
        .map(|k| ((b[0][axis] + k * width) / RASTER) * RASTER)
        .filter(|&p| p > b[0][axis] && p < b[1][axis])
        .collect();
    planes.dedup();
    planes
}

/// The forced split of an over-long deep leaf: the raster plane nearest the
/// middle of the longest axis (or the middle itself if no raster plane is
/// strictly inside).
pub fn forced_plane(b: &IBox, params: &KdParams) -> Option<(usize, i32)> {
    let axis = longest_axis(b);
    let len = b[1][axis] - b[0][axis];
    if params.depth != Depth::Deep || len <= params.max_leaf as i32 {
        return None;
    }
    let mid = (b[0][axis] + b[1][axis]) / 2;
    let snapped = ((mid + RASTER / 2) / RASTER) * RASTER;
    let p = if snapped > b[0][axis] && snapped < b[1][axis] {
        snapped
    } else {
        mid
    };
    Some((axis, p))
}

/// The halves of `b` at `plane` along `axis`.
pub fn halves(b: &IBox, axis: usize, plane: i32) -> (IBox, IBox) {
    let (mut l, mut r) = (*b, *b);
    l[1][axis] = plane;
    r[0][axis] = plane;
    (l, r)
}

/// One evaluated candidate: the plane and the tight boxes of its halves.
pub type Candidate = (i32, Option<IBox>, Option<IBox>);

/// The cheapest acceptable candidate: both halves non-empty and removing
/// more than 1/1000 of the node's volume.
pub fn choose(b: &IBox, candidates: &[Candidate]) -> Option<usize> {
    let vol = volume(b);
    let mut best: Option<(i64, usize)> = None;
    for (i, (_, l, r)) in candidates.iter().enumerate() {
        let (Some(l), Some(r)) = (l, r) else { continue };
        let cost = volume(l) + volume(r);
        if (vol - cost) * 1000 <= vol {
            continue;
        }
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, i));
        }
    }
    best.map(|(_, i)| i)
}

/// Cost-driven leaves (`--collapse on`): whether `b` as one leaf costs no
/// more than split into the tight boxes `l` and `r` kept as leaves (the
/// surface-area heuristic's termination test, with the measured constants).
/// Either way every active footprint stays inside a leaf.
pub fn cheaper_as_leaf(model: &CostModel, b: &IBox, l: &IBox, r: &IBox) -> bool {
    let (leaf, s) = model.leaf(b[0], b[1]);
    leaf <= model.inner(s, model.leaf(l[0], l[1]), model.leaf(r[0], r[1]))
}

/// A k-d tree node while building: a tight box, and children for inner nodes.
#[derive(Clone, Debug, PartialEq)]
pub enum KdNode {
    Leaf(IBox),
    Inner(IBox, Box<KdNode>, Box<KdNode>),
}

/// Flattens to the shared node format (depth first; root 0; leaf payload =
/// leaf number).
pub fn flatten(root: Option<&KdNode>) -> Vec<Node> {
    fn walk(n: &KdNode, out: &mut Vec<Node>, leaves: &mut i32) -> i32 {
        let me = out.len();
        out.push(Node::default());
        match n {
            KdNode::Leaf(b) => {
                out[me] = Node::leaf(b[0], b[1], *leaves);
                *leaves += 1;
            }
            KdNode::Inner(b, l, r) => {
                let li = walk(l, out, leaves);
                let ri = walk(r, out, leaves);
                out[me] = Node::inner(b[0], b[1], li, ri);
            }
        }
        me as i32
    }
    let mut out = Vec::new();
    if let Some(root) = root {
        walk(root, &mut out, &mut 0);
    }
    out
}

/// The leaf boxes of a node array.
pub fn leaf_boxes(nodes: &[Node]) -> Vec<IBox> {
    nodes
        .iter()
        .filter(|n| n.is_leaf())
        .map(|n| {
            let (lo, hi) = n.bounds();
            [lo, hi]
        })
        .collect()
}

/// The paper's k-d parameter sets as variants of `method` (whose schema has
/// `kd`, `max-leaf` and `collapse`): (depth, max leaf), then the deep set
/// with cost-driven leaves.
pub(crate) fn kd_variants(method: &dyn Method, sets: &[(Depth, u32)]) -> Result<Vec<(String, Params)>> {
    let name = method.name();
    let mut out = Vec::new();
    for &(depth, max_leaf) in sets {
        let (label, kd) = match depth {
            Depth::Shallow => (format!("{name} shallow"), "shallow"),
            Depth::Deep => (format!("{name} MLS={max_leaf}"), "deep"),
        };
        let max_leaf = max_leaf.to_string();
        let given = [("kd", kd), ("max-leaf", max_leaf.as_str())];
        out.push((label, Params::resolve(method.params(), &given)?));
    }
    if let Some(&(_, max_leaf)) = sets.iter().find(|(d, _)| *d == Depth::Deep) {
        let max_leaf = max_leaf.to_string();
        let given = [("kd", "deep"), ("max-leaf", max_leaf.as_str()), ("collapse", "on")];
        out.push((
            format!("{name} MLS={max_leaf}, collapsed"),
            Params::resolve(method.params(), &given)?,
        ));
    }
    Ok(out)
}
