//! Chebyshev distance-map skipping (Deakin & Knackstedt, Computational
//! Visual Media 2020). Per cell of the macro-cell grid, the L-infinity
//! distance in cells to the nearest active cell, rebuilt on the GPU on every
//! transfer-function change: the range classification (O(cells)) and a
//! separable distance transform (three linear-time 1-D passes,
//! `distance_rows.comp`, one-sided for octants in `distance_octant_rows.comp`),
//! with no host round trip; on a CPU device `Builder::build` classifies
//! and makes the transform on the host's cores instead (`build_on_host`). The march
//! (`glsl/march/distance.comp`) then takes one O(1) step per empty region.
//!
//! Every cell stores its distance to the nearest cell of the other kind, so
//! a ray crosses a cube of empty cells (skipped) or of active cells (marched
//! as one span) in one step. Two maps: `distance` stores one distance of
//! each kind per cell (the cube of half-width d-1 around the cell, 4 bytes a
//! cell); `distance-octant` stores one per ray direction octant (the cells
//! up to d-1 ahead of the ray, so jumps are longer, for 16 bytes a cell).

use super::bricks::GpuBricks;
use super::builder::{Builder, RangeKind, Ranges};
use super::classify::{classify_ranges_on_host, Classifier, Classify};
use super::distance_host;
pub use super::distance_host::{channels, reference, CAP};
use super::method::{submit_build, BuildInput, Built, March, Method};
use super::params::{self, Param, Params, Value};
use super::stats::Stats;
use super::tree::{STORAGE_TEXELS, STORAGE_XFER};
use crate::desc::Octants;
use crate::error::{Error, Result};
use crate::gpu::record::{self, Access};
use crate::gpu::shaders::{self, build_distance_octant_rows, build_distance_rows, march_distance};
use crate::gpu::Recording;
use crate::gpu::{
    vk, Binding, Bound, Buffer, Context, Kernel, MemoryLocation, OptionalTimer, TexelBuffer, Timer, Timings,
};
use crate::prims::entry_barrier;
use crate::volume::host_shared;

/// Default cell edge in voxels: the 8^3 brick grid.
pub const CELL: u32 = 8;

/// The cell parameter of the distance maps (default [`CELL`]).
const CELL_PARAM: Param = params::CELL.with_default(Value::Int(CELL));

/// Longest row whose envelope (deque) `distance_rows.comp`
/// (`distance_octant_rows.comp`) keeps in private arrays (their PRIVATE_ROW).
const PRIVATE_ROW: u32 = 64;

/// The linear-time distance-transform kernel of one pass (two-sided rows
/// for cube maps, one-sided rows for octant maps), specialized: with the
/// envelope (deque) in private arrays for rows of at most [`PRIVATE_ROW`]
/// cells, else in a storage buffer; reading the active flags (the first
/// pass) or map words. Each variant compiles on its first use (the
/// context keeps it).
fn rows_kernel(ctx: &Context, octants: bool, private: bool, first: bool) -> Result<Kernel> {
    let (shader, push_size) = match octants {
        true => (
            &shaders::BUILD_DISTANCE_OCTANT_ROWS,
            std::mem::size_of::<build_distance_octant_rows::Push>(),
        ),
        false => (
            &shaders::BUILD_DISTANCE_ROWS,
            std::mem::size_of::<build_distance_rows::Push>(),
        ),
    };
    let constants = [(0, private as u32), (1, first as u32)];
    // SAFETY: the constants are the ones this kernel is written for (its own table).
    unsafe { Kernel::specialized(ctx, shader, push_size, &constants) }
}

/// The tasks of an octant map's pass along `axis` for the octants `built`
/// (`distance_octant_rows.comp`'s `task`, each sweeping both kinds of
/// distance): per z sign read, the byte channels that depend on the signs
/// swept so far and that some built octant needs, and the words written.
fn octant_tasks(axis: usize, built: Octants) -> Vec<u32> {
    let task = |z: u32, js: &[u32], writes: u32| {
        let list = js.iter().enumerate().fold(0, |l, (k, j)| l | j << (8 + 2 * k));
        z | (js.len() as u32) << 2 | list | writes << 16
    };
    let classes = |mask: u32, z: Option<u32>| {
        let mut js: Vec<u32> = built
            .iter()
            .filter(|&o| z.is_none_or(|z| o >> 2 == z))
            .map(|o| o & mask)
            .collect();
        js.sort_unstable();
        js.dedup();
        js
    };
    let has_z = |z: u32| built.iter().any(|o| o >> 2 == z);
    match axis {
        // Along x: the x sign; pass y reads the z-positive words.
        0 => vec![task(0, &classes(1, None), 1)],
        // Along y: the x and y signs, copied to the z signs needed.
        1 => vec![task(0, &classes(3, None), has_z(0) as u32 | (has_z(1) as u32) << 1)],
        // Along z: each octant.
        _ => (0..2u32)
            .map(|z| (z, classes(3, Some(z))))
            .filter(|(_, js)| !js.is_empty())
            .map(|(z, js)| task(z, &js, 1))
            .collect(),
    }
}

/// A built distance map.
pub struct DistanceMap {
    pub cell: u32,
    pub counts: [u32; 3],
    pub octants: bool,
    /// The octants whose distances an octant map holds (all for a cube map):
    /// the march walks other octants cell by cell.
    pub built: Octants,
    /// u32 per cell, 1 = active (the classification).
    pub flags: Buffer,
    /// Per cell: [`channels`] byte distances packed in words, one texel a
    /// cell (`texel_format`): the march reads it as a texel buffer (llvmpipe
    /// loads a storage buffer lane by lane through the stack on an AVX2
    /// CPU, an eighth of a sparse frame there), the build passes write it
    /// as a storage buffer.
    pub distances: TexelBuffer,
    /// The transform's intermediate pass and row stacks (a device
    /// transform); kept until the build has run.
    _scratch: Vec<Buffer>,
    total: u64,
    active: std::sync::OnceLock<u64>,
}

fn words_per_cell(octants: bool) -> u64 {
    channels(octants).div_ceil(4) as u64
}

/// The rows' envelope stacks: three words per cell (cube maps), or two
/// deques (one per kind) of a word per cell for each of up to two tasks
/// of a pass (octant maps).
fn stack_bytes(cells: u64, octants: bool) -> u64 {
    cells * if octants { 4 * words_per_cell(true) } else { 12 }
}

/// The map's texel format: a cell's words in one texel.
fn texel_format(octants: bool) -> vk::Format {
    match octants {
        true => vk::Format::R32G32B32A32_UINT,
        false => vk::Format::R32_UINT,
    }
}

/// The bytes of a map's largest buffer: the map, or the row stacks.
fn largest_buffer(cells: u64, octants: bool) -> u64 {
    (cells * 4 * words_per_cell(octants)).max(stack_bytes(cells, octants))
}

/// Whether a map of `cells` cells fits the device: its largest buffer
/// within `maxStorageBufferRange`, and its cells (a texel each) within
/// `maxTexelBufferElements` (the error names the limit).
pub fn check_fits(info: &crate::gpu::DeviceInfo, cells: u64, octants: bool) -> Result<()> {
    let bytes = largest_buffer(cells, octants);
    info.check_texel_buffer(format!("distance map of {cells} cells ({bytes} bytes)"), bytes, cells)
}

/// The device limit a map of `cells` cells exceeds (`check_fits`), if any.
pub fn exceeded_limit(info: &crate::gpu::DeviceInfo, cells: u64, octants: bool) -> Option<&'static str> {
    info.exceeded_buffer_limit(largest_buffer(cells, octants), cells)
}

/// Records the classification of `cells` for a TF ("classify") and the
/// three transform passes ("distance x", "distance y", "distance z") into
/// `cmd`. Follows the `prims` barrier convention; ends with compute writes.
pub fn record(
    builder: &Builder,
    cmd: Recording<'_>,
    mut timer: Option<&mut Timer>,
    input: &BuildInput,
    cells: &GpuBricks,
    octants: bool,
) -> Result<DistanceMap> {
    let ctx = builder.context();
    let info = ctx.info();
    let mut map = classified_map(builder, cmd, &mut timer, input, cells, octants, MemoryLocation::GpuOnly)?;
    let bytes = map.distances.buffer().size();
    // Rows of at most PRIVATE_ROW cells keep their stacks in private arrays:
    // where every axis's rows do, the binding gets a one-word placeholder.
    let stack_bytes = match cells.counts.iter().any(|&n| n > PRIVATE_ROW) {
        true => stack_bytes(cells.total, octants),
        false => 4,
    };
    let scratch = Buffer::new(ctx, "distance scratch", bytes, STORAGE_XFER, MemoryLocation::GpuOnly)?;
    let stack = Buffer::new(
        ctx,
        "distance row stacks",
        stack_bytes,
        STORAGE_XFER,
        MemoryLocation::GpuOnly,
    )?;
    let (flags, distances, built) = (&map.flags, map.distances.buffer(), map.built);
    // x: flags -> distances, y: distances -> scratch, z: scratch -> distances.
    let c = cells.counts;
    let counts = [c[0], c[1], c[2], cells.total as u32];
    for (axis, (src, dst)) in [(flags, distances), (distances, &scratch), (&scratch, distances)]
        .into_iter()
        .enumerate()
    {
        let pass = timer.begin(cmd, ["distance x", "distance y", "distance z"][axis])?;
        if axis == 0 {
            entry_barrier(cmd);
        } else {
            cmd.compute_to_compute();
        }
        // One invocation per row (cube maps) or per row and task (octant
        // maps: a map word and the channels of it to compute).
        let k = rows_kernel(ctx, octants, c[axis] <= PRIVATE_ROW, axis == 0)?;
        let tasks = octant_tasks(axis, built);
        let per_row = if octants { tasks.len() as u64 } else { 1 };
        let rows = cells.total / c[axis] as u64;
        let groups = record::groups_linear(info, "distance rows", rows * per_row, k.local_size()[0])?;
        let (push, bindings) = if octants {
            let mut task = [0; 4];
            task[..tasks.len()].copy_from_slice(&tasks);
            let push = build_distance_octant_rows::Push {
                counts,
                axis: axis as u32,
                groups_x: groups[0],
                rows: rows as u32,
                tasks: tasks.len() as u32,
                task,
            };
            let bindings = build_distance_octant_rows::Bindings {
                src: Binding::Storage(src),
                dst: Binding::Storage(dst),
                deque: Binding::Storage(&stack),
            }
            .list();
            (bytemuck::bytes_of(&push).to_vec(), bindings)
        } else {
            let push = build_distance_rows::Push {
                counts,
                axis: axis as u32,
                groups_x: groups[0],
                rows: rows as u32,
            };
            let bindings = build_distance_rows::Bindings {
                src: Binding::Storage(src),
                dst: Binding::Storage(dst),
                stack: Binding::Storage(&stack),
            }
            .list();
            (bytemuck::bytes_of(&push).to_vec(), bindings)
        };
        // SAFETY: every binding is a live object of this context borrowed for
        // the call, or the host's (`Recording::adopt`, `HostImage::new`).
        unsafe { k.dispatch(cmd, &bindings, &push, groups) }?;
        timer.end(cmd, pass);
    }
    map._scratch = vec![scratch, stack];
    Ok(map)
}

/// The map's buffers (flags, distances; in `location`) and the recorded
/// classification of `cells` ("classify"), for the octants the input's
/// frames need (none named: all).
fn classified_map(
    builder: &Builder,
    cmd: Recording<'_>,
    timer: &mut Option<&mut Timer>,
    input: &BuildInput,
    cells: &GpuBricks,
    octants: bool,
    location: MemoryLocation,
) -> Result<DistanceMap> {
    let classifier = builder.shared::<Classifier>()?;
    let map = unclassified_map(builder.context(), input, cells, octants, location)?;
    let pass = timer.begin(cmd, "classify")?;
    classifier.record(cmd, Classify::Range, input.gpu_volume, cells, input.gpu_tf, &map.flags)?;
    timer.end(cmd, pass);
    Ok(map)
}

/// The map's buffers (flags, distances; in `location`), nothing in them
/// yet, for the octants the input's frames need (none named: all).
fn unclassified_map(
    ctx: &Context,
    input: &BuildInput,
    cells: &GpuBricks,
    octants: bool,
    location: MemoryLocation,
) -> Result<DistanceMap> {
    check_fits(ctx.info(), cells.total, octants)?;
    let bytes = cells.total * 4 * words_per_cell(octants);
    let flags = Buffer::new(ctx, "distance cell flags", cells.total * 4, STORAGE_XFER, location)?;
    let distances = Buffer::new(ctx, "distance map", bytes, STORAGE_TEXELS, location)?;
    let distances = TexelBuffer::new(ctx, distances, texel_format(octants))?;
    let built = match input.octants {
        o if !octants || o.is_empty() => Octants::ALL,
        o => o,
    };
    Ok(DistanceMap {
        cell: cells.brick,
        counts: cells.counts,
        octants,
        built,
        flags,
        distances,
        _scratch: Vec::new(),
        total: cells.total,
        active: std::sync::OnceLock::new(),
    })
}

/// Mapped bytes as words: in place, as mapped memory is aligned for them;
/// a copy where it were not.
fn words<T: bytemuck::Pod>(bytes: &[u8]) -> std::borrow::Cow<'_, [T]> {
    match bytemuck::try_cast_slice(bytes) {
        Ok(words) => words.into(),
        Err(_) => bytemuck::pod_collect_to_vec(bytes).into(),
    }
}

/// The map classified on the host from ranges the host sees
/// (`classify_ranges_on_host`), or None where it cannot see them. A
/// submission of two barriers first makes the ranges' writes, from any
/// earlier submission, visible to the host (timed with the rest).
fn host_classified_map(
    builder: &Builder,
    input: &BuildInput,
    cells: &GpuBricks,
    octants: bool,
) -> Result<Option<(DistanceMap, Timings)>> {
    let ctx = builder.context();
    if !cells.ranges.is_host_coherent() {
        return Ok(None);
    }
    input.tf.check_channels(cells.channels as usize)?;
    let mut map = unclassified_map(ctx, input, cells, octants, MemoryLocation::GpuToCpu)?;
    let start = std::time::Instant::now();
    ctx.submit_and_wait(|cmd| {
        // Ranges are computed, or copied from a series step's before.
        cmd.barrier(Access::COMPUTE_WRITE, Access::HOST_READ);
        cmd.barrier(Access::TRANSFER_WRITE, Access::HOST_READ);
        Ok(())
    })?;
    let channels = cells.channels as usize;
    let n = map.total as usize;
    // Read after the submission: coherent memory needs no invalidate.
    let mapped_ranges = cells.ranges.host()?;
    let ranges = words::<f32>(&mapped_ranges[..8 * n * channels]);
    // Mapped memory starts at a word boundary (Vulkan's map alignment).
    let flags = bytemuck::try_cast_slice_mut(&mut map.flags.host_mut()?[..4 * n])
        .map_err(|_| Error::Interface("distance cell flags mapped off a word boundary".into()))?;
    classify_ranges_on_host(&ranges, channels, input.tf, flags);
    let mut timings = Timings::default();
    timings.push("classify (host)", start.elapsed().as_secs_f64() * 1e3);
    Ok(Some((map, timings)))
}

/// As `record`, submitted and waited for, with the transform made on the
/// host (`distance_host::transform`) from the flags classified on the host
/// where it sees the ranges (`host_classified_map`), else on the device:
/// the same map, faster on a CPU device. The buffers must be host visible
/// (a device whose memory is the host's: `volume::host_shared`). Timings:
/// "classify (host)" or "classify" (GPU), and "distance (host)".
pub fn build_on_host(
    builder: &Builder,
    input: &BuildInput,
    cells: &GpuBricks,
    octants: bool,
) -> Result<(DistanceMap, Timings)> {
    let ctx = builder.context();
    let (mut map, mut timings) = match host_classified_map(builder, input, cells, octants)? {
        Some(classified) => classified,
        None => {
            let mut timer = Timer::new(ctx, 2)?;
            let map = ctx.submit_and_wait(|cmd| {
                timer.reset(cmd);
                let map = classified_map(
                    builder,
                    cmd,
                    &mut Some(&mut timer),
                    input,
                    cells,
                    octants,
                    MemoryLocation::GpuToCpu,
                )?;
                cmd.barrier(Access::COMPUTE_WRITE, Access::HOST_READ);
                Ok(map)
            })?;
            (map, timer.results()?)
        }
    };
    let start = std::time::Instant::now();
    let (counts, built) = (map.counts, map.built);
    {
        let mapped_flags = map.flags.host()?;
        let flags = words::<u32>(&mapped_flags[..4 * map.total as usize]);
        distance_host::transform(counts, &flags, octants, built, map.distances.host_mut()?);
    }
    timings.push("distance (host)", start.elapsed().as_secs_f64() * 1e3);
    Ok((map, timings))
}

impl DistanceMap {
    /// The distances on the host: [`channels`] per cell, in channel order.
    pub fn download(&self) -> Result<Vec<u32>> {
        let map = self.distances.buffer();
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&map.download(0, map.size())?);
        let per = words_per_cell(self.octants) as usize;
        let n = channels(self.octants);
        let built = self.built;
        // An octant the map does not hold reads as 1, as the march reads it.
        let held = move |ch: usize| !self.octants || built.has((ch % 8) as u32);
        Ok(words
            .chunks(per)
            .take(self.total as usize)
            .flat_map(|cell| {
                (0..n).map(move |ch| match held(ch) {
                    true => (cell[ch / 4] >> (8 * (ch % 4))) & 0xff,
                    false => 1,
                })
            })
            .collect())
    }

    pub fn stats(&self) -> Result<Stats> {
        let active = super::grid::count_active(&self.flags, self.total, &self.active)?;
        Ok(Stats {
            unit: if self.cell == 8 { "8^3 cells" } else { "cells" },
            total_bricks: self.total,
            active_bricks: active,
            nodes: self.total,
            leaves: active,
            height: 1,
            bytes: self.total * 4 * words_per_cell(self.octants),
        })
    }
}

/// `--accel distance` (one distance per cell) and `--accel distance-octant`
/// (one per ray direction octant).
pub struct DistanceMethod {
    pub octants: bool,
}

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for DistanceMethod {
    fn name(&self) -> &'static str {
        if self.octants {
            "distance-octant"
        } else {
            "distance"
        }
    }
    fn description(&self) -> &'static str {
        if self.octants {
            "Chebyshev distance map per direction octant (Deakin & Knackstedt), one O(1) jump per empty region"
        } else {
            "Chebyshev distance map (Deakin & Knackstedt), one O(1) jump per empty region"
        }
    }
    fn params(&self) -> &'static [Param] {
        &[CELL_PARAM]
    }
    fn ranges(&self, p: &Params) -> Result<RangeKind> {
        Ok(RangeKind::Cells(p.int("cell")?))
    }
    fn march(&self) -> March {
        March {
            shader: shaders::MARCH_DISTANCE,
            constants: if self.octants { &[1] } else { &[0] },
        }
    }
    fn variants(&self) -> Result<Vec<(String, Params)>> {
        [CELL, 4, 16]
            .into_iter()
            .map(|cell| {
                let p = Params::resolve(self.params(), &[("cell", &cell.to_string())])?;
                Ok((format!("{} cell {cell}", self.name()), p))
            })
            .collect()
    }
    fn record_build(
        &self,
        builder: &Builder,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        p: &Params,
    ) -> Result<Box<dyn Built>> {
        let cells = ranges.cells(p.int("cell")?)?;
        Ok(Box::new(record(builder, cmd, timer, input, cells, self.octants)?))
    }
    /// On a CPU device the transform runs on the host (`build_on_host`).
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        ranges: &Ranges,
        p: &Params,
    ) -> Result<(Box<dyn Built>, Timings)> {
        if !host_shared(builder.context()) {
            return submit_build(self, builder, input, ranges, p);
        }
        let cells = ranges.cells(p.int("cell")?)?;
        let (map, timings) = build_on_host(builder, input, cells, self.octants)?;
        Ok((Box::new(map), timings))
    }
}

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for DistanceMap {
    fn bindings(&self) -> Vec<Bound<'_>> {
        march_distance::Own {
            distance_texels: Binding::Texels(&self.distances),
        }
        .list()
    }
    fn push(&self) -> Vec<u8> {
        bytemuck::bytes_of(&march_distance::Push {
            counts: self.counts,
            cell: self.cell,
            built: self.built.bits() as u32,
            // A held octant's distances to active cells: 0 exactly in them.
            probe: self.built.iter().next().unwrap_or(0),
        })
        .to_vec()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        DistanceMap::stats(self).map(Some)
    }
    fn octants(&self) -> Octants {
        self.built
    }
}
