//! The volume on the GPU: a 3D image (R8/R16 UNORM kept native, else R32
//! float) read with `texelFetch`, so the sampler only needs nearest filtering.

use super::{Volume, VoxelData};
use crate::error::{Result, VkContext};
use crate::gpu::{vk, Context, Image3d};

pub struct GpuVolume {
    ctx: Context,
    pub image: Image3d,
    pub sampler: vk::Sampler,
    pub dims: [u32; 3],
    pub spacing: [f32; 3],
    /// Texel normalisation, as `Volume::norm`.
    pub norm: [f32; 2],
}

impl GpuVolume {
    /// Uploads `volume`; checks `maxImageDimension3D` and memory limits first.
    pub fn upload(ctx: &Context, volume: &Volume) -> Result<Self> {
        let (format, bytes): (vk::Format, &[u8]) = match &volume.data {
            VoxelData::U8(v) => (vk::Format::R8_UNORM, v),
            VoxelData::U16(v) => (vk::Format::R16_UNORM, bytemuck::cast_slice(v)),
            VoxelData::F32(v) => (vk::Format::R32_SFLOAT, bytemuck::cast_slice(v)),
        };
        let image = Image3d::with_data(ctx, &volume.name, format, volume.dims, volume.texel_bytes(), bytes)?;
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::NEAREST)
            .min_filter(vk::Filter::NEAREST)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .unnormalized_coordinates(false);
        let sampler = unsafe { ctx.device().create_sampler(&info, None) }.vk("vkCreateSampler")?;
        Ok(GpuVolume {
            ctx: ctx.clone(),
            image,
            sampler,
            dims: volume.dims,
            spacing: volume.spacing,
            norm: volume.norm,
        })
    }
}

impl Drop for GpuVolume {
    fn drop(&mut self) {
        unsafe { self.ctx.device().destroy_sampler(self.sampler, None) };
    }
}
