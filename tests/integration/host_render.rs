//! The host-facing render API: cameras from view and projection matrices
//! (bit for bit the orbit cameras' images), frames written to host storage
//! images of each format (against the frame buffer), and rays ended at a
//! host depth image (against the CPU reference, and bit-identical across
//! structures). Every test runs with validation and fails on any message.

use crate::host;

use crate::common::{accel, assert_clean, gpu, max_abs};
use glam::dcamera::rh::{proj::vulkan, view::look_at_mat4};
use glam::{DMat4, DVec3, DVec4};
use lacuna::accel::{Accel, BuildInput, Builder, Params, Structure};
use lacuna::frame::Frame;
use lacuna::gpu::{vk, Context};
use lacuna::render::Mode;
use lacuna::render::Octants;
use lacuna::render::{
    reference, Camera, CameraMatrices, Filter, FrameDesc, HostDepth, HostImage, Orbit, Output, Projection,
    RenderTarget, Renderer, Scene,
};
use lacuna::tf::GpuTransferFunction;
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::{TransferFunction, Volume};

const SIZE: u32 = 48;

struct Fixture {
    volume: Volume,
    tf: TransferFunction,
    gv: GpuVolume,
    lut: GpuTransferFunction,
    renderer: Renderer,
    structures: Vec<Structure>,
    /// Last: given back to the pool after what was made on it is freed.
    ctx: crate::common::Gpu,
}

/// nbody on a non-cubic grid with anisotropic spacing; naive first, then
/// skipping structures of every traversal style.
fn fixture(names: &[&str]) -> Fixture {
    let ctx = gpu();
    let mut volume = Volume::load("nbody:40x32x24", &LoadOptions::default()).unwrap();
    volume.spacing = [1.0, 1.25, 1.5];
    let tf = TransferFunction::parse("ramp:0.3:1").unwrap();
    let gv = GpuVolume::upload(&ctx, &volume).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let builder = Builder::new(&ctx).unwrap();
    let wanted: Vec<(Accel, Params)> = names.iter().map(|n| (accel(n), accel(n).defaults())).collect();
    let reads: Vec<(Accel, &Params)> = wanted.iter().map(|(a, p)| (*a, p)).collect();
    let (ranges, _) = builder.ranges_for(&reads, &gv).unwrap();
    let input = BuildInput {
        volume: &volume,
        gpu_volume: &gv,
        tf: &tf,
        gpu_tf: &lut,
        mode: Mode::Composite,
        frames: &[],
        octants: Octants::ALL,
    };
    let structures = wanted
        .iter()
        .map(|(a, p)| builder.build(*a, &input, &ranges, p).unwrap().0)
        .collect();
    let renderer = Renderer::new(&ctx).unwrap();
    Fixture {
        ctx,
        volume,
        tf,
        gv,
        lut,
        renderer,
        structures,
    }
}

impl Fixture {
    fn scene(&self, i: usize) -> Scene<'_> {
        Scene {
            structure: &self.structures[i],
            volume: &self.gv,
            tf: &self.lut,
        }
    }

    /// Records `view` into a fresh target's frame buffer and reads it back.
    fn frame(&self, i: usize, view: &FrameDesc) -> Frame {
        let target = RenderTarget::new(&self.ctx, SIZE, SIZE).unwrap();
        self.ctx
            .submit_and_wait(|cmd| {
                self.renderer
                    .record(cmd, None, &target, self.scene(i), view, Output::Buffer)?;
                self.renderer.record_readback(cmd, &target)
            })
            .unwrap();
        assert_clean(&self.ctx);
        target.read().unwrap()
    }
}

/// A SIZE x SIZE frame of `camera`.
fn view(camera: Camera) -> FrameDesc {
    FrameDesc::builder(SIZE, SIZE).camera(camera).build().unwrap()
}

fn cameras() -> Vec<Orbit> {
    let persp = |fov_deg, distance| Projection::Perspective { fov_deg, distance };
    [
        (30.0, 20.0, Projection::Orthographic),
        (0.0, 0.0, Projection::Orthographic),
        (90.0, 0.0, persp(40.0, None)),
        (45.0, 30.0, persp(40.0, Some(2.0))),
        (-120.0, 60.0, persp(60.0, Some(0.5))),
    ]
    .into_iter()
    .map(|(azimuth_deg, elevation_deg, projection)| Orbit {
        azimuth_deg,
        elevation_deg,
        projection,
    })
    .collect()
}

fn same_bits(a: &Frame, b: &Frame) -> bool {
    a.pixels
        .iter()
        .flatten()
        .map(|v| v.to_bits())
        .eq(b.pixels.iter().flatten().map(|v| v.to_bits()))
}

/// ERT off ends a ray once its alpha is exactly 1 (`ERT_OFF`): the frame
/// is bit for bit the one no ray ends early in, on a TF opaque enough that
/// many rays saturate.
#[test]
fn ert_off_ends_only_rays_no_later_sample_can_change() {
    let volume = Volume::load("menger:27", &LoadOptions::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.1:0.3").unwrap();
    let view = FrameDesc::builder(SIZE, SIZE).build().unwrap();
    let off = view.params_for(volume.dims, volume.spacing, volume.norm).unwrap();
    assert_eq!(off.ert, lacuna::render::ERT_OFF);
    let mut never = off;
    never.ert = 2.0;
    let ended = reference::render(&volume, &tf, &off);
    let full = reference::render(&volume, &tf, &never);
    assert!(same_bits(&ended, &full), "ERT off changed the frame");
    let saturated = full.pixels.iter().filter(|p| p[3] == 1.0).count();
    assert!(saturated > 100, "only {saturated} rays reach alpha 1");
    assert!(full.pixels.iter().all(|p| p[3] <= 1.0), "alpha past 1");
}

#[test]
fn matrices_render_the_orbit_cameras_images_bit_for_bit() {
    let f = fixture(&["naive"]);
    for camera in cameras() {
        let (orbit, _) = f.renderer.render(f.scene(0), &view(Camera::Orbit(camera))).unwrap();
        let m = camera.matrices(f.gv.dims(), f.gv.spacing(), SIZE, SIZE).unwrap();
        let (host, _) = f.renderer.render(f.scene(0), &view(Camera::Matrices(m))).unwrap();
        assert!(
            orbit.pixels.iter().any(|p| p[3] > 0.1),
            "{camera:?}: the volume is in view"
        );
        assert!(
            same_bits(&orbit, &host),
            "{camera:?}: max abs {}",
            max_abs(&orbit, &host)
        );
    }
    assert_clean(&f.ctx);
}

#[test]
fn glam_matrices_of_an_engine_render_the_orbit_image() {
    // The orbit camera at azimuth 0, elevation 0, as an engine would write
    // it with glam's right-handed look_at and Vulkan projections.
    let f = fixture(&["naive"]);
    let extent = DVec3::new(40.0, 32.0 * 1.25, 24.0 * 1.5);
    let centre = extent * 0.5;
    let radius = centre.length();
    let pixel = (2.0 * centre.x / SIZE as f64).max(2.0 * centre.y / SIZE as f64);
    let half = pixel * SIZE as f64 / 2.0;
    let eye = centre + DVec3::Z * (radius + 1.0);
    let ortho = CameraMatrices::new(
        look_at_mat4(eye, centre, DVec3::Y),
        vulkan::orthographic(-half, half, -half, half, 0.0, 2.0 * (radius + 1.0)),
    );
    let fov = 40f64.to_radians();
    let dist = radius / (fov / 2.0).sin();
    let eye = centre + DVec3::Z * dist;
    let persp = CameraMatrices::new(
        look_at_mat4(eye, centre, DVec3::Y),
        vulkan::perspective(fov, 1.0, 0.05, 1000.0),
    );
    for (m, projection) in [
        (ortho, Projection::Orthographic),
        (
            persp,
            Projection::Perspective {
                fov_deg: 40.0,
                distance: None,
            },
        ),
    ] {
        let camera = Orbit {
            azimuth_deg: 0.0,
            elevation_deg: 0.0,
            projection,
        };
        let (orbit, _) = f.renderer.render(f.scene(0), &view(Camera::Orbit(camera))).unwrap();
        let (host, _) = f.renderer.render(f.scene(0), &view(Camera::Matrices(m))).unwrap();
        assert!(
            same_bits(&orbit, &host),
            "{projection:?}: max abs {}",
            max_abs(&orbit, &host)
        );
    }
    assert_clean(&f.ctx);
}

/// Renders `view` into a host storage image of `format` and reads it back as
/// raw bytes.
fn render_to_image(f: &Fixture, i: usize, view: &FrameDesc, format: vk::Format, texel: u64) -> Vec<u8> {
    let (instance, pd, device) = (f.ctx.instance(), f.ctx.physical_device(), f.ctx.device());
    let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    let image = host::Image2d::new(
        instance,
        pd,
        device,
        format,
        usage,
        vk::ImageAspectFlags::COLOR,
        SIZE,
        SIZE,
    );
    let out = host::HostBuffer::new(
        instance,
        pd,
        device,
        SIZE as u64 * SIZE as u64 * texel,
        vk::BufferUsageFlags::TRANSFER_DST,
    );
    let target = RenderTarget::for_images(&f.ctx, SIZE, SIZE).unwrap();
    let host_image = unsafe { HostImage::new(image.view, format, vk::ImageLayout::GENERAL, SIZE, SIZE) };
    let compute_write = (
        vk::PipelineStageFlags2::COMPUTE_SHADER,
        vk::AccessFlags2::SHADER_STORAGE_WRITE,
    );
    f.ctx
        .submit_and_wait(|cmd| {
            image.transition(
                device,
                cmd.raw(),
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::GENERAL,
                (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
                compute_write,
            );
            f.renderer
                .record(cmd, None, &target, f.scene(i), view, Output::Image(host_image))?;
            image.transition(
                device,
                cmd.raw(),
                vk::ImageLayout::GENERAL,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                compute_write,
                (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_READ),
            );
            image.record_copy_out(device, cmd.raw(), out.buffer);
            Ok(())
        })
        .unwrap();
    assert_clean(&f.ctx);
    let bytes = out.bytes().to_vec();
    out.destroy(device);
    image.destroy(device);
    bytes
}

#[test]
fn host_images_of_each_format_hold_the_frame_buffers_pixels() {
    let f = fixture(&["naive", "grid", "lbvh"]);
    let camera = cameras()[3];
    let m = camera.matrices(f.gv.dims(), f.gv.spacing(), SIZE, SIZE).unwrap();
    let view = view(Camera::Matrices(m)).to_builder().step(0.7).build().unwrap();
    let frame = f.frame(0, &view);
    let values: Vec<f32> = frame.pixels.iter().flatten().copied().collect();
    assert!(values.iter().any(|&v| v > 0.1));
    for i in 0..f.structures.len() {
        let f32s: Vec<f32> =
            bytemuck::pod_collect_to_vec(&render_to_image(&f, i, &view, vk::Format::R32G32B32A32_SFLOAT, 16));
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&f32s), bits(&values), "rgba32f, structure {i}");
    }
    let halves: Vec<u16> =
        bytemuck::pod_collect_to_vec(&render_to_image(&f, 0, &view, vk::Format::R16G16B16A16_SFLOAT, 8));
    for (&h, &v) in halves.iter().zip(&values) {
        let h = half::f16::from_bits(h);
        // Vulkan allows either rounding of f32 to f16: one f16 step apart at most.
        let want = half::f16::from_f32(v);
        assert!(
            (h.to_bits() as i32 - want.to_bits() as i32).abs() <= 1,
            "rgba16f: {h} for {v}"
        );
    }
    let bytes = render_to_image(&f, 0, &view, vk::Format::R8G8B8A8_UNORM, 4);
    for (&b, &v) in bytes.iter().zip(&values) {
        let want = (v.clamp(0.0, 1.0) * 255.0).round();
        assert!((b as f32 - want).abs() <= 1.0, "rgba8: {b} for {v}");
    }
}

#[test]
fn prepare_makes_the_kernel_a_host_image_frame_records_so_recording_compiles_nothing() {
    let f = fixture(&["naive", "lbvh"]);
    let m = cameras()[1].matrices(f.gv.dims(), f.gv.spacing(), SIZE, SIZE).unwrap();
    let view = view(Camera::Matrices(m)).to_builder().step(0.6).build().unwrap();
    for (format, texel) in [
        (vk::Format::R8G8B8A8_UNORM, 4),
        (vk::Format::R16G16B16A16_SFLOAT, 8),
        (vk::Format::R32G32B32A32_SFLOAT, 16),
    ] {
        for i in 0..f.structures.len() {
            // Only the view's format matters to the kernel, not the view.
            let like = unsafe { HostImage::new(vk::ImageView::null(), format, vk::ImageLayout::GENERAL, SIZE, SIZE) };
            f.renderer.prepare(f.scene(i), &view, Output::Image(like)).unwrap();
            let made = f.ctx.kernels_created();
            // Cutting a frame into bands reads the kernel's workgroup size
            // without creating a kernel.
            let bands = f.renderer.bands(f.scene(i), &view, 1).unwrap();
            assert_eq!(bands.len(), SIZE.div_ceil(8) as usize, "one workgroup row a band");
            let pixels = render_to_image(&f, i, &view, format, texel);
            assert!(
                pixels.iter().any(|&b| b != 0),
                "{format:?}, structure {i}: an empty frame"
            );
            assert_eq!(
                f.ctx.kernels_created(),
                made,
                "{format:?}, structure {i}: recording compiled a kernel"
            );
        }
    }
    let bad = unsafe {
        HostImage::new(
            vk::ImageView::null(),
            vk::Format::B8G8R8A8_UNORM,
            vk::ImageLayout::GENERAL,
            SIZE,
            SIZE,
        )
    };
    let err = f.renderer.prepare(f.scene(0), &view, Output::Image(bad)).unwrap_err();
    assert!(err.to_string().contains("B8G8R8A8_UNORM"), "{err}");
    assert_clean(&f.ctx);
}

#[test]
fn a_target_for_host_images_takes_sizes_whose_frame_buffer_would_pass_the_storage_range() {
    let ctx = gpu();
    let range = ctx.info().max_storage_buffer_range;
    // A frame buffer holds 16 bytes a pixel; a host image target's largest
    // buffer, the rays' parameters, 4.
    let side = ((range / 16) as f64).sqrt() as u32 + 1;
    let err = RenderTarget::new(&ctx, side, side)
        .err()
        .expect("a frame buffer past the range");
    assert!(err.to_string().contains("maxStorageBufferRange"), "{err}");
    RenderTarget::for_images(&ctx, side, side).unwrap();
    let side = ((range / 4) as f64).sqrt() as u32 + 1;
    let err = RenderTarget::for_images(&ctx, side, side)
        .err()
        .expect("parameters past the range");
    assert!(err.to_string().contains("ray parameters"), "{err}");
    assert_clean(&ctx);
}

#[test]
fn a_host_image_of_another_format_or_size_is_refused_by_name() {
    let f = fixture(&["naive"]);
    let m = cameras()[0].matrices(f.gv.dims(), f.gv.spacing(), SIZE, SIZE).unwrap();
    let view = view(Camera::Matrices(m));
    let target = RenderTarget::for_images(&f.ctx, SIZE, SIZE).unwrap();
    let image =
        |format, width| unsafe { HostImage::new(vk::ImageView::null(), format, vk::ImageLayout::GENERAL, width, SIZE) };
    for (img, needle) in [
        (image(vk::Format::B8G8R8A8_UNORM, SIZE), "B8G8R8A8_UNORM"),
        (image(vk::Format::R8G8B8A8_UNORM, SIZE + 1), "49x48"),
    ] {
        let err = f
            .ctx
            .submit_and_wait(|cmd| {
                f.renderer
                    .record(cmd, None, &target, f.scene(0), &view, Output::Image(img))
            })
            .unwrap_err();
        assert!(err.to_string().contains(needle), "{err}");
    }
    // A target for images has no frame buffer to write or read back.
    let err = f
        .ctx
        .submit_and_wait(|cmd| f.renderer.record(cmd, None, &target, f.scene(0), &view, Output::Buffer))
        .unwrap_err();
    assert!(err.to_string().contains("no frame buffer"), "{err}");
    assert!(target.read().is_err());
    assert_clean(&f.ctx);
}

/// A host depth image cleared to `depth` everywhere, in DEPTH_READ_ONLY_OPTIMAL.
fn depth_plane(ctx: &Context, depth: f32) -> host::Image2d {
    let (instance, pd, device) = (ctx.instance(), ctx.physical_device(), ctx.device());
    let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let image = host::Image2d::new(
        instance,
        pd,
        device,
        vk::Format::D32_SFLOAT,
        usage,
        vk::ImageAspectFlags::DEPTH,
        SIZE,
        SIZE,
    );
    let transfer = (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
    ctx.submit_and_wait(|cmd| {
        image.transition(
            device,
            cmd.raw(),
            vk::ImageLayout::UNDEFINED,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
            transfer,
        );
        let value = vk::ClearDepthStencilValue { depth, stencil: 0 };
        let range = [host::range(vk::ImageAspectFlags::DEPTH)];
        unsafe {
            device.cmd_clear_depth_stencil_image(
                cmd.raw(),
                image.image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &value,
                &range,
            )
        };
        image.transition(
            device,
            cmd.raw(),
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL,
            transfer,
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_SAMPLED_READ,
            ),
        );
        Ok(())
    })
    .unwrap();
    image
}

#[test]
fn rays_end_at_a_host_depth_plane_as_the_cpu_reference_says() {
    let names = ["naive", "grid", "lbvh", "distance", "kd-cpu", "octree-rev"];
    let f = fixture(&names);
    // Reverse-Z: clip z' = w - z.
    let reverse = DMat4::from_cols(
        DVec4::X,
        DVec4::Y,
        DVec4::new(0.0, 0.0, -1.0, 0.0),
        DVec4::new(0.0, 0.0, 1.0, 1.0),
    );
    for (camera, reverse_z, depth) in [(cameras()[0], false, 0.5f32), (cameras()[3], true, 0.9985)] {
        let mut m = camera.matrices(f.gv.dims(), f.gv.spacing(), SIZE, SIZE).unwrap();
        if reverse_z {
            m.projection = reverse * m.projection;
            m = m.with_reverse_z(true);
        }
        // The CPU reference's arithmetic: the manual filter.
        let view = FrameDesc::builder(SIZE, SIZE)
            .camera(Camera::Matrices(m))
            .filter(Filter::Manual)
            .build()
            .unwrap();
        let plane = depth_plane(&f.ctx, depth);
        let host_depth = unsafe { HostDepth::new(plane.view, vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL, SIZE, SIZE) };
        let with = |d: HostDepth| view.to_builder().depth(Some(d)).build().unwrap();
        let ended = f.frame(0, &with(host_depth));
        let full = f.frame(0, &view);
        // The plane cuts the volume: some pixels lose much of their opacity.
        let cut = full.pixels.iter().zip(&ended.pixels).any(|(a, b)| a[3] - b[3] > 0.2);
        assert!(cut, "{camera:?}: the depth plane ends rays inside the volume");
        let params = with(host_depth).params(&f.gv).unwrap();
        let limits = reference::depth_limits(&params, &vec![depth; (SIZE * SIZE) as usize]);
        let cpu = reference::render_to(&f.volume, &f.tf, &params, Some(&limits));
        let err = max_abs(&cpu, &ended);
        assert!(
            err <= 1e-4,
            "{camera:?}: GPU vs CPU reference with a depth plane: {err}"
        );
        for (i, name) in names.iter().enumerate().skip(1) {
            let other = f.frame(i, &with(host_depth));
            assert!(
                same_bits(&ended, &other),
                "{name} vs naive with depth: {}",
                max_abs(&ended, &other)
            );
        }
        plane.destroy(f.ctx.device());
        // Nothing drawn (the far plane's depth everywhere) ends no ray.
        let far = depth_plane(&f.ctx, if reverse_z { 0.0 } else { 1.0 });
        let open = unsafe { HostDepth::new(far.view, vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL, SIZE, SIZE) };
        assert!(same_bits(&full, &f.frame(0, &with(open))));
        far.destroy(f.ctx.device());
    }
    assert_clean(&f.ctx);
}

#[test]
fn frame_descriptions_refuse_bad_values_by_name_and_fill_the_block() {
    let f = fixture(&["naive"]);
    let m = cameras()[0].matrices(f.gv.dims(), f.gv.spacing(), SIZE, SIZE).unwrap();
    let frame = || FrameDesc::builder(SIZE, SIZE).camera(Camera::Matrices(m));
    let refused = |b: lacuna::render::FrameBuilder, needle: &str| {
        let err = b.build().unwrap_err().to_string();
        assert!(err.contains(needle), "{needle}: {err}");
    };
    refused(frame().step(0.0), "step");
    refused(frame().step(f32::NAN), "step");
    refused(frame().ert(Some(1.5)), "ert");
    refused(frame().size(0, SIZE), "size");
    refused(
        frame().camera(Camera::Matrices(CameraMatrices::new(DMat4::ZERO, m.projection))),
        "view matrix",
    );
    refused(
        frame().orbit(f64::INFINITY, 0.0, Projection::Orthographic),
        "azimuth must be in [-360, 360]",
    );
    refused(
        frame().orbit(
            0.0,
            0.0,
            Projection::Perspective {
                fov_deg: 180.0,
                distance: None,
            },
        ),
        "field of view",
    );
    let depth = unsafe {
        HostDepth::new(
            vk::ImageView::null(),
            vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL,
            SIZE + 1,
            SIZE,
        )
    };
    refused(frame().depth(Some(depth)), "host depth");
    refused(
        frame().depth(Some(unsafe {
            HostDepth::new(vk::ImageView::null(), vk::ImageLayout::UNDEFINED, SIZE, SIZE)
        })),
        "host depth layout",
    );
    // Each field lands where the shader reads it; defaults are the one set.
    let p = frame()
        .step(0.25)
        .ert(Some(0.9))
        .build()
        .unwrap()
        .params(&f.gv)
        .unwrap();
    assert_eq!((p.step, p.ert, p.image, p.dims), (0.25, 0.9, [SIZE, SIZE], f.gv.dims()));
    assert_eq!(
        (p.norm, p.lut_size, p.depth_limits),
        (f.gv.norm(), lacuna::tf::LUT_SIZE as u32, 0)
    );
    let d = frame().build().unwrap();
    assert_eq!(
        (d.step(), d.ert(), d.filter()),
        (lacuna::render::DEFAULT_STEP, None, None)
    );
    assert_eq!(d.filter_for(&f.gv), f.gv.default_filter());
    assert_eq!(d.params(&f.gv).unwrap().ert, lacuna::render::ERT_OFF);
    // A step over the samples-per-ray cap is refused for the volume it meets.
    let fine = frame().step(1e-6).build().unwrap();
    assert!(fine.params(&f.gv).unwrap_err().to_string().contains("samples per ray"));
}
