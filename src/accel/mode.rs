//! What "empty" means in each frame mode (DESIGN invariant 2), so that a
//! structure built for a mode skips exactly in it. Each mode but average
//! classifies by a transfer function, the frame's or an *activity*
//! function derived from it (`activity`), so every structure's
//! classification applies unchanged:
//!
//! - composite (shaded or not): the frame's TF. Shading only changes colour
//!   and lowers opacity (gradient opacity), so its empty is the unshaded one;
//! - iso: a region is active iff its value range over the apron reaches an
//!   iso value: opaque at the LUT entries around each iso value. The march
//!   widens each active span by a step on both sides, so the pairs of
//!   samples that straddle a region's entry or exit are tested too (the
//!   lattice itself is naive's);
//! - mip (minip): the pixel is the TF at the largest (smallest) sample, and
//!   every value at or below the TF's first visible entry (at or above its
//!   last) maps to a transparent pixel, so a region whose range lies there
//!   cannot change it: opaque from one entry before the first visible one
//!   up (down from one after the last). The macro-cell grid also skips, per
//!   ray, every cell whose range cannot beat the ray's running max (min):
//!   `Mode::value_bound`, `volume::value_margin`, `glsl/march/grid.comp`;
//! - average: every sample counts, so nothing is skipped.
//!
//! A structure that does not march a mode is marched naively in it, saying
//! so (`MarchedKind::ModeFallback`).
//!
//! Several channels: a region is active iff it is active in any channel,
//! each classified by its own transfer function's activity function. In
//! mip (minip) this stays exact: a channel whose values in a region all map
//! to transparent shows nothing whether or not the region raises its
//! extreme, and a transparent channel adds nothing to the mix. The grid's
//! per-ray running extreme is kept for one channel only.

use super::method::{Accel, Built, MarchedAs, MarchedKind};
use super::naive::NAIVE;
use super::stats::Stats;
use crate::desc::{Iso, Mode};
use crate::error::Result;
use crate::gpu::Bound;
use crate::tf::{TransferFunction, LUT_SIZE};

/// The transfer function structures for frames of `mode` with the TF `tf`
/// classify by; None: `tf` itself (composite, and average, which skips
/// nothing).
pub fn activity(mode: &Mode, tf: &TransferFunction) -> Result<Option<TransferFunction>> {
    if tf.channel_count() > 1 {
        // One activity function per channel's transfer function.
        let mut per_channel = Vec::new();
        for t in tf.channels() {
            match channel_activity(mode, t)? {
                Some(a) => per_channel.push(a),
                None => return Ok(None),
            }
        }
        return TransferFunction::per_channel(per_channel).map(Some);
    }
    channel_activity(mode, tf)
}

/// `activity` of one channel's transfer function.
fn channel_activity(mode: &Mode, tf: &TransferFunction) -> Result<Option<TransferFunction>> {
    let n = LUT_SIZE;
    let opaque_where = |name: &str, keep: &dyn Fn(usize) -> bool| {
        let lut = (0..n).map(|i| if keep(i) { [1.0; 4] } else { [0.0; 4] }).collect();
        TransferFunction::from_lut(format!("{name} activity of {}", tf.spec), lut).map(Some)
    };
    match (mode, tf.visible_entries()) {
        (Mode::Composite | Mode::Average, _) => Ok(None),
        (Mode::Iso(iso), _) => iso_activity(iso).map(Some),
        (Mode::Mip | Mode::MinIp, None) => opaque_where(mode.name(), &|_| false),
        (Mode::Mip, Some([first, _])) => opaque_where("mip", &|i| i + 1 >= first as usize),
        (Mode::MinIp, Some([_, last])) => opaque_where("minip", &|i| i <= last as usize + 1),
    }
}

/// The transfer function whose classification is iso mode's: opaque at the
/// LUT entries that bracket each iso value, transparent elsewhere. A range
/// `[min, max]` reaching an iso value covers one of its entries, so it is
/// active; the classification widens the entries by one per side, which
/// only adds regions.
pub fn iso_activity(iso: &Iso) -> Result<TransferFunction> {
    let mut lut = vec![[0.0f32; 4]; LUT_SIZE];
    let last = (LUT_SIZE - 1) as f32;
    for &v in iso.values() {
        let x = v.clamp(0.0, 1.0) * last;
        for i in [x.floor(), x.ceil()] {
            lut[i as usize] = [1.0; 4];
        }
    }
    let values: Vec<String> = iso.values().iter().map(|v| v.to_string()).collect();
    TransferFunction::from_lut(format!("iso activity {}", values.join(",")), lut)
}

/// A structure that does not march a mode: frames of that mode are marched
/// naively.
pub(crate) struct ModeFallback {
    accel: Accel,
    mode: &'static str,
}

impl ModeFallback {
    pub(crate) fn new(accel: Accel, mode: &Mode) -> Self {
        ModeFallback {
            accel,
            mode: mode.name(),
        }
    }
}

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for ModeFallback {
    fn bindings(&self) -> Vec<Bound<'_>> {
        Vec::new()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        Ok(None)
    }
    fn marched_as(&self) -> Option<MarchedAs> {
        Some(MarchedAs {
            accel: NAIVE,
            label: NAIVE.name().into(),
            reason: format!("{} does not skip in {} mode", self.accel, self.mode),
            kind: MarchedKind::ModeFallback,
        })
    }
}
