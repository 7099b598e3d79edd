//! Shared test helpers: every GPU context runs with validation and
//! synchronization validation, and tests fail on any message.
#![allow(dead_code)]

use lacuna::gpu::{Context, ContextOptions};
use lacuna::render::{Accel, Frame, RenderSettings, Renderer};
use lacuna::volume::GpuVolume;
use lacuna::{TransferFunction, Volume};

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
        messages
            .iter()
            .map(|m| m.to_string())
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// Renders on the GPU with validation, asserting no validation message.
pub fn render(
    ctx: &Context,
    volume: &Volume,
    tf: &TransferFunction,
    settings: &RenderSettings,
    accel: Accel,
) -> Frame {
    let renderer = Renderer::new(ctx).unwrap();
    let gv = GpuVolume::upload(ctx, volume).unwrap();
    let lut = tf.upload(ctx).unwrap();
    let (frame, _) = renderer.render(accel, &gv, &lut, settings).unwrap();
    assert_clean(ctx);
    frame
}

/// Per-channel max abs difference.
pub fn max_abs(a: &Frame, b: &Frame) -> f64 {
    lacuna::render::diff(a, b).unwrap().max_abs
}
