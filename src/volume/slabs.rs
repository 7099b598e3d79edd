//! A file's voxels streamed into bricks slab by slab (`PoolStream`), in any
//! source type: each slab is decoded to the texels a dense load stores
//! (`decode.rs`: integers shifted into the unsigned range, wider types
//! normalised over the file's finite range as f32, big-endian words
//! swapped), so a streamed file is its dense load bit for bit and the host
//! holds one slab of it, not the volume.

use super::decode::{self, VoxelType};
use super::{stored_bytes, NoData, StreamTo, Volume, VoxelData};
use crate::error::{Error, Result};
use std::io::Read;
use std::path::Path;

/// Bytes of source voxels read at once (whole layers, at least one).
pub(super) const SLAB_BYTES: usize = 64 << 20;

/// Checks the bytes after a file's last voxel layer.
pub(super) type TailCheck<'a> = dyn Fn(&mut dyn Read) -> Result<()> + 'a;

/// A file's voxels: x fastest, then y, then z, from layer `z` on when
/// opened at `z`.
pub(super) struct SlabFile<'a> {
    /// Named in errors.
    pub path: &'a Path,
    pub dims: [u32; 3],
    pub ty: VoxelType,
    pub little: bool,
    /// A reader positioned at the first byte of layer `z`.
    pub open: &'a dyn Fn(u32) -> Result<Box<dyn Read + 'a>>,
    /// Checks what follows the volume's last layer, where a stream reads it.
    pub tail: Option<&'a TailCheck<'a>>,
    /// Source bytes read at once (`SLAB_BYTES`).
    pub slab_bytes: usize,
    /// Each voxel negated within its type as read (`decode::negate_raw`).
    pub negate: bool,
}

impl SlabFile<'_> {
    fn layer_bytes(&self) -> usize {
        self.dims[0] as usize * self.dims[1] as usize * self.ty.bytes()
    }

    /// Calls `f` with the source bytes of `layers`, whole layers in order.
    fn each_slab(&self, layers: std::ops::Range<u32>, mut f: impl FnMut(&[u8]) -> Result<()>) -> Result<()> {
        let layer = self.layer_bytes().max(1);
        let per_slab = (self.slab_bytes / layer).clamp(1, layers.len().max(1));
        let mut slab = crate::limits::zeroed::<u8>(
            format_args!("slab of {}", self.path.display()),
            (per_slab * layer) as u64,
        )?;
        let mut reader = (self.open)(layers.start)?;
        let mut z = layers.start as usize;
        while z < layers.end as usize {
            let n = per_slab.min(layers.end as usize - z);
            reader.read_exact(&mut slab[..n * layer]).map_err(|e| match e.kind() {
                std::io::ErrorKind::UnexpectedEof => Error::format(
                    self.path,
                    format!("ends before layer {} of its {} voxel layers", z + n, self.dims[2]),
                ),
                _ => Error::format(self.path, format!("cannot read layers {z} to {}: {e}", z + n)),
            })?;
            if self.negate {
                decode::negate_raw(&mut slab[..n * layer], self.ty, self.little);
            }
            f(&slab[..n * layer])?;
            z += n;
        }
        match self.tail {
            Some(tail) if layers.end == self.dims[2] => tail(&mut reader),
            _ => Ok(()),
        }
    }

    /// The least and greatest finite value of `layers` in source units
    /// (`(inf, -inf)` where there is none).
    fn finite_range(&self, layers: std::ops::Range<u32>) -> Result<(f64, f64)> {
        let mut range = (f64::INFINITY, f64::NEG_INFINITY);
        self.each_slab(layers, |bytes| {
            let (lo, hi) = decode::finite_range(decode::wide_values(bytes, self.ty, self.little));
            range = (range.0.min(lo), range.1.max(hi));
            Ok(())
        })?;
        Ok(range)
    }
}

/// The volume of `file` streamed into bricks as `to` says, named `name`.
pub(super) fn stream(file: &SlabFile, to: &StreamTo, name: String, spacing: [f32; 3]) -> Result<Volume> {
    let (_, layers) = to.rows_and_layers(file.dims);
    // Wider types store values normalised over the finite range: a first
    // pass finds it (the ranks' layers' ranges, agreed).
    let source_range = match file.ty {
        VoxelType::U8 | VoxelType::I8 | VoxelType::U16 | VoxelType::I16 => None,
        _ => {
            let mine = file.finite_range(layers);
            Some(match &to.across {
                Some(agree) => {
                    let whole = agree(mine.as_ref().ok().copied());
                    mine?;
                    whole?
                }
                None => mine?,
            })
        }
    };
    let mut no_data = NoData::default();
    let pool = to.run(file.dims, stored_bytes(file.ty), |stream, layers| {
        let mut texels = Vec::new();
        file.each_slab(layers, |bytes| {
            stored_texels(bytes, file.ty, file.little, source_range, &mut texels, &mut no_data);
            stream.push(&texels)
        })
    })?;
    let mut volume = Volume::new(
        name,
        file.dims,
        spacing,
        file.ty,
        VoxelData::Bricks(std::sync::Arc::new(pool)),
    )?;
    // The range in source units, as `decode` reports it.
    volume.value_range = match (file.ty, source_range) {
        (VoxelType::I8, _) => volume.value_range.map(|v| v - 128.0),
        (VoxelType::I16, _) => volume.value_range.map(|v| v - 32768.0),
        (_, Some(range)) => decode::source_units(range),
        _ => volume.value_range,
    };
    volume.no_data = no_data;
    Ok(volume)
}

/// A slab's stored texels into `out` (little-endian, `stored_bytes` each),
/// as `decode` and `Volume::new` store them: non-finite values become NaN
/// and are counted in `no_data`.
fn stored_texels(
    bytes: &[u8],
    ty: VoxelType,
    little: bool,
    range: Option<(f64, f64)>,
    out: &mut Vec<u8>,
    no_data: &mut NoData,
) {
    out.clear();
    match ty {
        VoxelType::U8 => out.extend_from_slice(bytes),
        VoxelType::I8 => out.extend(bytes.iter().map(|&b| decode::shifted_i8(b))),
        VoxelType::U16 => out.extend(decode::words::<2>(bytes, little).flatten()),
        VoxelType::I16 => {
            out.extend(decode::words::<2>(bytes, little).flat_map(|w| decode::shifted_i16(w).to_le_bytes()))
        }
        _ => {
            let normalize = decode::normalizer(range.unwrap_or((0.0, 0.0)));
            let mut values: Vec<f32> = decode::wide_values(bytes, ty, little).map(normalize).collect();
            no_data.mark_values(&mut values);
            out.extend(values.iter().flat_map(|v| v.to_le_bytes()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{PoolLimits, StreamTo};

    /// Values with NaN, both infinities and a constant run, as `ty` words.
    fn file_bytes(ty: VoxelType, little: bool, n: usize) -> Vec<u8> {
        (0..n)
            .flat_map(|i| {
                let v = match i % 41 {
                    3 => f64::NAN,
                    7 => f64::INFINITY,
                    9 => f64::NEG_INFINITY,
                    _ if i % 100 < 30 => 5.0,
                    _ => (i * 37 % 1000) as f64 - 300.0,
                };
                let mut w = match ty {
                    VoxelType::I16 => (v as i16).to_le_bytes().to_vec(),
                    VoxelType::U32 => (v.max(0.0) as u32).to_le_bytes().to_vec(),
                    VoxelType::F32 => (v as f32).to_le_bytes().to_vec(),
                    _ => v.to_le_bytes().to_vec(),
                };
                if !little {
                    w.reverse();
                }
                w
            })
            .collect()
    }

    #[test]
    fn slabs_of_one_or_two_layers_decode_as_the_dense_load() {
        let dims = [13, 7, 11];
        let n = 13 * 7 * 11;
        let path = Path::new("mem");
        for (ty, little) in [
            (VoxelType::F32, false),
            (VoxelType::F64, true),
            (VoxelType::I16, false),
            (VoxelType::U32, true),
        ] {
            let bytes = file_bytes(ty, little, n);
            let layer = 13 * 7 * ty.bytes();
            for (slab_layers, negate) in [(1, false), (2, false), (1, true), (2, true)] {
                let mut read = bytes.clone();
                if negate {
                    crate::volume::decode::negate_raw(&mut read, ty, little);
                }
                let dense = crate::volume::decode::decode(path, &read, ty, little, dims, [1.0; 3]).unwrap();
                let open = |z: u32| -> Result<Box<dyn Read>> {
                    Ok(Box::new(std::io::Cursor::new(bytes[z as usize * layer..].to_vec())))
                };
                let file = SlabFile {
                    path,
                    dims,
                    ty,
                    little,
                    open: &open,
                    tail: None,
                    slab_bytes: slab_layers * layer,
                    negate,
                };
                let limits = PoolLimits {
                    max_image_dim: 4096,
                    max_image_bytes: u64::MAX,
                    max_table_entries: 1 << 30,
                };
                let s = stream(&file, &StreamTo::new(4, limits), "mem".into(), [1.0; 3]).unwrap();
                let what = format!("{ty} little={little} negated={negate} in slabs of {slab_layers}");
                assert!(
                    (0..n).all(|i| s.data.texel(i).to_bits() == dense.data.texel(i).to_bits()),
                    "{what}"
                );
                assert_eq!(
                    (s.value_range, s.norm, s.no_data),
                    (dense.value_range, dense.norm, dense.no_data),
                    "{what}"
                );
            }
        }
    }
}
