//! Rendering: the march kernels and their dispatch (`Renderer`), where a
//! frame goes (`RenderTarget`, host images), and the CPU reference marcher.
//! What a frame is lives in `crate::desc` (re-exported here); frames and
//! their files in `crate::frame`.

mod marcher;
pub mod metadata;
mod mix;
pub mod reference;
mod target;

pub use crate::desc::{
    orthographic, parse_size, perspective, Camera, CameraMatrices, Clip, Filter, FrameBuilder, FrameDesc, HostDepth,
    Iso, Light, LookSpec, Mode, Octants, Orbit, Projection, Rays, Shading, DEFAULT_STEP, ERT_OFF, MAX_CLIP,
};
pub use crate::gpu::shaders::blocks::RenderParams;
pub use marcher::{Band, Renderer, Scene};
pub use target::{HostDepthOut, HostImage, Output, RenderTarget};
