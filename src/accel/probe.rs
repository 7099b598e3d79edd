//! Probe frames: a structure's march kernel run on a sparse sample of a
//! frame's tiles, to count what it does there (`count`) or to time it
//! (`time`). `auto` prices its candidates from the counts
//! (`auto::model`) and settles close calls with the times; the cost model
//! is calibrated on the same counts (`auto::calibrate`).
//!
//! A probe frame is the frame's own: its camera, step, early termination,
//! look, filter and the transfer function (LUT corrected for the step on
//! the host), on every `stride`-th 8x8 tile along each axis
//! (`MARCH_TILE_STRIDE`). Counting kernels (`MARCH_COUNT`) write per pixel
//! the loop iterations its SIMD group ran (glsl/common/lattice.glsl), and
//! into a second half of the buffer what naive marching would have run on
//! the same ray (`count_both`; glsl/common/march.glsl `count_naive`).

use super::builder::Builder;
use super::kernels::{MarchKernels, ProbeConstants};
use super::method::Structure;
use crate::desc::FrameDesc;
use crate::error::Result;
use crate::gpu::record::Access;
use crate::gpu::shaders::MarchCommon;
use crate::gpu::Recording;
use crate::gpu::{vk, Binding, Buffer, Context, MemoryLocation, TexelBuffer, Timer};
use crate::tf::TransferFunction;
use crate::volume::GpuVolume;
use std::collections::HashMap;

/// Pixels per tile edge (the march kernels' workgroup).
const TILE: u32 = 8;
/// Tiles per probe block edge (`PROBE_BLOCK` in glsl/common/march.glsl).
const BLOCK: u32 = 4;
/// Tiles a counting probe aims to cover (the stride is the largest that
/// leaves at least this many): 8192 rays count what a frame does well.
pub const COUNT_TILES: u32 = 128;
/// Tiles a timing probe aims to cover: enough to take a few milliseconds
/// even on a small frame, so its times are steady (a quarter of a 256x256
/// frame, an eighth of 512x512).
pub const TIME_TILES: u32 = 256;

/// Whether tile `t` (along one axis) is probed at `stride`.
fn probed(t: u32, stride: u32) -> bool {
    stride == 1 || t % (BLOCK * stride) < BLOCK
}

/// Probed tiles along an axis of `tiles`, and workgroups to dispatch.
fn probed_tiles(tiles: u32, stride: u32) -> (u32, u32) {
    if stride == 1 {
        return (tiles, tiles);
    }
    let n = (0..tiles).filter(|&t| probed(t, stride)).count() as u32;
    (n, tiles.div_ceil(BLOCK * stride) * BLOCK)
}

/// What a structure's kernel did on the probed tiles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Counts {
    /// Pixels (rays) probed.
    pub rays: u64,
    /// Iterations of the sample loop, summed over SIMD groups.
    pub samples: u64,
    /// Iterations of the traversal loop (walk, DDA or tree steps).
    pub steps: u64,
    /// Regions entered (spans marched).
    pub regions: u64,
    /// Samples taken, summed over rays (each ray's own, not its group's).
    pub ray_samples: u64,
}

impl Counts {
    /// These counts and `other`'s together.
    pub fn plus(&self, other: &Counts) -> Counts {
        Counts {
            rays: self.rays + other.rays,
            samples: self.samples + other.samples,
            steps: self.steps + other.steps,
            regions: self.regions + other.regions,
            ray_samples: self.ray_samples + other.ray_samples,
        }
    }

    /// These counts scaled from the probed tiles to the whole frame.
    pub fn scaled(&self, factor: f64) -> [f64; 4] {
        [self.rays, self.samples, self.steps, self.regions].map(|c| c as f64 * factor)
    }
}

/// One frame's probe: its parameters, LUT and output, ready for any
/// structure built over `volume`.
pub struct FrameProbe<'a> {
    ctx: Context,
    kernels: MarchKernels,
    volume: &'a GpuVolume,
    desc: FrameDesc,
    stride: u32,
    params: Buffer,
    lut: TexelBuffer,
    no_cells: TexelBuffer,
    out: Buffer,
    depth: Buffer,
    /// The march status of a counting frame (groups a device's loop cap
    /// may have cut short), host-visible: `count_both` refuses a cut frame,
    /// whose counts would misprice its structure. Trial frames write it
    /// too, unread: their times are only compared.
    status: Buffer,
    readback: Buffer,
}

impl<'a> FrameProbe<'a> {
    /// A probe of frames of `desc` over `volume` with the transfer function
    /// `tf` (the frame's, not a mode's classification), covering at least
    /// `tiles` tiles (all of a smaller frame).
    pub fn new(
        builder: &Builder,
        volume: &'a GpuVolume,
        tf: &TransferFunction,
        desc: &FrameDesc,
        tiles_wanted: u32,
    ) -> Result<Self> {
        let ctx = builder.context().clone();
        ctx.check_is(volume.context(), "volume")?;
        let (w, h) = desc.size();
        let tiles = [w.div_ceil(TILE), h.div_ceil(TILE)];
        let mut stride = 1;
        // No wider than the frame: past that every stride probes one block
        // (and a wish of a block or less would double it forever).
        while BLOCK * stride < tiles[0].max(tiles[1])
            && probed_tiles(tiles[0], stride * 2).0 * probed_tiles(tiles[1], stride * 2).0 >= tiles_wanted
        {
            stride *= 2;
        }
        let mut params = desc.params(volume)?;
        params.value_bound = desc.mode().value_bound(tf.visible_entries());
        tf.check_channels(volume.channels as usize)?;
        params.tf_channel_step = (tf.channel_count() > 1) as u32;
        let params = Buffer::with_data(
            &ctx,
            "probe params",
            bytemuck::bytes_of(&params),
            vk::BufferUsageFlags::STORAGE_BUFFER,
        )?;
        let tables = tf.frame_tables(desc.step());
        let lut = Buffer::with_data(
            &ctx,
            "probe LUT",
            bytemuck::cast_slice(&tables),
            vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
        )?;
        let lut = TexelBuffer::new(&ctx, lut, vk::Format::R32G32B32A32_SFLOAT)?;
        // Two halves where the device's storage range allows: the frame's
        // counts, then what naive would count (`count_both`).
        let half = w as u64 * h as u64 * 16;
        let bytes = match 2 * half <= ctx.info().max_storage_buffer_range {
            true => 2 * half,
            false => half,
        };
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_SRC
            | vk::BufferUsageFlags::TRANSFER_DST;
        Ok(FrameProbe {
            kernels: MarchKernels::new(&ctx),
            volume,
            desc: *desc,
            stride,
            params,
            lut,
            no_cells: crate::volume::no_cells(&ctx)?,
            out: Buffer::new(&ctx, "probe frame", bytes, usage, MemoryLocation::GpuOnly)?,
            depth: Buffer::new(&ctx, "probe depth", 16, usage, MemoryLocation::GpuOnly)?,
            status: Buffer::new(&ctx, "probe status", 16, usage, MemoryLocation::GpuToCpu)?,
            readback: Buffer::new(
                &ctx,
                "probe readback",
                bytes,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuToCpu,
            )?,
            ctx,
        })
    }

    /// Whether it marches every tile of the frame.
    pub fn whole_frame(&self) -> bool {
        self.stride == 1
    }

    /// The whole frame's counts over the probed ones' (tiles).
    pub fn scale(&self) -> f64 {
        let (w, h) = self.desc.size();
        let tiles = [w.div_ceil(TILE), h.div_ceil(TILE)];
        let probed = tiles.map(|t| probed_tiles(t, self.stride).0);
        (tiles[0] * tiles[1]) as f64 / (probed[0] * probed[1]) as f64
    }

    /// The frame this probes.
    pub fn desc(&self) -> &FrameDesc {
        &self.desc
    }

    /// Creates the kernels that counting (or timing) `structures` will
    /// dispatch, all at once (`MarchKernels::prepare`).
    pub fn prepare(&self, structures: &[&Structure], count: bool) -> Result<()> {
        let frame = self.desc.kernel_constants(self.volume);
        let probe = ProbeConstants {
            count,
            tile_stride: self.stride,
        };
        let wanted: Vec<_> = structures.iter().map(|s| (s.march(), frame, probe)).collect();
        self.kernels.prepare(&wanted)
    }

    /// Records `structure`'s probe dispatch (counting or not) writing the
    /// output buffer; the caller orders it after earlier writes to it.
    fn record(&self, cmd: Recording<'_>, structure: &Structure, count: bool) -> Result<()> {
        let desc = &self.desc;
        // As the renderer: a structure of another context, mode or grid
        // would read what its kernel was not sized for.
        structure.check_made_on(&self.ctx)?;
        structure.check_mode(desc.mode())?;
        structure.check_volume(self.volume)?;
        let filter = desc.filter_for(self.volume);
        let sampler = self.volume.sampler_for(filter)?;
        let probe = ProbeConstants {
            count,
            tile_stride: self.stride,
        };
        let kernel = self
            .kernels
            .get(structure.march(), None, desc.kernel_constants(self.volume), probe)?;
        let gradient = match (desc.lighting().is_some(), self.volume.gradient_view()) {
            (true, Some(view)) => view,
            _ => self.volume.image.view,
        };
        let mut bindings = MarchCommon {
            params: Binding::Storage(&self.params),
            volume_tex: Binding::Sampled(self.volume.image.view, sampler),
            tf_lut: Binding::Texels(&self.lut),
            frame: Binding::Storage(&self.out),
            frame_depth: Binding::Storage(&self.depth),
            gradient_tex: Binding::Sampled(gradient, sampler),
            volume_cells: Binding::Texels(self.volume.cells().unwrap_or(&self.no_cells)),
            gradient_cells: Binding::Texels(self.volume.gradient_cells().unwrap_or(&self.no_cells)),
            brick_table: Binding::Texels(self.volume.brick_table()),
            pool_1: Binding::Sampled(self.volume.pool_views()[0], self.volume.sampler),
            pool_2: Binding::Sampled(self.volume.pool_views()[1], self.volume.sampler),
            pool_3: Binding::Sampled(self.volume.pool_views()[2], self.volume.sampler),
            march_status: Binding::Storage(&self.status),
        }
        .list();
        bindings.extend(structure.built.bindings());
        let (w, h) = desc.size();
        let tiles = [w.div_ceil(TILE), h.div_ceil(TILE)];
        let groups = [
            probed_tiles(tiles[0], self.stride).1,
            probed_tiles(tiles[1], self.stride).1,
            1,
        ];
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe { kernel.dispatch(cmd, &bindings, &structure.built.push(), groups) }
    }

    /// What `structure`'s kernel does on the probed tiles.
    pub fn count(&self, structure: &Structure) -> Result<Counts> {
        Ok(self.count_both(structure)?.0)
    }

    /// As `count`, and what naive marching does on the same tiles, derived
    /// from the same march where the probe holds it (None: count naive's own
    /// march). Exact structures end every ray after naive's last sample,
    /// so naive's counts are known from theirs (`count_naive` in
    /// glsl/common/march.glsl); `tests/integration/auto.rs` checks them against naive's.
    pub fn count_both(&self, structure: &Structure) -> Result<(Counts, Option<Counts>)> {
        self.ctx.submit_and_wait(|cmd| {
            cmd.barrier(Access::COMPUTE_READ_WRITE, Access::TRANSFER_WRITE);
            cmd.fill_buffer(&self.out, 0, vk::WHOLE_SIZE, 0)?;
            cmd.fill_buffer(&self.status, 0, vk::WHOLE_SIZE, 0)?;
            cmd.barrier(Access::TRANSFER_WRITE, Access::COMPUTE_READ_WRITE);
            self.record(cmd, structure, true)?;
            cmd.barrier(Access::COMPUTE_WRITE, Access::HOST_READ);
            cmd.barrier(Access::COMPUTE_WRITE, Access::TRANSFER_READ);
            let region = [vk::BufferCopy {
                src_offset: 0,
                dst_offset: 0,
                size: self.out.size(),
            }];
            cmd.copy_buffer(&self.out, &self.readback, &region)?;
            cmd.barrier(Access::TRANSFER_WRITE, Access::HOST_READ);
            Ok(())
        })?;
        let cut: u32 = bytemuck::pod_read_unaligned(&self.status.host()?[..4]);
        if cut > 0 {
            return Err(structure.cut_error(self.ctx.info(), cut));
        }
        let readback = self.readback.host()?;
        let pixels: &[[f32; 4]] = bytemuck::cast_slice(&readback[..self.out.size() as usize]);
        let (w, h) = self.desc.size();
        let (own, naive) = pixels.split_at((w * h) as usize);
        let mut c = Counts::default();
        for (_, p) in self.probed_pixels(own) {
            c.rays += 1;
            c.samples += p[0] as u64;
            c.steps += p[1] as u64;
            c.regions += p[2] as u64;
            c.ray_samples += p[3] as u64;
        }
        if naive.len() < own.len() {
            return Ok((c, None));
        }
        // Naive's loop, per SIMD group of a tile's workgroup: its most full
        // samples, and one iteration more where a lane has its last left.
        let mut groups: HashMap<(u32, u32, u32), (u64, bool)> = HashMap::new();
        let mut n = Counts::default();
        for ((x, y), p) in self.probed_pixels(naive) {
            let (full, all) = (p[0] as u64, p[1] as u64);
            let g = groups.entry((x / TILE, y / TILE, p[2] as u32)).or_default();
            *g = (g.0.max(full), g.1 || all > full);
            n.rays += 1;
            n.ray_samples += all;
        }
        n.samples = groups.values().map(|&(full, last)| full + last as u64).sum();
        Ok((c, Some(n)))
    }

    /// The pixels of the probed tiles in `half` (a frame's worth, rows of
    /// the frame's width), with their coordinates.
    fn probed_pixels<'p>(&self, half: &'p [[f32; 4]]) -> impl Iterator<Item = ((u32, u32), &'p [f32; 4])> + 'p {
        let (w, h) = self.desc.size();
        let stride = self.stride;
        half.chunks_exact(w as usize)
            .enumerate()
            .take(h as usize)
            .filter(move |(y, _)| probed(*y as u32 / TILE, stride))
            .flat_map(move |(y, row)| {
                row.iter()
                    .enumerate()
                    .filter(move |(x, _)| probed(*x as u32 / TILE, stride))
                    .map(move |(x, p)| ((x as u32, y as u32), p))
            })
    }
}

/// What one figure of several timed rounds is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Statistic {
    Median,
    /// The least: noise on a shared machine only adds time.
    Least,
}

/// GPU milliseconds of each (probe, structure) pair's probe frame: one
/// untimed round, then `rounds` rounds timing each pair in turn
/// (interleaved, so the machine's load falls on all alike); `statistic` of
/// each pair's rounds.
pub fn time_interleaved(
    ctx: &Context,
    pairs: &[(&FrameProbe, &Structure)],
    rounds: usize,
    statistic: Statistic,
) -> Result<Vec<f64>> {
    let _device = ctx.device();
    let mut times = vec![Vec::new(); pairs.len()];
    for round in 0..=rounds {
        let mut timer = Timer::new(ctx, pairs.len() as u32)?;
        ctx.submit_and_wait(|cmd| {
            timer.reset(cmd);
            for (i, (probe, s)) in pairs.iter().enumerate() {
                // Dispatches may write the same buffers (the frame, the
                // march status, which they also read): order them.
                cmd.barrier(Access::COMPUTE_READ_WRITE, Access::COMPUTE_READ_WRITE);
                let pass = timer.begin(cmd, &i.to_string())?;
                probe.record(cmd, s, false)?;
                timer.end(cmd, pass);
            }
            Ok(())
        })?;
        if round > 0 {
            let t = timer.results()?;
            for (i, v) in times.iter_mut().enumerate() {
                v.push(t.phase(&i.to_string())?);
            }
        }
    }
    Ok(times
        .into_iter()
        .map(|t| match statistic {
            Statistic::Median => crate::gpu::timings::median(t),
            Statistic::Least => t.into_iter().fold(f64::INFINITY, f64::min),
        })
        .collect())
}
