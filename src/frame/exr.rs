//! OpenEXR frames: RGBA f32 with lacuna's metadata as text attributes
//! (`lacuna.*`).

use super::{write_atomically, Frame, PREFIX};
use crate::error::Result;
use std::collections::BTreeMap;
use std::path::Path;

impl Frame {
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        use exr::prelude::*;
        let (w, h) = (self.width as usize, self.height as usize);
        let pixels = &self.pixels;
        let channels = SpecificChannels::rgba(|p: Vec2<usize>| {
            let c = pixels[p.y() * w + p.x()];
            (c[0], c[1], c[2], c[3])
        });
        let layer = Layer::new(
            (w, h),
            LayerAttributes::named("lacuna"),
            Encoding::SMALL_LOSSLESS,
            channels,
        );
        let mut image = Image::from_layer(layer);
        for (k, v) in &self.metadata {
            image.attributes.other.insert(
                Text::from(format!("{PREFIX}{k}").as_str()),
                AttributeValue::Text(Text::from(v.as_str())),
            );
        }
        write_atomically(path, |tmp| {
            image.write().to_file(tmp).map_err(|e| match e {
                exr::error::Error::Io(io) => crate::Error::io(path, io),
                other => crate::Error::format(path, format!("cannot write EXR: {other}")),
            })
        })
    }

    pub fn read_exr(path: &Path) -> Result<Frame> {
        use exr::prelude::*;
        if let Err(e) = std::fs::metadata(path) {
            return Err(crate::Error::io(path, e));
        }
        let image = read_first_rgba_layer_from_file(
            path,
            |res: Vec2<usize>, _| (res.width(), vec![[0f32; 4]; res.width() * res.height()]),
            |(w, px): &mut (usize, Vec<[f32; 4]>), p: Vec2<usize>, (r, g, b, a): (f32, f32, f32, f32)| {
                px[p.y() * *w + p.x()] = [r, g, b, a];
            },
        )
        .map_err(|e| match e {
            exr::error::Error::Io(io) => crate::Error::format(path, format!("cannot read EXR: {io}")),
            other => crate::Error::format(path, format!("not a readable RGBA EXR: {other}")),
        })?;
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
        Ok(Frame {
            width: size.width() as u32,
            height: size.height() as u32,
            pixels: image.layer_data.channel_data.pixels.1,
            metadata,
        })
    }
}
