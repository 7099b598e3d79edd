//! The k-d decomposition of a volume's bricks into one block per rank, and
//! the ranks' visibility order for a camera.

use crate::desc::Rays;
use crate::error::{Error, Result};
use crate::volume::BrickBox;

/// One rank's block: whole bricks, `bricks[0]` inclusive to `bricks[1]`
/// exclusive, and the voxel box it covers (the last brick of an axis may
/// be partial).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Block {
    pub bricks: BrickBox,
    /// Voxel box `[lo, hi]`: what of the ray this rank samples.
    pub lo: [u32; 3],
    pub hi: [u32; 3],
}

impl Block {
    /// The bricks the rank stores: its own and one layer of ghost bricks
    /// around them (within the volume), which hold every voxel a sample
    /// inside the block reads (the trilinear cell's far corner, the
    /// gradient's neighbours, the classification's apron).
    pub fn with_ghosts(&self, counts: [u32; 3]) -> BrickBox {
        let [lo, hi] = self.bricks;
        [
            [0, 1, 2].map(|a| lo[a].saturating_sub(1)),
            [0, 1, 2].map(|a| (hi[a] + 1).min(counts[a])),
        ]
    }

    /// The block's box in voxel space (`FrameBuilder::segment`).
    pub fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        (self.lo.map(|v| v as f32), self.hi.map(|v| v as f32))
    }

    pub fn bricks_count(&self) -> u64 {
        (0..3).map(|a| (self.bricks[1][a] - self.bricks[0][a]) as u64).product()
    }
}

/// A split of the k-d tree: the plane `axis = at` (voxels) and the ranks
/// on each side; a leaf is one rank.
#[derive(Clone, Debug)]
enum Node {
    Leaf(u32),
    Split {
        axis: usize,
        at: u32,
        lo: Box<Node>,
        hi: Box<Node>,
    },
}

/// `ranks` blocks of whole bricks covering a volume, one per rank.
#[derive(Clone, Debug)]
pub struct Decomposition {
    pub dims: [u32; 3],
    /// Brick edge in voxels.
    pub edge: u32,
    /// Bricks per axis.
    pub counts: [u32; 3],
    /// Rank r's block is `blocks[r]`.
    pub blocks: Vec<Block>,
    tree: Node,
}

impl Decomposition {
    /// Splits the bricks of a volume of `dims` (bricks of `edge`^3) into
    /// `ranks` blocks: each split halves the ranks and cuts the box's
    /// longest side (in voxels, z first among equals) at the brick nearest the ranks' share, so
    /// blocks hold about equal voxels.
    pub fn new(dims: [u32; 3], edge: u32, ranks: u32) -> Result<Self> {
        if edge == 0 || dims.contains(&0) {
            return Err(Error::invalid(
                "decomposition",
                format!("{dims:?} in bricks of {edge}"),
                "is empty",
            ));
        }
        let counts = dims.map(|d| d.div_ceil(edge));
        let total: u64 = counts.iter().map(|&c| c as u64).product();
        if ranks == 0 || ranks as u64 > total {
            return Err(Error::invalid(
                "rank count",
                ranks.to_string(),
                format!(
                    "exceeds the {total} bricks of {edge}^3 of a {}x{}x{} volume: each rank needs one at least",
                    dims[0], dims[1], dims[2]
                ),
            ));
        }
        let mut d = Decomposition {
            dims,
            edge,
            counts,
            blocks: Vec::new(),
            tree: Node::Leaf(0),
        };
        d.tree = d.split([[0; 3], counts], ranks)?;
        Ok(d)
    }

    fn voxels(&self, bricks: BrickBox, axis: usize) -> u32 {
        (bricks[1][axis] * self.edge).min(self.dims[axis]) - bricks[0][axis] * self.edge
    }

    /// Where to cut `bricks` along `axis` for `ranks` ranks, and the ranks
    /// of the low side: half the ranks at the brick nearest their share of
    /// the voxels; where a side would have fewer bricks than ranks, the cut
    /// nearest the middle whose sides can hold their shares. None where the
    /// side cannot be cut so.
    fn cut(&self, bricks: BrickBox, axis: usize, ranks: u32) -> Option<(u32, u32)> {
        let [lo, hi] = bricks;
        let len = hi[axis] - lo[axis];
        let across: u64 = (0..3).filter(|&a| a != axis).map(|a| (hi[a] - lo[a]) as u64).product();
        let ranks = ranks as u64;
        // The low side's ranks for a cut: its share of the voxels, within
        // what each side's bricks can hold.
        let lo_ranks_at = |cut: u32, want: u64| -> Option<u64> {
            let (lo_bricks, hi_bricks) = (cut as u64 * across, (len - cut) as u64 * across);
            let least = ranks.saturating_sub(hi_bricks).max(1);
            let most = lo_bricks.min(ranks - 1);
            (least <= most).then(|| want.clamp(least, most))
        };
        let half = ranks / 2;
        let share = self.voxels(bricks, axis) as f64 * half as f64 / ranks as f64;
        let cut = ((share / self.edge as f64).round() as u32).clamp(1, len.max(2) - 1);
        if len >= 2 && lo_ranks_at(cut, half) == Some(half) {
            return Some((cut, half as u32));
        }
        let mut cuts: Vec<u32> = (1..len).collect();
        cuts.sort_by_key(|&c| (2 * c as i64 - len as i64).abs());
        cuts.into_iter().find_map(|cut| {
            let want = (ranks as f64 * cut as f64 / len as f64).round() as u64;
            lo_ranks_at(cut, want).map(|r| (cut, r as u32))
        })
    }

    fn split(&mut self, bricks: BrickBox, ranks: u32) -> Result<Node> {
        if ranks == 1 {
            let rank = self.blocks.len() as u32;
            self.blocks.push(Block {
                bricks,
                lo: bricks[0].map(|b| b * self.edge),
                hi: [0, 1, 2].map(|a| (bricks[1][a] * self.edge).min(self.dims[a])),
            });
            return Ok(Node::Leaf(rank));
        }
        // Longest side first, z first among equals (a cube's first cut is
        // across z, so each side reads or generates only its own layers,
        // `StreamTo::across`); a side of one brick cannot be cut.
        let mut axes = [2, 1, 0];
        axes.sort_by_key(|&a| std::cmp::Reverse(self.voxels(bricks, a)));
        for axis in axes {
            if let Some((cut, lo_ranks)) = self.cut(bricks, axis, ranks) {
                let [lo, _] = bricks;
                let mut lo_box = bricks;
                lo_box[1][axis] = lo[axis] + cut;
                let mut hi_box = bricks;
                hi_box[0][axis] = lo[axis] + cut;
                let lo_node = self.split(lo_box, lo_ranks)?;
                let hi_node = self.split(hi_box, ranks - lo_ranks)?;
                return Ok(Node::Split {
                    axis,
                    at: (lo[axis] + cut) * self.edge,
                    lo: Box::new(lo_node),
                    hi: Box::new(hi_node),
                });
            }
        }
        Err(Error::invalid(
            "rank count",
            ranks.to_string(),
            format!("cannot split bricks {bricks:?} into {ranks} blocks"),
        ))
    }

    /// The ranks front to back along every ray of `rays` (voxel space): at
    /// each split, the side the eye is on (perspective) or the side rays
    /// enter first (orthographic) comes first, which orders every ray's
    /// segments alike.
    pub fn order(&self, rays: &Rays) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.blocks.len());
        let mut stack = vec![&self.tree];
        while let Some(node) = stack.pop() {
            match node {
                Node::Leaf(rank) => out.push(*rank),
                Node::Split { axis, at, lo, hi } => {
                    let v = rays.eye_or_dir[*axis];
                    let lo_first = if rays.perspective { v < *at as f32 } else { v > 0.0 };
                    let (first, second) = if lo_first { (lo, hi) } else { (hi, lo) };
                    stack.push(second);
                    stack.push(first);
                }
            }
        }
        out
    }
}
