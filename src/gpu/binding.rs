//! What a kernel binds: a resource (`Binding`) with the name of the shader
//! binding it goes to (`Bound`). The generated `shaders::NAME::Bindings`
//! structs list them.

use super::memory::{Buffer, TexelBuffer};
use ash::vk;

/// A resource bound at one binding slot.
#[derive(Clone, Copy)]
pub enum Binding<'a> {
    Storage(&'a Buffer),
    /// A byte range (offset, size) of a storage buffer that may be the
    /// host's (a raw handle).
    StorageRange(vk::Buffer, u64, u64),
    Uniform(&'a Buffer),
    /// A sampled image with its sampler (`sampler3D` in GLSL), in
    /// SHADER_READ_ONLY_OPTIMAL.
    Sampled(vk::ImageView, vk::Sampler),
    /// A sampled image with its sampler in the given layout (a host's depth
    /// image in DEPTH_READ_ONLY_OPTIMAL, say).
    SampledIn(vk::ImageView, vk::Sampler, vk::ImageLayout),
    /// A storage image (`image2D` in GLSL) in GENERAL layout.
    StorageImage(vk::ImageView),
    /// A uniform texel buffer (`samplerBuffer` in GLSL): lacuna's.
    Texels(&'a TexelBuffer),
    /// A uniform texel buffer as a raw buffer view (a host's).
    TexelBuffer(vk::BufferView),
}

impl Binding<'_> {
    pub(crate) fn descriptor_type(&self) -> vk::DescriptorType {
        match self {
            Binding::Storage(_) | Binding::StorageRange(..) => vk::DescriptorType::STORAGE_BUFFER,
            Binding::Uniform(_) => vk::DescriptorType::UNIFORM_BUFFER,
            Binding::Sampled(..) | Binding::SampledIn(..) => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            Binding::StorageImage(_) => vk::DescriptorType::STORAGE_IMAGE,
            Binding::Texels(_) | Binding::TexelBuffer(_) => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
        }
    }
}

/// A resource with the name of the binding it goes to.
pub type Bound<'a> = (&'static str, Binding<'a>);
