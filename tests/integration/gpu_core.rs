//! The ash layer: validation catches a planted hazard, kernels and barriers,
//! buffers, timestamps, adoption of a host device, device limits.

use crate::common::{assert_clean, gpu};
use lacuna::gpu::shaders::prims_copy;
use lacuna::gpu::{record, Recording};
use lacuna::gpu::{
    required_features, shaders, vk, AdoptInfo, Binding, Bound, Buffer, Context, EnabledFeatures, Kernel,
    MemoryLocation, TexelBuffer, Timer, REQUIRED_EXTENSIONS,
};
use lacuna::Error;

fn copy_kernel(ctx: &Context) -> Kernel {
    Kernel::new::<prims_copy::Push>(ctx, &shaders::PRIMS_COPY).unwrap()
}

/// prims/copy's bindings: `src` is copied to `dst`.
fn copy<'a>(src: &'a Buffer, dst: &'a Buffer) -> Vec<Bound<'a>> {
    prims_copy::Bindings {
        src: Binding::Storage(src),
        dst: Binding::Storage(dst),
    }
    .list()
}

fn storage(ctx: &Context, name: &str, words: &[u32]) -> Buffer {
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
    Buffer::with_data(ctx, name, bytemuck::cast_slice(words), usage).unwrap()
}

fn push(count: u32, groups_x: u32) -> Vec<u8> {
    let p = prims_copy::Push {
        count,
        groups_x,
        ..Default::default()
    };
    bytemuck::bytes_of(&p).to_vec()
}

/// Two dependent dispatches (a -> b, then b -> c); `with_barrier` decides
/// whether the read-after-write on b is ordered.
fn chained_copies(ctx: &Context, with_barrier: bool) -> Vec<u32> {
    let n = 4096u32;
    let input: Vec<u32> = (0..n).map(|i| i.wrapping_mul(2654435761)).collect();
    let a = storage(ctx, "a", &input);
    let b = storage(ctx, "b", &vec![0; n as usize]);
    let c = storage(ctx, "c", &vec![0; n as usize]);
    let kernel = copy_kernel(ctx);
    let groups = record::groups_linear(ctx.info(), "copy", n as u64, 64).unwrap();
    ctx.submit_and_wait(|cmd| {
        // SAFETY: only lacuna's own buffers are bound.
        unsafe { kernel.dispatch(cmd, &copy(&a, &b), &push(n, groups[0]), groups) }?;
        if with_barrier {
            cmd.compute_to_compute();
        }
        // SAFETY: only lacuna's own buffers are bound.
        unsafe { kernel.dispatch(cmd, &copy(&b, &c), &push(n, groups[0]), groups) }?;
        Ok(())
    })
    .unwrap();
    bytemuck::pod_collect_to_vec(&c.download(0, n as u64 * 4).unwrap())
}

#[test]
fn validation_catches_a_missing_barrier_between_dependent_dispatches() {
    let ctx = gpu();
    assert!(ctx.validation_enabled());
    chained_copies(&ctx, false);
    let messages = ctx.take_validation_messages();
    assert!(
        messages
            .iter()
            .any(|m| m.id.contains("SYNC-HAZARD-READ-AFTER-WRITE") || m.text.contains("SYNC-HAZARD-READ-AFTER-WRITE")),
        "expected a read-after-write hazard, got: {messages:?}"
    );
}

#[test]
fn dependent_dispatches_with_a_barrier_are_clean_and_correct() {
    let ctx = gpu();
    let out = chained_copies(&ctx, true);
    let expected: Vec<u32> = (0..4096u32).map(|i| i.wrapping_mul(2654435761)).collect();
    assert_eq!(out, expected);
    assert_clean(&ctx);
}

#[test]
fn two_dimensional_dispatch_covers_counts_beyond_one_row() {
    let ctx = gpu();
    // Pretend the row limit is tiny by splitting explicitly: 1000 items, 3 groups per row.
    let n = 1000u32;
    let input: Vec<u32> = (0..n).map(|i| i ^ 0xA5A5_5A5A).collect();
    let a = storage(&ctx, "a", &input);
    let b = storage(&ctx, "b", &vec![0; n as usize]);
    let kernel = copy_kernel(&ctx);
    let groups_x = 3u32;
    let groups = [groups_x, n.div_ceil(64).div_ceil(groups_x), 1];
    ctx.submit_and_wait(|cmd| {
        // SAFETY: only lacuna's own buffers are bound.
        unsafe { kernel.dispatch(cmd, &copy(&a, &b), &push(n, groups_x), groups) }?;
        Ok(())
    })
    .unwrap();
    let out: Vec<u32> = bytemuck::pod_collect_to_vec(&b.download(0, n as u64 * 4).unwrap());
    assert_eq!(out, input);
    assert_clean(&ctx);
}

#[test]
fn buffers_round_trip_through_staging_at_odd_offsets() {
    let ctx = gpu();
    let buf = Buffer::new(
        &ctx,
        "rt",
        1000,
        vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC,
        MemoryLocation::GpuOnly,
    )
    .unwrap();
    let data: Vec<u8> = (0..600u32).map(|i| (i * 7 % 251) as u8).collect();
    buf.upload(100, &data).unwrap();
    assert_eq!(buf.download(100, 600).unwrap(), data);
    assert_clean(&ctx);
}

#[test]
fn timer_reports_named_passes_in_order() {
    let ctx = gpu();
    let n = 1 << 16;
    let a = storage(&ctx, "a", &vec![7; n]);
    let b = storage(&ctx, "b", &vec![0; n]);
    let kernel = copy_kernel(&ctx);
    let groups = record::groups_linear(ctx.info(), "copy", n as u64, 64).unwrap();
    let mut timer = Timer::new(&ctx, 2).unwrap();
    assert!(timer.supported(), "lavapipe and every GPU we target have timestamps");
    ctx.submit_and_wait(|cmd| {
        timer.reset(cmd);
        let p = timer.begin(cmd, "first")?;
        // SAFETY: only lacuna's own buffers are bound.
        unsafe { kernel.dispatch(cmd, &copy(&a, &b), &push(n as u32, groups[0]), groups) }?;
        timer.end(cmd, p);
        cmd.compute_to_compute();
        let p = timer.begin(cmd, "second")?;
        // SAFETY: only lacuna's own buffers are bound.
        unsafe { kernel.dispatch(cmd, &copy(&b, &a), &push(n as u32, groups[0]), groups) }?;
        timer.end(cmd, p);
        Ok(())
    })
    .unwrap();
    let t = timer.results().unwrap();
    let names: Vec<&str> = t.phases.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["first", "second"]);
    assert!(t.phases.iter().all(|(_, ms)| ms.is_finite() && *ms >= 0.0));
    // A third pass exceeds the capacity of two and is a clean error.
    let err = ctx
        .submit_and_wait(|cmd| {
            timer.reset(cmd);
            for name in ["a", "b", "c"] {
                let p = timer.begin(cmd, name)?;
                timer.end(cmd, p);
            }
            Ok(())
        })
        .unwrap_err();
    assert!(matches!(err, Error::Invalid { what: "timer pass", .. }), "{err}");
    assert_clean(&ctx);
}

/// A host's validated instance and a device created with `exts`, `v12` and
/// `v13`, and what it enabled.
struct HostDevice {
    entry: ash::Entry,
    instance: ash::Instance,
    pd: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    family: u32,
    enabled: EnabledFeatures,
}

fn host_device(
    exts: &[&std::ffi::CStr],
    v12: vk::PhysicalDeviceVulkan12Features<'static>,
    v13: vk::PhysicalDeviceVulkan13Features<'static>,
) -> HostDevice {
    host_device_on(true, exts, v12, v13)
}

/// As `host_device`; `validated` false: an instance with no layer and no
/// extension (no `VK_EXT_debug_utils`).
fn host_device_on(
    validated: bool,
    exts: &[&std::ffi::CStr],
    v12: vk::PhysicalDeviceVulkan12Features<'static>,
    v13: vk::PhysicalDeviceVulkan13Features<'static>,
) -> HostDevice {
    let entry = unsafe { ash::Entry::load() }.unwrap();
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_3);
    let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
    let inst_exts = [ash::ext::debug_utils::NAME.as_ptr()];
    let sync = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&sync);
    let info = vk::InstanceCreateInfo::default().application_info(&app);
    let info = match validated {
        true => info
            .enabled_layer_names(&layers)
            .enabled_extension_names(&inst_exts)
            .push_next(&mut features),
        false => info,
    };
    let instance = unsafe { entry.create_instance(&info, None) }.unwrap();
    let pd = unsafe { instance.enumerate_physical_devices() }.unwrap()[0];
    let family = unsafe { instance.get_physical_device_queue_family_properties(pd) }
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
        .unwrap() as u32;
    let prio = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&prio)];
    let dev_exts: Vec<_> = exts.iter().map(|e| e.as_ptr()).collect();
    let (mut c12, mut c13) = (v12, v13);
    let dinfo = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&dev_exts)
        .push_next(&mut c13)
        .push_next(&mut c12);
    let device = unsafe { instance.create_device(pd, &dinfo, None) }.unwrap();
    let queue = unsafe { device.get_device_queue(family, 0) };
    let enabled = EnabledFeatures {
        api_version: vk::API_VERSION_1_3,
        extensions: exts.iter().map(|e| (*e).to_owned()).collect(),
        vulkan12: v12,
        vulkan13: v13,
    };
    HostDevice {
        entry,
        instance,
        pd,
        device,
        queue,
        family,
        enabled,
    }
}

impl HostDevice {
    /// SAFETY (for the tests): the handles were created above, outlive the
    /// context, and nothing else uses the queue.
    fn adopt(&self) -> lacuna::Result<Context> {
        unsafe {
            Context::adopt(AdoptInfo {
                entry: Some(self.entry.clone()),
                instance: self.instance.clone(),
                physical_device: self.pd,
                device: self.device.clone(),
                queue: self.queue,
                queue_family: self.family,
                enabled: self.enabled.clone(),
            })
        }
    }

    fn destroy(self) {
        unsafe {
            self.device.destroy_device(None);
            self.instance.destroy_instance(None);
        }
    }
}

#[test]
fn adopting_with_a_messenger_on_an_instance_without_debug_utils_is_an_error() {
    let (v12, v13) = required_features();
    let host = host_device_on(false, &REQUIRED_EXTENSIONS, v12, v13);
    // ash would call a panicking stand-in for the missing command, which
    // aborts the process: lacuna refuses before that.
    let err = host.adopt().err().unwrap();
    assert!(err.to_string().contains("VK_EXT_debug_utils"), "{err}");
    // Without an entry, no messenger: adopted, and usable.
    let ctx = unsafe {
        Context::adopt(AdoptInfo {
            entry: None,
            instance: host.instance.clone(),
            physical_device: host.pd,
            device: host.device.clone(),
            queue: host.queue,
            queue_family: host.family,
            enabled: host.enabled.clone(),
        })
    }
    .unwrap();
    assert_eq!(chained_copies(&ctx, true)[1], 2654435761);
    drop(ctx);
    host.destroy();
}

#[test]
fn timer_misuse_is_an_error_not_a_panic() {
    let ctx = gpu();
    let mut timer = Timer::new(&ctx, 4).unwrap();
    // A pass opened inside another, and a pass never closed.
    let err = ctx
        .submit_and_wait(|cmd| {
            timer.reset(cmd);
            let _outer = timer.begin(cmd, "outer")?;
            timer.begin(cmd, "inner").map(|_| ())
        })
        .unwrap_err();
    assert!(err.to_string().contains("passes do not nest"), "{err}");
    let stale = ctx
        .submit_and_wait(|cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "open")
        })
        .unwrap();
    let err = timer.results().unwrap_err();
    assert!(err.to_string().contains("never closed"), "{err}");
    // After a reset the timer works again; the last recording's handle
    // (the same index) closes nothing of this one.
    ctx.submit_and_wait(|cmd| {
        timer.reset(cmd);
        let p = timer.begin(cmd, "whole")?;
        timer.end(cmd, stale);
        assert!(timer.begin(cmd, "nested").is_err(), "the stale handle closed the pass");
        timer.end(cmd, p);
        Ok(())
    })
    .unwrap();
    assert!(timer.results().unwrap().phase("whole").is_ok());
    assert_clean(&ctx);
}

#[test]
fn buffer_ranges_past_the_end_are_an_error() {
    let ctx = gpu();
    let b = storage(&ctx, "four words", &[1, 2, 3, 4]);
    let out_of_range = |e: Error| {
        matches!(
            e,
            Error::Invalid {
                what: "buffer range",
                ..
            }
        )
    };
    for (offset, len) in [(0, 17), (16, 1), (u64::MAX, 2)] {
        assert!(out_of_range(b.download(offset, len).unwrap_err()), "{offset} {len}");
    }
    assert!(out_of_range(b.upload(12, &[0u8; 8]).unwrap_err()));
    assert_eq!(b.download(4, 8).unwrap(), [2u8, 0, 0, 0, 3, 0, 0, 0]);
    assert_clean(&ctx);
}

#[test]
fn adopted_device_is_used_but_not_destroyed() {
    let (v12, v13) = required_features();
    let host = host_device(&REQUIRED_EXTENSIONS, v12, v13);
    let ctx = host.adopt().unwrap();
    assert!(!ctx.owns_device());
    let out = chained_copies(&ctx, true);
    assert_eq!(out[1], 2654435761);
    assert_clean(&ctx);
    drop(ctx);
    // The host's device still works after lacuna let go of it.
    unsafe {
        host.device.device_wait_idle().unwrap();
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(host.family);
        let pool = host.device.create_command_pool(&info, None).unwrap();
        host.device.destroy_command_pool(pool, None);
    }
    host.destroy();
}

#[test]
fn adopting_a_device_without_push_descriptors_names_the_extension() {
    let (v12, v13) = required_features();
    let host = host_device(&[], v12, v13);
    let err = host.adopt().err().unwrap();
    assert!(err.to_string().contains("VK_KHR_push_descriptor"), "{err}");
    // Listing the extension without creating the device with it is caught
    // on the device itself.
    let mut lying = host_device(&[], v12, v13);
    lying.enabled.extensions = REQUIRED_EXTENSIONS.iter().map(|e| (*e).to_owned()).collect();
    let err = lying.adopt().err().unwrap();
    assert!(
        err.to_string().contains("vkCmdPushDescriptorSetKHR is not loaded"),
        "{err}"
    );
    host.destroy();
    lying.destroy();
}

#[test]
fn adopting_a_device_without_a_required_feature_names_it() {
    let (v12, v13) = required_features();
    let host = host_device(&REQUIRED_EXTENSIONS, v12, v13.synchronization2(false));
    let err = host.adopt().err().unwrap();
    assert!(err.to_string().contains("synchronization2"), "{err}");
    host.destroy();
    let host = host_device(&REQUIRED_EXTENSIONS, v12.vulkan_memory_model_device_scope(false), v13);
    let err = host.adopt().err().unwrap();
    assert!(err.to_string().contains("vulkanMemoryModelDeviceScope"), "{err}");
    host.destroy();
    let mut host = host_device(&REQUIRED_EXTENSIONS, v12, v13);
    host.enabled.api_version = vk::API_VERSION_1_2;
    let err = host.adopt().err().unwrap();
    assert!(
        err.to_string().contains("Vulkan 1.3 (the instance asked for 1.2)"),
        "{err}"
    );
    host.destroy();
}

#[test]
fn adopting_a_queue_family_that_does_not_exist_is_an_error() {
    let ctx = gpu();
    let (vulkan12, vulkan13) = required_features();
    // SAFETY: the handles are the live context's; adoption fails before use.
    let err = unsafe {
        Context::adopt(AdoptInfo {
            entry: None,
            instance: ctx.instance().clone(),
            physical_device: ctx.physical_device(),
            device: ctx.device().clone(),
            queue: vk::Queue::null(),
            queue_family: 99,
            enabled: EnabledFeatures {
                api_version: vk::API_VERSION_1_3,
                extensions: REQUIRED_EXTENSIONS.iter().map(|e| (*e).to_owned()).collect(),
                vulkan12,
                vulkan13,
            },
        })
    }
    .err()
    .unwrap();
    assert!(err.to_string().contains("queue family '99'"), "{err}");
}

#[test]
fn limits_are_checked_by_name_before_use() {
    let ctx = gpu();
    let info = ctx.info().clone();
    assert!(info.subgroup_size > 0 && info.max_storage_buffer_range > 0);
    // A frame larger than maxStorageBufferRange.
    let side = ((info.max_storage_buffer_range / 16) as f64).sqrt() as u32 + 1;
    let err = lacuna::render::RenderTarget::new(&ctx, side, side).err().unwrap();
    assert!(
        matches!(
            err,
            Error::DeviceLimit {
                limit: "maxStorageBufferRange",
                ..
            }
        ),
        "{err}"
    );
    // A dispatch wider than maxComputeWorkGroupCount[0].
    let err = record::groups_for(&info, "test", [u32::MAX, 1, 1], [1, 1, 1]).unwrap_err();
    assert!(err.to_string().contains("maxComputeWorkGroupCount[0]"), "{err}");
    // 2-D linear dispatch splits long rows.
    let g = record::groups_linear(
        &info,
        "test",
        info.max_compute_work_group_count[0] as u64 * 64 * 3 + 1,
        64,
    )
    .unwrap();
    assert_eq!(g[0], info.max_compute_work_group_count[0]);
    assert_eq!(g[1], 4);
    assert_clean(&ctx);
}

#[test]
fn interfaces_are_read_from_the_spirv() {
    use lacuna::gpu::LocalDim;
    let d = vk::DescriptorType::STORAGE_BUFFER;
    let g = shaders::MARCH_GRID;
    assert_eq!(g.name(), "march/grid");
    let texels = vk::DescriptorType::UNIFORM_TEXEL_BUFFER;
    let slots: Vec<(&str, vk::DescriptorType)> = g.bindings().iter().map(|s| (s.name, s.ty)).collect();
    assert_eq!(
        slots,
        [
            ("params", d),
            ("volume_tex", vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
            ("tf_lut", texels),
            ("frame", d),
            ("frame_depth", d),
            ("gradient_tex", vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
            ("volume_cells", texels),
            ("gradient_cells", texels),
            ("brick_table", texels),
            ("pool_1", vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
            ("pool_2", vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
            ("pool_3", vk::DescriptorType::COMBINED_IMAGE_SAMPLER),
            ("march_status", d),
            ("cell_texels", texels)
        ]
    );
    assert_eq!(g.push_size(), 16);
    assert_eq!(std::mem::size_of::<shaders::march_grid::Push>(), 16);
    assert_eq!(
        g.local_size(),
        [LocalDim::Fixed(8), LocalDim::Fixed(8), LocalDim::Fixed(1)]
    );
    // The render parameters are a fixed-size storage block (see
    // render_params.glsl for why not a uniform block), generated from the
    // SPIR-V; the march status is one word; the structure's arrays have no
    // fixed size.
    assert_eq!(
        g.bindings()[0].block_size as usize,
        std::mem::size_of::<lacuna::render::RenderParams>()
    );
    let status = g.slot("march_status").unwrap().1;
    assert_eq!(status.block_size, 4);
    assert!(g.bindings()[2..]
        .iter()
        .filter(|s| s.name != "march_status")
        .all(|s| s.block_size == 0));
    // Every march kernel's parameter block is the one generated struct.
    for s in shaders::ALL.iter().filter(|s| s.name().starts_with("march/")) {
        let (_, params) = s.slot("params").unwrap();
        assert_eq!(
            params.block_size as usize,
            std::mem::size_of::<lacuna::render::RenderParams>()
        );
    }
    // local_size_x_id = 0: the width is specialization constant 0.
    let scan = shaders::PRIMS_SCAN_BLOCKS;
    assert!(matches!(scan.local_size()[0], LocalDim::Spec { id: 0, .. }));
    assert_eq!(scan.local_size_with(&[32, 32])[0], 32);
    assert!(shaders::ALL.iter().any(|s| s.name() == "march/naive"));
}

#[test]
fn a_push_block_of_the_wrong_size_fails_at_creation_naming_the_kernel() {
    let ctx = gpu();
    // march/grid's block is a uvec3 and a uint; a Rust side of three words is refused.
    let err = Kernel::new::<[u32; 3]>(&ctx, &shaders::MARCH_GRID).err().unwrap();
    let text = err.to_string();
    assert!(matches!(err, Error::Interface(_)), "{text}");
    assert!(
        text.contains("march/grid") && text.contains("12") && text.contains("16"),
        "{text}"
    );
    assert!(Kernel::new::<shaders::march_grid::Push>(&ctx, &shaders::MARCH_GRID).is_ok());
    assert_clean(&ctx);
}

#[test]
fn bindings_that_differ_from_the_shader_are_an_error_naming_the_kernel_and_binding() {
    let ctx = gpu();
    let kernel = copy_kernel(&ctx);
    let a = storage(&ctx, "a", &[1, 2, 3, 4]);
    let push = push(4, 1);
    let result = ctx.submit_and_wait(|cmd| {
        // prims/copy reads two storage buffers, src and dst.
        let attempts: [(&[Bound], &str); 4] = [
            (&[("src", Binding::Storage(&a))], "binding dst not given"),
            (
                &[("src", Binding::Storage(&a)), ("dst", Binding::Uniform(&a))],
                "binding dst is a",
            ),
            (
                &[("src", Binding::Storage(&a)), ("source", Binding::Storage(&a))],
                "no binding named source",
            ),
            (
                &[("src", Binding::Storage(&a)), ("src", Binding::Storage(&a))],
                "binding src given twice",
            ),
        ];
        Ok(attempts
            .iter()
            // SAFETY: only lacuna's own buffers are bound.
            .map(|(b, why)| (unsafe { kernel.dispatch(cmd, b, &push, [1, 1, 1]) }.err(), *why))
            .collect::<Vec<_>>())
    });
    for (err, why) in result.unwrap() {
        let err = err.expect(why).to_string();
        assert!(err.contains("kernel prims/copy") && err.contains(why), "{err}");
    }
    assert_clean(&ctx);
}

#[test]
fn resources_go_to_the_binding_of_their_name_whatever_its_number() {
    // test/copy_swapped declares dst at binding 0 and src at 1: the same
    // named resources copy the same way through both kernels.
    let ctx = gpu();
    let kernel = copy_kernel(&ctx);
    let swapped = Kernel::new::<shaders::test_copy_swapped::Push>(&ctx, &shaders::TEST_COPY_SWAPPED).unwrap();
    assert_eq!(shaders::TEST_COPY_SWAPPED.bindings()[0].name, "dst");
    assert_eq!(shaders::PRIMS_COPY.bindings()[0].name, "src");
    let n = 300u32;
    let input: Vec<u32> = (0..n).map(|i| i * 3 + 1).collect();
    let a = storage(&ctx, "a", &input);
    let (b, c) = (storage(&ctx, "b", &vec![0; 300]), storage(&ctx, "c", &vec![0; 300]));
    let groups = record::groups_linear(ctx.info(), "copy", n as u64, 64).unwrap();
    let swapped_bindings = shaders::test_copy_swapped::Bindings {
        src: Binding::Storage(&a),
        dst: Binding::Storage(&c),
    };
    ctx.submit_and_wait(|cmd| {
        // SAFETY: only lacuna's own buffers are bound.
        unsafe { kernel.dispatch(cmd, &copy(&a, &b), &push(n, groups[0]), groups) }?;
        // SAFETY: only lacuna's own buffers are bound.
        unsafe { swapped.dispatch(cmd, &swapped_bindings.list(), &push(n, groups[0]), groups) }
    })
    .unwrap();
    for out in [&b, &c] {
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&out.download(0, n as u64 * 4).unwrap());
        assert_eq!(words, input);
    }
    assert_clean(&ctx);
}

#[test]
fn texel_buffers_refuse_partial_texels_and_formats_they_do_not_read() {
    let ctx = gpu();
    let usage = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
    let make = |bytes: u64| Buffer::new(&ctx, "texels", bytes, usage, MemoryLocation::GpuOnly).unwrap();
    let whole = TexelBuffer::new(&ctx, make(64), vk::Format::R32G32B32A32_SFLOAT).unwrap();
    assert_eq!(whole.buffer().size(), 64);
    let partial = TexelBuffer::new(&ctx, make(20), vk::Format::R32G32B32A32_SFLOAT)
        .err()
        .unwrap();
    assert!(matches!(partial, Error::Interface(_)), "{partial}");
    assert!(partial.to_string().contains("20 bytes"), "{partial}");
    let format = TexelBuffer::new(&ctx, make(64), vk::Format::R8_UNORM).err().unwrap();
    assert!(matches!(format, Error::Unsupported(_)), "{format}");
    drop(whole);
    assert_clean(&ctx);
}

/// A context creates each kernel (SPIR-V and specialization) once: a
/// second renderer and builder on it, and the same frame again, create
/// none, and the frame is the same bit for bit. Kernels specialized
/// differently are new ones.
#[test]
fn a_context_creates_each_kernel_once() {
    use crate::common::{accel, fresh_gpu, max_abs, render};
    use lacuna::render::{Filter, FrameDesc, Projection};
    let ctx = fresh_gpu();
    assert_eq!(ctx.kernels_created(), 0);
    let volume = lacuna::Volume::load("nbody:24", &Default::default()).unwrap();
    let tf = lacuna::TransferFunction::parse("ramp:0.3:1").unwrap();
    let view = |filter| {
        FrameDesc::builder(32, 32)
            .orbit(30.0, 20.0, Projection::Orthographic)
            .filter(filter)
            .build()
            .unwrap()
    };
    let first = render(&ctx, &volume, &tf, &view(Filter::Manual), accel("grid"));
    let made = ctx.kernels_created();
    assert!(made > 0);
    let again = render(&ctx, &volume, &tf, &view(Filter::Manual), accel("grid"));
    assert_eq!(ctx.kernels_created(), made, "the same frame again created kernels");
    assert_eq!(max_abs(&first, &again), 0.0);
    render(&ctx, &volume, &tf, &view(Filter::Hardware), accel("grid"));
    assert!(ctx.kernels_created() > made, "another filter is another specialization");
    assert_clean(&ctx);
}

/// Records the copy of `from` into `to` (`n` words).
fn copy_job<'a>(
    kernel: &'a Kernel,
    from: &'a Buffer,
    to: &'a Buffer,
    n: u32,
    groups: [u32; 3],
) -> impl FnOnce(Recording<'_>) -> lacuna::Result<()> + 'a {
    // SAFETY: only lacuna's own buffers are bound.
    move |cmd| unsafe { kernel.dispatch(cmd, &copy(from, to), &push(n, groups[0]), groups) }
}

/// `submit_while` runs host work between the submission and the wait (here
/// a submission of its own), returns both results, and waits for the
/// commands even where the host work fails or panics: the context stays
/// usable and what the commands wrote is there.
#[test]
fn submit_while_runs_host_work_and_always_waits() {
    let ctx = gpu();
    let n = 4096u32;
    let input: Vec<u32> = (0..n).map(|i| i ^ 0x5a5a).collect();
    let a = storage(&ctx, "a", &input);
    let kernel = copy_kernel(&ctx);
    let groups = record::groups_linear(ctx.info(), "copy", n as u64, 64).unwrap();
    let words = |b: &Buffer| bytemuck::pod_collect_to_vec::<u8, u32>(&b.download(0, n as u64 * 4).unwrap());
    let zeros = |name| storage(&ctx, name, &vec![0; n as usize]);
    let (b, c) = (zeros("b"), zeros("c"));
    let ((), host) = ctx
        .submit_while(copy_job(&kernel, &a, &b, n, groups), || {
            ctx.submit_and_wait(copy_job(&kernel, &a, &c, n, groups))?;
            Ok(7)
        })
        .unwrap();
    assert_eq!((host, words(&b), words(&c)), (7, input.clone(), input.clone()));
    // Host work that fails: its error, after the wait.
    let d = zeros("d");
    let failed = ctx.submit_while(copy_job(&kernel, &a, &d, n, groups), || -> lacuna::Result<()> {
        Err(Error::Interface("planted".into()))
    });
    assert!(matches!(failed, Err(Error::Interface(m)) if m == "planted"));
    assert_eq!(words(&d), input);
    // Host work that panics: the panic comes back after the wait.
    let e = zeros("e");
    let panicked = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        ctx.submit_while(copy_job(&kernel, &a, &e, n, groups), || -> lacuna::Result<()> {
            panic!("planted panic")
        })
    }));
    assert!(panicked.is_err());
    assert_eq!(words(&e), input);
    assert_clean(&ctx);
}
