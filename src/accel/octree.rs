//! Octree over the active 8^3 bricks (Havran's centre subdivision) for the
//! volume renderer, walked by any of the four octree traversals
//! (`--accel octree-84|octree-89|octree-93|octree-rev`): the same node format
//! and the same GLSL traversals as the surface octrees in `crate::octree`.
//!
//! Per transfer function: bricks are classified on the GPU (over the one-voxel
//! apron, like the LBVH's), the flags are read back, and the tree is built on
//! the CPU from a summed-area table of the flags: the root is the cube of
//! 2^k bricks enclosing the volume, split at its centre; a node is a leaf when
//! it holds no active brick (empty), only active bricks (full) or one brick.
//! Nonempty leaves' spans are marched on the global lattice with the usual
//! margins (`glsl/march/octree.comp`), which keeps every image bit-identical
//! to naive marching.

use super::bricks::GpuBricks;
use super::builder::{Builder, RangeKind, Ranges};
use super::classify::{Classifier, Classify, APRON, CLASSIFY};
use super::method::{BuildInput, Built, March, Method};
use super::params::{Param, Params};
use super::stats::Stats;
use crate::error::Result;
use crate::gpu::record::Access;
use crate::gpu::shaders::{self, march_octree};
use crate::gpu::{vk, Binding, Bound, Buffer, MemoryLocation, Timer, Timings};
use crate::spatial::octree_node::{axis_bit, Node};
use crate::spatial::{Sat3, Traversal};

/// An octree over active bricks on the device, with the traversal it is
/// marched by (`--accel octree-84` ... `octree-rev`).
pub struct VolumeOctree {
    pub traversal: Traversal,
    pub nodes: Buffer,
    pub stats: Stats,
}

/// Leaves and interior nodes of a brick octree, as built on the host.
pub struct BrickOctree {
    pub nodes: Vec<Node>,
    pub leaves: u64,
    pub active_leaves: u64,
    pub depth: u32,
}

/// The corner `b0 + offset` (in bricks) in voxel units, as a node vec4.
fn voxels(b0: [u32; 3], offset: u32, brick: u32) -> [f32; 4] {
    let v = |a: usize| ((b0[a] + offset) * brick) as f32;
    [v(0), v(1), v(2), 0.0]
}

impl BrickOctree {
    /// Builds over `counts` bricks of `brick` voxels; `active[b] != 0` marks
    /// brick b (x fastest).
    pub fn build(counts: [u32; 3], brick: u32, active: &[u32]) -> BrickOctree {
        let n = counts.map(|c| c as usize);
        let sat = Sat3::<u32>::new(n, |x, y, z| active[x + n[0] * (y + n[1] * z)] != 0);
        let side = counts.iter().copied().max().unwrap_or(1).next_power_of_two();
        let mut out = BrickOctree {
            nodes: vec![Node::default()],
            leaves: 0,
            active_leaves: 0,
            depth: 0,
        };
        let mut queue = std::collections::VecDeque::new();
        queue.push_back((0u32, 0u32, [0u32; 3], side, 0u32));
        while let Some((index, parent, b0, s, depth)) = queue.pop_front() {
            let lo = b0.map(|v| v as usize);
            let hi = [0, 1, 2].map(|a| ((b0[a] + s).min(counts[a])) as usize);
            let inside: usize = (0..3).map(|a| hi[a].saturating_sub(lo[a])).product();
            let n_active = sat.count(lo, hi) as usize;
            let first = out.nodes.len() as u32;
            let node = &mut out.nodes[index as usize];
            node.lo = voxels(b0, 0, brick);
            node.hi = voxels(b0, s, brick);
            out.depth = out.depth.max(depth);
            if n_active == 0 || n_active == inside || s == 1 {
                node.info = [0, u32::from(n_active > 0), parent, 1 | depth << 1];
                out.leaves += 1;
                out.active_leaves += u64::from(n_active > 0);
                continue;
            }
            let h = s / 2;
            node.split = voxels(b0, h, brick);
            node.info = [first, 0, parent, depth << 1];
            out.nodes.extend([Node::default(); 8]);
            for c in 0..8u32 {
                let cb = [0, 1, 2].map(|a| b0[a] + if c & axis_bit(a) != 0 { h } else { 0 });
                queue.push_back((first + c, index, cb, h, depth + 1));
            }
        }
        out
    }
}

/// Classifies the 8^3 `bricks` for the input's TF, reads the flags back and
/// builds the octree ("classify" on the GPU; "octree build" and "upload" on
/// the host).
pub fn build(
    builder: &Builder,
    input: &BuildInput,
    bricks: &GpuBricks,
    mode: Classify,
    traversal: Traversal,
) -> Result<(VolumeOctree, Timings)> {
    let ctx = builder.context();
    let classifier = builder.shared::<Classifier>()?;
    let (volume, tf) = (input.gpu_volume, input.gpu_tf);
    let flags = Buffer::new(
        ctx,
        "octree brick flags",
        bricks.total * 4,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        MemoryLocation::GpuToCpu,
    )?;
    let mut timer = Timer::new(ctx, 1)?;
    ctx.submit_and_wait(|cmd| {
        timer.reset(cmd);
        let pass = timer.begin(cmd, "classify")?;
        classifier.record(cmd, mode, volume, bricks, tf, &flags)?;
        timer.end(cmd, pass);
        cmd.barrier(Access::COMPUTE_WRITE, Access::HOST_READ);
        Ok(())
    })?;
    let mut t = timer.results()?;
    let active: Vec<u32> = bytemuck::pod_collect_to_vec(&flags.host()?[..bricks.total as usize * 4]);
    let tree = t.cpu("octree build", || {
        BrickOctree::build(bricks.counts, bricks.brick, &active)
    });
    let nodes = t.cpu("upload", || {
        Buffer::with_data(
            ctx,
            "volume octree nodes",
            bytemuck::cast_slice(&tree.nodes),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )
    })?;
    let stats = Stats {
        unit: "8^3 bricks",
        total_bricks: bricks.total,
        active_bricks: active.iter().filter(|&&f| f != 0).count() as u64,
        nodes: tree.nodes.len() as u64,
        leaves: tree.leaves,
        height: tree.depth + 1,
        bytes: std::mem::size_of_val(tree.nodes.as_slice()) as u64,
    };
    Ok((
        VolumeOctree {
            traversal,
            nodes,
            stats,
        },
        t,
    ))
}

/// `--accel octree-84|octree-89|octree-93|octree-rev`: one entry per traversal.
pub struct OctreeMethod(pub Traversal);

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for OctreeMethod {
    fn name(&self) -> &'static str {
        match self.0 {
            Traversal::O84 => "octree-84",
            Traversal::O89 => "octree-89",
            Traversal::O93 => "octree-93",
            Traversal::Rev => "octree-rev",
        }
    }
    fn description(&self) -> &'static str {
        match self.0 {
            Traversal::O84 => "octree over active 8^3 bricks, Glassner's 1984 traversal",
            Traversal::O89 => "octree over active 8^3 bricks, Samet's 1989 neighbour finding",
            Traversal::O93 => "octree over active 8^3 bricks, Gargantini & Atkinson's 1993 traversal",
            Traversal::Rev => "octree over active 8^3 bricks, Revelles et al.'s 2000 parametric traversal",
        }
    }
    fn params(&self) -> &'static [Param] {
        &[CLASSIFY, APRON]
    }
    fn check(&self, p: &Params) -> Result<()> {
        Classify::from_params(p).map(|_| ())
    }
    fn ranges(&self, _: &Params) -> Result<RangeKind> {
        Ok(RangeKind::Bricks)
    }
    fn march(&self) -> March {
        // The GLSL traversal switches on specialization constant 0.
        const IDS: [u32; 4] = [0, 1, 2, 3];
        March {
            shader: shaders::MARCH_OCTREE,
            constants: std::slice::from_ref(&IDS[self.0 as usize]),
        }
    }
    /// Host-driven: the tree is built on the CPU from the flags read back.
    fn recordable(&self) -> bool {
        false
    }
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        ranges: &Ranges,
        p: &Params,
    ) -> Result<(Box<dyn Built>, Timings)> {
        let (tree, t) = build(builder, input, ranges.bricks()?, Classify::from_params(p)?, self.0)?;
        Ok((Box::new(tree), t))
    }
}

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for VolumeOctree {
    fn bindings(&self) -> Vec<Bound<'_>> {
        march_octree::Own {
            nodes: Binding::Storage(&self.nodes),
        }
        .list()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        Ok(Some(self.stats))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Leaf holding brick `b` (point location at the brick's centre).
    fn leaf_of(t: &BrickOctree, b: [u32; 3], brick: u32) -> &Node {
        let p = b.map(|v| ((v * brick) as f32) + brick as f32 * 0.5);
        let mut n = &t.nodes[0];
        while !n.is_leaf() {
            let mut c = 0;
            for (a, &v) in p.iter().enumerate() {
                if v > n.split[a] {
                    c |= axis_bit(a);
                }
            }
            n = &t.nodes[(n.first() + c) as usize];
        }
        n
    }

    #[test]
    fn leaves_are_empty_exactly_where_every_brick_is_inactive() {
        let counts = [5u32, 7, 3];
        let total = (counts[0] * counts[1] * counts[2]) as usize;
        for seed in 0..20u32 {
            // A deterministic mix of sparse and dense occupancy.
            let active: Vec<u32> = (0..total as u32)
                .map(|i| u32::from((i.wrapping_mul(2654435761).wrapping_add(seed * 977)) % 7 < seed % 7))
                .collect();
            let t = BrickOctree::build(counts, 8, &active);
            assert_eq!(t.nodes[0].lo[..3], [0.0; 3]);
            assert_eq!(t.nodes[0].hi[..3], [64.0; 3], "the cube of 2^k bricks");
            for z in 0..counts[2] {
                for y in 0..counts[1] {
                    for x in 0..counts[0] {
                        let i = (x + counts[0] * (y + counts[1] * z)) as usize;
                        let leaf = leaf_of(&t, [x, y, z], 8);
                        if active[i] != 0 {
                            assert_eq!(leaf.count(), 1, "an active brick lies in a nonempty leaf");
                        }
                    }
                }
            }
            let interior = t.nodes.len() as u64 - t.leaves;
            assert_eq!(t.leaves, 7 * interior + 1);
            let n_active = active.iter().filter(|&&a| a != 0).count();
            if n_active == 0 {
                assert_eq!(t.active_leaves, 0);
            }
            if n_active == total {
                assert!(t.active_leaves <= 8 && t.nodes.len() <= 9);
            }
        }
    }
}
