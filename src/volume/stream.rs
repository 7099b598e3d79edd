//! Streamed loading into bricks: a volume's texels arrive z-layer by
//! z-layer (a file read slab by slab, a generator's slabs) and leave as the
//! brick pool's slots, so the host never holds the dense volume: its peak
//! is the stored bricks plus a window of one brick row (`PoolStream`). The
//! result, `HostPool`, is the volume's voxels (`VoxelData::Bricks`): every
//! voxel reads through the table as on the GPU, and the upload copies its
//! slots into the pool images as they are.

use super::pool::{brick_origin, outside, BrickBox, PoolLayout, PoolLimits};
use crate::error::{Error, Result};
use rayon::prelude::*;
use std::ops::Range;

/// Per brick in `slot_of`: a constant brick's value index has this bit.
const VALUE: u32 = 1 << 31;

/// A volume's texels as the brick pool's slots on the host.
pub struct HostPool {
    pub layout: PoolLayout,
    /// The stored bricks' slots in slot order, (edge + 1)^3 texels each, x
    /// fastest: the pool images' slots, border layer included.
    slots: Vec<u8>,
    /// Per brick: its slot, or `VALUE | k` for `layout.values[k]`.
    slot_of: Vec<u32>,
    /// Least and greatest stored value of every voxel streamed, kept
    /// bricks or not (so every rank of a split volume normalises alike).
    range: (f64, f64),
}

impl std::fmt::Debug for HostPool {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "HostPool({})", self.layout.stats())
    }
}

impl HostPool {
    fn slot_bytes(&self) -> usize {
        ((self.layout.edge + 1) as usize).pow(3) * self.layout.texel_bytes as usize
    }

    /// The bytes of the texel of voxel (x, y, z).
    #[inline]
    pub fn texel_at(&self, x: u32, y: u32, z: u32) -> &[u8] {
        let l = &self.layout;
        let (e, tb) = (l.edge, l.texel_bytes as usize);
        let b = (x / e) as usize + l.counts[0] as usize * ((y / e) as usize + l.counts[1] as usize * (z / e) as usize);
        let s = self.slot_of[b];
        if s & VALUE != 0 {
            return &l.values[(s & !VALUE) as usize];
        }
        let n = (e + 1) as usize;
        let local = (x % e) as usize + n * ((y % e) as usize + n * (z % e) as usize);
        let at = s as usize * self.slot_bytes() + local * tb;
        &self.slots[at..at + tb]
    }

    /// The texel bytes of voxel index `i` (x fastest).
    #[inline]
    pub fn texel_bytes_at(&self, i: usize) -> &[u8] {
        let [w, h, _] = self.layout.dims.map(|d| d as usize);
        self.texel_at((i % w) as u32, (i / w % h) as u32, (i / (w * h)) as u32)
    }

    /// Stored slot `s`'s texels, (edge + 1)^3 of them, x fastest.
    pub fn slot(&self, s: usize) -> &[u8] {
        &self.slots[s * self.slot_bytes()..(s + 1) * self.slot_bytes()]
    }

    /// Pool image `k`'s texel planes from `first_plane` on (`out`, whole
    /// planes), as `PoolLayout::fill` makes them from the dense volume.
    pub fn fill(&self, k: usize, first_plane: u32, out: &mut [u8]) {
        let n = (self.layout.edge + 1) as usize;
        let tb = self.layout.texel_bytes as usize;
        let slot_bytes = self.slot_bytes();
        self.layout.fill_with(k, first_plane, out, |s, _, ly, lz, dst| {
            let at = s as usize * slot_bytes + (lz as usize * n + ly as usize) * n * tb;
            dst.copy_from_slice(&self.slots[at..at + n * tb]);
        });
    }

    /// A texel's value as `VoxelData::texel` gives it (UNORM for integers).
    #[inline]
    pub fn decode(&self, t: &[u8]) -> f32 {
        match t.len() {
            1 => t[0] as f32 / 255.0,
            2 => u16::from_le_bytes([t[0], t[1]]) as f32 / 65535.0,
            _ => f32::from_le_bytes([t[0], t[1], t[2], t[3]]),
        }
    }

    /// A texel's stored value (0..255, 0..65535, or the float).
    pub fn stored(&self, t: &[u8]) -> f64 {
        stored_value(t)
    }

    /// Least and greatest stored value of the whole volume as streamed
    /// (bricks left out by `keep` included; NaN ignored).
    pub fn stored_range(&self) -> (f64, f64) {
        self.range
    }

    /// Host bytes held: the slots and the table's copies.
    pub fn host_bytes(&self) -> u64 {
        self.slots.len() as u64 + self.slot_of.len() as u64 * 4 + self.layout.table_bytes()
    }
}

/// Called with (layers streamed, layers in all) after each brick row.
pub type StreamProgress = std::sync::Arc<dyn Fn(u32, u32) + Send + Sync>;

/// How processes that each stream only their own layers of one volume
/// (MPI ranks) learn its stored range: given this process's layers' range,
/// or None where its stream failed, the least and greatest over every
/// process, or an error where any failed. A collective: each process calls
/// it once per stream, failed or not, so none waits on one that failed.
pub type RangeAcross = std::sync::Arc<dyn Fn(Option<(f64, f64)>) -> Result<(f64, f64)> + Send + Sync>;

/// How a load streams into bricks (`Series::load_bricks`): the brick edge,
/// the pool's limits, the bricks to keep (None: all), whether the source
/// streams only the kept layers (`across`), and who hears of its progress.
#[derive(Clone)]
pub struct StreamTo {
    pub edge: u32,
    pub limits: PoolLimits,
    pub keep: Option<BrickBox>,
    pub across: Option<RangeAcross>,
    pub progress: Option<StreamProgress>,
}

impl StreamTo {
    pub fn new(edge: u32, limits: PoolLimits) -> Self {
        StreamTo {
            edge,
            limits,
            keep: None,
            across: None,
            progress: None,
        }
    }

    /// Keeps only the bricks of `keep` (one rank's block and ghosts).
    pub fn keep(mut self, keep: Option<BrickBox>) -> Self {
        self.keep = keep;
        self
    }

    /// Streams only the layers the kept bricks' slots hold (every layer
    /// where nothing is kept), and learns the whole volume's range from
    /// `agree`: each rank of a split volume reads or generates its own
    /// layers, and all of them normalise alike.
    pub fn across(mut self, agree: RangeAcross) -> Self {
        self.across = Some(agree);
        self
    }

    /// The brick rows (z) a stream cuts, and the layers it takes: the kept
    /// rows and the layer after them (their slots' border) with `across`,
    /// else all of them.
    pub fn rows_and_layers(&self, dims: [u32; 3]) -> (Range<u32>, Range<u32>) {
        match (self.keep, &self.across) {
            (Some([lo, hi]), Some(_)) => (
                lo[2]..hi[2],
                (lo[2] * self.edge).min(dims[2])..(hi[2] * self.edge + 1).min(dims[2]),
            ),
            _ => (0..dims[2].div_ceil(self.edge.max(1)), 0..dims[2]),
        }
    }

    /// The pool of a volume of `dims` with texels of `texel_bytes` whose
    /// layers `feed` pushes into the stream it is given (the layers it must
    /// push, in order, are the range it is given).
    pub fn run(
        &self,
        dims: [u32; 3],
        texel_bytes: u64,
        feed: impl FnOnce(&mut PoolStream, Range<u32>) -> Result<()>,
    ) -> Result<HostPool> {
        let fed = self.stream(dims, texel_bytes).and_then(|mut s| {
            let layers = s.layers.clone();
            feed(&mut s, layers)?;
            Ok(s)
        });
        let stream = match &self.across {
            None => fed?,
            Some(agree) => {
                let whole = agree(fed.as_ref().ok().map(|s| s.range));
                let mut s = fed?;
                s.range = whole?;
                s
            }
        };
        stream.finish(self.limits)
    }

    /// Reports each brick row cut.
    pub fn progress(mut self, f: StreamProgress) -> Self {
        self.progress = Some(f);
        self
    }

    /// The stream for a volume of `dims` with texels of `texel_bytes`.
    pub fn stream(&self, dims: [u32; 3], texel_bytes: u64) -> Result<PoolStream> {
        let mut s = PoolStream::new(dims, texel_bytes, self.edge, self.limits, self.keep)?;
        let (rows, layers) = self.rows_and_layers(dims);
        (s.base, s.row) = (layers.start, rows.start);
        (s.rows, s.layers) = (rows, layers);
        s.progress = self.progress.clone();
        Ok(s)
    }
}

/// Builds a `HostPool` from a volume's z-layers pushed in order.
pub struct PoolStream {
    dims: [u32; 3],
    edge: u32,
    tb: usize,
    counts: [u32; 3],
    keep: Option<BrickBox>,
    /// The brick rows (z) cut, and the layers pushed: all of them, or a
    /// kept block's (`StreamTo::across`). Rows outside hold one value.
    rows: Range<u32>,
    layers: Range<u32>,
    /// Layers `base ..` of the volume, at most edge + 1 of them.
    window: Vec<u8>,
    base: u32,
    filled: u32,
    /// The next brick row (z) to cut.
    row: u32,
    /// Per brick of the rows cut: its one value, or None where it is stored.
    one_value: Vec<Option<Vec<u8>>>,
    /// The first texel pushed: the value of the rows not cut.
    first: Option<Vec<u8>>,
    slots: Vec<u8>,
    range: (f64, f64),
    progress: Option<StreamProgress>,
}

impl PoolStream {
    /// A stream for a volume of `dims` with texels of `texel_bytes`, in
    /// bricks of `edge` (bricks outside `keep` left out as their first
    /// texel's value, as `PoolLayout::plan_kept`; with `StreamTo::across`,
    /// the brick rows outside the streamed layers as the first texel
    /// streamed).
    pub fn new(
        dims: [u32; 3],
        texel_bytes: u64,
        edge: u32,
        limits: PoolLimits,
        keep: Option<BrickBox>,
    ) -> Result<Self> {
        let (counts, total) = PoolLayout::check(dims, edge, limits)?;
        crate::limits::check_host("brick table", total, 40)?;
        let layer = dims[0] as u64 * dims[1] as u64 * texel_bytes;
        let window = crate::limits::zeroed::<u8>(format_args!("brick row window"), layer * (edge as u64 + 1))?;
        Ok(PoolStream {
            dims,
            edge,
            tb: texel_bytes as usize,
            counts,
            keep,
            rows: 0..counts[2],
            layers: 0..dims[2],
            window,
            base: 0,
            filled: 0,
            row: 0,
            one_value: Vec::with_capacity(total as usize),
            first: None,
            slots: Vec::new(),
            range: (f64::INFINITY, f64::NEG_INFINITY),
            progress: None,
        })
    }

    fn layer_bytes(&self) -> usize {
        self.dims[0] as usize * self.dims[1] as usize * self.tb
    }

    /// Takes whole z-layers, the next in order.
    pub fn push(&mut self, mut layers: &[u8]) -> Result<()> {
        let layer = self.layer_bytes();
        if !layers.len().is_multiple_of(layer)
            || self.base + self.filled + (layers.len() / layer) as u32 > self.layers.end
        {
            return Err(Error::invalid(
                "volume stream",
                format!("{} bytes after layer {}", layers.len(), self.base + self.filled),
                format!(
                    "expected whole layers of {layer} bytes, up to layer {}",
                    self.layers.end
                ),
            ));
        }
        if self.first.is_none() && !layers.is_empty() {
            self.first = Some(layers[..self.tb].to_vec());
        }
        let tb = self.tb;
        let (lo, hi) = layers
            .par_chunks(tb * 4096)
            .map(|c| match tb {
                // Bytes in a plain loop the compiler vectorises.
                1 => {
                    let (lo, hi) = c.iter().fold((u8::MAX, 0u8), |(lo, hi), &v| (lo.min(v), hi.max(v)));
                    (lo as f64, hi as f64)
                }
                _ => c
                    .chunks_exact(tb)
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), t| {
                        let v = stored_value(t);
                        (lo.min(v), hi.max(v))
                    }),
            })
            .reduce(
                || (f64::INFINITY, f64::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        self.range = (self.range.0.min(lo), self.range.1.max(hi));
        loop {
            let room = (self.edge + 1 - self.filled) as usize;
            let take = room.min(layers.len() / layer);
            let at = self.filled as usize * layer;
            self.window[at..at + take * layer].copy_from_slice(&layers[..take * layer]);
            self.filled += take as u32;
            layers = &layers[take * layer..];
            // A row needs its bricks' layers and the next row's first (or
            // the volume's last); a short last row may be whole at once.
            while self.row < self.rows.end
                && self.base + self.filled > (self.row * self.edge + self.edge).min(self.dims[2] - 1)
            {
                self.cut_row();
                // The next row starts at the layer after this row's bricks.
                let next = (self.row + 1) * self.edge;
                let keep_from = next.min(self.base + self.filled) - self.base;
                let kept = self.filled - keep_from;
                self.window
                    .copy_within(keep_from as usize * layer..(keep_from + kept) as usize * layer, 0);
                self.base += keep_from;
                self.filled = kept;
                self.row += 1;
                if let Some(f) = &self.progress {
                    f(self.base + self.filled - self.layers.start, self.layers.len() as u32);
                }
            }
            if layers.is_empty() {
                break;
            }
        }
        Ok(())
    }

    /// Cuts brick row `self.row` out of the window: each brick's one value,
    /// or its slot appended.
    fn cut_row(&mut self) {
        let (edge, tb, dims, counts, base) = (self.edge, self.tb, self.dims, self.counts, self.base);
        let n = (edge + 1) as usize;
        let window = &self.window;
        let layer = self.layer_bytes();
        let row = self.row;
        let per_row = counts[0] as u64 * counts[1] as u64;
        let keep = self.keep;
        let cut: Vec<(Option<Vec<u8>>, Vec<u8>)> = (0..per_row)
            .into_par_iter()
            .map(|i| {
                let b = i + per_row * row as u64;
                let lo = brick_origin(b, counts, edge);
                // The slot's x-rows in the window, clamped to the volume as
                // the sampler clamps: the texels inside the volume (past
                // its last x the row repeats its last texel).
                let inside = (dims[0] - lo[0]).min(n as u32) as usize;
                let rows = || {
                    (0..=edge).flat_map(move |lz| {
                        let z = (lo[2] + lz).min(dims[2] - 1);
                        (0..=edge).map(move |ly| {
                            let y = (lo[1] + ly).min(dims[1] - 1);
                            let at =
                                (z - base) as usize * layer + (y as usize * dims[0] as usize + lo[0] as usize) * tb;
                            &window[at..at + inside * tb]
                        })
                    })
                };
                let first = &window
                    [(lo[2] - base) as usize * layer + (lo[1] as usize * dims[0] as usize + lo[0] as usize) * tb..]
                    [..tb];
                let same = |r: &[u8]| match tb {
                    1 => r.iter().all(|&v| v == first[0]),
                    _ => r.chunks_exact(tb).all(|t| t == first),
                };
                if outside(keep, lo, edge) || rows().all(same) {
                    return (Some(first.to_vec()), Vec::new());
                }
                let mut slot = Vec::with_capacity(n * n * n * tb);
                for r in rows() {
                    slot.extend_from_slice(r);
                    let last = &r[r.len() - tb..];
                    for _ in inside..n {
                        slot.extend_from_slice(last);
                    }
                }
                (None, slot)
            })
            .collect();
        for (value, slot) in cut {
            self.slots.extend_from_slice(&slot);
            self.one_value.push(value);
        }
    }

    /// The pool, once every layer was pushed.
    pub fn finish(self, limits: PoolLimits) -> Result<HostPool> {
        if self.base + self.filled != self.layers.end || self.row != self.rows.end {
            return Err(Error::invalid(
                "volume stream",
                format!("{} of {} layers", self.base + self.filled, self.layers.end),
                "ended before the volume's last layer",
            ));
        }
        // The rows not cut (outside a kept block's layers) hold one value
        // of the volume, as a brick outside the block does.
        let per_row = self.counts[0] as usize * self.counts[1] as usize;
        let fill = self.first.as_deref();
        let (before, after) = (self.rows.start as usize, (self.counts[2] - self.rows.end) as usize);
        let one_value: Vec<Option<&[u8]>> = std::iter::repeat_n(fill, before * per_row)
            .chain(self.one_value.iter().map(|v| v.as_deref()))
            .chain(std::iter::repeat_n(fill, after * per_row))
            .collect();
        let layout = PoolLayout::assemble(self.edge, self.dims, self.tb as u64, limits, &one_value)?;
        let mut value_index = std::collections::HashMap::new();
        for (k, v) in layout.values.iter().enumerate() {
            value_index.insert(v.as_slice(), k as u32);
        }
        let mut next_slot = 0u32;
        let slot_of = one_value
            .iter()
            .map(|v| match v {
                Some(v) => VALUE | value_index[v],
                None => {
                    next_slot += 1;
                    next_slot - 1
                }
            })
            .collect();
        Ok(HostPool {
            layout,
            slots: self.slots,
            slot_of,
            range: self.range,
        })
    }
}

/// A texel's stored value: 1 byte u8, 2 bytes u16, 4 bytes f32 (little-endian).
fn stored_value(t: &[u8]) -> f64 {
    match t.len() {
        1 => t[0] as f64,
        2 => u16::from_le_bytes([t[0], t[1]]) as f64,
        _ => f32::from_le_bytes([t[0], t[1], t[2], t[3]]) as f64,
    }
}
