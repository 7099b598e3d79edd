//! Rendering: camera, settings, the marcher dispatch, readback, EXR frames,
//! frame diffs, and the CPU reference marcher.

mod camera;
pub mod diff;
mod frame;
mod marcher;
mod params;
pub mod reference;
mod settings;

pub use crate::accel::Accel;
pub use camera::{Camera, Projection};
pub use diff::{diff, DiffStats};
pub use frame::{write_atomically, Frame};
pub use marcher::{RenderTarget, Renderer};
pub use params::{RenderParams, ERT_OFF};
pub use settings::{parse_size, RenderSettings};
