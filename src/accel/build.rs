//! `Builder::build` and `record_build`: a structure for one transfer
//! function and frame mode, classified by the mode's activity function
//! (`accel::mode`), or marched naively in a mode it does not skip in.

use super::builder::{Builder, RangeKind, Ranges};
use super::method::{Accel, BuildInput, Built, Structure};
use super::mode::{activity, ModeFallback};
use super::params::Params;
use crate::error::Result;
use crate::gpu::Recording;
use crate::gpu::{Timer, Timings};
use crate::volume::GpuVolume;
use std::any::Any;

impl Builder {
    /// Builds `accel` with `params` for the input's transfer function and
    /// mode, and waits: the path a TF change takes. Returns the structure
    /// and its timings per phase. A structure that does not march the mode
    /// is not built: it is marched naively (`MarchedKind::ModeFallback`).
    pub fn build(
        &self,
        accel: Accel,
        input: &BuildInput,
        ranges: &Ranges,
        params: &Params,
    ) -> Result<(Structure, Timings)> {
        accel.method().check(params)?;
        input.check(self.context())?;
        ranges.check_volume(input.gpu_volume)?;
        if !accel.method().marches(&input.mode) {
            return Ok((fallback(accel, params, input), Timings::default()));
        }
        if let Some(frame) = input.frames.iter().find(|f| !f.mode().same_classification(&input.mode)) {
            return Err(crate::error::Error::invalid(
                "build frame",
                frame.mode().name(),
                format!("the build is for {} frames", input.mode.name()),
            ));
        }
        let classifies = accel.method().classifies();
        let (built, t) = match activity(&input.mode, input.tf)?.filter(|_| classifies) {
            Some(activity) => {
                let gpu_activity = activity.upload(self.context())?;
                let classified = BuildInput {
                    tf: &activity,
                    gpu_tf: &gpu_activity,
                    ..*input
                };
                accel.method().build(self, &classified, ranges, params)?
            }
            None => accel.method().build(self, input, ranges, params)?,
        };
        Ok((
            Structure {
                accel,
                params: params.clone(),
                mode: Some(input.mode),
                volume: Some(input.built_over()),
                built_for: input.built_for(accel),
                made_on: Some(self.context().clone()),
                built,
                _keep: None,
            },
            t,
        ))
    }

    /// Records the build of a recordable structure into `cmd` (see
    /// [`Method::record_build`] for the barriers); host-driven structures
    /// return an error saying so.
    pub fn record_build(
        &self,
        accel: Accel,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        params: &Params,
    ) -> Result<Structure> {
        accel.method().check(params)?;
        self.context().check_is(cmd.context(), "command buffer")?;
        input.check(self.context())?;
        ranges.check_volume(input.gpu_volume)?;
        if !accel.method().marches(&input.mode) {
            return Ok(fallback(accel, params, input));
        }
        let (built, keep): (Box<dyn Built>, Option<Box<dyn Any + Send + Sync>>) = match activity(&input.mode, input.tf)?
        {
            Some(activity) => {
                let (gpu_activity, staging) = activity.record_upload(cmd)?;
                let classified = BuildInput {
                    tf: &activity,
                    gpu_tf: &gpu_activity,
                    ..*input
                };
                let built = accel
                    .method()
                    .record_build(self, cmd, timer, &classified, ranges, params)?;
                (built, Some(Box::new((gpu_activity, staging))))
            }
            None => (
                accel.method().record_build(self, cmd, timer, input, ranges, params)?,
                None,
            ),
        };
        Ok(Structure {
            accel,
            params: params.clone(),
            mode: Some(input.mode),
            volume: Some(input.built_over()),
            built_for: input.built_for(accel),
            made_on: Some(self.context().clone()),
            built,
            _keep: keep,
        })
    }

    /// The per-volume ranges the structures read (each kind once): once
    /// per volume upload.
    pub fn ranges_for(&self, structures: &[(Accel, &Params)], volume: &GpuVolume) -> Result<(Ranges, Timings)> {
        self.ranges(&self.kinds_for(structures, volume)?, volume)
    }

    /// The kinds of ranges `structures` read.
    fn kinds_for(&self, structures: &[(Accel, &Params)], volume: &GpuVolume) -> Result<Vec<RangeKind>> {
        let mut kinds = Vec::new();
        for (a, p) in structures {
            kinds.extend(a.method().range_kinds(p, volume, self.context().info())?);
        }
        Ok(kinds)
    }

    /// As `ranges_for` on a series step's input: with its voxels on the
    /// host, which a CPU device's step ranges are made from
    /// (`Builder::ranges_with`).
    pub(super) fn step_ranges_for(
        &self,
        structures: &[(Accel, &Params)],
        input: &BuildInput,
    ) -> Result<(Ranges, Timings)> {
        let kinds = self.kinds_for(structures, input.gpu_volume)?;
        self.ranges_with(&kinds, input.gpu_volume, Some(input.volume))
    }
}

/// A structure that does not march the input's mode: naive marching.
fn fallback(accel: Accel, params: &Params, input: &BuildInput) -> Structure {
    Structure {
        accel,
        params: params.clone(),
        mode: Some(input.mode),
        volume: Some(input.built_over()),
        built_for: None,
        made_on: None,
        built: Box::new(ModeFallback::new(accel, &input.mode)),
        _keep: None,
    }
}
