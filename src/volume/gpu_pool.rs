//! The brick pool's device side: its plan against the device's limits,
//! its images' texels and its brick table.

use super::pool::{BrickBox, PoolLayout, PoolLimits};
use super::Volume;
use crate::error::Result;
use crate::gpu::{check_image3d_of, vk, Buffer, Context, TexelBuffer};

/// The pool of `volume`'s texels (`bytes`, `texel` bytes each), after its
/// image, allocation, heap and host memory checks.
pub(super) fn plan_pool(
    ctx: &Context,
    volume: &Volume,
    (texel, bytes): (u64, &[u8]),
    edge: u32,
    limits: PoolLimits,
    keep: Option<BrickBox>,
) -> Result<PoolLayout> {
    let device = PoolLimits::of(ctx.info());
    let limits = PoolLimits {
        max_image_dim: limits.max_image_dim.min(device.max_image_dim),
        max_image_bytes: limits.max_image_bytes.min(device.max_image_bytes),
        max_table_entries: limits.max_table_entries.min(device.max_table_entries),
    };
    let layout = PoolLayout::plan_kept(bytes, volume.dims, texel, edge, limits, keep)?;
    check_pool(ctx, volume, &layout)?;
    Ok(layout)
}

/// The pool's images against the device's image limits, and all of them
/// with the table against the device-local heap.
pub(super) fn check_pool(ctx: &Context, volume: &Volume, layout: &PoolLayout) -> Result<()> {
    let texel = layout.texel_bytes;
    let info = ctx.info();
    if info.device_local_bytes > 0 {
        let total = layout.pool_bytes() + layout.table_bytes();
        info.check(
            format!("brick pool of {} ({total} bytes)", volume.name),
            "device-local heap size",
            total,
            info.device_local_bytes,
        )?;
    }
    for k in 0..layout.images.len() {
        let what = format!("brick pool image {k} of {}", volume.name);
        check_image3d_of(ctx.info(), &what, layout.extent(k), texel)?;
    }
    Ok(())
}

/// Pool image `k`'s texels, after the host memory check.
pub(super) fn pool_image_texels(layout: &PoolLayout, k: usize, bytes: &[u8]) -> Result<Vec<u8>> {
    let mut pool = crate::limits::zeroed::<u8>(format_args!("brick pool image {k}"), layout.image_bytes(k))?;
    layout.fill(k, bytes, &mut pool);
    Ok(pool)
}

pub(super) const BRICK_TABLE_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
pub(super) const BRICK_TABLE_FORMAT: vk::Format = vk::Format::R32G32_UINT;

/// A pool's brick table in device memory, uploaded and waited for.
pub(super) fn brick_table(ctx: &Context, layout: &PoolLayout) -> Result<TexelBuffer> {
    let table = Buffer::with_data(
        ctx,
        "brick table",
        bytemuck::cast_slice(&layout.table),
        BRICK_TABLE_USAGE,
    )?;
    TexelBuffer::new(ctx, table, BRICK_TABLE_FORMAT)
}
