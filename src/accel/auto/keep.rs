//! A new time step of a series: `Builder::build_step`. For `auto` it keeps
//! the structure chosen on an earlier step for the same transfer function
//! and mode, and builds only that one from the new step's data, while the
//! share of its regions that are active stays within `KEEP_SHARE` of the
//! share it had when chosen; otherwise, and where the choice has no share
//! to compare (naive; a structure whose every region is active, as the
//! grid of MIP frames, which decides per ray), auto prices its candidates
//! anew. A playing series then pays one build a
//! step, not a build of each of auto's candidates, counting frames and trial. Every
//! candidate is exact, so keeping one changes speed, never the frame.

use super::{Choice, Chosen, AUTO};
use crate::accel::builder::{Builder, Ranges};
use crate::accel::method::{Accel, BuildInput, Structure};
use crate::accel::params::Params;
use crate::error::Result;
use crate::gpu::Timings;

/// How far the share of the kept structure's active regions may move, as
/// a ratio either way, before a step is priced anew: a data set whose
/// visible part grows or shrinks by more than a quarter may favour another
/// cell size or structure.
pub const KEEP_SHARE: f64 = 1.25;

/// A structure built for a new time step, and what it took.
pub struct StepBuild {
    pub structure: Structure,
    /// The ranges the asked-for structure reads, where they were computed
    /// (a kept choice computes only its own: None).
    pub ranges: Option<Ranges>,
    pub ranges_timings: Timings,
    pub build_timings: Timings,
}

/// `t`'s phases, each name after `prefix`.
fn prefixed(prefix: &str, t: Timings) -> Timings {
    Timings {
        phases: t
            .phases
            .into_iter()
            .map(|(name, ms)| (format!("{prefix}{name}"), ms))
            .collect(),
    }
}

/// The share of `s`'s regions that are active, where some but not all
/// are (every region active says nothing of how the data moved: the grid
/// of MIP and MinIP frames keeps every cell and decides per ray).
fn active_share(s: &Structure) -> Result<Option<f64>> {
    Ok(s.built
        .stats()?
        .filter(|st| st.active_bricks < st.total_bricks)
        .map(|st| st.active_bricks as f64 / st.total_bricks as f64))
}

/// Whether `now` is within `KEEP_SHARE` of `then` (both empty counts).
fn near(now: f64, then: f64) -> bool {
    match (now > 0.0, then > 0.0) {
        (false, false) => true,
        (true, true) => (now / then).max(then / now) <= KEEP_SHARE,
        _ => false,
    }
}

/// The share of the chosen structure's active regions, for `Choice::share`
/// (None: naive, or no share to compare), its readback's time pushed to
/// `t` as `share`.
pub(super) fn share_of(s: &Structure, t: &mut Timings) -> Result<Option<f64>> {
    if s.marched_as().is_naive() {
        return Ok(None);
    }
    t.cpu("share", || active_share(s))
}

impl Builder {
    /// Builds `accel` with `params` for a new time step of a series (a
    /// volume on the same grid), computing the ranges it reads first. For
    /// `auto` with `last`, auto's choice on an earlier step for the same
    /// transfer function and mode, the chosen structure is built alone and
    /// kept while its share of active regions stays near the choice's
    /// (`KEEP_SHARE`; `Choice::kept` counts the steps); otherwise auto
    /// chooses anew, and a kept try's ranges and build count toward this
    /// step's timings. A kept choice was priced for the frame of its step:
    /// a host whose camera moved since, and wants the choice priced for the
    /// new frame, passes None (`view` keeps it, as it keeps a choice while
    /// the camera moves). Other structures build as `ranges_for` then
    /// `build` would, the ranges made with the step's voxels at hand
    /// (`Builder::ranges_with`: on the host for a CPU device).
    pub fn build_step(
        &self,
        accel: Accel,
        params: &Params,
        last: Option<&Choice>,
        input: &BuildInput,
    ) -> Result<StepBuild> {
        input.check(self.context())?;
        let kept = last.filter(|c| accel == AUTO && c.share.is_some() && c.mode == input.mode && c.tf == input.tf.spec);
        let mut spent = (Timings::default(), Timings::default());
        if let Some(choice) = kept {
            let c = &choice.candidate;
            let (ranges, ranges_t) = self.step_ranges_for(&[(c.accel, &c.params)], input)?;
            match self.build(c.accel, input, &ranges, &c.params) {
                Ok((structure, mut build_t)) => {
                    let now = share_of(&structure, &mut build_t)?;
                    if let (Some(now), Some(then)) = (now, choice.share) {
                        if near(now, then) {
                            let choice = Choice {
                                kept: choice.kept + 1,
                                share_now: Some(now),
                                ..choice.clone()
                            };
                            let chosen = Chosen {
                                choice,
                                inner: structure.built,
                            };
                            return Ok(StepBuild {
                                structure: Structure {
                                    accel,
                                    params: params.clone(),
                                    mode: Some(input.mode),
                                    volume: Some(input.built_over()),
                                    built_for: input.built_for(accel),
                                    made_on: Some(self.context().clone()),
                                    built: Box::new(chosen),
                                    _keep: None,
                                },
                                ranges: None,
                                ranges_timings: ranges_t,
                                build_timings: build_t,
                            });
                        }
                    }
                    spent = (prefixed("kept ", ranges_t), prefixed("kept ", build_t));
                }
                // A kept tree whose buffers (sized by the data) no longer
                // fit: this step is priced anew, as auto's build would.
                Err(e) if c.is_tree() && e.is_device_too_small() => {
                    spent = (prefixed("kept ", ranges_t), Timings::default());
                }
                Err(e) => return Err(e),
            }
        }
        let (ranges, ranges_t) = self.step_ranges_for(&[(accel, params)], input)?;
        let (structure, build_t) = self.build(accel, input, &ranges, params)?;
        let (mut ranges_timings, mut build_timings) = spent;
        ranges_timings.extend(ranges_t);
        build_timings.extend(build_t);
        Ok(StepBuild {
            structure,
            ranges: Some(ranges),
            ranges_timings,
            build_timings,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shares_are_near_within_a_quarter_either_way_and_empty_only_to_empty() {
        assert!(near(0.1, 0.1));
        assert!(near(0.12, 0.1) && near(0.1, 0.12));
        assert!(!near(0.13, 0.1) && !near(0.1, 0.13));
        assert!(near(0.0, 0.0));
        assert!(!near(0.0, 0.1) && !near(0.1, 0.0));
    }
}
