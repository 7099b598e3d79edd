//! The volume on the GPU: a 3D image (R8/R16 UNORM kept native, else R32
//! float) with a nearest sampler (`texelFetch`: the manual filter, ranges,
//! classification) and, where the format filters linearly, a linear one
//! for `Filter::Hardware`; and, for shaded and iso frames, the volume's
//! gradient (`gradient.rs`).

use super::filter::Filter;
use super::gradient::{gradient_texels, GRADIENT_TEXEL_BYTES};
use super::{Volume, VoxelData};
use crate::error::{Error, Result, VkContext};
use crate::gpu::{check_image3d, vk, Context, Image3d, Staging};

/// The gradient's texel format (x, y, z, unused).
const GRADIENT_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

pub struct GpuVolume {
    ctx: Context,
    pub image: Image3d,
    /// Nearest filtering: every `texelFetch` user binds this one.
    pub sampler: vk::Sampler,
    /// Linear filtering, clamp to edge; None where the format lacks
    /// `SAMPLED_IMAGE_FILTER_LINEAR` on this device.
    linear: Option<vk::Sampler>,
    pub dims: [u32; 3],
    pub spacing: [f32; 3],
    /// Texel normalisation, as `Volume::norm`.
    pub norm: [f32; 2],
    /// It holds NaN voxels (no data): the march kernels test samples for
    /// NaN, and only the manual filter samples it.
    pub has_nan: bool,
    /// The gradient shaded and iso frames read (`add_gradient`).
    gradient: Option<Image3d>,
}

fn sampler(ctx: &Context, filter: vk::Filter) -> Result<vk::Sampler> {
    // Normalised coordinates: Vulkan forbids unnormalised ones on 3D images.
    // Clamp to edge equals the manual path's clamped texel indices.
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(filter)
        .min_filter(filter)
        .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
        .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .unnormalized_coordinates(false);
    unsafe { ctx.device().create_sampler(&info, None) }.vk("vkCreateSampler")
}

/// The image format and texel bytes of a volume (R8/R16 kept native).
fn texels(volume: &Volume) -> (vk::Format, &[u8]) {
    match &volume.data {
        VoxelData::U8(v) => (vk::Format::R8_UNORM, v),
        VoxelData::U16(v) => (vk::Format::R16_UNORM, bytemuck::cast_slice(v)),
        VoxelData::F32(v) => (vk::Format::R32_SFLOAT, bytemuck::cast_slice(v)),
    }
}

impl GpuVolume {
    /// Uploads `volume` and waits; checks `maxImageDimension3D` and memory
    /// limits first.
    pub fn upload(ctx: &Context, volume: &Volume) -> Result<Self> {
        let (format, bytes) = texels(volume);
        let image = Image3d::with_data(ctx, &volume.name, format, volume.dims, volume.texel_bytes(), bytes)?;
        Self::with_image(ctx, volume, image)
    }

    /// As `upload`, recorded into `cmd`: leaves the image in
    /// SHADER_READ_ONLY_OPTIMAL behind a barrier to compute-shader reads.
    /// Keep the returned `Staging` until the submission completed.
    pub fn record_upload(ctx: &Context, cmd: vk::CommandBuffer, volume: &Volume) -> Result<(Self, Staging)> {
        let (format, bytes) = texels(volume);
        let (image, staging) =
            Image3d::record_with_data(ctx, cmd, &volume.name, format, volume.dims, volume.texel_bytes(), bytes)?;
        Ok((Self::with_image(ctx, volume, image)?, staging))
    }

    fn with_image(ctx: &Context, volume: &Volume, image: Image3d) -> Result<Self> {
        let format = image.format;
        let mut gv = GpuVolume {
            ctx: ctx.clone(),
            image,
            sampler: sampler(ctx, vk::Filter::NEAREST)?,
            linear: None,
            dims: volume.dims,
            spacing: volume.spacing,
            norm: volume.norm,
            has_nan: volume.no_data.total() > 0,
            gradient: None,
        };
        if ctx.filters_linearly(format) {
            gv.linear = Some(sampler(ctx, vk::Filter::LINEAR)?);
        }
        Ok(gv)
    }

    /// The sampler the march kernels bind for `filter`; hardware filtering
    /// of a format the device cannot filter is an error naming the format.
    pub fn sampler_for(&self, filter: Filter) -> Result<vk::Sampler> {
        match (filter, self.linear) {
            (Filter::Manual, _) => Ok(self.sampler),
            // IEEE arithmetic carries a NaN voxel into every sample that
            // reads it; a filter unit's fixed-point weights need not.
            (Filter::Hardware, _) if self.has_nan => Err(Error::invalid(
                "filter",
                "hardware",
                "the volume has voxels without data (NaN), which only the manual filter samples exactly; use --filter manual",
            )),
            (Filter::Hardware, Some(linear)) => Ok(linear),
            (Filter::Hardware, None) => Err(Error::invalid(
                "filter",
                "hardware",
                format!(
                    "{} has no linear filtering of {:?} (SAMPLED_IMAGE_FILTER_LINEAR); use --filter manual",
                    self.ctx.info().name,
                    self.image.format
                ),
            )),
        }
    }

    /// Uploads the gradient shaded and iso frames read (`volume`'s, the
    /// volume this was uploaded from: `volume::gradient_texels`) and waits.
    /// 8 bytes per voxel; once is enough.
    pub fn add_gradient(&mut self, volume: &Volume) -> Result<()> {
        let ctx = self.ctx.clone();
        self.put_gradient(volume, |bytes, dims| {
            let image = Image3d::with_data(&ctx, "gradient", GRADIENT_FORMAT, dims, GRADIENT_TEXEL_BYTES, bytes)?;
            Ok((image, ()))
        })?;
        Ok(())
    }

    /// As `add_gradient`, recorded into `cmd` (see `record_upload`); None
    /// when it is already there.
    pub fn record_add_gradient(&mut self, cmd: vk::CommandBuffer, volume: &Volume) -> Result<Option<Staging>> {
        let ctx = self.ctx.clone();
        self.put_gradient(volume, |bytes, dims| {
            Image3d::record_with_data(
                &ctx,
                cmd,
                "gradient",
                GRADIENT_FORMAT,
                dims,
                GRADIENT_TEXEL_BYTES,
                bytes,
            )
        })
    }

    /// Computes the gradient and hands its bytes to `upload`, unless it is
    /// already there.
    fn put_gradient<R>(
        &mut self,
        volume: &Volume,
        upload: impl FnOnce(&[u8], [u32; 3]) -> Result<(Image3d, R)>,
    ) -> Result<Option<R>> {
        if self.gradient.is_some() {
            return Ok(None);
        }
        let texels = self.gradient_texels(volume)?;
        let (image, extra) = upload(bytemuck::cast_slice(&texels), self.dims)?;
        self.gradient = Some(image);
        Ok(Some(extra))
    }

    fn gradient_texels(&self, volume: &Volume) -> Result<Vec<[half::f16; 4]>> {
        if volume.dims != self.dims || volume.norm != self.norm {
            return Err(Error::invalid(
                "gradient",
                volume.name.clone(),
                "is not the volume this was uploaded from",
            ));
        }
        check_image3d(self.ctx.info(), self.dims, GRADIENT_TEXEL_BYTES)?;
        crate::limits::check_host(
            format_args!("gradient of {}", volume.name),
            volume.voxel_count(),
            GRADIENT_TEXEL_BYTES,
        )?;
        Ok(gradient_texels(volume))
    }

    /// The gradient's view, where `add_gradient` uploaded it.
    pub fn gradient_view(&self) -> Option<vk::ImageView> {
        self.gradient.as_ref().map(|g| g.view)
    }

    /// The faster filter this volume supports on this device (`Filter::device_default`).
    pub fn default_filter(&self) -> Filter {
        Filter::device_default(self.linear.is_some() && !self.has_nan)
    }
}

impl Drop for GpuVolume {
    fn drop(&mut self) {
        unsafe {
            self.ctx.device().destroy_sampler(self.sampler, None);
            if let Some(linear) = self.linear {
                self.ctx.device().destroy_sampler(linear, None);
            }
        }
    }
}
