//! The volume on the GPU: a 3D image (R8/R16 UNORM kept native, else R32
//! float) with a nearest sampler (`texelFetch`: the manual filter, ranges,
//! classification) and, where the format filters linearly, a linear one
//! for `Filter::Hardware`; for shaded and iso frames, the volume's
//! gradient (`gradient.rs`); and optionally the cells copy the manual
//! filter reads one texel per sample from (`cells.rs`). With bricked
//! storage (`pool.rs`) the image is the brick pool and the brick table
//! finds each voxel in it.

use super::cells::{self, TexelKind};
use super::filter::Filter;
use super::gpu_pool::{brick_table, check_pool, plan_pool, pool_image_texels, BRICK_TABLE_FORMAT, BRICK_TABLE_USAGE};
use super::gradient::{gradient_texels, GRADIENT_TEXEL_BYTES};
use super::gradient_cells;
use super::pool::{BrickBox, PoolLayout, PoolLimits, PoolStats, Storage};
use super::{channels, HostPool, Volume, VoxelData, MAX_CHANNELS};
use crate::error::{Error, Result, VkContext};
use crate::gpu::Recording;
use crate::gpu::{check_image3d, vk, Buffer, Context, Image3d, Kernel, Staging, TexelBuffer};
use std::borrow::Cow;

/// The gradient's texel format (x, y, z, unused).
const GRADIENT_FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// Its fields are read through methods (`dims()`, `image()`, ...): the
/// kernels trust them to describe the memory it owns.
pub struct GpuVolume {
    pub(super) ctx: Context,
    /// The volume's texels: the dense image, or the brick pool.
    pub(crate) image: Image3d,
    /// Nearest filtering: every `texelFetch` user binds this one.
    pub(crate) sampler: vk::Sampler,
    /// Linear filtering, clamp to edge; None where the format lacks
    /// `SAMPLED_IMAGE_FILTER_LINEAR` on this device.
    linear: Option<vk::Sampler>,
    pub(crate) dims: [u32; 3],
    pub(crate) spacing: [f32; 3],
    /// Texel normalisation, as `Volume::norm` (channel 1's).
    pub(crate) norm: [f32; 2],
    /// How many channels each texel holds (`Volume::channel_count`).
    pub(crate) channels: u32,
    /// Each channel's texel normalisation (unused channels: [0, 0]).
    pub(crate) norms: [[f32; 2]; MAX_CHANNELS],
    /// It holds NaN voxels (no data): the march kernels test samples for
    /// NaN, and only the manual filter samples it.
    pub(crate) has_nan: bool,
    /// How texels are stored (the march kernels' `VOLUME_KIND`).
    pub(crate) kind: TexelKind,
    /// The gradient shaded and iso frames read (`add_gradient`).
    pub(super) gradient: Option<Image3d>,
    /// The cells copy the manual filter reads (`add_cells`).
    pub(super) cells: Option<TexelBuffer>,
    /// The kernel `record_add_cells` recorded: kept while a recorded
    /// packing may be pending.
    pub(super) cells_kernel: Option<Kernel>,
    /// The gradient's cells copy the manual filter reads in lit frames
    /// (`add_gradient`, when the volume has its cells copy).
    pub(super) gradient_cells: Option<TexelBuffer>,
    /// The brick table (RG32UI); a 16-byte stand-in with dense storage.
    brick_table: TexelBuffer,
    /// The pool's images past the first (`image`), where it spans several.
    pool_images: Vec<Image3d>,
    /// The staging buffer `replace` writes a series' steps through, kept
    /// from step to step (no new memory to fault in per step): as large as
    /// the largest upload chunk so far, at most 64 MiB (`STAGING_CHUNK`)
    /// or one z-slice where a slice is larger; a lit series' gradient
    /// (8 bytes a voxel) takes it there for volumes past 2^23 voxels.
    pub(super) step_staging: Option<Buffer>,
    /// The staging buffer a series' steps pass through to the image where
    /// the image fits one (`Image3d::upload_mirrored`): it holds the last
    /// step's texels, so a step rewrites in it only what changed.
    pub(super) image_mirror: Option<Buffer>,
    /// Bricked storage's layout in numbers; None: dense (`pool()`).
    pub(crate) pool: Option<PoolStats>,
    /// Whether `replace` with the step before at hand uploads only the
    /// bricks of the image that changed (one copy region each), rather
    /// than the whole image. By default on devices that are not the CPU
    /// (the copy crosses a bus, regions are cheap); lavapipe copies
    /// region by region at about a millisecond each (nbody:256's thousand
    /// took 1.25 s against 5 ms for the whole image).
    pub upload_changed: bool,
    /// A series step (`upload_step`): which, and what changed from the
    /// step before, for the builds that reuse that step's work.
    pub(super) step: Option<StepMark>,
    /// Unique to this upload in this process (`content_id` before a step).
    pub(super) uploaded: u64,
}

/// A dense series step's identity on the device, and where it was put in
/// place of the step before with that step's voxels at hand (or, on a CPU
/// device, the staging mirror of them), what changed since (`replace`).
#[derive(Clone, Debug)]
pub struct StepMark {
    /// Unique to these texels in this process.
    pub id: u64,
    /// The step before's `id` and the segments changed since.
    pub since: Option<(u64, std::sync::Arc<super::StepDelta>)>,
}

impl StepMark {
    pub(super) fn new(since: Option<(u64, std::sync::Arc<super::StepDelta>)>) -> StepMark {
        StepMark { id: next_id(), since }
    }
}

/// A number no upload or step of this process had before.
fn next_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
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

/// The image format, texel size and bytes of a volume (R8/R16 kept
/// native; several channels interleaved, `channels.rs`).
pub(super) fn texels(volume: &Volume) -> Result<(vk::Format, u64, Cow<'_, [u8]>)> {
    let (kind, n) = (channels::common_kind(volume), volume.channel_count());
    let texel = channels::texel_bytes(kind, n);
    // A volume streamed into bricks is made whole here: checked first.
    if let VoxelData::Bricks(_) = &volume.data {
        let what = format_args!(
            "{} made dense for its upload (upload_as keeps it in bricks)",
            volume.name
        );
        crate::limits::check_host(what, volume.data.len() as u64, texel)?;
    }
    Ok((channels::format(kind, n), texel, channels::texel_data(volume)))
}

/// Checks `volume`'s dense image (every channel) against `info`'s limits;
/// returns its bytes.
pub fn check_dense(info: &crate::gpu::DeviceInfo, volume: &Volume) -> Result<u64> {
    let (kind, n) = (channels::common_kind(volume), volume.channel_count());
    check_image3d(info, volume.dims, channels::texel_bytes(kind, n))
}

/// The storage `storage` means for `volume` on this device: auto is dense
/// while the dense image fits the device's limits.
pub fn resolve_storage(ctx: &Context, volume: &Volume, storage: Storage) -> Storage {
    // Streamed into bricks: uploaded as it is.
    if let (Storage::Auto, VoxelData::Bricks(host)) = (storage, &volume.data) {
        return Storage::Bricks { edge: host.layout.edge };
    }
    match storage {
        Storage::Auto => match check_dense(ctx.info(), volume) {
            Ok(_) => Storage::Dense,
            Err(_) => Storage::BRICKS,
        },
        s => s,
    }
}

impl GpuVolume {
    /// Uploads `volume` (auto storage: `upload_as`) and waits. Frames then
    /// sample with `Filter::device_default`; `prepare` adds what a CPU
    /// device's faster filter reads (`lacuna render` calls it, so its
    /// frames are those of an upload then prepared).
    pub fn upload(ctx: &Context, volume: &Volume) -> Result<Self> {
        Self::upload_as(ctx, volume, Storage::Auto)
    }

    /// Uploads `volume` in `storage` and waits; checks the device's image,
    /// allocation and heap limits first (bricks: the pool's, after the
    /// bricks are sorted).
    pub fn upload_as(ctx: &Context, volume: &Volume, storage: Storage) -> Result<Self> {
        volume.check()?;
        if let Storage::Bricks { edge } = resolve_storage(ctx, volume, storage) {
            return Self::upload_bricks(ctx, volume, edge);
        }
        let (format, texel, bytes) = texels(volume)?;
        let image = Image3d::with_data(ctx, &volume.name, format, volume.dims, texel, &bytes)?;
        Self::with_images(ctx, volume, vec![image], None)
    }

    /// Uploads `volume` in bricks of `edge`^3 voxels and waits.
    pub fn upload_bricks(ctx: &Context, volume: &Volume, edge: u32) -> Result<Self> {
        Self::upload_bricks_within(ctx, volume, edge, PoolLimits::of(ctx.info()))
    }

    /// As `upload_bricks`, each pool image also within `limits` (to leave
    /// a device room, or to split a pool on purpose).
    pub fn upload_bricks_within(ctx: &Context, volume: &Volume, edge: u32, limits: PoolLimits) -> Result<Self> {
        volume.check()?;
        Self::upload_pool(ctx, volume, edge, limits, None)
    }

    /// Uploads only the bricks of `volume` inside `keep` (one rank's block
    /// and its ghost bricks, `crate::parallel`) and waits: samples inside
    /// `keep` less one brick equal the whole volume's; outside, the pool
    /// holds stand-in values no frame cropped to the block reads.
    pub fn upload_bricks_kept(ctx: &Context, volume: &Volume, edge: u32, keep: BrickBox) -> Result<Self> {
        volume.check()?;
        Self::upload_pool(ctx, volume, edge, PoolLimits::of(ctx.info()), Some(keep))
    }

    fn upload_pool(
        ctx: &Context,
        volume: &Volume,
        edge: u32,
        limits: PoolLimits,
        keep: Option<BrickBox>,
    ) -> Result<Self> {
        if let VoxelData::Bricks(host) = &volume.data {
            return Self::upload_host_pool(ctx, volume, host, edge);
        }
        let (format, texel, bytes) = texels(volume)?;
        let layout = plan_pool(ctx, volume, (texel, &bytes), edge, limits, keep)?;
        // One image's texels on the host at a time.
        let mut images = Vec::with_capacity(layout.images.len());
        for k in 0..layout.images.len() {
            let pool = pool_image_texels(&layout, k, &bytes)?;
            images.push(Image3d::with_data(
                ctx,
                "brick pool",
                format,
                layout.extent(k),
                texel,
                &pool,
            )?);
        }
        Self::with_images(ctx, volume, images, Some((&layout, brick_table(ctx, &layout)?)))
    }

    /// A volume streamed into bricks (`HostPool`): its slots copied into
    /// the pool images a staging chunk at a time, never a whole image on
    /// the host. Its bricks (and those it keeps) were chosen as it loaded.
    fn upload_host_pool(ctx: &Context, volume: &Volume, host: &HostPool, edge: u32) -> Result<Self> {
        let layout = &host.layout;
        if layout.edge != edge {
            return Err(Error::invalid(
                "brick edge",
                edge.to_string(),
                format!("{} was streamed into bricks of {}", volume.name, layout.edge),
            ));
        }
        check_pool(ctx, volume, layout)?;
        let format = channels::format(TexelKind::of(&volume.data), 1);
        let mut images = Vec::with_capacity(layout.images.len());
        for k in 0..layout.images.len() {
            images.push(Image3d::with_slices(
                ctx,
                "brick pool",
                format,
                layout.extent(k),
                layout.texel_bytes,
                |z, _, out| host.fill(k, z, out),
            )?);
        }
        Self::with_images(ctx, volume, images, Some((layout, brick_table(ctx, layout)?)))
    }

    /// As `upload`, recorded into `cmd`: leaves the image in
    /// SHADER_READ_ONLY_OPTIMAL behind a barrier to compute-shader reads.
    /// Keep the returned `Staging` until the submission completed.
    pub fn record_upload(cmd: Recording<'_>, volume: &Volume) -> Result<(Self, Staging)> {
        Self::record_upload_as(cmd, volume, Storage::Auto)
    }

    /// As `upload_as`, recorded into `cmd` (see `record_upload`).
    pub fn record_upload_as(cmd: Recording<'_>, volume: &Volume, storage: Storage) -> Result<(Self, Staging)> {
        let ctx = cmd.context();
        volume.check()?;
        let (format, texel, bytes) = texels(volume)?;
        if let Storage::Bricks { edge } = resolve_storage(ctx, volume, storage) {
            let layout = plan_pool(ctx, volume, (texel, &bytes), edge, PoolLimits::of(ctx.info()), None)?;
            let mut images = Vec::with_capacity(layout.images.len());
            let mut staged: Vec<Staging> = Vec::new();
            for k in 0..layout.images.len() {
                let pool = pool_image_texels(&layout, k, &bytes)?;
                let (image, staging) =
                    Image3d::record_with_data(cmd, "brick pool", format, layout.extent(k), texel, &pool)?;
                images.push(image);
                staged.push(staging);
            }
            let table = bytemuck::cast_slice(&layout.table);
            let (table, staging) = Buffer::record_with_data(cmd, "brick table", table, BRICK_TABLE_USAGE)?;
            let table = TexelBuffer::new(ctx, table, BRICK_TABLE_FORMAT)?;
            let gv = Self::with_images(ctx, volume, images, Some((&layout, table)))?;
            return Ok((gv, staged.into_iter().fold(staging, Staging::join)));
        }
        let (image, staging) = Image3d::record_with_data(cmd, &volume.name, format, volume.dims, texel, &bytes)?;
        Ok((Self::with_images(ctx, volume, vec![image], None)?, staging))
    }

    /// `images`: the dense image, or the pool's images (one or more).
    fn with_images(
        ctx: &Context,
        volume: &Volume,
        mut images: Vec<Image3d>,
        pool: Option<(&PoolLayout, TexelBuffer)>,
    ) -> Result<Self> {
        let image = images.remove(0);
        let format = image.format;
        let (pool, brick_table) = match pool {
            Some((layout, table)) => (Some(layout), table),
            None => (None, super::cells::no_cells(ctx)?),
        };
        let mut gv = GpuVolume {
            ctx: ctx.clone(),
            image,
            sampler: sampler(ctx, vk::Filter::NEAREST)?,
            linear: None,
            dims: volume.dims,
            spacing: volume.spacing,
            norm: volume.norm,
            channels: volume.channel_count() as u32,
            norms: std::array::from_fn(|c| volume.channels().nth(c).map_or([0.0; 2], |v| v.norm)),
            has_nan: volume.no_data_total() > 0,
            kind: channels::common_kind(volume),
            gradient: None,
            cells: None,
            cells_kernel: None,
            gradient_cells: None,
            brick_table,
            pool_images: images,
            step_staging: None,
            image_mirror: None,
            upload_changed: !ctx.info().is_cpu(),
            step: None,
            uploaded: next_id(),
            pool: pool.map(PoolLayout::stats),
        };
        // Bricked storage samples with the manual filter only: the
        // sampler's weights at pool coordinates need not equal the dense
        // image's.
        if pool.is_none() && ctx.filters_linearly(format) {
            gv.linear = Some(sampler(ctx, vk::Filter::LINEAR)?);
        }
        Ok(gv)
    }

    /// The sampler the march kernels bind for `filter`; hardware filtering
    /// of a format the device cannot filter is an error naming the format.
    pub fn sampler_for(&self, filter: Filter) -> Result<vk::Sampler> {
        match (filter, self.linear) {
            (Filter::Manual, _) => Ok(self.sampler),
            (Filter::Hardware, _) if self.pool.is_some() => Err(Error::invalid(
                "filter",
                "hardware",
                "bricked storage is sampled by the manual filter only (the sampler's weights at pool coordinates need not equal the dense image's); use --filter manual or --storage dense",
            )),
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
    /// 8 bytes per voxel; once is enough. With the volume's cells copy
    /// (`add_cells` first), also the gradient's (48 bytes per voxel, where
    /// the device holds it): the manual filter then reads a lit sample's
    /// eight gradients in three fetches instead of eight.
    pub fn add_gradient(&mut self, volume: &Volume) -> Result<()> {
        let wants_cells = self.cells.is_some()
            && self.gradient_cells.is_none()
            && gradient_cells::check_gradient_cells(self.ctx.info(), self.dims).is_ok();
        if self.gradient.is_some() && !wants_cells {
            return Ok(());
        }
        // One gradient computed for both copies.
        let texels = self.gradient_texels(volume)?;
        if self.gradient.is_none() {
            self.gradient = Some(Image3d::with_data(
                &self.ctx,
                "gradient",
                GRADIENT_FORMAT,
                self.dims,
                GRADIENT_TEXEL_BYTES,
                bytemuck::cast_slice(&texels),
            )?);
        }
        if wants_cells {
            self.gradient_cells = Some(gradient_cells::upload_gradient_cells(&self.ctx, &texels, self.dims)?);
        }
        Ok(())
    }

    /// The gradient's cells copy, where `add_gradient` made it.
    pub fn gradient_cells(&self) -> Option<&TexelBuffer> {
        self.gradient_cells.as_ref()
    }

    /// As `add_gradient`, recorded into `cmd` (see `record_upload`); the
    /// staging to keep, None when no image was recorded. The gradient's
    /// cells copy is made too where the device shares the host's memory
    /// (a CPU device: written through its mapping, nothing recorded or
    /// submitted); elsewhere lit frames read the gradient image, the same
    /// frames bit for bit.
    pub fn record_add_gradient(&mut self, cmd: Recording<'_>, volume: &Volume) -> Result<Option<Staging>> {
        self.ctx.check_is(cmd.context(), "command buffer")?;
        let wants_cells = self.cells.is_some()
            && self.gradient_cells.is_none()
            && cells::host_shared(&self.ctx)
            && gradient_cells::check_gradient_cells(self.ctx.info(), self.dims).is_ok();
        if self.gradient.is_some() && !wants_cells {
            return Ok(None);
        }
        let texels = self.gradient_texels(volume)?;
        let mut staging = None;
        if self.gradient.is_none() {
            let bytes = bytemuck::cast_slice(&texels);
            let (image, kept) =
                Image3d::record_with_data(cmd, "gradient", GRADIENT_FORMAT, self.dims, GRADIENT_TEXEL_BYTES, bytes)?;
            self.gradient = Some(image);
            staging = Some(kept);
        }
        if wants_cells {
            self.gradient_cells = Some(gradient_cells::upload_gradient_cells(&self.ctx, &texels, self.dims)?);
        }
        Ok(staging)
    }

    pub(super) fn gradient_texels(&self, volume: &Volume) -> Result<Vec<[half::f16; 4]>> {
        self.check_same(volume, "gradient")?;
        self.check_one_channel("shaded and iso frames")?;
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

    /// An error naming `what` unless the volume has one channel: shading
    /// and isosurfaces read one field's gradient.
    pub fn check_one_channel(&self, what: &str) -> Result<()> {
        check_one_channel(self.channels as usize, what)
    }

    /// How the voxels are stored, in a line: "dense (N MiB)" or the pool's
    /// numbers (`PoolStats`).
    pub fn describe_storage(&self) -> String {
        match self.pool {
            Some(pool) => pool.to_string(),
            None => {
                let texel = channels::texel_bytes(self.kind, self.channels as usize);
                let bytes = self.dims.iter().fold(texel, |a, &e| a * e as u64);
                format!("dense ({:.1} MiB)", bytes as f64 / (1u64 << 20) as f64)
            }
        }
    }

    /// The brick table march and build kernels bind (a stand-in with dense
    /// storage, which nothing reads).
    pub fn brick_table(&self) -> &TexelBuffer {
        &self.brick_table
    }

    /// The views kernels bind as `pool_1` to `pool_3`: the pool's further
    /// images, the first one's view where it has fewer (nothing reads them).
    pub fn pool_views(&self) -> [vk::ImageView; 3] {
        std::array::from_fn(|i| self.pool_images.get(i).map_or(self.image.view, |p| p.view))
    }

    /// The images the pool spans: `POOL_IMAGES` of the kernels (1 when dense).
    pub fn pool_image_count(&self) -> u32 {
        1 + self.pool_images.len() as u32
    }

    /// Bricked storage's layout in numbers; None: dense.
    pub fn pool(&self) -> Option<PoolStats> {
        self.pool
    }

    /// The pool's brick edge: `VOLUME_BRICK` of the kernels, 0 when dense.
    pub fn brick_edge(&self) -> u32 {
        self.pool.map_or(0, |p| p.edge)
    }

    pub(super) fn check_dense(&self, what: &str) -> Result<()> {
        if self.pool.is_some() {
            return Err(Error::invalid(
                "volume",
                "in bricked storage",
                format!("{what} is a dense copy of the volume; upload it with dense storage for that"),
            ));
        }
        Ok(())
    }

    pub(super) fn check_same(&self, volume: &Volume, what: &'static str) -> Result<()> {
        if volume.dims != self.dims
            || volume.norm != self.norm
            || volume.channel_count() as u32 != self.channels
            || channels::common_kind(volume) != self.kind
        {
            return Err(Error::invalid(
                what,
                volume.name.clone(),
                "is not the volume this was uploaded from",
            ));
        }
        Ok(())
    }

    /// Adds what frames will read beyond the voxels: the gradient for lit
    /// frames (and its cells copy beside the volume's), and the cells copy
    /// where the manual filter will sample
    /// (`filter` asks for it, or it is the default: `filter` None on a CPU
    /// device, where one fetch per sample instead of eight makes it the
    /// faster filter) and the device holds it (`cells::check_cells`).
    pub fn prepare(&mut self, volume: &Volume, lit: bool, filter: Option<Filter>) -> Result<()> {
        let cpu = self.ctx.info().is_cpu();
        let manual = match filter {
            Some(f) => f == Filter::Manual,
            None => cpu,
        };
        // The cells copy holds one channel (`cells.rs`).
        if manual
            && self.channels == 1
            && self.pool.is_none()
            && cells::check_cells(self.ctx.info(), self.dims, self.kind).is_ok()
        {
            self.add_cells(volume)?;
        }
        // After the cells copy: the gradient's goes with it.
        if lit {
            self.add_gradient(volume)?;
        }
        Ok(())
    }

    /// The faster filter this volume supports on this device: manual where
    /// it has its cells copy (`prepare`), else `Filter::device_default`.
    pub fn default_filter(&self) -> Filter {
        if self.cells.is_some() {
            return Filter::Manual;
        }
        Filter::device_default(self.linear.is_some() && !self.has_nan)
    }
}

impl Drop for GpuVolume {
    fn drop(&mut self) {
        let samplers = std::iter::once(self.sampler).chain(self.linear);
        self.ctx.retire(samplers.map(crate::gpu::Retired::Sampler));
    }
}

/// An error naming `what` unless a volume of `channels` has one: shading
/// and isosurfaces read one field's gradient.
pub fn check_one_channel(channels: usize, what: &str) -> Result<()> {
    if channels > 1 {
        return Err(Error::Unsupported(format!(
            "the volume has {channels} channels, and {what} read one channel's gradient and values; render a multi-channel volume unshaded in composite, mip, minip or average mode"
        )));
    }
    Ok(())
}
