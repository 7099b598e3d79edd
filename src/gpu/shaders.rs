//! SPIR-V of every `glsl/**/*.comp`, compiled by `build.rs` and embedded as
//! `u32` words (so no alignment trap from `include_bytes!`), each with the
//! interface `build.rs` read from the SPIR-V itself: kernels are created from
//! this, never from hand-kept copies of bindings or sizes.

use ash::vk;

/// One workgroup dimension of a shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocalDim {
    /// `local_size_x = N`.
    Fixed(u32),
    /// `local_size_x_id = id`: a specialization constant, with its default.
    Spec { id: u32, default: u32 },
}

/// A compute shader and its reflected interface.
#[derive(Clone, Copy, Debug)]
pub struct Shader {
    /// Path under `glsl/` without `.comp`, e.g. `march/naive`.
    pub name: &'static str,
    pub words: &'static [u32],
    /// Descriptor types of bindings 0.. of set 0.
    pub bindings: &'static [vk::DescriptorType],
    /// Per binding: the block size in bytes of a uniform or storage buffer
    /// (of a storage block ending in a runtime array, the part before it),
    /// else 0.
    pub block_sizes: &'static [u32],
    /// Size in bytes of the push-constant block (0: none).
    pub push_size: u32,
    pub local_size: [LocalDim; 3],
}

impl Shader {
    /// The workgroup size with specialization `constants` (constant_id 0, 1, ...).
    pub fn local_size_with(&self, constants: &[u32]) -> [u32; 3] {
        let entries: Vec<(u32, u32)> = (0..).zip(constants.iter().copied()).collect();
        self.local_size_for(&entries)
    }

    /// The workgroup size with specialization (`constant_id`, value) pairs.
    pub fn local_size_for(&self, constants: &[(u32, u32)]) -> [u32; 3] {
        self.local_size.map(|d| match d {
            LocalDim::Fixed(n) => n,
            LocalDim::Spec { id, default } => constants.iter().find(|c| c.0 == id).map_or(default, |c| c.1),
        })
    }
}

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
