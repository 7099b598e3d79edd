//! Frames and files: the `Frame` type with its OpenEXR reading and writing
//! and PNG writing, frame diffs, and atomic writes (a temporary name, then a rename, so no
//! partial file is ever left). Used by render, octree, scene and bench.

mod atomic;
pub mod diff;
mod exr;
mod png;

pub use atomic::{check_parent, write_atomically};
pub use diff::{diff, DiffStats};
pub use exr::Frame;
pub use png::{srgb8_over, srgb_decode, srgb_encode, srgba8, Background};

use crate::error::{Error, Result};
use std::path::Path;

/// The file formats a frame is written in, chosen by file name extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameFormat {
    /// `.exr`: RGBA f32, linear, premultiplied, with metadata (`Frame::write_exr`).
    Exr,
    /// `.png`: 8-bit sRGB RGBA, straight alpha, with metadata (`Frame::write_png`).
    Png,
}

impl FrameFormat {
    /// The format named by `path`'s extension (`.exr` or `.png`, any case).
    pub fn from_path(path: &Path) -> Result<Self> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("exr") => Ok(FrameFormat::Exr),
            Some("png") => Ok(FrameFormat::Png),
            _ => Err(Error::invalid(
                "frame output",
                path.display().to_string(),
                "expected a .exr (RGBA f32) or .png (8-bit sRGB) file name",
            )),
        }
    }
}

impl Frame {
    /// Writes the frame in `format`, atomically.
    pub fn write(&self, path: &Path, format: FrameFormat) -> Result<()> {
        match format {
            FrameFormat::Exr => self.write_exr(path),
            FrameFormat::Png => self.write_png(path),
        }
    }
}
