//! A small host engine: its own instance, device, queue and command pool; it
//! rasterizes an opaque cube with a depth buffer, then records lacuna's
//! uploads, ranges, structure build and volume render into the SAME command
//! buffer (lacuna submits nothing), the volume
//! written to the engine's storage image and its rays ended at the cube's
//! depth. The engine composites the volume over the cube on the CPU.

use super::host::{HostBuffer, Image2d};
use lacuna::accel::{Accel, BuildInput, Builder, Ranges, Structure};
use lacuna::ash::{self, vk};
use lacuna::frame::Frame;
use lacuna::glam::{DVec3, Vec4};
use lacuna::gpu::{
    record, required_features, AdoptInfo, Context, EnabledFeatures, Recording, Staging, Timer, REQUIRED_EXTENSIONS,
};
use lacuna::render::Mode;
use lacuna::render::Octants;
use lacuna::render::{
    Camera, Filter, FrameDesc, HostDepth, HostImage, Orbit, Output, Projection, RenderTarget, Renderer, Scene,
};
use lacuna::tf::GpuTransferFunction;
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::Timings;
use lacuna::{TransferFunction, Volume};

mod shaders {
    include!(concat!(env!("OUT_DIR"), "/example_shaders.rs"));
}

/// What to draw.
pub struct Settings {
    pub size: u32,
    pub volume: String,
    pub tf: Option<String>,
    pub accel: String,
    pub camera: Orbit,
    /// Validation layer with synchronization validation on the engine's instance.
    pub validate: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            size: 128,
            volume: "menger:64".into(),
            tf: None,
            accel: "grid".into(),
            camera: Orbit {
                azimuth_deg: 30.0,
                elevation_deg: 20.0,
                projection: Projection::Perspective {
                    fov_deg: 40.0,
                    distance: Some(2.5),
                },
            },
            validate: false,
        }
    }
}

/// The engine's frame and its layers.
pub struct Rendered {
    /// The volume composited over the cube (premultiplied RGBA).
    pub composite: Frame,
    /// lacuna's layer as it wrote the engine's storage image.
    pub volume: Frame,
    /// The cube alone (alpha 1 where drawn).
    pub mesh: Frame,
    /// The cube's depth buffer (1.0 where nothing was drawn).
    pub depth: Vec<f32>,
    /// lacuna's GPU timings of the recorded build and march.
    pub timings: Timings,
    /// Validation messages (with `validate`).
    pub validation: Vec<String>,
    /// Command buffers lacuna submitted on the engine's queue: none, as it
    /// only records (`Context::submissions`).
    pub lacuna_submissions: u64,
}

struct Device {
    entry: ash::Entry,
    instance: ash::Instance,
    pd: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    family: u32,
    enabled: EnabledFeatures,
}

fn create_device(validate: bool) -> Result<Device, String> {
    let entry = unsafe { ash::Entry::load() }.map_err(|e| format!("no Vulkan loader: {e}"))?;
    let api_version = vk::API_VERSION_1_3;
    let app = vk::ApplicationInfo::default().api_version(api_version);
    let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
    let exts = [ash::ext::debug_utils::NAME.as_ptr()];
    let sync = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync);
    let mut info = vk::InstanceCreateInfo::default().application_info(&app);
    if validate {
        info = info
            .enabled_layer_names(&layers)
            .enabled_extension_names(&exts)
            .push_next(&mut features);
    }
    let instance = unsafe { entry.create_instance(&info, None) }.map_err(|e| format!("vkCreateInstance: {e}"))?;
    let pds = unsafe { instance.enumerate_physical_devices() }.map_err(|e| e.to_string())?;
    // The first device with a graphics + compute queue (lavapipe here).
    let found = pds.iter().find_map(|&pd| {
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let want = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
        families
            .iter()
            .position(|f| f.queue_flags.contains(want))
            .map(|i| (pd, i as u32))
    });
    let Some((pd, family)) = found else {
        unsafe { instance.destroy_instance(None) };
        return Err("no Vulkan device with a graphics and compute queue".into());
    };
    // lacuna's needs plus the engine's own (dynamic rendering).
    let (v12, v13) = required_features();
    let v13 = v13.dynamic_rendering(true);
    let (mut c12, mut c13) = (v12, v13);
    let dev_exts = REQUIRED_EXTENSIONS.map(|e| e.as_ptr());
    let prio = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&prio)];
    let dinfo = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&dev_exts)
        .push_next(&mut c13)
        .push_next(&mut c12);
    let device = match unsafe { instance.create_device(pd, &dinfo, None) } {
        Ok(d) => d,
        Err(e) => {
            unsafe { instance.destroy_instance(None) };
            return Err(format!("vkCreateDevice: {e}"));
        }
    };
    let queue = unsafe { device.get_device_queue(family, 0) };
    let enabled = EnabledFeatures {
        api_version,
        extensions: REQUIRED_EXTENSIONS.iter().map(|e| (*e).to_owned()).collect(),
        vulkan12: v12,
        vulkan13: v13,
    };
    Ok(Device {
        entry,
        instance,
        pd,
        device,
        queue,
        family,
        enabled,
    })
}

const COLOUR: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const DEPTH: vk::Format = vk::Format::D32_SFLOAT;

/// The cube's pipeline (dynamic rendering, depth test and write).
fn mesh_pipeline(device: &ash::Device, size: u32) -> (vk::Pipeline, vk::PipelineLayout, [vk::ShaderModule; 2]) {
    unsafe {
        let module = |words: &[u32]| {
            device
                .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(words), None)
                .unwrap()
        };
        let modules = [module(&shaders::MESH_VERT), module(&shaders::MESH_FRAG)];
        let ranges = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::VERTEX,
            offset: 0,
            size: 80,
        }];
        let layout = device
            .create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&ranges),
                None,
            )
            .unwrap();
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(modules[0])
                .name(c"main"),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(modules[1])
                .name(c"main"),
        ];
        let vertex = vk::PipelineVertexInputStateCreateInfo::default();
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewports = [vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: size as f32,
            height: size as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        }];
        let scissors = [vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D {
                width: size,
                height: size,
            },
        }];
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewports(&viewports)
            .scissors(&scissors);
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::NONE)
            .line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(vk::CompareOp::LESS);
        let attachments =
            [vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA)];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let formats = [COLOUR];
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&formats)
            .depth_attachment_format(DEPTH);
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .layout(layout)
            .push_next(&mut rendering)];
        let pipeline = device
            .create_graphics_pipelines(vk::PipelineCache::null(), &info, None)
            .map_err(|(_, e)| e)
            .unwrap()[0];
        (pipeline, layout, modules)
    }
}

type Access = (vk::PipelineStageFlags2, vk::AccessFlags2);
const NOTHING: Access = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);
const TRANSFER_READ: Access = (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_READ);

/// Renders one frame as described in the module documentation.
pub fn run(settings: &Settings) -> Result<Rendered, String> {
    let host = create_device(settings.validate)?;
    let result = frame(&host, settings);
    unsafe {
        host.device.destroy_device(None);
        host.instance.destroy_instance(None);
    }
    result
}

fn frame(host: &Device, settings: &Settings) -> Result<Rendered, String> {
    let (instance, pd, device) = (&host.instance, host.pd, &host.device);
    let size = settings.size;
    // SAFETY: the handles were created above with what `enabled` says and
    // outlive the context (dropped at the end of this function); lacuna only
    // records here, so it never submits on the engine's queue (the test
    // checks `Context::submissions`), and the engine submits lacuna's
    // commands to a queue of `host.family`, the family adopted.
    let ctx = unsafe {
        Context::adopt(AdoptInfo {
            entry: settings.validate.then(|| host.entry.clone()),
            instance: instance.clone(),
            physical_device: pd,
            device: device.clone(),
            queue: host.queue,
            queue_family: host.family,
            enabled: host.enabled.clone(),
        })
    }
    .map_err(|e| e.to_string())?;
    let err = |e: lacuna::Error| e.to_string();
    let volume = Volume::load(&settings.volume, &LoadOptions::default()).map_err(err)?;
    let tf_spec = settings
        .tf
        .clone()
        .or(volume.default_tf.clone())
        .unwrap_or_else(|| "ramp:0.3:1".into());
    let tf = TransferFunction::parse(&tf_spec).map_err(err)?;
    let builder = Builder::new(&ctx).map_err(err)?;
    let accel: Accel = settings.accel.parse().map_err(err)?;
    let params = accel.defaults();
    let renderer = Renderer::new(&ctx).map_err(err)?;
    let target = RenderTarget::for_images(&ctx, size, size).map_err(err)?;
    let mut timer = Timer::new(&ctx, 16).map_err(err)?;

    // The camera: lacuna's orbit camera as the engine's view and projection.
    let m = settings
        .camera
        .matrices(volume.dims, volume.spacing, size, size)
        .map_err(err)?;
    let clip_from_world = (m.projection * m.view).as_mat4();
    // The cube: between the eye and the volume, off to the right of centre.
    let extent = DVec3::from(volume.extent().map(f64::from));
    let (centre, radius) = (extent * 0.5, extent.length() * 0.5);
    let eye = m.view.inverse().transform_point3(DVec3::ZERO);
    let right = m.view.row(0).truncate();
    // Outside the volume's bounding sphere, so the cube is entirely in front.
    let cube = centre + (eye - centre).normalize() * (1.45 * radius) + right * (0.3 * radius);
    let push: [f32; 20] = {
        let mut p = [0.0; 20];
        p[..16].copy_from_slice(&clip_from_world.to_cols_array());
        p[16..].copy_from_slice(
            &Vec4::new(cube.x as f32, cube.y as f32, cube.z as f32, (0.15 * radius) as f32).to_array(),
        );
        p
    };

    let colour_usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
    let depth_usage = vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
        | vk::ImageUsageFlags::SAMPLED
        | vk::ImageUsageFlags::TRANSFER_SRC;
    let layer_usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC;
    let colour = Image2d::new(
        instance,
        pd,
        device,
        COLOUR,
        colour_usage,
        vk::ImageAspectFlags::COLOR,
        size,
        size,
    );
    let depth = Image2d::new(
        instance,
        pd,
        device,
        DEPTH,
        depth_usage,
        vk::ImageAspectFlags::DEPTH,
        size,
        size,
    );
    let layer = Image2d::new(
        instance,
        pd,
        device,
        COLOUR,
        layer_usage,
        vk::ImageAspectFlags::COLOR,
        size,
        size,
    );
    let pixels = size as u64 * size as u64;
    let readback = |bytes| HostBuffer::new(instance, pd, device, pixels * bytes, vk::BufferUsageFlags::TRANSFER_DST);
    let (colour_out, depth_out, layer_out) = (readback(16), readback(4), readback(16));
    let (pipeline, layout, modules) = mesh_pipeline(device, size);

    let pool = unsafe {
        device.create_command_pool(
            &vk::CommandPoolCreateInfo::default().queue_family_index(host.family),
            None,
        )
    }
    .map_err(|e| e.to_string())?;
    let alloc = vk::CommandBufferAllocateInfo::default()
        .command_pool(pool)
        .level(vk::CommandBufferLevel::PRIMARY)
        .command_buffer_count(1);
    let cmd = unsafe { device.allocate_command_buffers(&alloc) }.map_err(|e| e.to_string())?[0];
    // Everything the command buffer uses, kept until its submission completed.
    struct Recorded {
        _staging: Staging,
        _volume: GpuVolume,
        _lut: GpuTransferFunction,
        _ranges: Ranges,
        structure: Structure,
    }
    let recorded = (|| -> Result<Recorded, lacuna::Error> {
        unsafe { device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()) }.unwrap();
        // 1. The engine's raster pass: the cube into colour and depth.
        let colour_write = (
            vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        );
        let depth_write = (
            vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
            vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ,
        );
        let (undefined, general) = (vk::ImageLayout::UNDEFINED, vk::ImageLayout::GENERAL);
        colour.transition(
            device,
            cmd,
            undefined,
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            NOTHING,
            colour_write,
        );
        depth.transition(
            device,
            cmd,
            undefined,
            vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            NOTHING,
            depth_write,
        );
        let colour_att = [vk::RenderingAttachmentInfo::default()
            .image_view(colour.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue::default())];
        let depth_att = vk::RenderingAttachmentInfo::default()
            .image_view(depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 },
            });
        let area = vk::Rect2D {
            offset: vk::Offset2D::default(),
            extent: vk::Extent2D {
                width: size,
                height: size,
            },
        };
        let rendering = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colour_att)
            .depth_attachment(&depth_att);
        unsafe {
            device.cmd_begin_rendering(cmd, &rendering);
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline);
            device.cmd_push_constants(
                cmd,
                layout,
                vk::ShaderStageFlags::VERTEX,
                0,
                bytemuck::cast_slice(&push),
            );
            device.cmd_draw(cmd, 36, 1, 0, 0);
            device.cmd_end_rendering(cmd);
        }
        // 2. Hand the depth to compute reads, the volume layer to storage writes.
        let sampled = (
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_SAMPLED_READ,
        );
        let storage = (
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_STORAGE_WRITE,
        );
        let depth_read = vk::ImageLayout::DEPTH_READ_ONLY_OPTIMAL;
        depth.transition(
            device,
            cmd,
            vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
            depth_read,
            depth_write,
            sampled,
        );
        layer.transition(device, cmd, undefined, general, NOTHING, storage);
        // 3. lacuna, recorded only: the uploads (once per volume / TF), the
        // per-volume ranges, the structure's build for this TF, the march.
        // SAFETY: `cmd` is this engine's, on the device `ctx` adopted, begun
        // above and submitted below to the adopted queue; everything lacuna
        // records a use of is returned in `Recorded` and kept until the
        // fence wait, as are the engine's images and buffers.
        let rec = unsafe { Recording::adopt(&ctx, cmd) };
        timer.reset(rec);
        let (gv, volume_staging) = GpuVolume::record_upload(rec, &volume)?;
        let (lut, tf_staging) = tf.record_upload(rec)?;
        let ranges = builder.record_ranges(rec, Some(&mut timer), &[accel.method().ranges(&params)?], &gv)?;
        let input = BuildInput {
            volume: &volume,
            gpu_volume: &gv,
            tf: &tf,
            gpu_tf: &lut,
            mode: Mode::Composite,
            frames: &[],
            octants: Octants::ALL,
        };
        let structure = builder.record_build(accel, rec, Some(&mut timer), &input, &ranges, &params)?;
        rec.barrier(record::Access::COMPUTE_WRITE, record::Access::COMPUTE_READ);
        let scene = Scene {
            structure: &structure,
            volume: &gv,
            tf: &lut,
        };

        // SAFETY: the engine's layer image (STORAGE usage) and depth image
        // (SAMPLED), alive in these layouts until the fence wait.
        let (out, ends) = unsafe {
            (
                HostImage::new(layer.view, COLOUR, general, size, size),
                HostDepth::new(depth.view, depth_read, size, size),
            )
        };
        // The engine's matrices; rays end at its depth image.
        let frame = FrameDesc::builder(size, size)
            .camera(Camera::Matrices(m))
            .step(0.5)
            .filter(Filter::Manual)
            .depth(Some(ends))
            .build()?;
        renderer.record(rec, Some(&mut timer), &target, scene, &frame, Output::Image(out))?;
        // 4. The engine reads its three images back.
        let src = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
        colour.transition(
            device,
            cmd,
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            src,
            colour_write,
            TRANSFER_READ,
        );
        depth.transition(device, cmd, depth_read, src, sampled, TRANSFER_READ);
        layer.transition(device, cmd, general, src, storage, TRANSFER_READ);
        colour.record_copy_out(device, cmd, colour_out.buffer);
        depth.record_copy_out(device, cmd, depth_out.buffer);
        layer.record_copy_out(device, cmd, layer_out.buffer);
        unsafe { device.end_command_buffer(cmd) }.unwrap();
        Ok(Recorded {
            _staging: volume_staging.join(tf_staging),
            _volume: gv,
            _lut: lut,
            _ranges: ranges,
            structure,
        })
    })();
    let submitted = recorded.map_err(err).and_then(|recorded| {
        unsafe {
            let fence = device.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
            let done = device
                .queue_submit2(host.queue, &submit, fence)
                .and_then(|_| device.wait_for_fences(&[fence], true, u64::MAX));
            device.destroy_fence(fence, None);
            done.map_err(|e| format!("submit: {e}"))?;
        }
        // A device that caps a shader's loop passes (lavapipe) may have cut
        // the march short: such a frame is not the exact one.
        renderer.check_whole(&target, &recorded.structure).map_err(err)?;
        drop(recorded);
        Ok(())
    });
    let frame_of = |b: &HostBuffer| Frame::new(size, size, bytemuck::pod_collect_to_vec(b.bytes()));
    let result = submitted.and_then(|_| {
        let mesh = frame_of(&colour_out);
        let layer_frame = frame_of(&layer_out);
        // Premultiplied "over": the volume in front of the cube.
        let composite = layer_frame
            .pixels
            .iter()
            .zip(&mesh.pixels)
            .map(|(v, c)| std::array::from_fn(|i| v[i] + (1.0 - v[3]) * c[i]))
            .collect();
        Ok(Rendered {
            composite: Frame::new(size, size, composite),
            volume: layer_frame,
            mesh,
            depth: bytemuck::pod_collect_to_vec(depth_out.bytes()),
            timings: timer.results().map_err(err)?,
            validation: ctx.take_validation_messages().iter().map(|m| m.to_string()).collect(),
            lacuna_submissions: ctx.submissions(),
        })
    });
    unsafe {
        device.destroy_command_pool(pool, None);
        device.destroy_pipeline(pipeline, None);
        device.destroy_pipeline_layout(layout, None);
        for m in modules {
            device.destroy_shader_module(m, None);
        }
    }
    for b in [&colour_out, &depth_out, &layer_out] {
        b.destroy(device);
    }
    for i in [&colour, &depth, &layer] {
        i.destroy(device);
    }
    result
}
