//! Frames and files: the `Frame` type with its OpenEXR reading and writing,
//! frame diffs, and atomic writes (a temporary name, then a rename, so no
//! partial file is ever left). Used by render, octree, scene and bench.

mod atomic;
pub mod diff;
mod exr;

pub use atomic::{check_parent, write_atomically};
pub use diff::{diff, DiffStats};
pub use exr::Frame;
