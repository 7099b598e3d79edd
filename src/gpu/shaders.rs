//! SPIR-V of every `glsl/**/*.comp`, compiled by `build.rs` and embedded as
//! `u32` words (so no alignment trap from `include_bytes!`), each with the
//! interface `build.rs` read from the SPIR-V itself: kernels are created from
//! this, never from hand-kept copies of bindings or sizes.
//!
//! Generated beside each shader constant (`MARCH_GRID`) is a module of its
//! host-side interface (`march_grid`): `Push`, its push-constant block as a
//! `#[repr(C)]` Pod struct with the shader's member names, offsets and types,
//! and `Bindings` (march kernels: `Own`), its bindings as named fields.
//! Kernels bind by name, so a binding renumbered in a `.comp` still gets its
//! resource, and a binding renamed, added or removed, or a push member
//! renamed, retyped or moved, fails to compile where Rust fills them.
//! `blocks` holds the structs the host lays out in GPU memory
//! (`RenderParams`, the node and primitive formats), checked to agree across
//! every shader that declares them.

use ash::vk;

/// One workgroup dimension of a shader.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LocalDim {
    /// `local_size_x = N`.
    Fixed(u32),
    /// `local_size_x_id = id`: a specialization constant, with its default.
    Spec { id: u32, default: u32 },
}

/// One binding of set 0: its name in the shader (the variable's, or an
/// anonymous block's in snake_case), its type and, for a uniform or storage
/// block, the size of its fixed part in bytes (else 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    pub name: &'static str,
    pub ty: vk::DescriptorType,
    pub block_size: u32,
    /// Whether the shader may write it (a storage buffer not `readonly`,
    /// or a storage image).
    pub writes: bool,
}

/// A compute shader and its reflected interface.
#[derive(Clone, Copy, Debug)]
///
/// Only the generated constants of this module are shaders: a kernel is
/// made from SPIR-V compiled by `build.rs` with the interface read from it.
pub struct Shader {
    /// Path under `glsl/` without `.comp`, e.g. `march/naive`.
    pub(crate) name: &'static str,
    pub(crate) words: &'static [u32],
    /// Bindings 0.. of set 0.
    pub(crate) bindings: &'static [Slot],
    /// Size in bytes of the push-constant block (0: none).
    pub(crate) push_size: u32,
    pub(crate) local_size: [LocalDim; 3],
}

impl Shader {
    /// Its path under `glsl/` without `.comp`, e.g. `march/naive`.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Its SPIR-V words.
    pub fn words(&self) -> &'static [u32] {
        self.words
    }

    /// Bindings 0.. of set 0, as the SPIR-V declares them.
    pub fn bindings(&self) -> &'static [Slot] {
        self.bindings
    }

    /// Size in bytes of the push-constant block (0: none).
    pub fn push_size(&self) -> u32 {
        self.push_size
    }

    /// The workgroup size as declared: literal or specialization constants.
    pub fn local_size(&self) -> [LocalDim; 3] {
        self.local_size
    }

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

    /// The binding named `name`.
    pub fn slot(&self, name: &str) -> Option<(u32, &Slot)> {
        (0..).zip(self.bindings).find(|(_, s)| s.name == name)
    }
}

use super::binding::Binding;

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
