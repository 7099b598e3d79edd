//! PNG output: 8-bit sRGB-encoded RGBA with straight (unassociated) alpha,
//! row 0 at the top as in the EXR.
//!
//! A frame is linear and premultiplied; PNG defines its colour samples as not
//! premultiplied by alpha, and every viewer composites them over its own
//! background on that assumption. So each pixel's colour is divided by its
//! alpha (clamped to [0, 1]; black where alpha is 0), then sRGB-encoded,
//! and alpha is kept linear: a viewer shows the volume over its checkerboard
//! or page colour exactly as the EXR composited over that colour would look
//! (to 8-bit precision). Writing the premultiplied colour with alpha would
//! darken every semi-transparent pixel; flattening over black would lose
//! alpha. The frame's metadata goes into iTXt chunks (`lacuna.volume`, ...).

use super::{write_atomically, Frame};
use crate::error::{Error, Result};
use std::path::Path;

/// The sRGB encoding (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// A linear premultiplied pixel as 8-bit sRGB colour with straight alpha,
/// as `Frame::write_png` writes it. Non-finite channels count as 0.
pub fn srgba8(pixel: [f32; 4]) -> [u8; 4] {
    let finite = |v: f32| if v.is_finite() { v } else { 0.0 };
    let alpha = finite(pixel[3]).clamp(0.0, 1.0);
    if alpha == 0.0 {
        return [0; 4];
    }
    let quantise = |v: f32| (v * 255.0 + 0.5) as u8;
    let colour = |c: f32| quantise(srgb_encode((finite(c) / alpha).clamp(0.0, 1.0)));
    [colour(pixel[0]), colour(pixel[1]), colour(pixel[2]), quantise(alpha)]
}

impl Frame {
    /// Writes the frame as an 8-bit sRGB RGBA PNG with straight alpha (see
    /// the module documentation), atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        let data: Vec<u8> = self.pixels.iter().flat_map(|&p| srgba8(p)).collect();
        let text: Vec<(String, String)> = self
            .metadata
            .iter()
            .map(|(k, v)| (format!("{}{k}", super::exr::PREFIX), v.clone()))
            .collect();
        write_png8(path, self.width, self.height, ::png::ColorType::Rgba, &data, &text)
    }
}

/// Writes 8-bit `data` (rows top to bottom) as a PNG marked sRGB, with
/// `text` as iTXt chunks, through a temporary file. It is encoded in memory
/// first, so every write error (a full disk too) is reported.
pub(crate) fn write_png8(
    path: &Path,
    width: u32,
    height: u32,
    color: ::png::ColorType,
    data: &[u8],
    text: &[(String, String)],
) -> Result<()> {
    let format = |e: ::png::EncodingError| Error::format(path, format!("cannot write PNG: {e}"));
    let mut bytes = Vec::new();
    let mut encoder = ::png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(color);
    encoder.set_depth(::png::BitDepth::Eight);
    encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
    for (k, v) in text {
        encoder.add_itxt_chunk(k.clone(), v.clone()).map_err(format)?;
    }
    let mut writer = encoder.write_header().map_err(format)?;
    writer.write_image_data(data).map_err(format)?;
    writer.finish().map_err(format)?;
    write_atomically(path, |tmp| std::fs::write(tmp, &bytes).map_err(|e| Error::io(path, e)))
}
