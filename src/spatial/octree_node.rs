//! The octree node format shared by the builder, the CPU reference and the
//! GLSL traversals (`glsl/common/octree_node.glsl`), 64 bytes, std430:
//!
//! - `lo`, `hi`: the node's box (w unused);
//! - `split`: the point where its three split planes meet (interior nodes);
//! - `info.x`: first of 8 contiguous children (interior) or first entry in
//!   the reference list (leaf); `info.y`: reference count (leaf);
//!   `info.z`: parent (the root's is itself); `info.w`: bit 0 = leaf,
//!   bits 1.. = depth.
//!
//! Child `i` lies on the high side of the x split when `i & 4`, of y when
//! `i & 2`, of z when `i & 1` (Revelles' numbering).

use bytemuck::{Pod, Zeroable};

/// An octree node as the traversals read it: its box, split point, and
/// children or primitive list in `info`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Node {
    pub lo: [f32; 4],
    pub hi: [f32; 4],
    pub split: [f32; 4],
    pub info: [u32; 4],
}

crate::gpu::check_layout!(Node => crate::gpu::shaders::blocks::OctNode {
    lo: lo,
    hi: hi,
    split: split,
    info: info,
});

impl Node {
    pub fn is_leaf(&self) -> bool {
        self.info[3] & 1 == 1
    }

    pub fn depth(&self) -> u32 {
        self.info[3] >> 1
    }

    pub fn first(&self) -> u32 {
        self.info[0]
    }

    pub fn count(&self) -> u32 {
        self.info[1]
    }

    pub fn parent(&self) -> u32 {
        self.info[2]
    }
}

/// Bit of axis `a` in a child index.
pub const fn axis_bit(a: usize) -> u32 {
    4 >> a
}
