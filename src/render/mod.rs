//! Rendering: camera, settings, the marcher dispatch and readback, and the
//! CPU reference marcher. Frames and their files live in `crate::frame`.

mod camera;
mod marcher;
mod params;
pub mod reference;
mod settings;

pub use crate::volume::Filter;
pub use camera::{Camera, Projection};
pub use marcher::{RenderTarget, Renderer};
pub use params::{RenderParams, ERT_OFF};
pub use settings::{parse_size, RenderSettings};
