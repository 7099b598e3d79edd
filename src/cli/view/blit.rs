//! The viewer's present step: its canvas blitted into a swapchain image.

use lacuna::gpu::record::Access;
use lacuna::gpu::{vk, Recording};

/// Records the blit of the canvas image (of `canvas.1`, in
/// TRANSFER_SRC_OPTIMAL) into the swapchain image `target` of `extent`,
/// scaled, leaving it in PRESENT_SRC_KHR.
///
/// # Safety
/// `target` is a live swapchain image of `rec`'s device, of `extent`, whose
/// contents may be discarded; the canvas is a live image of that device.
pub unsafe fn record_to_swapchain(
    device: &ash::Device,
    rec: Recording<'_>,
    canvas: (vk::Image, vk::Extent2D),
    target: vk::Image,
    extent: vk::Extent2D,
) {
    // The acquire semaphore is waited on at the transfer stage, where the
    // image's transition starts.
    // SAFETY: no access at the transfer stage, which every device has.
    let transfer = unsafe { Access::new(vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::NONE) };
    // SAFETY: the acquired swapchain image (one level and layer); its
    // old contents are not needed.
    unsafe {
        rec.image_barrier(
            target,
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            transfer,
            Access::TRANSFER_WRITE,
        )
    };
    let (c, s) = (canvas.1, extent);
    let corner = |e: vk::Extent2D| vk::Offset3D {
        x: e.width as i32,
        y: e.height as i32,
        z: 1,
    };
    let layers = vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        mip_level: 0,
        base_array_layer: 0,
        layer_count: 1,
    };
    let blit = [vk::ImageBlit {
        src_subresource: layers,
        src_offsets: [vk::Offset3D::default(), corner(c)],
        dst_subresource: layers,
        dst_offsets: [vk::Offset3D::default(), corner(s)],
    }];
    unsafe {
        device.cmd_blit_image(
            rec.raw(),
            canvas.0,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            target,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &blit,
            vk::Filter::NEAREST,
        )
    };
    // SAFETY: the same image, in TRANSFER_DST_OPTIMAL since the blit.
    unsafe {
        rec.image_barrier(
            target,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::PRESENT_SRC_KHR,
            Access::TRANSFER_WRITE,
            Access::NONE,
        )
    };
}
