//! Trees in the shared 32-byte node format that `glsl/march/bvh.comp` (and
//! the hybrid kernel) traverse: the LBVH and the k-d trees.
//!
//! Node format (`glsl/common/bvh_node.glsl`): `lo: [i32; 4]`, `hi: [i32; 4]`.
//! `lo[0..3]`/`hi[0..3]` are the node's box in voxel units. `lo[3]` is the
//! left child, or -1 for a leaf; `hi[3]` is the right child, or for a leaf a
//! payload (the LBVH's brick index, a k-d leaf's number). The root is node 0.
//! Siblings' boxes lie on opposite sides of their split plane, which is what
//! makes the stack traversal visit leaves in ray order.

use super::registry::{Built, March};
use super::stats::Stats;
use crate::error::Result;
use crate::gpu::{shaders, vk, Binding, Buffer, Context, MemoryLocation};

/// The march kernel of every structure in this format (`glsl/march/bvh.comp`).
pub const TREE_MARCH: March = March::plain(shaders::MARCH_BVH);

impl Built for GpuTree {
    fn bindings(&self) -> Vec<Binding<'_>> {
        vec![Binding::Storage(&self.nodes), Binding::Storage(&self.count)]
    }
    fn stats(&self) -> Result<Option<Stats>> {
        GpuTree::stats(self).map(Some)
    }
    fn tree(&self) -> Option<&GpuTree> {
        Some(self)
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Node {
    pub lo: [i32; 4],
    pub hi: [i32; 4],
}

impl Node {
    pub fn is_leaf(&self) -> bool {
        self.lo[3] < 0
    }

    pub fn leaf(lo: [i32; 3], hi: [i32; 3], payload: i32) -> Self {
        Node {
            lo: [lo[0], lo[1], lo[2], -1],
            hi: [hi[0], hi[1], hi[2], payload],
        }
    }

    pub fn inner(lo: [i32; 3], hi: [i32; 3], left: i32, right: i32) -> Self {
        Node {
            lo: [lo[0], lo[1], lo[2], left],
            hi: [hi[0], hi[1], hi[2], right],
        }
    }

    pub fn bounds(&self) -> ([i32; 3], [i32; 3]) {
        (
            [self.lo[0], self.lo[1], self.lo[2]],
            [self.hi[0], self.hi[1], self.hi[2]],
        )
    }
}

/// Height (nodes on the longest root-to-leaf path) of a node array.
pub fn height(nodes: &[Node]) -> u32 {
    if nodes.is_empty() {
        return 0;
    }
    let mut best = 0;
    let mut stack = vec![(0usize, 1u32)];
    while let Some((i, depth)) = stack.pop() {
        best = best.max(depth);
        let n = nodes[i];
        if !n.is_leaf() {
            stack.push((n.lo[3] as usize, depth + 1));
            stack.push((n.hi[3] as usize, depth + 1));
        }
    }
    best
}

/// A tree on the GPU: what the tree march kernels read.
pub struct GpuTree {
    pub nodes: Buffer,
    /// u32 leaf count on the GPU (0: empty tree, nothing is marched).
    pub count: Buffer,
    pub leaves: u32,
    pub node_count: u32,
    /// Statistics known at build time; the height is derived on request.
    pub(crate) stats: Stats,
    /// Known at upload for CPU-built trees; an LBVH reads its nodes back for
    /// it only when statistics are asked for, never on the build path.
    pub(crate) height: std::sync::OnceLock<u32>,
}

pub(crate) const STORAGE_XFER: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw()
        | vk::BufferUsageFlags::TRANSFER_SRC.as_raw()
        | vk::BufferUsageFlags::TRANSFER_DST.as_raw(),
);

impl GpuTree {
    /// Uploads a tree built on the CPU.
    pub fn upload(ctx: &Context, nodes: &[Node], mut stats: Stats) -> Result<Self> {
        let leaves = nodes.iter().filter(|n| n.is_leaf()).count() as u32;
        crate::prims::check_range(ctx.info(), "tree nodes", nodes.len() as u64 * 32)?;
        let node_buf = if nodes.is_empty() {
            Buffer::new(ctx, "tree nodes", 32, STORAGE_XFER, MemoryLocation::GpuOnly)?
        } else {
            Buffer::with_data(ctx, "tree nodes", bytemuck::cast_slice(nodes), STORAGE_XFER)?
        };
        let count = Buffer::with_data(ctx, "tree leaf count", bytemuck::bytes_of(&leaves), STORAGE_XFER)?;
        stats.nodes = nodes.len() as u64;
        stats.leaves = leaves as u64;
        stats.bytes = nodes.len() as u64 * 32;
        Ok(GpuTree {
            nodes: node_buf,
            count,
            leaves,
            node_count: nodes.len() as u32,
            stats,
            height: std::sync::OnceLock::from(height(nodes)),
        })
    }

    /// The paper's Table 1 statistics (reads the nodes back once if the
    /// height is not known yet).
    pub fn stats(&self) -> Result<Stats> {
        let h = match self.height.get() {
            Some(h) => *h,
            None => {
                let h = height(&self.read_nodes()?);
                *self.height.get_or_init(|| h)
            }
        };
        Ok(Stats {
            height: h,
            ..self.stats
        })
    }

    /// Reads the node array back (for tests and inspection).
    pub fn read_nodes(&self) -> Result<Vec<Node>> {
        if self.node_count == 0 {
            return Ok(Vec::new());
        }
        Ok(bytemuck::pod_collect_to_vec(
            &self.nodes.download(0, self.node_count as u64 * 32)?,
        ))
    }
}
