//! OpenEXR frames: RGBA f32 with lacuna's metadata as text attributes
//! (`lacuna.*`).

use super::{write_atomically, Frame, PREFIX};
use crate::error::Result;
use std::collections::BTreeMap;
use std::path::Path;

/// Writes `channels` of a `size` frame with `frame`'s metadata to `path`,
/// atomically (a macro: each channel list is its own type).
macro_rules! write_layer {
    ($frame:expr, $path:expr, $size:expr, $channels:expr) => {{
        use exr::prelude::*;
        let layer = Layer::new(
            $size,
            LayerAttributes::named("lacuna"),
            Encoding::SMALL_LOSSLESS,
            $channels,
        );
        let mut image = Image::from_layer(layer);
        for (k, v) in &$frame.metadata {
            image.attributes.other.insert(
                Text::from(format!("{PREFIX}{k}").as_str()),
                AttributeValue::Text(Text::from(v.as_str())),
            );
        }
        write_atomically($path, |tmp| {
            image.write().to_file(tmp).map_err(|e| match e {
                exr::error::Error::Io(io) => crate::Error::io($path, io),
                other => crate::Error::format($path, format!("cannot write EXR: {other}")),
            })
        })
    }};
}

impl Frame {
    /// Writes RGBA (and `Z` when the frame has depth) as f32, with the
    /// metadata, atomically.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        use exr::prelude::*;
        self.check()?;
        let (w, h) = (self.width as usize, self.height as usize);
        let pixels = &self.pixels;
        match &self.depth {
            None => {
                let channels = SpecificChannels::rgba(|p: Vec2<usize>| {
                    let c = pixels[p.y() * w + p.x()];
                    (c[0], c[1], c[2], c[3])
                });
                write_layer!(self, path, (w, h), channels)
            }
            Some(depth) => {
                let channels = SpecificChannels::build()
                    .with_channel("R")
                    .with_channel("G")
                    .with_channel("B")
                    .with_channel("A")
                    .with_channel("Z")
                    .with_pixel_fn(|p: Vec2<usize>| {
                        let i = p.y() * w + p.x();
                        let c = pixels[i];
                        (c[0], c[1], c[2], c[3], depth[i])
                    });
                write_layer!(self, path, (w, h), channels)
            }
        }
    }

    pub fn read_exr(path: &Path) -> Result<Frame> {
        // The magic number before the file: a large file of anything else
        // is refused without reading it.
        let (mut file, _) = crate::limits::open_input(path)?;
        if !exr::meta::magic_number::is_exr(&mut file).unwrap_or(false) {
            return Err(crate::Error::format(
                path,
                "not an EXR file (it does not start with EXR's magic number)",
            ));
        }
        let bytes = crate::limits::read_input(path, "EXR frame", u64::MAX)?;
        Self::read_exr_bytes(&bytes, path)
    }

    /// Reads the first RGBA layer of an EXR held in memory; `origin` names it in errors.
    pub fn read_exr_bytes(bytes: &[u8], origin: &Path) -> Result<Frame> {
        use exr::prelude::*;
        let unreadable = |e: exr::error::Error| match e {
            exr::error::Error::Io(io) => crate::Error::format(origin, format!("cannot read EXR: {io}")),
            other => crate::Error::format(origin, format!("not a readable RGBA EXR: {other}")),
        };
        // Each layer's pixels are allocated from its header: check them
        // first, against memory and against what the file can hold (EXR's
        // codecs stay far below 16384 pixels per byte; ZIP of f32 RGBA ~64).
        let meta = exr::meta::MetaData::read_from_buffered(bytes, false).map_err(unreadable)?;
        for header in meta.headers.iter() {
            let [w, h] = [header.layer_size.width(), header.layer_size.height()];
            let pixels = (w as u64).saturating_mul(h as u64);
            if pixels > (bytes.len() as u64).saturating_mul(1 << 14) {
                return Err(crate::Error::format(
                    origin,
                    format!(
                        "EXR header claims {w}x{h} pixels, more than {} bytes can hold",
                        bytes.len()
                    ),
                ));
            }
            crate::limits::check_host(
                format_args!("EXR frame {w}x{h} ({})", origin.display()),
                (w as u64).saturating_mul(h as u64),
                16,
            )?;
        }
        // The crate fills a missing alpha with 1: a frame without one is
        // not lacuna's (premultiplied RGBA), and would diff as opaque.
        let has = |h: &exr::meta::header::Header, name: &str| h.channels.list.iter().any(|c| c.name.eq(name));
        if let Some(rgb) = meta.headers.iter().find(|h| ["R", "G", "B"].iter().all(|c| has(h, c))) {
            if !has(rgb, "A") {
                return Err(crate::Error::format(
                    origin,
                    "EXR layer has R, G and B but no A (alpha) channel: lacuna's frames are RGBA",
                ));
            }
        }
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .rgba_channels(
                |res: Vec2<usize>, _: &RgbaChannels| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
                |(w, px): &mut (usize, Vec<[f32; 4]>), p: Vec2<usize>, (r, g, b, a): (f32, f32, f32, f32)| {
                    px[p.y() * *w + p.x()] = [r, g, b, a];
                },
            )
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::Cursor::new(bytes))
            .map_err(unreadable)?;
        let size = image.layer_data.size;
        let mut metadata = BTreeMap::new();
        for (k, v) in image
            .attributes
            .other
            .iter()
            .chain(image.layer_data.attributes.other.iter())
        {
            let key = k.to_string();
            if let (Some(stripped), AttributeValue::Text(t)) = (key.strip_prefix(PREFIX), v) {
                metadata.insert(stripped.to_string(), t.to_string());
            }
        }
        // An iso frame's depth: the first layer's Z channel, when it has one.
        let has_z = meta
            .headers
            .first()
            .is_some_and(|h| h.channels.list.iter().any(|c| c.name.eq("Z")));
        let depth = if has_z {
            let z = read()
                .no_deep_data()
                .largest_resolution_level()
                .specific_channels()
                .required("Z")
                .collect_pixels(
                    |res: Vec2<usize>, _| (res.width(), vec![0f32; res.width() * res.height()]),
                    |(w, px): &mut (usize, Vec<f32>), p: Vec2<usize>, (z,): (f32,)| {
                        px[p.y() * *w + p.x()] = z;
                    },
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(std::io::Cursor::new(bytes))
                .map_err(unreadable)?;
            Some(z.layer_data.channel_data.pixels.1)
        } else {
            None
        };
        let frame = Frame {
            width: size.width() as u32,
            height: size.height() as u32,
            pixels: image.layer_data.channel_data.pixels.1,
            metadata,
            depth,
        };
        let data_at = image.layer_data.attributes.layer_position;
        in_display_window(frame, data_at, image.attributes.display_window, origin)
    }
}

/// The frame as its display window shows it: an EXR's pixels are its data
/// window, which other tools crop to the visible pixels or offset (lacuna
/// writes the two the same). Outside the data window a pixel is
/// transparent black, as EXR viewers show it; data outside the display
/// window is not part of the image. A depth has no such "empty" value, so
/// a frame with one must cover its display window.
fn in_display_window(
    frame: Frame,
    data_at: exr::math::Vec2<i32>,
    display: exr::meta::attribute::IntegerBounds,
    origin: &Path,
) -> Result<Frame> {
    let (dw, dh) = (display.size.width() as u64, display.size.height() as u64);
    if data_at == display.position && (dw, dh) == (frame.width as u64, frame.height as u64) {
        return Ok(frame);
    }
    let window = |at: exr::math::Vec2<i32>, w: u64, h: u64| {
        format!(
            "({}, {})-({}, {})",
            at.x(),
            at.y(),
            at.x() as i64 + w as i64 - 1,
            at.y() as i64 + h as i64 - 1
        )
    };
    let windows = format!(
        "its data window {} is not its display window {}",
        window(data_at, frame.width as u64, frame.height as u64),
        window(display.position, dw, dh)
    );
    let side = crate::limits::MAX_FRAME_SIDE as u64;
    if dw > side || dh > side {
        return Err(crate::Error::format(
            origin,
            format!("{windows}, of more than {side} pixels a side, as no lacuna frame is"),
        ));
    }
    // The data window's pixel (x, y) in display coordinates, where it is one.
    let dx = data_at.x() as i64 - display.position.x() as i64;
    let dy = data_at.y() as i64 - display.position.y() as i64;
    let (w, h) = (frame.width as i64, frame.height as i64);
    let covers = dx <= 0 && dy <= 0 && dx + w >= dw as i64 && dy + h >= dh as i64;
    if frame.depth.is_some() && !covers {
        return Err(crate::Error::format(
            origin,
            format!("{windows}, and a depth (Z) where the data window does not reach has no value"),
        ));
    }
    let what = format_args!("EXR display window {dw}x{dh} ({})", origin.display());
    let mut pixels: Vec<[f32; 4]> = crate::limits::zeroed(what, dw * dh)?;
    let mut depth: Option<Vec<f32>> = match frame.depth {
        Some(_) => Some(crate::limits::zeroed(what, dw * dh)?),
        None => None,
    };
    for y in 0..h {
        let Ok(row) = u64::try_from(y + dy) else { continue };
        if row >= dh {
            continue;
        }
        for x in 0..w {
            let Some(col) = u64::try_from(x + dx).ok().filter(|&c| c < dw) else {
                continue;
            };
            let (to, from) = ((row * dw + col) as usize, (y * w + x) as usize);
            pixels[to] = frame.pixels[from];
            if let (Some(out), Some(z)) = (depth.as_mut(), frame.depth.as_ref()) {
                out[to] = z[from];
            }
        }
    }
    Ok(Frame {
        width: dw as u32,
        height: dh as u32,
        pixels,
        depth,
        metadata: frame.metadata,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_exr_without_alpha_is_refused_not_read_as_opaque() {
        let path = std::env::temp_dir().join(format!("lacuna-rgb-{}.exr", std::process::id()));
        exr::prelude::write_rgb_file(&path, 4, 3, |x, y| (x as f32, y as f32, 0.5)).unwrap();
        let e = Frame::read_exr(&path).unwrap_err().to_string();
        let _ = std::fs::remove_file(&path);
        assert!(e.contains("no A (alpha) channel"), "{e}");
    }

    /// An EXR whose 3x2 data window sits at `at` in a display window at
    /// (-1, 0) of `size` (6x4 unless said); pixel (x, y) of the data is
    /// (x, y, 0.5, 1), its depth (with `depth`) 10 x + y.
    fn offset_exr(name: &str, at: (i32, i32), depth: bool) -> std::path::PathBuf {
        offset_exr_in(name, at, (6, 4), depth)
    }

    fn offset_exr_in(name: &str, at: (i32, i32), size: (usize, usize), depth: bool) -> std::path::PathBuf {
        use exr::prelude::*;
        let path = std::env::temp_dir().join(format!("lacuna-{name}-{}.exr", std::process::id()));
        let attributes = LayerAttributes {
            layer_position: Vec2(at.0, at.1),
            ..LayerAttributes::default()
        };
        let display = IntegerBounds::new((-1, 0), size);
        let rgba = |p: Vec2<usize>| (p.x() as f32, p.y() as f32, 0.5, 1.0);
        if depth {
            let channels = SpecificChannels::build()
                .with_channel("R")
                .with_channel("G")
                .with_channel("B")
                .with_channel("A")
                .with_channel("Z")
                .with_pixel_fn(|p: Vec2<usize>| {
                    let (x, y) = (p.x() as f32, p.y() as f32);
                    (x, y, 0.5f32, 1.0f32, 10.0 * x + y)
                });
            let mut image = Image::from_layer(Layer::new((3, 2), attributes, Encoding::UNCOMPRESSED, channels));
            image.attributes.display_window = display;
            image.write().to_file(&path).unwrap();
        } else {
            let channels = SpecificChannels::rgba(rgba);
            let mut image = Image::from_layer(Layer::new((3, 2), attributes, Encoding::UNCOMPRESSED, channels));
            image.attributes.display_window = display;
            image.write().to_file(&path).unwrap();
        }
        path
    }

    #[test]
    fn a_data_window_is_placed_in_the_display_window_and_the_rest_is_transparent() {
        // At (1, 1): display columns 2..5 and rows 1..3 hold the data.
        let path = offset_exr("window", (1, 1), false);
        let frame = Frame::read_exr(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        assert_eq!((frame.width, frame.height), (6, 4));
        for y in 0..4 {
            for x in 0..6 {
                let inside = (2..5).contains(&x) && (1..3).contains(&y);
                let want = match inside {
                    true => [(x - 2) as f32, (y - 1) as f32, 0.5, 1.0],
                    false => [0.0; 4],
                };
                assert_eq!(frame.pixels[y * 6 + x], want, "display pixel ({x}, {y})");
            }
        }
        // Data past the display window's left and top edges is cut.
        let path = offset_exr("overscan", (-2, -1), false);
        let frame = Frame::read_exr(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        assert_eq!(frame.pixels[0], [1.0, 1.0, 0.5, 1.0], "data (1, 1) at display (0, 0)");
        assert_eq!(frame.pixels[1], [2.0, 1.0, 0.5, 1.0]);
        assert_eq!(frame.pixels[2], [0.0; 4]);
        assert_eq!(frame.pixels[6], [0.0; 4], "the data's last row is row 0");
    }

    #[test]
    fn a_depth_that_does_not_cover_its_display_window_is_refused_and_overscan_is_cut() {
        let path = offset_exr("window-z", (1, 1), true);
        let e = Frame::read_exr(&path).unwrap_err().to_string();
        let _ = std::fs::remove_file(&path);
        assert!(
            e.contains("data window (1, 1)-(3, 2) is not its display window (-1, 0)-(4, 3)")
                && e.contains("a depth (Z) where the data window does not reach"),
            "{e}"
        );
        // Data (0..3, 0..2) at (-2, 0) covers a 2x1 display at (-1, 0):
        // display (0, 0) is data (1, 0), display (1, 0) data (2, 0).
        let path = offset_exr_in("overscan-z", (-2, 0), (2, 1), true);
        let frame = Frame::read_exr(&path).unwrap();
        let _ = std::fs::remove_file(&path);
        assert_eq!((frame.width, frame.height), (2, 1));
        assert_eq!(frame.pixels, vec![[1.0, 0.0, 0.5, 1.0], [2.0, 0.0, 0.5, 1.0]]);
        assert_eq!(frame.depth, Some(vec![10.0, 20.0]));
    }

    #[test]
    fn a_display_window_past_a_frames_largest_side_is_refused() {
        let path = offset_exr_in("huge", (0, 0), (20000, 4), false);
        let e = Frame::read_exr(&path).unwrap_err().to_string();
        let _ = std::fs::remove_file(&path);
        assert!(e.contains("of more than 16384 pixels a side"), "{e}");
    }
}
