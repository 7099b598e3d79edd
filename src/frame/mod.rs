//! Frames and files: the `Frame` type, its OpenEXR reading and writing and
//! PNG writing (feature `frames`), frame diffs, and atomic writes (a
//! temporary name, then a rename, so no partial file is ever left). Used by
//! render, octree, scene and bench.

mod atomic;
pub mod diff;
#[cfg(feature = "frames")]
mod exr;
#[cfg(feature = "frames")]
mod png;

pub use atomic::{check_parent, write_atomically};
pub use diff::{diff, DiffStats};
#[cfg(feature = "frames")]
pub use png::{srgb8_over, srgb_decode, srgb_encode, srgba8, Background};

#[cfg(feature = "frames")]
use crate::error::{Error, Result};
use std::collections::BTreeMap;
#[cfg(feature = "frames")]
use std::path::Path;

/// The prefix of lacuna's metadata keys in frame files.
#[cfg(feature = "frames")]
const PREFIX: &str = "lacuna.";

/// RGBA f32, linear, premultiplied alpha, row 0 at the top, with metadata
/// that says what made it.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
    /// Attribute name (without the `lacuna.` prefix) to value.
    pub metadata: BTreeMap<String, String>,
    /// Per pixel, an iso frame's surface depth (`render::HostDepthOut` says
    /// what it holds), or a segment's MIP/MinIP ray value
    /// (`FrameDesc::writes_ray_values`); an EXR's `Z` channel.
    pub depth: Option<Vec<f32>>,
}

impl Frame {
    /// A frame of `pixels`, row-major.
    ///
    /// # Panics
    /// When `pixels` does not hold `width x height` pixels (a caller's
    /// programming error; frames read from files are checked as they are
    /// decoded).
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 4]>) -> Self {
        assert_eq!(pixels.len(), width as usize * height as usize);
        Frame {
            width,
            height,
            pixels,
            metadata: BTreeMap::new(),
            depth: None,
        }
    }

    /// Its fields agree (they are public): `width x height` pixels, and
    /// as many depths where it has them. Writing a frame checks it first.
    pub fn check(&self) -> crate::error::Result<()> {
        let n = self.width as usize * self.height as usize;
        let depths = self.depth.as_ref().map_or(n, Vec::len);
        if self.pixels.len() != n || depths != n {
            return Err(crate::error::Error::invalid(
                "frame",
                format!("{}x{}", self.width, self.height),
                format!(
                    "holds {} pixels and {depths} depths where its size needs {n}",
                    self.pixels.len()
                ),
            ));
        }
        Ok(())
    }

    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// The file formats a frame is written in, chosen by file name extension.
#[cfg(feature = "frames")]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameFormat {
    /// `.exr`: RGBA f32, linear, premultiplied, with metadata (`Frame::write_exr`).
    Exr,
    /// `.png`: 8-bit sRGB RGBA, straight alpha, with metadata (`Frame::write_png`).
    Png,
}

#[cfg(feature = "frames")]
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

#[cfg(feature = "frames")]
impl Frame {
    /// Writes the frame in `format`, atomically.
    pub fn write(&self, path: &Path, format: FrameFormat) -> Result<()> {
        match format {
            FrameFormat::Exr => self.write_exr(path),
            FrameFormat::Png => self.write_png(path),
        }
    }
}
