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
//!
//! With a `Background` the frame is instead composited over that colour in
//! linear light (`c + (1 - a) * bg`, the over operator on premultiplied
//! colour) and written opaque as 8-bit sRGB RGB.

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

/// The sRGB decoding (IEC 61966-2-1) of an encoded value in [0, 1].
pub fn srgb_decode(encoded: f32) -> f32 {
    if encoded <= 0.040_45 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// An opaque colour to composite a frame over, given as sRGB hex
/// (`RRGGBB`, optionally `#RRGGBB`, as in CSS) and kept linear.
#[derive(Clone, Debug, PartialEq)]
pub struct Background {
    /// The colour as given.
    pub spec: String,
    /// Linear RGB in [0, 1].
    pub linear: [f32; 3],
}

impl std::str::FromStr for Background {
    type Err = Error;

    fn from_str(spec: &str) -> Result<Self> {
        let hex = spec.strip_prefix('#').unwrap_or(spec);
        let bad = || Error::invalid("background", spec, "expected an sRGB colour RRGGBB in hex, e.g. 1a1a1a");
        if hex.len() != 6 || !hex.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(bad());
        }
        let channel = |i: usize| u8::from_str_radix(&hex[2 * i..2 * i + 2], 16).map_err(|_| bad());
        let linear = [channel(0)?, channel(1)?, channel(2)?].map(|c| srgb_decode(f32::from(c) / 255.0));
        Ok(Background {
            spec: spec.to_string(),
            linear,
        })
    }
}

/// A linear premultiplied pixel composited over `background` (linear) and
/// sRGB-encoded to 8 bits. Non-finite channels count as 0.
pub fn srgb8_over(pixel: [f32; 4], background: [f32; 3]) -> [u8; 3] {
    let finite = |v: f32| if v.is_finite() { v } else { 0.0 };
    let alpha = finite(pixel[3]).clamp(0.0, 1.0);
    let over = |c: usize| (finite(pixel[c]) + (1.0 - alpha) * background[c]).clamp(0.0, 1.0);
    [0, 1, 2].map(|c| (srgb_encode(over(c)) * 255.0 + 0.5) as u8)
}

impl Frame {
    /// Writes the frame composited over `background` as an opaque 8-bit
    /// sRGB RGB PNG, atomically.
    pub fn write_png_over(&self, path: &Path, background: &Background) -> Result<()> {
        self.check()?;
        let data: Vec<u8> = self
            .pixels
            .iter()
            .flat_map(|&p| srgb8_over(p, background.linear))
            .collect();
        write_png8(
            path,
            self.width,
            self.height,
            ::png::ColorType::Rgb,
            &data,
            &self.png_text(),
        )
    }

    /// The frame's metadata as PNG text chunks.
    fn png_text(&self) -> Vec<(String, String)> {
        self.metadata
            .iter()
            .map(|(k, v)| (format!("{}{k}", super::PREFIX), v.clone()))
            .collect()
    }

    /// Writes the frame as an 8-bit sRGB RGBA PNG with straight alpha (see
    /// the module documentation), atomically.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        self.check()?;
        let data: Vec<u8> = self.pixels.iter().flat_map(|&p| srgba8(p)).collect();
        write_png8(
            path,
            self.width,
            self.height,
            ::png::ColorType::Rgba,
            &data,
            &self.png_text(),
        )
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
