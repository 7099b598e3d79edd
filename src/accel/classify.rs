//! Brick classification for a transfer function.
//!
//! - `Range` (default): active iff the TF's max alpha over the brick's value
//!   range (apron included) is > 0. O(bricks) per TF change; conservative.
//! - `Voxel { apron: true }`: every trilinear cell a sample in the brick can
//!   read goes through the TF (O(voxels) per TF change); gives exactly the
//!   same active bricks as `Range`.
//! - `Voxel { apron: false }`: the paper's brick voting, each voxel of the
//!   brick through the TF at its own value; not conservative (interpolated
//!   samples near brick faces can be lost), kept to reproduce the paper.

use super::bricks::GpuBricks;
use super::params::{Param, Params};
use crate::error::{Error, Result};
use crate::gpu::record;
use crate::gpu::shaders::{self, build_classify_range, build_classify_voxel};
use crate::gpu::Recording;
use crate::gpu::{Binding, Buffer, Context, Kernel};
use crate::prims::entry_barrier;
use crate::tf::{GpuTransferFunction, TransferFunction, LUT_SIZE};
use crate::volume::GpuVolume;
use rayon::prelude::*;

/// How a brick is found active: by its value range against the transfer
/// function (exact, conservative), or voxel by voxel (the paper's rule,
/// with or without the apron; not exact).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Classify {
    Range,
    Voxel { apron: bool },
}

/// `--classify range|voxel`.
pub const CLASSIFY: Param = Param::choice(
    "classify",
    &["range", "voxel"],
    "range",
    "Brick classification: range (O(bricks) per TF change) or voxel (every voxel through the TF)",
);
/// `--apron on|off` (with `--classify voxel`).
pub const APRON: Param = Param::switch(
    "apron",
    true,
    "With --classify voxel: keep the one-voxel apron (on), or drop it as the paper does (off; not conservative)",
);

impl Classify {
    /// From a structure's `classify` and `apron` parameters: dropping the
    /// apron is the paper's voxel voting only (range classification is
    /// always conservative).
    pub fn from_params(p: &Params) -> Result<Self> {
        match (p.choice("classify")?, p.switch("apron")?) {
            ("range", true) => Ok(Classify::Range),
            ("range", false) => Err(Error::invalid(
                "apron",
                "off",
                "only --classify voxel can drop the apron (range classification is always conservative)",
            )),
            (_, apron) => Ok(Classify::Voxel { apron }),
        }
    }
}

/// The classification kernels (`Builder::shared`).
pub struct Classifier {
    ctx: Context,
    voxel: Kernel,
}

impl Classifier {
    pub fn new(ctx: &Context) -> Result<Self> {
        Ok(Classifier {
            ctx: ctx.clone(),
            voxel: Kernel::new::<build_classify_voxel::Push>(ctx, &shaders::BUILD_CLASSIFY_VOXEL)?,
        })
    }

    /// Records `flags[b] = 1` for active bricks, 0 otherwise (u32 per brick).
    /// Follows the `prims` barrier convention; ends with compute writes.
    pub fn record(
        &self,
        cmd: Recording<'_>,
        mode: Classify,
        volume: &GpuVolume,
        bricks: &GpuBricks,
        tf: &GpuTransferFunction,
        flags: &Buffer,
    ) -> Result<()> {
        // Their image views and buffers are bound below: this context's only.
        self.ctx.check_is(volume.context(), "volume")?;
        self.ctx.check_is(tf.context(), "transfer function")?;
        self.ctx.check_is(bricks.ranges.context(), "brick ranges")?;
        tf.check_channels(volume.channels)?;
        let need = [bricks.total * 4, bricks.total * 8 * volume.channels as u64];
        if flags.size() < need[0] || bricks.ranges.size() < need[1] {
            return Err(Error::invalid(
                "classification buffers",
                format!("{} and {} bytes", flags.size(), bricks.ranges.size()),
                format!(
                    "{} bricks need {} bytes of flags and {} of ranges",
                    bricks.total, need[0], need[1]
                ),
            ));
        }
        entry_barrier(cmd);
        match mode {
            Classify::Range => {
                // One kernel per channel count (made on first use).
                // SAFETY: the constants are the ones this kernel is written for (its own table).
                let range = unsafe {
                    Kernel::specialized(
                        &self.ctx,
                        &shaders::BUILD_CLASSIFY_RANGE,
                        std::mem::size_of::<build_classify_range::Push>(),
                        &[(0, bricks.channels)],
                    )
                }?;
                let groups = record::groups_linear(self.ctx.info(), "classify", bricks.total, range.local_size()[0])?;
                let push = build_classify_range::Push {
                    bricks: bricks.total as u32,
                    groups_x: groups[0],
                    lut_size: LUT_SIZE as u32,
                    tf_stride: tf.channel_step() * tf.max_stride,
                };
                // SAFETY: every binding is a live object of this context borrowed for
                // the call, or the host's (`Recording::adopt`, `HostImage::new`).
                unsafe {
                    range.dispatch(
                        cmd,
                        &build_classify_range::Bindings {
                            ranges: Binding::Storage(&bricks.ranges),
                            transfer_max: Binding::Storage(&tf.max_table),
                            flags: Binding::Storage(flags),
                        }
                        .list(),
                        bytemuck::bytes_of(&push),
                        groups,
                    )
                }
            }
            Classify::Voxel { apron } => {
                let groups =
                    record::groups_linear(self.ctx.info(), "classify", bricks.total, self.voxel.local_size()[0])?;
                let c = bricks.counts;
                // dims.w: brick edge; counts.w: total bricks.
                let push = build_classify_voxel::Push {
                    dims: [volume.dims[0], volume.dims[1], volume.dims[2], bricks.brick],
                    counts: [c[0], c[1], c[2], bricks.total as u32],
                    lo: volume.norms.map(|n| n[0]),
                    scale: volume.norms.map(|n| n[1]),
                    apron: if apron { crate::volume::APRON } else { 0 },
                    groups_x: groups[0],
                    lut_size: LUT_SIZE as u32,
                    channels: volume.channels,
                    tf_step: tf.channel_step(),
                    max_stride: tf.max_stride,
                    pool_brick: volume.brick_edge(),
                    ..Default::default()
                };
                // SAFETY: every binding is a live object of this context borrowed for
                // the call, or the host's (`Recording::adopt`, `HostImage::new`).
                unsafe {
                    self.voxel.dispatch(
                        cmd,
                        &build_classify_voxel::Bindings {
                            volume_tex: Binding::Sampled(volume.image.view, volume.sampler),
                            transfer_lut: Binding::Storage(&tf.lut),
                            transfer_max: Binding::Storage(&tf.max_table),
                            flags: Binding::Storage(flags),
                            brick_table: Binding::Texels(volume.brick_table()),
                            pool_1: Binding::Sampled(volume.pool_views()[0], volume.sampler),
                            pool_2: Binding::Sampled(volume.pool_views()[1], volume.sampler),
                            pool_3: Binding::Sampled(volume.pool_views()[2], volume.sampler),
                        }
                        .list(),
                        bytemuck::bytes_of(&push),
                        groups,
                    )
                }
            }
        }
    }
}

impl super::builder::PerContext for Classifier {
    fn new(ctx: &Context) -> Result<Self> {
        Classifier::new(ctx)
    }
}

/// Range classification on the host (`Classify::Range`, as
/// `glsl/build/classify_range.comp` makes it): `flags[b]` is 1 iff any
/// channel's `TransferFunction::max_alpha` over brick b's value range is
/// above 0 (the same span of LUT entries in the same f32 arithmetic, and
/// the rule `BrickRanges::active` applies), the ranges being (min, max) per
/// brick and channel, brick-major, as `GpuBricks::ranges` holds them. So
/// the kernel's flags; a NaN bound counts as the end it bounds (the
/// kernel's clamp may take either end), which can only add active bricks.
/// For a CPU device, where a dispatch over the bricks costs more than this
/// loop.
pub fn classify_ranges_on_host(ranges: &[f32], channels: usize, tf: &TransferFunction, flags: &mut [u32]) {
    let per_brick = 2 * channels;
    flags
        .par_chunks_mut(4096)
        .zip(ranges.par_chunks(4096 * per_brick))
        .for_each(|(flags, ranges)| {
            for (flag, r) in flags.iter_mut().zip(ranges.chunks_exact(per_brick)) {
                let visible = |c: usize| tf.channel(c).visible(r[2 * c], r[2 * c + 1]);
                *flag = (0..channels).any(visible) as u32;
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each brick's flag is its own ranges' (brick-major, two channels of
    /// their own TFs, then one, across the parallel chunks' edges): ranges
    /// on, between and beside LUT entries, empty ones (lo > hi), and NaN
    /// bounds.
    #[test]
    fn host_classification_is_max_alpha_above_zero() {
        let tf = TransferFunction::parse_channels("band:0.4:0.41 | ramp:0.9:1").unwrap();
        let mut r = 12345u64;
        let mut next = || {
            r = r.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (r >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut ranges = Vec::new();
        for _ in 0..20000 {
            let (a, b) = (next() * 1.2 - 0.1, next() * 1.2 - 0.1);
            let on_entry = |x: f32| (x * 1023.0).round() / 1023.0;
            let (a, b) = if next() < 0.3 {
                (on_entry(a), on_entry(b))
            } else {
                (a, b)
            };
            let nan = |x: f32, p: f32| if p < 0.02 { f32::NAN } else { x };
            ranges.extend([nan(a.min(b), next()), a.max(b), b, nan(a, next())]);
        }
        let mut flags = vec![7u32; ranges.len() / 4];
        classify_ranges_on_host(&ranges, 2, &tf, &mut flags);
        let mut active = 0;
        for (i, &f) in flags.iter().enumerate() {
            let r = &ranges[4 * i..4 * i + 4];
            let want = (0..2).any(|c| tf.channel(c).max_alpha(r[2 * c], r[2 * c + 1]) > 0.0);
            assert_eq!(f, want as u32, "brick {i}: ranges {r:?}");
            active += f as usize;
        }
        assert!(active > 0 && active < flags.len(), "{active} of {} active", flags.len());
        // One channel: the first channel's ranges alone.
        let first: Vec<f32> = ranges.chunks_exact(4).flat_map(|r| [r[0], r[1]]).collect();
        let band = tf.channel(0);
        classify_ranges_on_host(&first, 1, band, &mut flags);
        let mut active = 0;
        for (i, &f) in flags.iter().enumerate() {
            let want = band.max_alpha(first[2 * i], first[2 * i + 1]) > 0.0;
            assert_eq!(f, want as u32, "one channel, brick {i}");
            active += f as usize;
        }
        assert!(
            active > 0 && active < flags.len(),
            "one channel: {active} of {} active",
            flags.len()
        );
    }
}
