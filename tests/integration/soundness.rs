//! What safe code cannot do through lacuna's recording API: mix objects of
//! two contexts in one command buffer, copy past a buffer's end, bind a
//! buffer without the usage its binding needs, make an image whose texels
//! disagree with its format, free what a recorded command reads, or touch on
//! the host memory a submission reads or writes.

use crate::common::{assert_clean, fresh_gpu, gpu};
use lacuna::accel::{Builder, RangeKind};
use lacuna::gpu::{vk, Buffer, Context, Image3d, MemoryLocation, Recording, TexelBuffer};
use lacuna::prims::{BrickMinMax, Scan};
use lacuna::volume::GpuVolume;
use lacuna::Volume;

fn error<T>(r: lacuna::Result<T>) -> String {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

fn storage(ctx: &Context, words: u64) -> Buffer {
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    Buffer::new(ctx, "test", words * 4, usage, MemoryLocation::GpuOnly).unwrap()
}

fn uploaded(ctx: &Context) -> GpuVolume {
    GpuVolume::upload(ctx, &Volume::load("nbody:16", &Default::default()).unwrap()).unwrap()
}

#[test]
fn recording_calls_refuse_objects_of_another_context() {
    let (ctx, other) = (gpu(), fresh_gpu());
    let scan = Scan::new(&ctx).unwrap();
    let scratch = scan.scratch(64).unwrap();
    let data = storage(&ctx, 64);
    let e = error(other.submit_and_wait(|cmd| scan.record(cmd, &data, 64, &scratch)));
    assert!(e.contains("invalid command buffer 'of another lacuna Context'"), "{e}");
    let foreign = storage(&other, 64);
    let e = error(ctx.submit_and_wait(|cmd| scan.record(cmd, &foreign, 64, &scratch)));
    assert!(e.contains("invalid bound buffer 'of another lacuna Context'"), "{e}");
    // Ranges kept into the other's buffer, dropped in the closure: before,
    // a copy into memory freed at once (retirement is per context).
    let gv = uploaded(&ctx);
    let (ranges, _) = Builder::new(&ctx).unwrap().ranges(&[RangeKind::Bricks], &gv).unwrap();
    let bricks = ranges.bricks().unwrap();
    let e = error(ctx.submit_and_wait(|cmd| {
        let to = storage(&other, bricks.ranges().size() / 4);
        bricks.record_keep(cmd, &to)
    }));
    assert!(
        e.contains("invalid copied-to buffer 'of another lacuna Context'"),
        "{e}"
    );
    let usage = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
    let texels = Buffer::new(&other, "texels", 64, usage, MemoryLocation::GpuOnly).unwrap();
    let e = error(TexelBuffer::new(&ctx, texels, vk::Format::R32_UINT));
    assert!(
        e.contains("invalid texel buffer's buffer 'of another lacuna Context'"),
        "{e}"
    );
    assert_clean(&ctx);
    assert_clean(&other);
}

#[test]
fn copies_bindings_and_images_are_checked_against_sizes_usage_and_format() {
    let ctx = gpu();
    let gv = uploaded(&ctx);
    let (ranges, _) = Builder::new(&ctx).unwrap().ranges(&[RangeKind::Bricks], &gv).unwrap();
    let tiny = storage(&ctx, 1);
    let e = error(ctx.submit_and_wait(|cmd| ranges.bricks()?.record_keep(cmd, &tiny)));
    assert!(e.contains("invalid buffer copy"), "{e}");
    let minmax = BrickMinMax::new(&ctx).unwrap();
    let e = error(ctx.submit_and_wait(|cmd| minmax.record(cmd, &gv, 8, 1, &tiny)));
    assert!(e.contains("invalid brick ranges '4 bytes'"), "{e}");
    let e = error(Buffer::new(
        &ctx,
        "none",
        64,
        vk::BufferUsageFlags::empty(),
        MemoryLocation::GpuOnly,
    ));
    assert!(e.contains("invalid buffer usage"), "{e}");
    let scan = Scan::new(&ctx).unwrap();
    let scratch = scan.scratch(16).unwrap();
    let usage = vk::BufferUsageFlags::TRANSFER_DST;
    let copy_only = Buffer::new(&ctx, "copy only", 64, usage, MemoryLocation::GpuOnly).unwrap();
    let e = error(ctx.submit_and_wait(|cmd| scan.record(cmd, &copy_only, 16, &scratch)));
    assert!(e.contains("needs a buffer of STORAGE_BUFFER usage"), "{e}");
    let e = error(TexelBuffer::new(&ctx, storage(&ctx, 16), vk::Format::R32_UINT));
    assert!(e.contains("without UNIFORM_TEXEL_BUFFER usage"), "{e}");
    let rgba = vk::Format::R32G32B32A32_SFLOAT;
    let e = error(Image3d::with_data(&ctx, "image", rgba, [4, 4, 4], 1, &[0; 64]));
    assert!(e.contains("invalid image texels"), "{e}");
    let e = error(Image3d::with_data(
        &ctx,
        "image",
        vk::Format::R8_UNORM,
        [4, 0, 4],
        1,
        &[],
    ));
    assert!(e.contains("invalid image extent"), "{e}");
    assert_clean(&ctx);
}

/// A host's command buffer on the context's device and queue family.
struct HostCmd {
    pool: vk::CommandPool,
    raw: vk::CommandBuffer,
}

impl HostCmd {
    fn begin(ctx: &Context) -> HostCmd {
        let d = ctx.device();
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(ctx.queue_family());
        unsafe {
            let pool = d.create_command_pool(&info, None).unwrap();
            let alloc = vk::CommandBufferAllocateInfo::default()
                .command_pool(pool)
                .level(vk::CommandBufferLevel::PRIMARY)
                .command_buffer_count(1);
            let raw = d.allocate_command_buffers(&alloc).unwrap()[0];
            d.begin_command_buffer(raw, &vk::CommandBufferBeginInfo::default())
                .unwrap();
            HostCmd { pool, raw }
        }
    }

    /// Ends, submits on the context's queue (no lacuna call is submitting
    /// meanwhile: the context is this test's) and waits.
    fn submit_and_wait(self, ctx: &Context) {
        let d = ctx.device();
        unsafe {
            d.end_command_buffer(self.raw).unwrap();
            let queue = d.get_device_queue(ctx.queue_family(), 0);
            let fence = d.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(self.raw)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
            d.queue_submit2(queue, &submit, fence).unwrap();
            d.wait_for_fences(&[fence], true, u64::MAX).unwrap();
            d.destroy_fence(fence, None);
            d.destroy_command_pool(self.pool, None);
        }
    }
}

/// `Builder::put` replaces a per-context value (here the brick min/max
/// kernels, whose stand-in list buffer every ranges pass binds) while a
/// host's command buffer that bound it is pending: the old value lives as
/// long as the builder, so the ranges come out as a builder's own.
#[test]
fn what_builder_put_replaces_outlives_the_recordings_that_bound_it() {
    let ctx = gpu();
    let gv = uploaded(&ctx);
    let builder = Builder::new(&ctx).unwrap();
    let host = HostCmd::begin(&ctx);
    // SAFETY: recording on this context's device, outside a render pass,
    // submitted to its family below after no failed call; the builder, the
    // volume and the ranges returned are kept, and unread, until the wait.
    let rec = unsafe { Recording::adopt(&ctx, host.raw) };
    let ranges = builder.record_ranges(rec, None, &[RangeKind::Bricks], &gv).unwrap();
    builder.put(BrickMinMax::new(&ctx).unwrap());
    host.submit_and_wait(&ctx);
    let (want, _) = Builder::new(&ctx).unwrap().ranges(&[RangeKind::Bricks], &gv).unwrap();
    let bytes = |r: &lacuna::accel::Ranges| {
        let b = r.bricks().unwrap().ranges();
        b.download(0, b.size()).unwrap()
    };
    assert_eq!(bytes(&ranges), bytes(&want));
    assert_clean(&ctx);
}

/// The second review's holes: each is now an error, nothing recorded.
#[test]
fn views_copies_ranges_lbvh_buffers_and_octrees_are_checked_before_use() {
    let (ctx, other) = (gpu(), fresh_gpu());
    // A k-d tree of this context over the other's volume (its views are
    // bound, which a dispatch cannot check: a segfault before).
    let kd = lacuna::accel::kd::gpu::KdGpuBuilder::new(&ctx).unwrap();
    let tf = lacuna::TransferFunction::parse("ramp:0.35:1").unwrap();
    let (gv_other, lut) = (uploaded(&other), tf.upload(&ctx).unwrap());
    let params = lacuna::accel::kd::KdParams::default();
    let e = error(kd.build(&gv_other, &lut, &params, None));
    assert!(e.contains("invalid volume 'of another lacuna Context'"), "{e}");
    // Copies and fills: usage, alignment, overlap.
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let storage_only = Buffer::new(&ctx, "storage only", 64, usage, MemoryLocation::GpuOnly).unwrap();
    let both = storage(&ctx, 16);
    let region = |src_offset, dst_offset, size| {
        [vk::BufferCopy {
            src_offset,
            dst_offset,
            size,
        }]
    };
    for (attempt, needle) in [
        (
            ctx.submit_and_wait(|cmd| cmd.copy_buffer(&storage_only, &both, &region(0, 0, 4))),
            "without TRANSFER_SRC",
        ),
        (
            ctx.submit_and_wait(|cmd| cmd.copy_buffer(&both, &storage_only, &region(0, 0, 4))),
            "without TRANSFER_DST",
        ),
        (
            ctx.submit_and_wait(|cmd| cmd.copy_buffer(&both, &both, &region(0, 4, 8))),
            "invalid buffer copy",
        ),
        (
            ctx.submit_and_wait(|cmd| cmd.copy_buffer(&both, &both, &region(0, 32, 0))),
            "invalid buffer copy",
        ),
        (
            ctx.submit_and_wait(|cmd| cmd.fill_buffer(&both, 2, 4, 0)),
            "invalid buffer fill",
        ),
        (
            ctx.submit_and_wait(|cmd| cmd.fill_buffer(&both, 0, 5, 0)),
            "invalid buffer fill",
        ),
        (storage_only.upload(0, &[0; 4]), "without TRANSFER_DST"),
    ] {
        let e = error(attempt);
        assert!(e.contains(needle), "{e} (wanted {needle})");
    }
    // A buffer bound whole past maxStorageBufferRange.
    let range = ctx.info().max_storage_buffer_range;
    let big = Buffer::new(&ctx, "big", range + 4096, usage, MemoryLocation::GpuOnly).unwrap();
    let scan = Scan::new(&ctx).unwrap();
    let scratch = scan.scratch(64).unwrap();
    let e = error(ctx.submit_and_wait(|cmd| scan.record(cmd, &big, 64, &scratch)));
    assert!(e.contains("maxStorageBufferRange"), "{e}");
    drop(big);
    // An LBVH hierarchy recorded into a node buffer too small for it.
    let gv = uploaded(&ctx);
    let (ranges, _) = Builder::new(&ctx).unwrap().ranges(&[RangeKind::Bricks], &gv).unwrap();
    let bricks = ranges.bricks().unwrap();
    let lbvh = lacuna::accel::lbvh::LbvhBuilder::new(&ctx).unwrap();
    let classifier = lacuna::accel::Classifier::new(&ctx).unwrap();
    let input = lacuna::accel::lbvh::LbvhInput {
        classifier: &classifier,
        mode: lacuna::accel::Classify::Range,
        volume: &gv,
        bricks,
        tf: &lut,
        collapse: None,
    };
    let select = lbvh.select_scratch(bricks).unwrap();
    let h = lbvh.hierarchy_scratch(bricks.total()).unwrap();
    let e = error(ctx.submit_and_wait(|cmd| lbvh.record_hierarchy(cmd, None, &input, &select, &h, &storage(&ctx, 1))));
    assert!(e.contains("invalid LBVH buffers"), "{e}");
    // An octree whose child index points outside it, or back at its root.
    use lacuna::octree::{GpuTracer, Mode, Octree, OctreeOptions, TraceKernels, TraceScene};
    let scene = lacuna::scene::Scene::generate(lacuna::scene::SpdScene::Balls, Some(1)).unwrap();
    let traced = TraceScene::new(&scene);
    let options = OctreeOptions {
        mode: Mode::Center,
        max_depth: 3,
        max_objects: 1,
    };
    let kernels = TraceKernels::new(&ctx).unwrap();
    let tree = Octree::for_scene(&traced, options);
    assert!(
        GpuTracer::new(&kernels, &tree, &traced).is_ok(),
        "the builder's own octree"
    );
    let interior = tree.nodes.iter().position(|n| !n.is_leaf()).expect("an interior node");
    for first in [1_000_000, 0] {
        let mut bad = Octree::for_scene(&traced, options);
        bad.nodes[interior].info[0] = first;
        let e = error(GpuTracer::new(&kernels, &bad, &traced));
        assert!(e.contains("invalid octree"), "{e}");
    }
    assert_clean(&ctx);
    assert_clean(&other);
}

/// A timer's results are read only after the submission that recorded its
/// reset completed: inside the closure, or after a closure that failed (never
/// submitted), its queries hold nothing yet.
#[test]
fn timer_results_wait_for_the_submission_that_recorded_them() {
    let ctx = gpu();
    let mut timer = lacuna::gpu::Timer::new(&ctx, 1).unwrap();
    let inside = ctx
        .submit_and_wait(|cmd| {
            timer.reset(cmd);
            let pass = timer.begin(cmd, "empty")?;
            timer.end(cmd, pass);
            Ok(timer.results().map(|_| ()).map_err(|e| e.to_string()))
        })
        .unwrap();
    let e = inside.expect_err("results inside the recording closure");
    assert!(e.contains("before the submission that recorded them completed"), "{e}");
    assert!(timer.results().unwrap().get("empty").is_some(), "after the wait");
    let failed = ctx.submit_and_wait(|cmd| {
        timer.reset(cmd);
        let pass = timer.begin(cmd, "empty")?;
        timer.end(cmd, pass);
        Err::<(), _>(lacuna::Error::Interface("planted".into()))
    });
    assert!(failed.is_err());
    let e = error(timer.results());
    assert!(e.contains("before the submission that recorded them completed"), "{e}");
    assert_clean(&ctx);
}

#[test]
fn host_reads_and_device_writes_of_one_buffer_never_overlap() {
    let ctx = gpu();
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
    let buf = Buffer::new(&ctx, "shared", 64, usage, MemoryLocation::GpuToCpu).unwrap();
    // Read while the submission that fills it runs (on a CPU device, its
    // queue thread): before, safe code raced the device's writes.
    let ((), during) = ctx
        .submit_while(
            |cmd| {
                cmd.fill_buffer(&buf, 0, vk::WHOLE_SIZE, 7)?;
                cmd.barrier(
                    lacuna::gpu::record::Access::TRANSFER_WRITE,
                    lacuna::gpu::record::Access::HOST_READ,
                );
                Ok(())
            },
            || Ok(buf.host().map(|_| ()).map_err(|e| e.to_string())),
        )
        .unwrap();
    let e = during.expect_err("a host read while the fill runs");
    assert!(e.contains("a submission that writes it has not completed"), "{e}");
    // Inside the closure too: the write is recorded, not yet run.
    let e = error(ctx.submit_and_wait(|cmd| {
        cmd.fill_buffer(&buf, 0, vk::WHOLE_SIZE, 8)?;
        buf.host().map(|_| ())
    }));
    assert!(e.contains("a submission that writes it has not completed"), "{e}");
    // That closure failed: nothing ran, and the buffer still holds 7s.
    assert!(buf.host().unwrap().chunks(4).all(|w| w == 7u32.to_le_bytes()));
    // A live host read refuses a recorded device write, copy, fill or bind.
    let read = buf.host().unwrap();
    let e = error(ctx.submit_and_wait(|cmd| cmd.fill_buffer(&buf, 0, vk::WHOLE_SIZE, 9)));
    assert!(e.contains("invalid device write 'into buffer 'shared''"), "{e}");
    let scan = Scan::new(&ctx).unwrap();
    let scratch = scan.scratch(16).unwrap();
    let e = error(ctx.submit_and_wait(|cmd| scan.record(cmd, &buf, 16, &scratch)));
    assert!(e.contains("the host is reading it"), "{e}");
    assert!(
        read.chunks(4).all(|w| w == 7u32.to_le_bytes()),
        "unchanged under the read"
    );
    drop(read);
    // A frame's readback, read while it is copied: refused, then read.
    let target = lacuna::render::RenderTarget::new(&ctx, 8, 8).unwrap();
    let renderer = lacuna::render::Renderer::new(&ctx).unwrap();
    let ((), during) = ctx
        .submit_while(
            |cmd| renderer.record_readback(cmd, &target),
            || Ok(target.read().map(|_| ()).map_err(|e| e.to_string())),
        )
        .unwrap();
    let e = during.expect_err("a frame read while its readback runs");
    assert!(e.contains("a submission that writes it has not completed"), "{e}");
    assert!(target.read().is_ok(), "after the wait");
    assert_clean(&ctx);
}

#[test]
fn host_writes_wait_for_device_reads_and_read_only_bindings_are_not_writes() {
    use lacuna::gpu::record::Access;
    use lacuna::prims::Compact;
    use std::cell::RefCell;
    let ctx = gpu();
    let usage =
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    // A host write into the source of a running copy: before, it tore the copy.
    let src = RefCell::new(Buffer::new(&ctx, "src", 1 << 16, usage, MemoryLocation::CpuToGpu).unwrap());
    let dst = Buffer::new(&ctx, "dst", 1 << 16, usage, MemoryLocation::GpuToCpu).unwrap();
    src.borrow_mut().host_mut().unwrap().fill(1);
    let region = [vk::BufferCopy {
        src_offset: 0,
        dst_offset: 0,
        size: 1 << 16,
    }];
    let ((), during) = ctx
        .submit_while(
            |cmd| {
                cmd.copy_buffer(&src.borrow(), &dst, &region)?;
                cmd.barrier(Access::TRANSFER_WRITE, Access::HOST_READ);
                Ok(())
            },
            || {
                Ok(src
                    .borrow_mut()
                    .host_mut()
                    .map(|m| m.fill(2))
                    .map_err(|e| e.to_string()))
            },
        )
        .unwrap();
    let e = during.expect_err("a host write while the copy reads it");
    assert!(
        e.contains("a submission that reads or writes it has not completed"),
        "{e}"
    );
    assert!(dst.host().unwrap().iter().all(|&b| b == 1), "the copy is whole");
    src.borrow_mut().host_mut().unwrap().fill(2);
    // Compaction only reads its flags (`readonly` in the shader): a host
    // read of them is no conflict, either way round.
    let flags = Buffer::host_written(&ctx, "flags", bytemuck::cast_slice(&[1u32, 0, 1, 1]), usage).unwrap();
    let (indices, count) = (storage(&ctx, 4), storage(&ctx, 1));
    let compact = Compact::new(&ctx).unwrap();
    let scratch = compact.scratch(4).unwrap();
    let read = flags.host().unwrap();
    ctx.submit_and_wait(|cmd| compact.record(cmd, &flags, 4, &indices, &count, &scratch))
        .unwrap();
    drop(read);
    let flags = RefCell::new(flags);
    let ((), during) = ctx
        .submit_while(
            |cmd| compact.record(cmd, &flags.borrow(), 4, &indices, &count, &scratch),
            || {
                let read = flags.borrow().host().map(|b| b.len()).map_err(|e| e.to_string());
                let write = flags.borrow_mut().host_mut().map(|_| ()).map_err(|e| e.to_string());
                Ok((read, write))
            },
        )
        .unwrap();
    assert_eq!(during.0, Ok(16), "a host read of flags the kernel only reads");
    let e = during.1.expect_err("a host write of flags the kernel reads");
    assert!(e.contains("reads or writes it has not completed"), "{e}");
    assert_eq!(count.download(0, 4).unwrap(), 3u32.to_le_bytes(), "three flags set");
    // A forgotten HostRead: `&mut` proves none is alive, and clears it.
    let mut leaky = Buffer::new(&ctx, "leaky", 64, usage, MemoryLocation::GpuToCpu).unwrap();
    std::mem::forget(leaky.host().unwrap());
    let e = error(ctx.submit_and_wait(|cmd| cmd.fill_buffer(&leaky, 0, vk::WHOLE_SIZE, 1)));
    assert!(e.contains("the host is reading it"), "{e}");
    leaky.host_mut().unwrap();
    ctx.submit_and_wait(|cmd| cmd.fill_buffer(&leaky, 0, vk::WHOLE_SIZE, 1))
        .unwrap();
    assert!(leaky.host().unwrap().chunks(4).all(|w| w == 1u32.to_le_bytes()));
    assert_clean(&ctx);
}

#[test]
fn another_thread_cannot_write_a_buffer_a_recorded_copy_reads() {
    let ctx = gpu();
    let n: u64 = 1 << 20;
    let usage = vk::BufferUsageFlags::TRANSFER_SRC | vk::BufferUsageFlags::TRANSFER_DST;
    let src = std::sync::Mutex::new(Buffer::new(&ctx, "src", n, usage, MemoryLocation::CpuToGpu).unwrap());
    let dst = Buffer::new(&ctx, "dst", n, usage, MemoryLocation::GpuToCpu).unwrap();
    src.lock().unwrap().host_mut().unwrap().fill(1);
    let (recorded, tried) = (std::sync::Barrier::new(2), std::sync::Barrier::new(2));
    let tries = std::thread::scope(|s| {
        // The mutex guards only the recording call: `&mut` is the other
        // thread's once the copy is recorded, and until it has run.
        let other = s.spawn(|| {
            recorded.wait();
            let before = src
                .lock()
                .unwrap()
                .host_mut()
                .map(|m| m.fill(2))
                .map_err(|e| e.to_string());
            tried.wait();
            before
        });
        ctx.submit_and_wait(|cmd| {
            let region = [vk::BufferCopy {
                src_offset: 0,
                dst_offset: 0,
                size: n,
            }];
            cmd.copy_buffer(&src.lock().unwrap(), &dst, &region)?;
            recorded.wait();
            tried.wait();
            Ok(())
        })
        .unwrap();
        other.join().unwrap()
    });
    let e = tries.expect_err("host_mut while a recorded copy reads it");
    assert!(e.contains("reads or writes it has not completed"), "{e}");
    assert!(dst.host().unwrap().iter().all(|&b| b == 1), "the copy is whole");
    src.lock().unwrap().host_mut().unwrap().fill(2);
    assert_clean(&ctx);
}
