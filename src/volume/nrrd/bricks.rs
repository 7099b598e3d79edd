//! A NRRD's step streamed into bricks: raw data read from its first
//! needed layer on, gzip data inflated on the fly.

use super::super::{StreamTo, Volume};
use super::{head, header, load_step, short_data, streamed_layout};
use crate::error::{Error, Result};
use std::io::Read;
use std::path::Path;

/// Step `step` of a NRRD streamed into bricks as `to` says (`slabs.rs`):
/// raw data read from its first needed layer on, gzip data inflated on the
/// fly, so the host never holds the dense volume. A NRRD with channels (or
/// a header past 64 KiB) loads whole.
pub fn load_step_bricks(path: &Path, step: u32, to: &StreamTo) -> Result<Volume> {
    if streamed_layout(path).is_none() {
        return load_step(path, step, None);
    }
    let h = header(path, &head(path)?, true)?;
    super::super::check_file_step(path, step, h.axes.steps)?;
    // Sizes before arithmetic on them: as the dense load checks them.
    super::super::check_dims(h.dims, &path.display().to_string())?;
    let too_big = || Error::format(path, "NRRD data is larger than a file can be");
    let all = h.block().checked_mul(h.axes.steps as u64).ok_or_else(too_big)?;
    let (source, start) = match &h.data_file {
        Some(data_path) => (data_path.clone(), 0),
        None => (path.to_path_buf(), h.offset as u64),
    };
    let end = start
        .checked_add(h.skip)
        .and_then(|b| b.checked_add(all))
        .ok_or_else(too_big)?;
    // A short (or long) file is found before a layer is read.
    let (_, len) = crate::limits::open_input(&source)?;
    match h.gzip {
        true => super::super::check_gzip_holds(&source, len.saturating_sub(start), end - start)?,
        false if len != end => return Err(short_data(&source, &h, len.saturating_sub(start + h.skip))),
        false => {}
    }
    let layer = h.dims[0] as u64 * h.dims[1] as u64 * h.ty.bytes() as u64;
    let first = h.skip + h.block() * step as u64;
    // Gzip data is whole where a stream reaches the step's last layer: the
    // steps after it inflate and the data ends there (its trailer's CRC
    // checked), as the dense load requires.
    let rest = all - h.block() * (step as u64 + 1);
    let tail = |reader: &mut dyn Read| -> Result<()> {
        let more = std::io::copy(&mut reader.take(rest + 1), &mut std::io::sink())
            .map_err(|e| Error::format(&source, format!("corrupt gzip data: {e}")))?;
        match more == rest {
            true => Ok(()),
            false => Err(short_data(&source, &h, h.skip + all - rest + more)),
        }
    };
    let open = |z: u32| -> Result<Box<dyn Read + '_>> {
        let mut file = std::fs::File::open(&source).map_err(|e| Error::io(&source, e))?;
        let at = first + z as u64 * layer;
        match h.gzip {
            false => {
                std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(start + at))
                    .map_err(|e| Error::io(&source, e))?;
                Ok(Box::new(std::io::BufReader::new(file)))
            }
            true => inflating(&source, file, start, at),
        }
    };
    let file = super::super::slabs::SlabFile {
        path: &source,
        dims: h.dims,
        ty: h.ty,
        little: h.little,
        open: &open,
        tail: if h.gzip { Some(&tail) } else { None },
        slab_bytes: super::super::slabs::SLAB_BYTES,
        negate: false,
    };
    super::super::slabs::stream(&file, to, path.display().to_string(), h.spacing)
}

/// `file`'s gzip data from byte `start` on, inflated, its first `skip`
/// inflated bytes passed over.
#[cfg(feature = "loaders")]
fn inflating<'a>(source: &Path, mut file: std::fs::File, start: u64, skip: u64) -> Result<Box<dyn Read + 'a>> {
    std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(start)).map_err(|e| Error::io(source, e))?;
    let mut inflated = flate2::read::MultiGzDecoder::new(std::io::BufReader::new(file));
    let passed = std::io::copy(&mut (&mut inflated).take(skip), &mut std::io::sink())
        .map_err(|e| Error::format(source, format!("corrupt gzip data: {e}")))?;
    if passed < skip {
        return Err(Error::format(
            source,
            format!("holds {passed} bytes of inflated data before the layers asked for, at byte {skip}"),
        ));
    }
    Ok(Box::new(inflated))
}

#[cfg(not(feature = "loaders"))]
fn inflating<'a>(source: &Path, _: std::fs::File, _: u64, _: u64) -> Result<Box<dyn Read + 'a>> {
    super::inflate(source, &[], 0).map(|_| -> Box<dyn Read + 'a> { Box::new(std::io::empty()) })
}
