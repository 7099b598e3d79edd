//! Trees in the shared 32-byte node format that `glsl/march/bvh.comp` (and
//! the hybrid kernel) traverse: the LBVH and the k-d trees.
//!
//! Node format (`glsl/common/bvh_node.glsl`): `lo: [i32; 4]`, `hi: [i32; 4]`.
//! `lo[0..3]`/`hi[0..3]` are the node's box in voxel units. `lo[3]` is the
//! left child, or -1 for a leaf; `hi[3]` is the right child, or for a leaf a
//! payload (the LBVH's brick index, a k-d leaf's number). The root is node 0.
//! Siblings' boxes lie on opposite sides of their split plane, which is what
//! makes the stack traversal visit leaves in ray order.

use super::method::{Built, March, MarchedAs, MarchedKind, Structure};
use super::naive::NAIVE;
use super::stats::Stats;
use crate::error::Result;
use crate::gpu::shaders::{self, march_bvh};
use crate::gpu::{vk, Binding, Bound, Buffer, Context, MemoryLocation, Timings};

/// The march kernel of every structure in this format (`glsl/march/bvh.comp`).
pub const TREE_MARCH: March = March::plain(shaders::MARCH_BVH);

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for GpuTree {
    fn bindings(&self) -> Vec<Bound<'_>> {
        if self.whole_box {
            // Marched by the naive kernel, which binds nothing of a structure.
            return Vec::new();
        }
        march_bvh::Own {
            nodes: Binding::Storage(&self.nodes),
            count: Binding::Storage(&self.count),
        }
        .list()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        GpuTree::stats(self).map(Some)
    }
    /// A tree of one leaf covering the volume box has nothing to skip: the
    /// naive kernel takes the same samples without a traversal.
    fn marched_as(&self) -> Option<MarchedAs> {
        self.whole_box.then(|| MarchedAs {
            accel: NAIVE,
            label: NAIVE.name().into(),
            reason: "the tree is one leaf covering the volume".into(),
            kind: MarchedKind::NothingToSkip,
        })
    }
}

impl Structure {
    /// The tree, for structures in the shared node format (LBVH, k-d trees).
    pub fn tree(&self) -> Option<&GpuTree> {
        self.built_as::<GpuTree>()
    }
}

/// A tree node as the march reads it: its box in voxels, and in the fourth
/// words the two children (interior) or -1 and the leaf's payload (a leaf).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Node {
    pub lo: [i32; 4],
    pub hi: [i32; 4],
}

crate::gpu::check_layout!(Node => shaders::blocks::BvhNode { lo: lo, hi: hi });

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
    shape(nodes).height
}

/// What the traversal reaches from the root: nodes, leaves and height. A
/// collapsed subtree's nodes stay in the array but are not reached.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Shape {
    pub nodes: u64,
    pub leaves: u64,
    pub height: u32,
}

/// The reachable shape of a node array (root 0).
pub fn shape(nodes: &[Node]) -> Shape {
    let mut s = Shape::default();
    if nodes.is_empty() {
        return s;
    }
    let mut stack = vec![(0usize, 1u32)];
    while let Some((i, depth)) = stack.pop() {
        s.nodes += 1;
        s.height = s.height.max(depth);
        let n = nodes[i];
        if n.is_leaf() {
            s.leaves += 1;
        } else {
            stack.push((n.lo[3] as usize, depth + 1));
            stack.push((n.hi[3] as usize, depth + 1));
        }
    }
    s
}

/// A tree on the GPU: what the tree march kernels read.
pub struct GpuTree {
    pub nodes: Buffer,
    /// u32 leaf count on the GPU (0: empty tree, nothing is marched).
    pub count: Buffer,
    /// Leaf and node counts: known at build time, except for an LBVH whose
    /// build was recorded (its active count exists only on the GPU until the
    /// submission completed; read from `count` on first request).
    pub(crate) sizes: std::sync::OnceLock<Sizes>,
    /// Statistics known at build time; the reachable shape (nodes, leaves,
    /// height) is derived on request, and for a recorded LBVH the active
    /// brick count and bytes too.
    pub(crate) stats: Stats,
    /// Known at upload for CPU-built trees; an LBVH reads its nodes back for
    /// it only when statistics are asked for (the build path reads at most a
    /// collapsed tree's root: `whole_box_leaf`).
    pub(crate) shape: std::sync::OnceLock<Shape>,
    /// Scratch buffers a recorded build's command buffer uses, kept alive
    /// with the structure (which must outlive the submission anyway); set
    /// exactly for recorded LBVH builds.
    pub(crate) keep: Option<Box<dyn std::any::Any + Send + Sync>>,
    /// One leaf covering the volume box (`check_whole_box`): marched naively.
    pub(crate) whole_box: bool,
}

/// A tree's leaf count and the length of its node array.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Sizes {
    pub leaves: u32,
    pub node_count: u32,
}

impl Sizes {
    /// An LBVH over n bricks: 2n - 1 nodes (none for n = 0).
    pub fn lbvh(n: u32) -> Self {
        Sizes {
            leaves: n,
            node_count: if n == 0 { 0 } else { 2 * n - 1 },
        }
    }
}

pub(crate) const STORAGE_XFER: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw()
        | vk::BufferUsageFlags::TRANSFER_SRC.as_raw()
        | vk::BufferUsageFlags::TRANSFER_DST.as_raw(),
);

/// `STORAGE_XFER`, and read by a march kernel as a texel buffer (the
/// distance maps, the grid's cells).
pub(crate) const STORAGE_TEXELS: vk::BufferUsageFlags =
    vk::BufferUsageFlags::from_raw(STORAGE_XFER.as_raw() | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER.as_raw());

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
        stats.bytes = nodes.len() as u64 * 32;
        Ok(GpuTree {
            nodes: node_buf,
            count,
            sizes: std::sync::OnceLock::from(Sizes {
                leaves,
                node_count: nodes.len() as u32,
            }),
            stats,
            shape: std::sync::OnceLock::from(shape(nodes)),
            keep: None,
            whole_box: false,
        })
    }

    fn sizes(&self) -> Result<Sizes> {
        if let Some(s) = self.sizes.get() {
            return Ok(*s);
        }
        // Only a recorded LBVH defers its sizes: read its leaf count (after
        // the submission completed).
        let n: u32 = bytemuck::pod_read_unaligned(&self.count.download(0, 4)?);
        Ok(*self.sizes.get_or_init(|| Sizes::lbvh(n)))
    }

    /// The root node when it is a leaf whose box is all of `dims` (a tree
    /// with nothing to skip), else None. Reads the root back (32 bytes) only
    /// when its sizes cannot rule it out: a tree whose shape is known at
    /// upload is one leaf only with one node, an uncollapsed LBVH only with
    /// one brick.
    pub fn whole_box_leaf(&self, dims: [u32; 3], collapsed: bool) -> Result<Option<Node>> {
        let sizes = self.sizes()?;
        let known_inner = match self.shape.get() {
            Some(shape) => shape.nodes != 1,
            None => !collapsed && sizes.leaves != 1,
        };
        if sizes.node_count == 0 || known_inner {
            return Ok(None);
        }
        let root: Node = bytemuck::pod_read_unaligned(&self.nodes.download(0, 32)?);
        let whole = (0..3).all(|a| root.lo[a] <= 0 && root.hi[a] >= dims[a] as i32);
        Ok((root.is_leaf() && whole).then_some(root))
    }

    /// After a host build (phase "root check"): whether the tree is one leaf
    /// covering the volume of `dims`, which the naive kernel then marches
    /// (`Built::marched_as`). Recorded builds cannot read back and skip it.
    pub(crate) fn check_whole_box(&mut self, dims: [u32; 3], collapsed: bool, t: &mut Timings) -> Result<()> {
        self.whole_box = t.cpu("root check", || self.whole_box_leaf(dims, collapsed))?.is_some();
        Ok(())
    }

    /// The number of leaves the build produced (for an LBVH, its active
    /// bricks; a recorded LBVH reads it back once, after its submission).
    pub fn leaves(&self) -> Result<u32> {
        Ok(self.sizes()?.leaves)
    }

    /// The number of nodes the build wrote (0 for an empty tree; a recorded
    /// LBVH's node buffer is larger, sized for every brick).
    pub fn node_count(&self) -> Result<u32> {
        Ok(self.sizes()?.node_count)
    }

    /// The paper's Table 1 statistics, nodes and leaves as the traversal
    /// reaches them (reads the nodes back once if not known yet). `bytes` is
    /// the node array's size.
    pub fn stats(&self) -> Result<Stats> {
        let sizes = self.sizes()?;
        let mut known = self.stats;
        if self.keep.is_some() {
            // A recorded LBVH: what the host path knows at build time.
            known.active_bricks = sizes.leaves as u64;
            known.bytes = sizes.node_count as u64 * 32;
        }
        let s = match self.shape.get() {
            Some(s) => *s,
            None => {
                let s = shape(&self.read_nodes()?);
                *self.shape.get_or_init(|| s)
            }
        };
        Ok(Stats {
            nodes: s.nodes,
            leaves: s.leaves,
            height: s.height,
            ..known
        })
    }

    /// Reads the node array back (for tests and inspection).
    pub fn read_nodes(&self) -> Result<Vec<Node>> {
        let count = self.node_count()? as u64;
        if count == 0 {
            return Ok(Vec::new());
        }
        Ok(bytemuck::pod_collect_to_vec(&self.nodes.download(0, count * 32)?))
    }
}
