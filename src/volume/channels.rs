//! Several channels in one image: one texel of 1, 2 or 4 components per
//! voxel (3 channels take 4, the last one unused), every channel stored in
//! the widest type among them, so one fetch reads every channel.
//!
//! The widening keeps each channel's texel value (its value as the sampler
//! reads it, in [0, 1] for integer types): a u8 voxel `v` widens to the u16
//! `v * 257` (`v / 255 == v * 257 / 65535` exactly) or to the f32 `v / 255`,
//! so each channel's normalisation (`Volume::norm`) still applies as it is.

use super::cells::TexelKind;
use super::delta::StepDelta;
use super::{Volume, VoxelData};
use crate::gpu::vk;
use std::borrow::Cow;

/// `constant_id` of `VOLUME_CHANNELS` in `glsl/common/volume.glsl`.
pub const CHANNELS_CONSTANT_ID: u32 = 26;

/// The kind every channel of `volume` is stored as: the widest of theirs.
pub fn common_kind(volume: &Volume) -> TexelKind {
    let rank = |k: TexelKind| match k {
        TexelKind::Unorm8 => 0,
        TexelKind::Unorm16 => 1,
        TexelKind::Float32 => 2,
    };
    volume
        .channels()
        .map(|c| TexelKind::of(&c.data))
        .max_by_key(|&k| rank(k))
        .unwrap_or(TexelKind::Float32)
}

/// Components per texel for `channels` channels (Vulkan has no portable
/// three-component 3D image formats).
pub fn components(channels: usize) -> usize {
    if channels == 3 {
        4
    } else {
        channels
    }
}

/// Bytes of one texel of a volume of `channels` channels of `kind`.
pub fn texel_bytes(kind: TexelKind, channels: usize) -> u64 {
    let one = match kind {
        TexelKind::Unorm8 => 1,
        TexelKind::Unorm16 => 2,
        TexelKind::Float32 => 4,
    };
    one * components(channels) as u64
}

/// The image format of a volume of `channels` channels of `kind`.
pub fn format(kind: TexelKind, channels: usize) -> vk::Format {
    use vk::Format as F;
    match (kind, components(channels)) {
        (TexelKind::Unorm8, 1) => F::R8_UNORM,
        (TexelKind::Unorm8, 2) => F::R8G8_UNORM,
        (TexelKind::Unorm8, _) => F::R8G8B8A8_UNORM,
        (TexelKind::Unorm16, 1) => F::R16_UNORM,
        (TexelKind::Unorm16, 2) => F::R16G16_UNORM,
        (TexelKind::Unorm16, _) => F::R16G16B16A16_UNORM,
        (TexelKind::Float32, 1) => F::R32_SFLOAT,
        (TexelKind::Float32, 2) => F::R32G32_SFLOAT,
        (TexelKind::Float32, _) => F::R32G32B32A32_SFLOAT,
    }
}

/// The image's bytes: a one-channel volume's own, else every channel's
/// voxel interleaved per texel, widened to `common_kind`.
impl StepDelta {
    /// The segments whose texels differ from `before` to `after`, or None
    /// where they cannot be compared texel for texel: other dims, channels
    /// or texel kinds, or voxels streamed into bricks.
    pub fn between(before: &Volume, after: &Volume) -> Option<StepDelta> {
        let dense = |v: &Volume| v.channels().all(|c| !matches!(c.data, VoxelData::Bricks(_)));
        let comparable = before.dims == after.dims
            && before.channel_count() == after.channel_count()
            && common_kind(before) == common_kind(after)
            && dense(before)
            && dense(after);
        comparable.then(|| StepDelta::of_texels(after.dims, &texel_data(before), &texel_data(after)))?
    }
}

pub fn texel_data(volume: &Volume) -> Cow<'_, [u8]> {
    if volume.channel_count() == 1 {
        return match &volume.data {
            VoxelData::U8(v) => Cow::Borrowed(v.as_slice()),
            VoxelData::U16(v) => Cow::Borrowed(bytemuck::cast_slice(v)),
            VoxelData::F32(v) => Cow::Borrowed(bytemuck::cast_slice(v)),
            // The dense image's bytes (a streamed volume uploaded dense).
            VoxelData::Bricks(p) => {
                let mut out = Vec::with_capacity(volume.data.len() * p.layout.texel_bytes as usize);
                for i in 0..volume.data.len() {
                    out.extend_from_slice(p.texel_bytes_at(i));
                }
                Cow::Owned(out)
            }
        };
    }
    let kind = common_kind(volume);
    let per = components(volume.channel_count());
    let n = volume.data.len();
    let channels: Vec<&Volume> = volume.channels().collect();
    match kind {
        TexelKind::Unorm8 => {
            let mut out = vec![0u8; n * per];
            for (c, ch) in channels.iter().enumerate() {
                // Every channel is u8 here (a wider one widens the kind).
                for (i, x) in out.iter_mut().skip(c).step_by(per).enumerate() {
                    *x = ch.data.stored_at(i) as u8;
                }
            }
            Cow::Owned(out)
        }
        TexelKind::Unorm16 => {
            let mut out = vec![0u16; n * per];
            for (c, ch) in channels.iter().enumerate() {
                match &ch.data {
                    VoxelData::U8(v) => v
                        .iter()
                        .enumerate()
                        .for_each(|(i, &x)| out[i * per + c] = x as u16 * 257),
                    VoxelData::U16(v) => v.iter().enumerate().for_each(|(i, &x)| out[i * per + c] = x),
                    VoxelData::Bricks(p) => {
                        let widen = if p.layout.texel_bytes == 1 { 257 } else { 1 };
                        for (i, x) in out.iter_mut().skip(c).step_by(per).enumerate() {
                            *x = ch.data.stored_at(i) as u16 * widen;
                        }
                    }
                    VoxelData::F32(_) => unreachable!("a float channel makes the common kind float"),
                }
            }
            Cow::Owned(bytemuck::cast_slice(&out).to_vec())
        }
        TexelKind::Float32 => {
            let mut out = vec![0f32; n * per];
            for (c, ch) in channels.iter().enumerate() {
                for (i, x) in out.iter_mut().skip(c).step_by(per).enumerate() {
                    *x = ch.data.texel(i);
                }
            }
            Cow::Owned(bytemuck::cast_slice(&out).to_vec())
        }
    }
}

/// Channel `c`'s texel at voxel `i` as the GPU stores it (widened to
/// `kind`), for the CPU reference.
#[inline]
pub fn stored_texel(channel: &VoxelData, kind: TexelKind, i: usize) -> f32 {
    match (kind, channel) {
        (TexelKind::Unorm16, VoxelData::U8(v)) => (v[i] as u16 * 257) as f32 / 65535.0,
        _ => channel.texel(i),
    }
}
