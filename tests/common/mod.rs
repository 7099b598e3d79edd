//! Shared test helpers: every GPU context runs with validation and
//! synchronization validation, and tests fail on any message.
#![allow(dead_code)]

use lacuna::accel::{Accel, BuildInput, Builder, Params, Structure};
use lacuna::frame::Frame;
use lacuna::gpu::{Context, ContextOptions};
use lacuna::render::{FrameDesc, Renderer, Scene};
use lacuna::volume::GpuVolume;
use lacuna::{TransferFunction, Volume};
use std::process::Command;

/// A validated context (LACUNA_DEVICE still selects the device).
pub fn gpu() -> Context {
    Context::new(&ContextOptions {
        validation: true,
        device: None,
    })
    .expect("validated Vulkan context (lavapipe + vulkan-validationlayers)")
}

/// Panics with every validation message collected so far.
pub fn assert_clean(ctx: &Context) {
    let messages = ctx.take_validation_messages();
    assert!(
        messages.is_empty(),
        "{} validation message(s):\n{}",
        messages.len(),
        messages.iter().map(|m| m.to_string()).collect::<Vec<_>>().join("\n")
    );
}

/// Renders on the GPU with validation, asserting no validation message.
pub fn render(ctx: &Context, volume: &Volume, tf: &TransferFunction, desc: &FrameDesc, accel: Accel) -> Frame {
    render_with(ctx, volume, tf, desc, accel, &accel.defaults())
}

/// As `render`, with the structure's parameters.
pub fn render_with(
    ctx: &Context,
    volume: &Volume,
    tf: &TransferFunction,
    desc: &FrameDesc,
    accel: Accel,
    params: &Params,
) -> Frame {
    let renderer = Renderer::new(ctx).unwrap();
    let gv = GpuVolume::upload(ctx, volume).unwrap();
    let lut = tf.upload(ctx).unwrap();
    let builder = Builder::new(ctx).unwrap();
    let (ranges, _) = builder.ranges_for(&[(accel, params)], &gv).unwrap();
    let input = BuildInput {
        volume,
        gpu_volume: &gv,
        tf,
        gpu_tf: &lut,
    };
    let (structure, _) = builder.build(accel, &input, &ranges, params).unwrap();
    let scene = Scene {
        structure: &structure,
        volume: &gv,
        tf: &lut,
    };
    let (frame, _) = renderer.render(scene, desc).unwrap();
    assert_clean(ctx);
    frame
}

/// Renders `structure` (built for `lut` over `gv`) with `desc`.
pub fn frame(
    renderer: &Renderer,
    structure: &Structure,
    gv: &GpuVolume,
    lut: &lacuna::tf::GpuTransferFunction,
    desc: &FrameDesc,
) -> Frame {
    let scene = Scene {
        structure,
        volume: gv,
        tf: lut,
    };
    renderer.render(scene, desc).unwrap().0
}

/// Per-channel max abs difference.
pub fn max_abs(a: &Frame, b: &Frame) -> f64 {
    lacuna::frame::diff(a, b).unwrap().max_abs
}

/// The registry entry named `name`.
pub fn accel(name: &str) -> Accel {
    name.parse().unwrap()
}

/// What a run of the `lacuna` binary printed and returned.
pub struct Run {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

pub fn lacuna(args: &[&str], env: &[(&str, &str)]) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lacuna"));
    cmd.args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().unwrap();
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into(),
        stderr: String::from_utf8_lossy(&out.stderr).into(),
    }
}
