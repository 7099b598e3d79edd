//! Rendering: cameras (orbit, or a host's matrices), typed march inputs, settings, the marcher dispatch and readback, and the
//! CPU reference marcher. Frames and their files live in `crate::frame`.

mod camera;
mod marcher;
mod matrices;
mod params;
pub mod reference;
mod settings;
mod target;
mod view;

pub use crate::volume::Filter;
pub use camera::{Camera, Projection};
pub use marcher::{Renderer, Scene};
pub use matrices::{orthographic, perspective, CameraMatrices};
pub use params::{RenderParams, ERT_OFF};
pub use settings::{parse_size, RenderSettings};
pub use target::{HostDepth, HostImage, Output, RenderTarget};
pub use view::View;
