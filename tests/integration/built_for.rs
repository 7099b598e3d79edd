//! A structure skips for the texels and transfer function it was built
//! for, and ranges are of the volume they were computed over: an embedding
//! that hands the renderer or the builder others gets an error naming
//! which, never a frame that differs from naive's.

use crate::common::{accel, builder, frame, gpu};
use lacuna::accel::{BuildInput, Structure};
use lacuna::gpu::{vk, Buffer, Timer};
use lacuna::render::{FrameDesc, Iso, Mode, Octants, Output, RenderTarget, Renderer, Scene};
use lacuna::volume::GpuVolume;
use lacuna::{TransferFunction, Volume};

fn input<'a>(
    volume: &'a Volume,
    gv: &'a GpuVolume,
    tf: &'a TransferFunction,
    lut: &'a lacuna::tf::GpuTransferFunction,
    mode: Mode,
) -> BuildInput<'a> {
    BuildInput {
        volume,
        gpu_volume: gv,
        tf,
        gpu_tf: lut,
        mode,
        frames: &[],
        octants: Octants::ALL,
    }
}

fn error(r: lacuna::Result<impl Sized>) -> String {
    match r {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_structure_refuses_another_transfer_function_or_other_texels() {
    let ctx = gpu();
    let volume = Volume::load("nbody:16", &Default::default()).unwrap();
    let other = Volume::load("nbody:16:7", &Default::default()).unwrap();
    let (tf, tf2) = (
        TransferFunction::parse("ramp:0.35:1").unwrap(),
        TransferFunction::parse("ramp:0.1:1").unwrap(),
    );
    let gv = GpuVolume::upload(&ctx, &volume).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let b = builder(&ctx);
    let renderer = Renderer::new(&ctx).unwrap();
    let desc = FrameDesc::builder(32, 32).build().unwrap();
    for name in ["grid", "distance", "kd-cpu", "lbvh", "auto"] {
        let a = accel(name);
        let (ranges, _) = b.ranges_for(&[(a, &a.defaults())], &gv).unwrap();
        let (s, _) = b
            .build(
                a,
                &input(&volume, &gv, &tf, &lut, Mode::Composite),
                &ranges,
                &a.defaults(),
            )
            .unwrap();
        let render = |s: &Structure, gv: &GpuVolume, lut| {
            renderer.render(
                Scene {
                    structure: s,
                    volume: gv,
                    tf: lut,
                },
                &desc,
            )
        };
        // The same transfer function uploaded again is the same one.
        let again = tf.upload(&ctx).unwrap();
        let naive = frame(&renderer, &Structure::naive(), &gv, &again, &desc);
        assert_eq!(render(&s, &gv, &again).unwrap().0.pixels, naive.pixels, "{name}");
        let lut2 = tf2.upload(&ctx).unwrap();
        let e = error(render(&s, &gv, &lut2));
        assert!(e.contains("built for other opacities"), "{name}: {e}");
        // Other texels on the same grid: another upload, or a series step
        // put in this one's memory.
        let gv2 = GpuVolume::upload(&ctx, &other).unwrap();
        let e = error(render(&s, &gv2, &lut));
        assert!(e.contains("built over other texels"), "{name}: {e}");
        let mut stepped = GpuVolume::upload(&ctx, &volume).unwrap();
        let (ranges, _) = b.ranges_for(&[(a, &a.defaults())], &stepped).unwrap();
        let (s2, _) = b
            .build(
                a,
                &input(&volume, &stepped, &tf, &lut, Mode::Composite),
                &ranges,
                &a.defaults(),
            )
            .unwrap();
        assert!(render(&s2, &stepped, &lut).is_ok());
        assert!(stepped.replace(&other, Some(&volume)).unwrap());
        let e = error(render(&s2, &stepped, &lut));
        assert!(e.contains("built over other texels"), "{name} after replace: {e}");
        // The step's ranges are the ranges before: refused at the build.
        let e = error(b.build(
            a,
            &input(&other, &stepped, &tf, &lut, Mode::Composite),
            &ranges,
            &a.defaults(),
        ));
        assert!(
            e.contains("invalid ranges 'of another upload or series step'"),
            "{name}: {e}"
        );
    }
    // Naive skips nothing: any texels, any transfer function.
    let gv2 = GpuVolume::upload(&ctx, &other).unwrap();
    let lut2 = tf2.upload(&ctx).unwrap();
    frame(&renderer, &Structure::naive(), &gv2, &lut2, &desc);
}

#[test]
fn a_build_refuses_disagreeing_inputs_and_names_iso_values() {
    let ctx = gpu();
    let volume = Volume::load("nbody:16", &Default::default()).unwrap();
    let small = Volume::load("nbody:8", &Default::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.35:1").unwrap();
    let gv = GpuVolume::upload(&ctx, &volume).unwrap();
    let gv_small = GpuVolume::upload(&ctx, &small).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let b = builder(&ctx);
    let a = accel("grid");
    let (small_ranges, _) = b.ranges_for(&[(a, &a.defaults())], &gv_small).unwrap();
    let e = error(b.build(
        a,
        &input(&volume, &gv, &tf, &lut, Mode::Composite),
        &small_ranges,
        &a.defaults(),
    ));
    assert!(e.contains("invalid ranges"), "{e}");
    // The host transfer function classifies; the uploaded one must be it.
    let (ranges, _) = b.ranges_for(&[(a, &a.defaults())], &gv).unwrap();
    let other = TransferFunction::parse("band:0.2:0.4").unwrap();
    let e = error(b.build(
        a,
        &input(&volume, &gv, &other, &lut, Mode::Composite),
        &ranges,
        &a.defaults(),
    ));
    assert!(
        e.contains("is not the transfer function gpu_tf was uploaded from"),
        "{e}"
    );
    // A structure for iso 0.3 at iso 0.5 names the values.
    let iso = |v: f32| Mode::Iso(Iso::new(&[v]).unwrap());
    let (s, _) = b
        .build(a, &input(&volume, &gv, &tf, &lut, iso(0.3)), &ranges, &a.defaults())
        .unwrap();
    let mut gv = gv;
    gv.prepare(&volume, true, None).unwrap();
    let desc = FrameDesc::builder(16, 16).mode(iso(0.5)).build().unwrap();
    let e = error(Renderer::new(&ctx).unwrap().render(
        Scene {
            structure: &s,
            volume: &gv,
            tf: &lut,
        },
        &desc,
    ));
    assert!(e.contains("built for iso values 0.3: build it for the frame's"), "{e}");
    // Iso values classify, not the transfer function: another one renders.
    let lut2 = TransferFunction::parse("band:0.1:0.2").unwrap().upload(&ctx).unwrap();
    let at = FrameDesc::builder(16, 16).mode(iso(0.3)).build().unwrap();
    let renderer = Renderer::new(&ctx).unwrap();
    let with = |lut| frame(&renderer, &s, &gv, lut, &at);
    let naive = frame(&renderer, &Structure::naive(), &gv, &lut2, &at);
    assert_eq!(with(&lut2).pixels, naive.pixels);
}

#[test]
fn objects_of_another_context_are_refused_before_anything_is_recorded() {
    let (ctx, other) = (gpu(), crate::common::fresh_gpu());
    let volume = Volume::load("nbody:8", &Default::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.35:1").unwrap();
    let (gv, lut) = (GpuVolume::upload(&ctx, &volume).unwrap(), tf.upload(&ctx).unwrap());
    let (gv_other, lut_other) = (GpuVolume::upload(&other, &volume).unwrap(), tf.upload(&other).unwrap());
    let renderer = Renderer::new(&ctx).unwrap();
    let desc = FrameDesc::builder(16, 16).build().unwrap();
    let naive = Structure::naive();
    let render = |gv, lut, s| {
        error(renderer.render(
            Scene {
                structure: s,
                volume: gv,
                tf: lut,
            },
            &desc,
        ))
    };
    assert!(render(&gv_other, &lut, &naive).contains("invalid volume 'of another lacuna Context'"));
    assert!(render(&gv, &lut_other, &naive).contains("invalid transfer function 'of another lacuna Context'"));
    let b_other = builder(&other);
    let a = accel("grid");
    let (ranges, _) = b_other.ranges_for(&[(a, &a.defaults())], &gv_other).unwrap();
    let (s_other, _) = b_other
        .build(
            a,
            &input(&volume, &gv_other, &tf, &lut_other, Mode::Composite),
            &ranges,
            &a.defaults(),
        )
        .unwrap();
    assert!(render(&gv, &lut, &s_other).contains("invalid structure 'of another lacuna Context'"));
    let e = error(b_other.build(
        a,
        &input(&volume, &gv, &tf, &lut, Mode::Composite),
        &ranges,
        &a.defaults(),
    ));
    assert!(e.contains("invalid volume 'of another lacuna Context'"), "{e}");
    // A command buffer of the other context, given to this one's renderer,
    // builder or timer: refused, nothing of this context recorded into it.
    let target = RenderTarget::new(&ctx, 16, 16).unwrap();
    let scene = Scene {
        structure: &naive,
        volume: &gv,
        tf: &lut,
    };
    let e = error(other.submit_and_wait(|cmd| renderer.record(cmd, None, &target, scene, &desc, Output::Buffer)));
    assert!(e.contains("invalid command buffer 'of another lacuna Context'"), "{e}");
    let e = error(other.submit_and_wait(|cmd| renderer.record_readback(cmd, &target)));
    assert!(e.contains("invalid command buffer 'of another lacuna Context'"), "{e}");
    let b = builder(&ctx);
    let kinds = [a.method().ranges(&a.defaults()).unwrap()];
    let e = error(other.submit_and_wait(|cmd| b.record_ranges(cmd, None, &kinds, &gv)));
    assert!(e.contains("invalid command buffer 'of another lacuna Context'"), "{e}");
    let mut timer = Timer::new(&ctx, 1).unwrap();
    let e = error(other.submit_and_wait(|cmd| {
        timer.reset(cmd);
        timer.begin(cmd, "march")
    }));
    assert!(
        e.contains("invalid timer's command buffer 'of another lacuna Context'"),
        "{e}"
    );
    // Reset into the other's and begun in its own: its queries were never reset.
    ctx.submit_and_wait(|own| {
        other.submit_and_wait(|cmd| {
            timer.reset(cmd);
            Ok(())
        })?;
        let e = error(timer.begin(own, "march"));
        assert!(e.contains("last reset went to another lacuna Context's"), "{e}");
        Ok(())
    })
    .unwrap();
    crate::common::assert_clean(&other);
    crate::common::assert_clean(&ctx);
}

/// Objects dropped in a submission's closure, while the commands that use
/// them are still to run, live until the submission completed: safe code
/// cannot free what a command is about to read.
#[test]
fn objects_dropped_while_recorded_live_until_their_commands_ran() {
    let ctx = gpu();
    let words: Vec<u32> = (0..4096u32).map(|i| i.wrapping_mul(2654435761)).collect();
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
    let buffer = ctx
        .submit_and_wait(|cmd| {
            let (buffer, staging) = Buffer::record_with_data(cmd, "copied", bytemuck::cast_slice(&words), usage)?;
            drop(staging);
            Ok(buffer)
        })
        .unwrap();
    let got: Vec<u32> = bytemuck::pod_collect_to_vec(&buffer.download(0, 4096 * 4).unwrap());
    assert_eq!(got, words);
    // A volume uploaded and dropped with its staging in the closure, and
    // one kept: the kept one renders as a volume uploaded the usual way.
    let volume = Volume::load("nbody:16", &Default::default()).unwrap();
    let kept = ctx
        .submit_and_wait(|cmd| {
            drop(GpuVolume::record_upload(cmd, &volume)?);
            let (kept, staging) = GpuVolume::record_upload(cmd, &volume)?;
            drop(staging);
            Ok(kept)
        })
        .unwrap();
    let tf = TransferFunction::parse("ramp:0.35:1").unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let renderer = Renderer::new(&ctx).unwrap();
    let desc = FrameDesc::builder(32, 32).build().unwrap();
    let usual = GpuVolume::upload(&ctx, &volume).unwrap();
    let [a, b] = [&kept, &usual].map(|gv| frame(&renderer, &Structure::naive(), gv, &lut, &desc));
    assert_eq!(a.pixels, b.pixels);
    assert!(a.pixels.iter().any(|p| p[3] > 0.0), "the volume shows");
    crate::common::assert_clean(&ctx);
}

#[test]
fn a_submission_inside_a_recording_closure_is_an_error_not_a_hang() {
    let (inside, after) = on_a_fresh_context_within_a_minute("a submission from a recording closure", |ctx| {
        let tf = TransferFunction::parse("ramp:0.35:1").unwrap();
        let inside = ctx.submit_and_wait(|_| tf.upload(ctx).map(|_| ()));
        let after = tf.upload(ctx).map(|_| ());
        (inside.map_err(|e| e.to_string()), after.is_ok())
    });
    let e = inside.expect_err("a submission inside a recording closure");
    assert!(e.contains("inside another's recording closure"), "{e}");
    assert!(after, "submissions work again after it");
}

/// `Volume`, `Frame` and `Rays` have public fields: values that disagree
/// are errors where they are used, not panics or frames from nowhere.
#[test]
fn public_fields_that_disagree_are_errors() {
    let ctx = gpu();
    let volume = Volume::load("nbody:8", &Default::default()).unwrap();
    let mut short = volume.clone();
    short.data = lacuna::volume::VoxelData::U8(vec![0; 100]);
    let e = error(GpuVolume::upload(&ctx, &short));
    assert!(e.contains("channel 1 holds 100 voxels on a 8x8x8 grid"), "{e}");
    let mut nan = volume.clone();
    nan.spacing[1] = f32::NAN;
    let e = error(GpuVolume::upload(&ctx, &nan));
    assert!(e.starts_with("invalid spacing") && e.contains("finite and > 0"), "{e}");
    let mut frame = lacuna::frame::Frame::new(2, 2, vec![[0.0; 4]; 4]);
    frame.pixels.pop();
    let dir = tempfile::tempdir().unwrap();
    let e = error(frame.write_exr(&dir.path().join("f.exr")));
    assert!(e.contains("holds 3 pixels and 4 depths where its size needs 4"), "{e}");
    assert!(error(lacuna::frame::diff(&frame, &frame)).contains("holds 3 pixels"));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    let still = lacuna::render::Rays::orthographic([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3]);
    let e = error(
        FrameDesc::builder(4, 4)
            .camera(lacuna::render::Camera::Rays(still))
            .build(),
    );
    assert!(e.contains("an orthographic direction must not be zero"), "{e}");
}

#[test]
fn a_recording_closure_may_wait_for_another_threads_submission() {
    // Before, the closure held the context's one command pool through the
    // wait, and the other thread's upload waited for it: neither returned.
    let uploaded = on_a_fresh_context_within_a_minute("a closure waiting for another thread's submission", |ctx| {
        let tf = TransferFunction::parse("ramp:0.35:1").unwrap();
        let uploaded = ctx.submit_and_wait(|cmd| {
            let lut = std::thread::scope(|s| s.spawn(|| tf.upload(ctx)).join().unwrap())?;
            cmd.compute_to_compute();
            Ok(lut)
        });
        uploaded.map(|lut| lut.channels()).map_err(|e| e.to_string())
    });
    assert_eq!(uploaded, Ok(1), "the other thread's upload");
}

#[test]
fn an_object_waits_only_for_the_submissions_in_flight_when_it_was_dropped() {
    // Before, a dropped object waited until no submission of lacuna's was
    // open at all, so under overlapping submissions from several threads
    // they piled up.
    let (while_first, while_second) = on_a_fresh_context_within_a_minute("two overlapping submissions", |ctx| {
        let usage = lacuna::gpu::vk::BufferUsageFlags::STORAGE_BUFFER;
        let (opened, dropped) = (std::sync::Barrier::new(2), std::sync::Barrier::new(2));
        std::thread::scope(|s| {
            let first = s.spawn(|| {
                ctx.submit_and_wait(|cmd| {
                    opened.wait();
                    dropped.wait();
                    cmd.compute_to_compute();
                    Ok(())
                })
            });
            opened.wait();
            let b = lacuna::gpu::Buffer::new(ctx, "dropped", 64, usage, lacuna::gpu::MemoryLocation::GpuOnly).unwrap();
            drop(b);
            let while_first = ctx.retired_waiting();
            // A second submission opens after the drop and stays open while
            // the first runs to its end.
            let while_second = ctx
                .submit_and_wait(|cmd| {
                    dropped.wait();
                    first.join().unwrap()?;
                    cmd.compute_to_compute();
                    Ok(ctx.retired_waiting())
                })
                .unwrap();
            (while_first, while_second)
        })
    });
    assert_eq!(while_first, 1, "the buffer waits for the submission it may be in");
    assert_eq!(
        while_second, 0,
        "destroyed once that one completed, the second still open"
    );
}

/// Runs `f` on a context of its own, in a thread: were it to hang, the test
/// fails after a minute and leaves the shared contexts alone. It fails on
/// any validation message too.
fn on_a_fresh_context_within_a_minute<T: Send + 'static>(
    what: &str,
    f: impl FnOnce(&lacuna::gpu::Context) -> T + Send + 'static,
) -> T {
    let (sent, got) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let ctx = crate::common::fresh_gpu();
        let value = f(&ctx);
        sent.send((value, ctx.take_validation_messages().len())).unwrap();
    });
    let (value, messages) = got
        .recv_timeout(std::time::Duration::from_secs(60))
        .unwrap_or_else(|e| panic!("{what}: hung or failed ({e})"));
    assert_eq!(messages, 0, "{what}: validation messages");
    value
}

#[test]
fn concurrent_submissions_from_several_threads_keep_their_data_and_free_what_they_drop() {
    let (whole, waiting) = on_a_fresh_context_within_a_minute("concurrent submissions", |ctx| {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let region = [vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: 4096,
        }];
        let whole = std::thread::scope(|s| {
            let threads: Vec<_> = (0..4u32)
                .map(|t| {
                    s.spawn(move || {
                        (0..15u32).all(|i| {
                            let words: Vec<u32> = (0..1024u32).map(|k| k ^ (t << 24) ^ (i << 12)).collect();
                            let bytes: &[u8] = bytemuck::cast_slice(&words);
                            let a = Buffer::with_data(ctx, "a", bytes, usage).unwrap();
                            // Staging and a copy target dropped in the closure,
                            // the copy source after it.
                            let b = ctx
                                .submit_and_wait(|cmd| {
                                    let (b, staging) = Buffer::record_with_data(cmd, "b", bytes, usage)?;
                                    drop(staging);
                                    let c = Buffer::upload_target(ctx, "c", 4096, usage)?;
                                    cmd.copy_buffer(&a, &c, &region)?;
                                    drop(c);
                                    Ok(b)
                                })
                                .unwrap();
                            drop(a);
                            b.download(0, 4096).unwrap() == bytes
                        })
                    })
                })
                .collect();
            threads.into_iter().all(|h| h.join().unwrap())
        });
        (whole, ctx.retired_waiting())
    });
    assert!(whole, "every thread's buffers hold what it uploaded");
    assert_eq!(waiting, 0, "everything dropped is destroyed once all submissions ended");
}

#[test]
fn structures_built_on_loader_threads_render_from_other_threads_as_naive() {
    fn send_and_share<T: Send + Sync>(_: &T) {}
    let ctx = gpu();
    let volume = Volume::load("vessels:24", &Default::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.3:1").unwrap();
    let gv = GpuVolume::upload(&ctx, &volume).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let b = builder(&ctx);
    let renderer = Renderer::new(&ctx).unwrap();
    let desc = FrameDesc::builder(32, 32).build().unwrap();
    let names = ["kd-cpu", "lbvh", "distance-octant", "auto"];
    // Each structure built on a thread of its own, as a loader would, and
    // handed back.
    let structures: Vec<Structure> = std::thread::scope(|s| {
        let loaders: Vec<_> = names
            .iter()
            .map(|name| {
                let (b, volume, gv, tf, lut) = (&b, &volume, &gv, &tf, &lut);
                s.spawn(move || {
                    let a = accel(name);
                    let (ranges, _) = b.ranges_for(&[(a, &a.defaults())], gv).unwrap();
                    let input = input(volume, gv, tf, lut, Mode::Composite);
                    b.build(a, &input, &ranges, &a.defaults()).unwrap().0
                })
            })
            .collect();
        loaders.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let naive = frame(&renderer, &Structure::naive(), &gv, &lut, &desc);
    assert!(naive.pixels.iter().any(|p| p[3] > 0.0), "an empty frame");
    // Each marched from a thread of its own, all sharing the structures.
    let frames: Vec<_> = std::thread::scope(|s| {
        let renders: Vec<_> = structures
            .iter()
            .map(|structure| {
                send_and_share(structure);
                let (renderer, gv, lut, desc) = (&renderer, &gv, &lut, &desc);
                s.spawn(move || frame(renderer, structure, gv, lut, desc))
            })
            .collect();
        renders.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for (name, f) in names.iter().zip(&frames) {
        assert_eq!(f.pixels, naive.pixels, "{name}");
    }
    crate::common::assert_clean(&ctx);
}
