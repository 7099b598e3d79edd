//! auto's choice: its candidates (naive marching, the distance maps and
//! the macro-cell grid at cells the device holds, and on GPUs a collapsed
//! k-d tree), each built and counted
//! on the frame's probe tiles, priced by the kernel constants, and, where
//! the best is close to another, timed on the same tiles.

use super::super::builder::RangeKind;
use super::super::distance::{self, DistanceMethod};
use super::super::grid::{self, GridMethod};
use super::super::kd::gpu::KdGpu;
use super::super::method::Accel;
use super::super::morton::MAX_BRICKS_PER_AXIS;
use super::super::naive::NAIVE;
use super::super::params::Params;
use super::super::probe::Counts;
use super::super::probe::TIME_TILES;
use crate::desc::{FrameDesc, Mode};
use crate::error::Result;
use crate::gpu::DeviceInfo;

/// Distance map cells (voxels) auto tries; grids of at most
/// [`OCTANT_CELLS`] cells get octant maps.
pub const DISTANCE_CELLS: [u32; 2] = [4, 8];
/// Macro-cell grid cells auto tries.
pub const GRID_CELLS: [u32; 2] = [8, 16];

/// Coarser distance map cells, finest first: where no map of
/// [`DISTANCE_CELLS`] fits the device (nbody:2048 on lavapipe's 128 MiB
/// buffers), auto tries the finest of these that does.
pub const COARSE_DISTANCE_CELLS: [u32; 3] = [16, 32, 64];

/// Grids of at most this many cells (64^3) get octant maps, which march
/// faster (their boxes reach further ahead: 30 % at 256^3, cell 4) but
/// whose transform costs several times the cube map's (91 against 23 ms
/// there on lavapipe, `docs/results/auto.md`); larger grids get the cube
/// map, whose rebuild stays a fraction of a frame.
pub const OCTANT_CELLS: u64 = 1 << 18;

/// A runner-up within this fraction of the best predicted time makes a
/// close call, settled by timing the candidates within it on the probe
/// tiles: the model's predictions were within about 20 % of the frames
/// measured on lavapipe (`docs/results/auto.md`).
pub const CLOSE: f64 = 0.3;
/// The most views of a build's frames auto prices its candidates on
/// (`priced_views`). A structure built once for an orbit marches every
/// view, and on ch2 at ERT off the octant map at cell 4 and at cell 8 tied
/// on the first view of `--suite auto`'s orbit where cell 8 was 7 to 15 %
/// faster on the other three (`docs/results/auto.md`): priced on the first
/// view alone, the choice was a coin toss that cost the orbit 15 %.
pub const PRICED_VIEWS: usize = 4;

/// The views of `frames` auto prices on: all of them up to
/// [`PRICED_VIEWS`], else that many spread evenly from the first.
pub fn priced_views(frames: &[FrameDesc]) -> Vec<FrameDesc> {
    let n = frames.len().min(PRICED_VIEWS);
    (0..n).map(|i| frames[i * frames.len() / n]).collect()
}

/// A skipping structure predicted less than this much faster than naive
/// marching is timed against it before it is chosen: a wrong prediction
/// must not leave the default slower than naive.
pub const NAIVE_GUARD: f64 = 0.5;
/// A timed skipping structure must beat naive marching by this fraction to
/// be chosen over it: closer than that the trial is within its noise, and
/// naive is never slower than itself.
pub const NAIVE_MARGIN: f64 = 0.03;

/// A close call whose fastest timed candidate is predicted to march the
/// whole frame in less than this (GPU milliseconds) is timed on the whole
/// frame rather than on [`TIME_TILES`] of its tiles. A probe's share of a
/// frame that small is a few microseconds of latency on a large GPU, not
/// the frame's throughput: on an H100 the grid beat naive marching on a
/// quarter of turbulence:64's 256x256 tiles and then marched the whole
/// frame 7 % slower. Whole frames that cheap cost the trial little.
pub const WHOLE_FRAME_TRIAL_MS: f64 = 4.0;

/// The largest volume (voxels) auto prices a k-d tree for: the tree's GPU
/// build took 21 ms at 256^3 and 92 ms at 512^3 on an H100
/// (`docs/results/h100/paper-table2.md`); past 512^3 it would cost more
/// than the rest of auto's pricing.
pub const TREE_VOXELS: u64 = 1 << 27;

const DISTANCE: Accel = Accel(&DistanceMethod { octants: false });
const OCTANT: Accel = Accel(&DistanceMethod { octants: true });
const GRID: Accel = Accel(&GridMethod);
const TREE: Accel = Accel(&KdGpu);

/// A structure auto may march with.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub accel: Accel,
    pub params: Params,
    /// `naive`, `distance-octant (cell 4)`, `grid (cell 16)`.
    pub label: String,
}

impl Candidate {
    fn new(accel: Accel, cell: Option<u32>) -> Result<Self> {
        match cell {
            Some(c) => Ok(Candidate {
                accel,
                params: accel.params(&[("cell", &c.to_string())])?,
                label: format!("{accel} (cell {c})"),
            }),
            None => Ok(Candidate {
                accel,
                params: accel.defaults(),
                label: accel.to_string(),
            }),
        }
    }

    /// The k-d tree auto prices: deep, leaves of at most 32 voxels,
    /// collapsed, built on the device: the fastest exact structure for
    /// sparse data on an H100 (nbody:256: 17.9x naive at 1024x1024, the
    /// octant map 14.3x; MIP and iso 1.5 to 1.6x the octant map's speed).
    pub fn tree() -> Result<Self> {
        Ok(Candidate {
            accel: TREE,
            params: TREE.params(&[("kd", "deep"), ("max-leaf", "32"), ("collapse", "on")])?,
            label: format!("{TREE} (MLS=32, collapsed)"),
        })
    }

    /// Whether this is the k-d tree candidate (`Candidate::tree`).
    pub fn is_tree(&self) -> bool {
        self.accel == TREE
    }

    /// The ranges its build reads.
    pub fn ranges(&self) -> Result<RangeKind> {
        self.accel.method().ranges(&self.params)
    }
}

fn cells_of(dims: [u32; 3], cell: u32) -> u64 {
    dims.iter().map(|&d| d.div_ceil(cell) as u64).product()
}

/// Whether auto prices a k-d tree on `info`'s device: `tree` is auto's
/// `tree` parameter (on, off, or auto: on devices that are not CPUs). On
/// lavapipe the tree never led auto's suite by the contract's 10 %, and
/// its build took 0.6 to 0.85 s at 256^3 (`docs/results/lavapipe`), more
/// than auto's whole pricing.
pub fn prices_tree(info: &DeviceInfo, tree: &str) -> bool {
    match tree {
        "on" => true,
        "off" => false,
        _ => !info.is_cpu(),
    }
}

/// The candidates for a volume of `dims` in `mode` on `info`'s device,
/// naive first, and a note for each left out because the device cannot
/// hold it; with `tree`, the k-d tree last (up to [`TREE_VOXELS`]; its
/// build may still find the device too small, `auto::choose` notes it).
/// Average frames read every sample: naive only.
pub fn candidates(info: &DeviceInfo, dims: [u32; 3], mode: &Mode, tree: bool) -> Result<(Vec<Candidate>, Vec<String>)> {
    let mut out = vec![Candidate::new(NAIVE, None)?];
    let mut notes = Vec::new();
    if matches!(mode, Mode::Average) {
        return Ok((out, notes));
    }
    // The candidate, or the device limit it exceeds.
    let distance_map = |cell: u32| -> Result<std::result::Result<Candidate, &'static str>> {
        let n = cells_of(dims, cell);
        let octants = n <= OCTANT_CELLS;
        match distance::exceeded_limit(info, n, octants) {
            None => Ok(Ok(Candidate::new(if octants { OCTANT } else { DISTANCE }, Some(cell))?)),
            Some(limit) => Ok(Err(limit)),
        }
    };
    let mut fine_map = false;
    for cell in DISTANCE_CELLS {
        match distance_map(cell)? {
            Ok(c) => {
                out.push(c);
                fine_map = true;
            }
            Err(limit) => notes.push(format!(
                "no distance map at cell {cell}: over {limit} ({} cells)",
                cells_of(dims, cell)
            )),
        }
    }
    if !fine_map {
        for cell in COARSE_DISTANCE_CELLS {
            if let Ok(c) = distance_map(cell)? {
                notes.push(format!("a distance map at cell {cell}: the finest that fits"));
                out.push(c);
                break;
            }
        }
    }
    for cell in GRID_CELLS {
        match grid::exceeded_limit(info, cells_of(dims, cell)) {
            None => out.push(Candidate::new(GRID, Some(cell))?),
            Some(limit) => notes.push(format!(
                "no grid at cell {cell}: over {limit} ({} cells)",
                cells_of(dims, cell)
            )),
        }
    }
    if tree {
        let voxels: u64 = dims.iter().map(|&d| d as u64).product();
        // Its build orders 8^3 bricks by Morton code (`kd::gpu`).
        let bricks = dims.map(|d| d.div_ceil(8));
        if voxels > TREE_VOXELS {
            notes.push(format!(
                "no k-d tree: {voxels} voxels, over the {TREE_VOXELS} its build is priced for"
            ));
        } else if bricks.iter().any(|&b| b > MAX_BRICKS_PER_AXIS) {
            notes.push(format!(
                "no k-d tree: {bricks:?} bricks of 8^3, over the {MAX_BRICKS_PER_AXIS} per axis its Morton codes address"
            ));
        } else {
            out.push(Candidate::tree()?);
        }
    }
    Ok((out, notes))
}

/// A candidate as priced: its counts on the probe tiles and its predicted
/// frame time, and its time on them when it was timed.
#[derive(Clone, Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Priced {
    pub label: String,
    /// Summed over the priced views' probe tiles.
    pub counts: Counts,
    /// Predicted milliseconds for a whole frame: the mean over the priced
    /// views.
    pub predicted: f64,
    /// Milliseconds on the probe tiles of every priced view together,
    /// when timed.
    pub trial: Option<f64>,
}

/// Which of the priced candidates to time, by index: none when the best
/// prediction stands clear of the others (by [`CLOSE`]) and of naive (by
/// [`NAIVE_GUARD`]); else every one within `CLOSE` of the best, naive
/// included when the best is not naive and naive is within the guard.
pub fn to_time(priced: &[Priced], always: bool) -> Vec<usize> {
    let best = index_of_min(priced.iter().map(|p| p.predicted));
    let b = priced[best].predicted;
    if always {
        return (0..priced.len()).collect();
    }
    let close = priced
        .iter()
        .enumerate()
        .any(|(i, p)| i != best && p.predicted <= b * (1.0 + CLOSE));
    // Candidate 0 is naive.
    let naive_near = best != 0 && priced[0].predicted <= b * (1.0 + NAIVE_GUARD);
    if !close && !naive_near {
        return Vec::new();
    }
    let mut out: Vec<usize> = (0..priced.len())
        .filter(|&i| priced[i].predicted <= b * (1.0 + CLOSE))
        .collect();
    if naive_near && !out.contains(&0) {
        out.insert(0, 0);
    }
    out
}

/// `timed` (from `to_time`) with the k-d tree, candidate `tree`, and the
/// best prediction added, where the tree is a candidate and a trial is
/// wanted at all: the model overprices the tree's kernel on GPUs, so the
/// tree is always timed against the best prediction. On an H200 it
/// predicted nbody:256's tree at 2.0 times the octant map's frame at
/// 1024x1024 (2.19 against 1.08 ms), which the tree then marched in 0.89
/// of the map's time (0.078 against 0.088 ms). A tree predicted best and
/// clear of the rest is picked untimed: overpriced, it is faster still.
pub fn with_tree(mut timed: Vec<usize>, priced: &[Priced], tree: Option<usize>) -> Vec<usize> {
    let Some(t) = tree else {
        return timed;
    };
    let best = index_of_min(priced.iter().map(|p| p.predicted));
    for i in [best, t] {
        if !timed.contains(&i) {
            timed.push(i);
        }
    }
    timed.sort_unstable();
    // The tree best and clear of the rest: the prediction picks it.
    if timed.len() == 1 {
        timed.clear();
    }
    timed
}

/// The tiles a trial of the candidates `timed` covers: every tile of the
/// frame (`u32::MAX`) when the fastest of them is predicted under
/// [`WHOLE_FRAME_TRIAL_MS`], else [`TIME_TILES`].
pub fn trial_tiles(priced: &[Priced], timed: &[usize]) -> u32 {
    let fastest = timed.iter().map(|&i| priced[i].predicted).fold(f64::INFINITY, f64::min);
    match fastest < WHOLE_FRAME_TRIAL_MS {
        true => u32::MAX,
        false => TIME_TILES,
    }
}

/// The candidate to march with: the fastest on the probe tiles when any
/// was timed (naive, candidate 0, unless another beats it by
/// [`NAIVE_MARGIN`]), else the cheapest prediction.
pub fn pick(priced: &[Priced]) -> usize {
    if priced.iter().all(|p| p.trial.is_none()) {
        return index_of_min(priced.iter().map(|p| p.predicted));
    }
    let best = index_of_min(priced.iter().map(|p| p.trial.unwrap_or(f64::INFINITY)));
    match (priced[0].trial, priced[best].trial) {
        (Some(naive), Some(t)) if best != 0 && t > naive * (1.0 - NAIVE_MARGIN) => 0,
        _ => best,
    }
}

/// The index of the least value (the first of equals).
pub fn index_of_min(values: impl Iterator<Item = f64>) -> usize {
    let mut best = (0, f64::INFINITY);
    for (i, v) in values.enumerate() {
        if v < best.1 {
            best = (i, v);
        }
    }
    best.0
}

/// Builder helpers auto's build needs from a candidate list: the ranges
/// they read, each kind once.
pub fn range_kinds(candidates: &[Candidate]) -> Result<Vec<RangeKind>> {
    let mut out = Vec::new();
    for c in candidates {
        let k = c.ranges()?;
        if !out.contains(&k) {
            out.push(k);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orbit_is_priced_on_up_to_four_views_spread_evenly() {
        let orbit = |n: usize| -> Vec<FrameDesc> {
            (0..n)
                .map(|i| {
                    let az = 360.0 * i as f64 / n as f64;
                    let ortho = crate::desc::Projection::Orthographic;
                    FrameDesc::builder(8, 8).orbit(az, 20.0, ortho).build().unwrap()
                })
                .collect()
        };
        for (n, want) in [
            (1, vec![0]),
            (3, vec![0, 1, 2]),
            (4, vec![0, 1, 2, 3]),
            (6, vec![0, 1, 3, 4]),
            (12, vec![0, 3, 6, 9]),
        ] {
            let frames = orbit(n);
            let got: Vec<usize> = priced_views(&frames)
                .iter()
                .map(|v| frames.iter().position(|f| f == v).unwrap())
                .collect();
            assert_eq!(got, want, "{n} views");
        }
    }

    fn priced(times: &[f64]) -> Vec<Priced> {
        times
            .iter()
            .map(|&t| Priced {
                label: String::new(),
                counts: Counts::default(),
                predicted: t,
                trial: None,
            })
            .collect()
    }

    #[test]
    fn only_close_calls_are_timed() {
        // Far ahead of everything, naive included: no trial.
        assert!(to_time(&priced(&[100.0, 20.0, 50.0]), false).is_empty());
        // Two within CLOSE: both timed; naive far behind stays out.
        assert_eq!(to_time(&priced(&[100.0, 20.0, 25.0, 40.0]), false), vec![1, 2]);
        // Best ahead of naive by less than the guard: naive is timed against it.
        assert_eq!(to_time(&priced(&[140.0, 100.0, 200.0]), false), vec![0, 1]);
        // Naive best and clear: no trial.
        assert!(to_time(&priced(&[50.0, 90.0, 200.0]), false).is_empty());
        // Always: everything.
        assert_eq!(to_time(&priced(&[50.0, 90.0]), true), vec![0, 1]);
    }

    #[test]
    fn the_tree_is_timed_against_the_best_prediction() {
        let p = priced(&[100.0, 20.0, 50.0, 45.0]);
        // A clear call: the tree (3) timed against the best (1) alone.
        assert_eq!(with_tree(to_time(&p, false), &p, Some(3)), vec![1, 3]);
        // A close call keeps its list, the tree joining it.
        let p = priced(&[100.0, 20.0, 25.0, 45.0]);
        assert_eq!(with_tree(to_time(&p, false), &p, Some(3)), vec![1, 2, 3]);
        // The tree best and clear: no trial, the prediction picks it.
        let p = priced(&[100.0, 50.0, 60.0, 10.0]);
        assert!(with_tree(to_time(&p, false), &p, Some(3)).is_empty());
        // No tree: to_time's list unchanged.
        assert!(with_tree(to_time(&p, false), &p, None).is_empty());
    }

    #[test]
    fn cheap_frames_are_timed_whole() {
        let p = priced(&[1.0, 0.5, 0.6]);
        assert_eq!(trial_tiles(&p, &[0, 1, 2]), u32::MAX);
        let p = priced(&[40.0, 20.0, 25.0]);
        assert_eq!(trial_tiles(&p, &[1, 2]), TIME_TILES);
        // The fastest of those timed decides, not of every candidate.
        let p = priced(&[40.0, 2.0, 25.0, 30.0]);
        assert_eq!(trial_tiles(&p, &[2, 3]), TIME_TILES);
        assert_eq!(trial_tiles(&p, &[1, 2]), u32::MAX);
    }

    #[test]
    fn the_trial_decides_and_naive_keeps_near_ties() {
        let mut p = priced(&[100.0, 50.0, 60.0]);
        assert_eq!(pick(&p), 1, "untimed: the cheapest prediction");
        p[1].trial = Some(9.0);
        p[2].trial = Some(8.0);
        assert_eq!(pick(&p), 2, "timed: the fastest, whatever was predicted");
        p[0].trial = Some(8.1);
        assert_eq!(pick(&p), 0, "within NAIVE_MARGIN of naive: naive");
        p[0].trial = Some(9.0);
        assert_eq!(pick(&p), 2);
    }
}
