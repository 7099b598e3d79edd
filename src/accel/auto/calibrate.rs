//! Measuring a kernel's constants (`model::KernelCost`) on the device: the
//! kernel marches a few small scenes chosen so that samples, traversal
//! steps and regions vary apart from each other; each is counted
//! (`probe::FrameProbe::count`) and timed (interleaved rounds, medians),
//! and the constants are the non-negative least-squares fit of the times to
//! the counts, relative errors weighted alike.
//!
//! The scenes: a 96^3 volume of 12-voxel blocks in a checkerboard, low
//! blocks at 0.25 and high ones at 0.75 rising to 0.79 along x, in the
//! frame's texel kind (with one NaN voxel if the frame's volume has some),
//! at 128x128 from azimuth 30 and elevation 20, in the frame's mode,
//! shading and filter; three transfer functions (everything visible,
//! nothing, the high or the low blocks: each mode's own, so its
//! classification sees them so) or, for iso, three iso values; steps 0.5
//! and 1.5; and, for structures with cells, cells of 4 and 8 voxels (a low
//! block holds an empty 4-voxel cell inside its apron; 8-voxel cells halve
//! the traversal steps, so steps and rays vary apart). Each scene's time is
//! the least of its rounds: noise on a shared machine only adds time.

use super::super::builder::{Builder, Ranges};
use super::super::method::{Accel, BuildInput, Structure};
use super::super::params::Params;
use super::super::probe::{time_interleaved, FrameProbe, Statistic};
use super::model::{nnls, KernelCost};
use crate::desc::{FrameDesc, Iso, Mode, Octants, Projection};
use crate::error::Result;
use crate::tf::TransferFunction;
use crate::volume::{GpuVolume, TexelKind, Volume, VoxelData, VoxelType};

const EDGE: u32 = 96;
const BLOCK: u32 = 12;
const SIZE: u32 = 128;
const STEPS: [f32; 2] = [0.5, 1.5];
/// Timed rounds per scene (after one untimed).
const ROUNDS: usize = 5;
/// Cell edges of structures with cells.
const CELLS: [u32; 2] = [4, 8];

/// The calibration volumes' patterns.
#[derive(Clone, Copy, PartialEq)]
enum Pattern {
    /// 12-voxel blocks in a checkerboard: high ones at 0.75 rising to 0.79
    /// along x, low ones at 0.25.
    Blocks,
    /// One voxel in every 12^3 block at `high`, the rest at `low`:
    /// isolated points, so traversals take many short steps through empty
    /// space and enter few regions.
    Points { high: f32, low: f32 },
}

/// A calibration volume in `kind` (the corners 0 and 1 fix the
/// normalisation of integer and float data).
fn volume(pattern: Pattern, kind: TexelKind, nan: bool) -> Result<Volume> {
    let n = EDGE as usize;
    let b = BLOCK as usize;
    let values: Vec<f32> = (0..n * n * n)
        .map(|i| {
            let (x, y, z) = (i % n, i / n % n, i / (n * n));
            if i == 0 {
                return 0.0;
            }
            if i == n * n * n - 1 {
                return 1.0;
            }
            match pattern {
                Pattern::Blocks if (x / b + y / b + z / b).is_multiple_of(2) => 0.75 + 0.04 * x as f32 / n as f32,
                Pattern::Blocks => 0.25,
                Pattern::Points { high, .. } if x % b == b / 2 && y % b == b / 2 && z % b == b / 2 => high,
                Pattern::Points { low, .. } => low,
            }
        })
        .collect();
    let dims = [EDGE; 3];
    let (ty, data) = match kind {
        TexelKind::Unorm8 => (
            VoxelType::U8,
            VoxelData::U8(values.iter().map(|v| (v * 255.0).round() as u8).collect()),
        ),
        TexelKind::Unorm16 => (
            VoxelType::U16,
            VoxelData::U16(values.iter().map(|v| (v * 65535.0).round() as u16).collect()),
        ),
        TexelKind::Float32 => {
            let mut v = values;
            if nan {
                v[n * n * n / 2 + n / 2] = f32::NAN;
            }
            (VoxelType::F32, VoxelData::F32(v))
        }
    };
    Volume::new("cost calibration", dims, [1.0; 3], ty, data)
}

/// The scenes of a mode: (pattern, transfer function, iso value): all
/// visible, none, the high (MinIP: low) blocks, the points.
fn scenes(mode: &Mode) -> Vec<(Pattern, &'static str, Option<f32>)> {
    let high = Pattern::Points { high: 0.75, low: 0.25 };
    match mode {
        Mode::Iso(_) => vec![
            (Pattern::Blocks, "ramp:0:1", Some(0.5)),
            (Pattern::Blocks, "ramp:0:1", Some(0.95)),
            (Pattern::Blocks, "ramp:0:1", Some(0.77)),
            (high, "ramp:0:1", Some(0.5)),
        ],
        Mode::MinIp => vec![
            (Pattern::Blocks, "band:0:1", None),
            (Pattern::Blocks, "band:0:0.1", None),
            (Pattern::Blocks, "band:0:0.5", None),
            (Pattern::Points { high: 0.25, low: 0.75 }, "band:0:0.5", None),
        ],
        _ => vec![
            (Pattern::Blocks, "band:0:1", None),
            (Pattern::Blocks, "ramp:0.9:1", None),
            (Pattern::Blocks, "ramp:0.5:1", None),
            (high, "ramp:0.5:1", None),
        ],
    }
}

/// Measures the constants of `accel`'s kernel (with `params`, its cell set
/// to each of [`CELLS`] where it has one) for frames like `frame` (mode,
/// shading, filter) on volumes like `like` (texel kind, NaN voxels, cells
/// copy).
pub fn calibrate(
    builder: &Builder,
    accel: Accel,
    params: &Params,
    frame: &FrameDesc,
    like: &GpuVolume,
) -> Result<KernelCost> {
    let ctx = builder.context();
    let filter = frame.filter_for(like);
    let lit = frame.lighting().is_some() || matches!(frame.mode(), Mode::Iso(_));
    let variants: Vec<Params> = match params.has("cell") {
        true => CELLS
            .iter()
            .map(|c| accel.params(&[("cell", &c.to_string())]))
            .collect::<Result<_>>()?,
        false => vec![params.clone()],
    };
    let with: Vec<(Accel, &Params)> = variants.iter().map(|p| (accel, p)).collect();
    let scenes = scenes(frame.mode());
    let mut volumes: Vec<(Pattern, Volume, GpuVolume, Ranges)> = Vec::new();
    for &(pattern, _, _) in &scenes {
        if !volumes.iter().any(|v| v.0 == pattern) {
            let host = volume(pattern, like.kind, like.has_nan)?;
            let mut gpu = GpuVolume::upload(ctx, &host)?;
            gpu.prepare(&host, lit, Some(filter))?;
            let (ranges, _) = builder.ranges_for(&with, &gpu)?;
            volumes.push((pattern, host, gpu, ranges));
        }
    }
    let mut probes = Vec::new();
    let mut structures = Vec::new();
    // (probe, structure) index pairs.
    let mut scenes_run = Vec::new();
    for (pattern, tf_spec, iso) in scenes {
        let Some((_, host, gpu, ranges)) = volumes.iter().find(|v| v.0 == pattern) else {
            unreachable!("the pattern's volume was just made")
        };
        let tf = TransferFunction::parse(tf_spec)?;
        let mode = match iso {
            Some(v) => Mode::Iso(Iso::new(&[v])?),
            None => *frame.mode(),
        };
        let lut = tf.upload(ctx)?;
        let input = BuildInput {
            volume: host,
            gpu_volume: gpu,
            tf: &tf,
            gpu_tf: &lut,
            mode,
            frames: &[],
            octants: Octants::ALL,
        };
        let first_probe = probes.len();
        for step in STEPS {
            let desc = frame
                .to_builder()
                .size(SIZE, SIZE)
                .orbit(30.0, 20.0, Projection::Orthographic)
                .step(step)
                .ert(None)
                .filter(filter)
                .mode(mode)
                .clip(Default::default())
                .jitter(false)
                .depth(None)
                .build()?;
            probes.push(FrameProbe::new(builder, gpu, &tf, &desc, u32::MAX)?);
        }
        for p in &variants {
            let (structure, _) = builder.build(accel, &input, ranges, p)?;
            for probe in first_probe..probes.len() {
                scenes_run.push((probe, structures.len()));
            }
            structures.push(structure);
        }
    }
    let pairs: Vec<(&FrameProbe, &Structure)> = scenes_run.iter().map(|&(p, s)| (&probes[p], &structures[s])).collect();
    let mut rows = Vec::new();
    for (probe, structure) in &pairs {
        let c = probe.count(structure)?;
        rows.push(([c.rays, c.samples, c.steps, c.regions].map(|v| v as f64), 0.0));
    }
    let times = time_interleaved(ctx, &pairs, ROUNDS, Statistic::Least)?;
    for (row, ms) in rows.iter_mut().zip(&times) {
        row.1 = ms * 1e6;
    }
    // Relative errors weigh alike: weight 1 / time^2.
    let weights: Vec<f64> = rows.iter().map(|(_, ns)| 1.0 / (ns * ns).max(1.0)).collect();
    Ok(KernelCost::from_array(nnls(&rows, &weights)?))
}
