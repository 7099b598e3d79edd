//! When things are timed: the interleaved schedule of timed frames, the
//! warm-up until times are stable, and the noise spread of a set of times.

use crate::error::Result;

/// One timed frame of the interleaved schedule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slot {
    pub view: u32,
    pub round: u32,
    /// Index into the structures, in timing order (naive first).
    pub structure: usize,
}

/// The order frames are timed in: for each view, `rounds` rounds, and in
/// each round every structure once, in order. A structure's frames of one
/// view are thus spread over the same stretch of time as every other's.
pub fn schedule(views: u32, rounds: u32, structures: usize) -> impl Iterator<Item = Slot> {
    (0..views).flat_map(move |view| {
        (0..rounds).flat_map(move |round| (0..structures).map(move |structure| Slot { view, round, structure }))
    })
}

/// How a warm-up ended: runs made, and whether it stopped at the cap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WarmedUp {
    pub runs: u32,
    pub capped: bool,
}

/// Runs `once` (which returns a time) at least `least` times and until two
/// consecutive times agree within the fraction `stable`, or `cap` times.
/// One run is never enough: on lavapipe the frames after the first are
/// still slow with a cold shader cache.
pub fn warm_up(least: u32, cap: u32, stable: f64, mut once: impl FnMut(u32) -> Result<f64>) -> Result<WarmedUp> {
    let least = least.max(2);
    let mut previous: Option<f64> = None;
    for i in 0..cap.max(least) {
        let t = once(i)?;
        if i + 1 >= least {
            if let Some(p) = previous {
                if (t - p).abs() <= stable * t.min(p) {
                    return Ok(WarmedUp {
                        runs: i + 1,
                        capped: false,
                    });
                }
            }
        }
        previous = Some(t);
    }
    Ok(WarmedUp {
        runs: cap.max(least),
        capped: true,
    })
}

/// max/min of positive times; 1 when there is nothing to compare.
pub(crate) fn spread(ms: &[f64]) -> f64 {
    let min = ms.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = ms.iter().cloned().fold(0.0, f64::max);
    if min > 0.0 && min.is_finite() {
        max / min
    } else {
        1.0
    }
}
