//! Iso surfaces' depth written where a host asks (`Output::ImageAndDepth`):
//! NDC depth in the host camera's convention, equal to the CPU reference's
//! for every structure, the far depth where a ray hits nothing and in every
//! other mode; a host buffer too small or misaligned is refused by name.

use crate::host;

use crate::common::{accel, assert_clean, gpu};
use lacuna::accel::{BuildInput, Builder, Structure};
use lacuna::gpu::{vk, Context};
use lacuna::render::Octants;
use lacuna::render::{
    reference, Camera, Filter, FrameDesc, HostDepthOut, HostImage, Iso, Mode, Orbit, Output, Projection, RenderTarget,
    Renderer, Scene,
};
use lacuna::volume::GpuVolume;
use lacuna::{TransferFunction, Volume};

const SIZE: u32 = 40;

struct Host {
    image: host::Image2d,
    depth: host::HostBuffer,
}

impl Host {
    fn new(ctx: &Context) -> Host {
        let (instance, pd, device) = (ctx.instance(), ctx.physical_device(), ctx.device());
        let image = host::Image2d::new(
            instance,
            pd,
            device,
            vk::Format::R32G32B32A32_SFLOAT,
            vk::ImageUsageFlags::STORAGE,
            vk::ImageAspectFlags::COLOR,
            SIZE,
            SIZE,
        );
        let depth = host::HostBuffer::new(
            instance,
            pd,
            device,
            SIZE as u64 * SIZE as u64 * 4,
            vk::BufferUsageFlags::STORAGE_BUFFER,
        );
        Host { image, depth }
    }

    fn output(&self, size: u64, offset: u64) -> Output {
        let image = unsafe {
            HostImage::new(
                self.image.view,
                vk::Format::R32G32B32A32_SFLOAT,
                vk::ImageLayout::GENERAL,
                SIZE,
                SIZE,
            )
        };
        let depth = unsafe { HostDepthOut::new(self.depth.buffer, offset, size) };
        Output::ImageAndDepth(image, depth)
    }

    /// Records `desc` of `structure` into the host image and depth buffer;
    /// returns the depth.
    fn render(&self, ctx: &Context, renderer: &Renderer, scene: Scene, desc: &FrameDesc) -> lacuna::Result<Vec<f32>> {
        let target = RenderTarget::for_images(ctx, SIZE, SIZE)?;
        let device = ctx.device();
        let compute_write = (
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_STORAGE_WRITE,
        );
        ctx.submit_and_wait(|cmd| {
            self.image.transition(
                device,
                cmd.raw(),
                vk::ImageLayout::UNDEFINED,
                vk::ImageLayout::GENERAL,
                (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE),
                compute_write,
            );
            renderer.record(
                cmd,
                None,
                &target,
                scene,
                desc,
                self.output(SIZE as u64 * SIZE as u64 * 4, 0),
            )?;
            cmd.barrier(
                lacuna::gpu::record::Access::COMPUTE_WRITE,
                lacuna::gpu::record::Access::HOST_READ,
            );
            Ok(())
        })?;
        Ok(bytemuck::pod_collect_to_vec(self.depth.bytes()))
    }

    fn destroy(&self, ctx: &Context) {
        self.image.destroy(ctx.device());
        self.depth.destroy(ctx.device());
    }
}

#[test]
fn iso_depth_in_the_host_buffer_is_the_references_ndc_depth_for_every_structure() {
    let ctx = gpu();
    let renderer = Renderer::new(&ctx).unwrap();
    let builder = Builder::new(&ctx).unwrap();
    let mut volume = Volume::load("shells:36x32x28", &Default::default()).unwrap();
    volume.spacing = [1.0, 1.25, 0.8];
    let tf = TransferFunction::parse(volume.default_tf.as_ref().unwrap()).unwrap();
    let mut gv = GpuVolume::upload(&ctx, &volume).unwrap();
    gv.add_gradient(&volume).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let iso = Mode::Iso(Iso::new(&[0.5]).unwrap());
    let host = Host::new(&ctx);
    let orbit = Orbit {
        azimuth_deg: 35.0,
        elevation_deg: 20.0,
        projection: Projection::Perspective {
            fov_deg: 45.0,
            distance: None,
        },
    };
    let m = orbit.matrices(gv.dims(), gv.spacing(), SIZE, SIZE).unwrap();
    let desc = FrameDesc::builder(SIZE, SIZE)
        .camera(Camera::Matrices(m))
        .filter(Filter::Manual)
        .mode(iso)
        .build()
        .unwrap();
    let cpu = reference::render_frame(&volume, &tf, &desc).unwrap();
    let want = cpu.depth.unwrap();
    let far = if m.reverse_z { 0.0 } else { 1.0 };
    assert!(want.iter().any(|&d| d != far) && want.contains(&far));
    for name in ["naive", "grid", "lbvh", "distance"] {
        let a = accel(name);
        let (ranges, _) = builder.ranges_for(&[(a, &a.defaults())], &gv).unwrap();
        let input = BuildInput {
            volume: &volume,
            gpu_volume: &gv,
            tf: &tf,
            gpu_tf: &lut,
            mode: iso,
            frames: &[],
            octants: Octants::ALL,
        };
        let s = builder.build(a, &input, &ranges, &a.defaults()).unwrap().0;
        let scene = Scene {
            structure: &s,
            volume: &gv,
            tf: &lut,
        };
        let got = host.render(&ctx, &renderer, scene, &desc).unwrap();
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            assert!(
                g == w || ((g - w).abs() <= 1e-5 && *w != far),
                "{name}, pixel {i}: depth {g}, reference {w}"
            );
            assert!(*g > -1.0 && *g <= 1.0 || *g == far, "{name}: {g} is not an NDC depth");
        }
    }
    // Every other mode writes the far depth: nothing opaque.
    let composite = desc.to_builder().mode(Mode::Composite).build().unwrap();
    let naive = Structure::naive();
    let scene = Scene {
        structure: &naive,
        volume: &gv,
        tf: &lut,
    };
    let got = host.render(&ctx, &renderer, scene, &composite).unwrap();
    assert!(got.iter().all(|&d| d == far));
    assert_clean(&ctx);
    host.destroy(&ctx);
}

#[test]
fn a_host_depth_buffer_too_small_or_misaligned_is_refused() {
    let ctx = gpu();
    let renderer = Renderer::new(&ctx).unwrap();
    let volume = Volume::load("shells:16", &Default::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0:1").unwrap();
    let gv = GpuVolume::upload(&ctx, &volume).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let host = Host::new(&ctx);
    let naive = Structure::naive();
    let scene = Scene {
        structure: &naive,
        volume: &gv,
        tf: &lut,
    };
    let desc = FrameDesc::builder(SIZE, SIZE).build().unwrap();
    let target = RenderTarget::for_images(&ctx, SIZE, SIZE).unwrap();
    let align = ctx.info().min_storage_buffer_offset_alignment;
    for (size, offset, needle) in [
        (SIZE as u64 * SIZE as u64 * 4 - 4, 0, "needs 6400"),
        (
            SIZE as u64 * SIZE as u64 * 4,
            align + 1,
            "minStorageBufferOffsetAlignment",
        ),
    ] {
        let err = ctx
            .submit_and_wait(|cmd| renderer.record(cmd, None, &target, scene, &desc, host.output(size, offset)))
            .unwrap_err();
        assert!(err.to_string().contains(needle), "{err}");
    }
    assert_clean(&ctx);
    host.destroy(&ctx);
}
