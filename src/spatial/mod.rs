//! Spatial formats shared by more than one user, placed below both: the
//! 64-byte octree node and the four octree traversals (the CPU mirror of
//! `glsl/common/octree_traverse.glsl`), used by the volume octrees
//! (`accel::octree`) and by Havran's surface octrees (`octree`); and the 3-D
//! summed-area table the host-built structures count with.

pub mod octree_node;
pub mod octree_traverse;
pub mod sat;

pub use octree_node::Node as OctreeNode;
pub use octree_traverse::Traversal;
pub use sat::Sat3;
