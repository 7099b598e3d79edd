//! The time to the first exact frame of a new time step, per structure:
//! the step's voxels are in host memory (loading or generating them is
//! timed apart), then its upload (with the cells copy and gradient the
//! frames read; once a step, the same for every structure), the ranges the
//! structure reads, its build and one frame, each timed, interleaved
//! across the structures step by step. Each step is built as `view` builds
//! it (`Builder::build_step`: auto keeps its choice from step to step while
//! the choice's active share holds). Every frame is compared with naive's
//! on the same step.

use super::config::StructureSpec;
use super::progress::Progress;
use crate::accel::auto::{self, Choice};
use crate::accel::{BuildInput, Builder};
use crate::error::{Error, Result};
use crate::frame::{diff, Frame};
use crate::gpu::timings::median;
use crate::gpu::Context;
use crate::render::{FrameDesc, Scene};
use crate::tf::{GpuTransferFunction, TransferFunction};
use crate::volume::{Filter, GpuVolume, Series, Storage};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// One structure's new-step figures on one data set: medians over steps.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct StepRecord {
    pub dataset: String,
    pub structure: String,
    /// Steps timed (the first is the warm-up step and is not among them).
    pub steps: Vec<u32>,
    /// Reading or generating a step on the host (the same for every
    /// structure; overlapped with the previous step's frames by `view`).
    pub load_ms: f64,
    /// Upload, with the cells copy and gradient the frames read (wall;
    /// once a step, shared by every structure).
    pub upload_ms: f64,
    /// The ranges the structure reads (GPU).
    pub ranges_ms: f64,
    /// The structure's build (GPU phases, host phases in wall time).
    pub build_ms: f64,
    /// The step's first frame (GPU).
    pub frame_ms: f64,
    /// The same view's next frame, timed right after the first (GPU): the
    /// frame time of this step, interleaved with its new-step time.
    #[serde(default)]
    pub next_frame_ms: f64,
    /// upload + ranges + build + frame: the first exact frame of a new step.
    pub new_step_ms: f64,
    /// Pixels of its frames that differ from naive's on the same step.
    pub differing_pixels: u64,
    /// auto's choice on the last step, and on how many of the timed steps
    /// it was kept without pricing (None for the other structures).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chosen: Option<String>,
}

/// What `steps` measures with.
pub struct StepBench<'a> {
    pub ctx: &'a Context,
    pub builder: &'a Builder,
    pub structures: &'a [StructureSpec],
    pub tf: &'a TransferFunction,
    pub lut: &'a GpuTransferFunction,
    /// The frame timed on every step (the orbit's view 0, its filter set).
    pub desc: &'a FrameDesc,
    /// The filter the run asked for (None: the device's default), for
    /// what the upload adds.
    pub filter: Option<Filter>,
    /// The data set's voxel storage.
    pub storage: Storage,
}

/// An error unless `[first, last]` is a range of `series`' steps with
/// FIRST < LAST (the first step warms up, the rest are timed).
pub(super) fn check_range(series: &Series, [first, last]: [u32; 2]) -> Result<()> {
    if first >= last {
        return Err(Error::invalid(
            "time",
            format!("[{first}, {last}]"),
            "expected [FIRST, LAST] with FIRST < LAST: the first step warms up, the rest are timed",
        ));
    }
    series.check_step(last)
}

impl StepBench<'_> {
    /// Times steps `first..=last` of `series` (`first` warms up untimed).
    pub fn run(
        &self,
        label: &str,
        series: &Series,
        [first, last]: [u32; 2],
        mut frame: impl FnMut(Scene, &FrameDesc, bool) -> Result<(f64, Option<Frame>)>,
        progress: &Progress,
    ) -> Result<Vec<StepRecord>> {
        check_range(series, [first, last])?;
        let n = self.structures.len();
        let mut times: Vec<[Vec<f64>; 6]> = vec![Default::default(); n];
        let mut loads = Vec::new();
        let mut differing = vec![0u64; n];
        // auto's choice on the last step, and the timed steps that kept
        // one, per structure.
        let mut choices: Vec<Option<Choice>> = vec![None; n];
        let mut kept = vec![0u32; n];
        // The last step on the device, and its voxels: the next step
        // rewrites only what changed (`GpuVolume::replace`).
        let mut on_device: Option<(GpuVolume, crate::volume::Volume)> = None;
        // Each structure's step ranges of its own, as when it plays the
        // series alone (no structure starts from another's).
        let builders: Vec<Builder> = self.structures.iter().map(|_| self.builder.fork()).collect();
        for k in first..=last {
            progress.at(&format!("{label} - new step {k}"));
            let t = Instant::now();
            let volume = series.load_stored(k, self.storage, self.ctx.info(), None)?;
            let load_ms = ms_since(t);
            // One upload a step, every structure reading it; in the last
            // step's memory, as the viewer plays a series.
            let t = Instant::now();
            let lit = self.desc.lighting().is_some();
            let (last_gv, previous) = on_device.take().unzip();
            let gv = GpuVolume::upload_step(
                self.ctx,
                last_gv.map(|gv| (gv, previous.as_ref())),
                &volume,
                self.storage,
                lit,
                self.filter,
            )?;
            let upload = ms_since(t);
            let mut naive: Option<Frame> = None;
            for (i, s) in self.structures.iter().enumerate() {
                let input = BuildInput {
                    volume: &volume,
                    gpu_volume: &gv,
                    tf: self.tf,
                    gpu_tf: self.lut,
                    mode: *self.desc.mode(),
                    frames: std::slice::from_ref(self.desc),
                    octants: self.desc.octants(volume.dims, volume.spacing)?,
                };
                let step = builders[i].build_step(s.accel, &s.params, choices[i].as_ref(), &input)?;
                let (structure, ranges_t, build_t) = (step.structure, step.ranges_timings, step.build_timings);
                choices[i] = auto::choice_of(&structure).cloned();
                if k > first {
                    kept[i] += choices[i].as_ref().is_some_and(|c| c.kept > 0) as u32;
                }
                let scene = Scene {
                    structure: &structure,
                    volume: &gv,
                    tf: self.lut,
                };
                let (frame_ms, image) = frame(scene, self.desc, true)?;
                let image = image.ok_or_else(|| Error::Unsupported("a frame read back was not returned".into()))?;
                let (next_ms, _) = frame(scene, self.desc, false)?;
                match &naive {
                    None => naive = Some(image),
                    Some(reference) => differing[i] += diff(reference, &image)?.differing as u64,
                }
                if k > first {
                    let parts = [upload, ranges_t.total(), build_t.total(), frame_ms];
                    let total = parts.iter().sum();
                    for (series, v) in times[i].iter_mut().zip(parts.into_iter().chain([total, next_ms])) {
                        series.push(v);
                    }
                }
                progress.step(1);
            }
            if k > first {
                loads.push(load_ms);
            }
            // The step before's voxels freed once the new step's frames are
            // timed, as a host frees them off the new step's path (unmapping
            // nbody:256's 16 MB took up to 4 ms on lavapipe's host).
            drop(previous);
            on_device = Some((gv, volume));
        }
        let load_ms = median(loads);
        let timed = last - first;
        let chosen: Vec<Option<String>> = choices
            .iter()
            .zip(&kept)
            .map(|(c, kept)| {
                c.as_ref()
                    .map(|c| format!("{}, kept on {kept} of the {timed} timed steps", c.describe()))
            })
            .collect();
        Ok(self
            .structures
            .iter()
            .zip(times)
            .zip(differing)
            .zip(chosen)
            .map(
                |(((s, [upload, ranges, build, frame, total, next]), differing_pixels), chosen)| StepRecord {
                    dataset: label.to_string(),
                    structure: s.label.clone(),
                    steps: (first + 1..=last).collect(),
                    load_ms,
                    upload_ms: median(upload),
                    ranges_ms: median(ranges),
                    build_ms: median(build),
                    frame_ms: median(frame),
                    next_frame_ms: median(next),
                    new_step_ms: median(total),
                    differing_pixels,
                    chosen,
                },
            )
            .collect())
    }
}

impl super::BenchOutput {
    /// The new-step table, beside each structure's median frame time.
    pub fn steps_md(&self) -> String {
        steps_md(&self.steps, |d, s| {
            self.records
                .iter()
                .find(|r| r.dataset == d && r.structure == s)
                .map(|r| r.frame.median_ms)
        })
    }
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1000.0
}

/// The new-step table: per data set and structure, the parts and the
/// total; the total over the step's next frame (the same view, timed right
/// after the new step's frame: interleaved, so the machine's drift between
/// a run's phases stays out of it), and over the structure's median frame
/// in the run's timed frames (`frame_of`, over the orbit's views), where it
/// has one.
pub fn steps_md(records: &[StepRecord], frame_of: impl Fn(&str, &str) -> Option<f64>) -> String {
    let mut out = String::from(
        "Time to the first exact frame of a new time step (ms, medians over the timed steps; the step's voxels already in host memory)\n\n\
         | data set | structure | load (host) | upload | ranges | build | frame | new step | next frame | new step / next frame | new step / run's frame | differing px |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in records {
        let ratio = frame_of(&r.dataset, &r.structure).map_or("-".to_string(), |f| format!("{:.2}", r.new_step_ms / f));
        let next = match r.next_frame_ms > 0.0 {
            true => format!("{:.2}", r.new_step_ms / r.next_frame_ms),
            false => "-".to_string(),
        };
        out += &format!(
            "| {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {next} | {ratio} | {} |\n",
            r.dataset,
            r.structure,
            r.load_ms,
            r.upload_ms,
            r.ranges_ms,
            r.build_ms,
            r.frame_ms,
            r.new_step_ms,
            r.next_frame_ms,
            r.differing_pixels
        );
    }
    for r in records {
        if let Some(chosen) = &r.chosen {
            out += &format!("\n{} on {}: {chosen}.\n", r.structure, r.dataset);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(structure: &str, chosen: Option<&str>) -> StepRecord {
        StepRecord {
            dataset: "nbody:256".into(),
            structure: structure.into(),
            steps: vec![1, 2],
            load_ms: 300.0,
            upload_ms: 40.0,
            ranges_ms: 60.0,
            build_ms: 100.0,
            frame_ms: 60.0,
            next_frame_ms: 52.0,
            new_step_ms: 260.0,
            differing_pixels: 0,
            chosen: chosen.map(String::from),
        }
    }

    #[test]
    fn the_steps_table_says_what_auto_chose_and_kept_and_its_ratio_to_a_frame() {
        let records = [
            record("grid", None),
            record("auto", Some("distance-octant (cell 4), kept on 2 of the 2 timed steps")),
        ];
        let md = steps_md(&records, |_, s| (s == "auto").then_some(65.0));
        assert!(
            md.contains("| nbody:256 | auto | 300.0 | 40.0 | 60.0 | 100.0 | 60.0 | 260.0 | 52.0 | 5.00 | 4.00 | 0 |"),
            "{md}"
        );
        assert!(
            md.contains("| nbody:256 | grid | 300.0 | 40.0 | 60.0 | 100.0 | 60.0 | 260.0 | 52.0 | 5.00 | - | 0 |"),
            "{md}"
        );
        assert!(
            md.ends_with("\nauto on nbody:256: distance-octant (cell 4), kept on 2 of the 2 timed steps.\n"),
            "{md}"
        );
        assert_eq!(md.matches(" on nbody:256: ").count(), 1, "{md}");
    }
}
