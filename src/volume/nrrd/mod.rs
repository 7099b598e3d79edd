//! NRRD reader (attached or detached header; raw or gzip encoding; 1- to 3-D,
//! a slice or row one voxel thick). Honours `spacings` or the lengths of `space directions`. A 4-D NRRD
//! holds channels on a component axis first (`kinds: vector domain domain
//! domain`, or any non-domain kind: up to `MAX_CHANNELS`), or a time series
//! on a `time` axis last.

use super::decode::{decode, VoxelType};
use super::Volume;
use crate::error::{Error, Result};
use crate::gpu::DeviceInfo;
use std::borrow::Cow;
use std::collections::HashMap;
use std::io::Read;
use std::path::{Path, PathBuf};

mod bricks;
mod fields;
pub use bricks::load_step_bricks;
use fields::{direction_lengths, is_list, nrrd_type, numbers};

pub fn load(path: &Path, device: Option<&DeviceInfo>) -> Result<Volume> {
    load_step(path, 0, device)
}

/// Time step `step` of a NRRD (step 0 of one without a time axis).
pub fn load_step(path: &Path, step: u32, device: Option<&DeviceInfo>) -> Result<Volume> {
    // The header first, from the file's head: a file that is no NRRD, or
    // longer than its header says, is refused before the rest is read.
    let head = head(path)?;
    let limit = match header(path, &head, true) {
        Ok(h) if h.ended || head.len() < HEAD_BYTES => read_limit(path, &h, head.len())?,
        Err(e) if holds_header(&head) || !head.starts_with(b"NRRD") => return Err(e),
        // A header longer than the head: the file is read whole.
        _ => u64::MAX,
    };
    let bytes = read_at_most(path, limit)?;
    stepped(path, parse(path, &bytes, true, device, Some(step)))
}

/// The bytes of `path` a load reads, from its header `h` and the length
/// of the head it came from: the head for a detached header; else the
/// header and the data it describes (gzip's at most about twice), and
/// attached raw data longer than that is refused from the file's length.
fn read_limit(path: &Path, h: &Header, head: usize) -> Result<u64> {
    if h.data_file.is_some() {
        return Ok(head as u64);
    }
    super::check_dims(h.dims, &path.display().to_string())?;
    let wanted = h.skip.saturating_add(h.block().saturating_mul(h.axes.steps as u64));
    let data = match h.gzip {
        true => wanted.saturating_mul(2).saturating_add(1 << 16),
        false => wanted,
    };
    let limit = (h.offset as u64).saturating_add(data);
    let (_, len) = crate::limits::open_input(path)?;
    match !h.gzip && len > limit {
        true => Err(short_data(path, h, len - h.offset as u64 - h.skip)),
        false => Ok(limit),
    }
}

/// Whether `head` holds a whole header: the file is shorter than a head,
/// or the header's blank line is in it.
fn holds_header(head: &[u8]) -> bool {
    head.len() < HEAD_BYTES || head.windows(2).any(|w| w == b"\n\n") || head.windows(4).any(|w| w == b"\r\n\r\n")
}

/// The volume `parse` read for the step asked for.
fn stepped(path: &Path, parsed: Result<(Option<Volume>, u32)>) -> Result<Volume> {
    parsed?.0.ok_or_else(|| Error::format(path, "NRRD step not read"))
}

/// How many time steps a NRRD holds (1 without a time axis); reads its header.
pub fn steps(path: &Path) -> Result<u32> {
    header_only(path).map(|h| h.axes.steps)
}

/// How many channels a NRRD holds (its component axis; 1 without one);
/// reads its header.
pub fn channels(path: &Path) -> Result<u32> {
    header_only(path).map(|h| h.axes.channels)
}

/// A NRRD's header, read from its first bytes.
fn header_only(path: &Path) -> Result<Header> {
    // Headers are short: the first 64 KiB hold one, else the first 16 MiB.
    let head = head(path)?;
    match header(path, &head, true) {
        Ok(h) => Ok(h),
        Err(_) if !holds_header(&head) => header(path, &first_bytes(path, crate::limits::MAX_TEXT_INPUT)?, true),
        Err(e) => Err(e),
    }
}

/// A NRRD with attached data from memory (detached data files are an error).
pub fn from_bytes(origin: &Path, bytes: &[u8]) -> Result<Volume> {
    stepped(origin, parse(origin, bytes, false, None, Some(0)))
}

/// Where a NRRD's axes put its channels and time steps.
struct Axes {
    /// The spatial axes' indices among `sizes`.
    spatial: [usize; 3],
    /// Channels on axis 0 (1: none).
    channels: u32,
    /// Time steps on the last axis (1: none).
    steps: u32,
}

/// The axes of a `dimension`-D NRRD of `sizes`, by its `kinds`.
fn axes(path: &Path, dimension: usize, sizes: &[f64], kinds: Option<&str>) -> Result<Axes> {
    if sizes.len() != dimension {
        return Err(Error::format(
            path,
            format!(
                "NRRD 'sizes' gives {} numbers but 'dimension' is {dimension}",
                sizes.len()
            ),
        ));
    }
    if dimension == 3 {
        return Ok(Axes {
            spatial: [0, 1, 2],
            channels: 1,
            steps: 1,
        });
    }
    if dimension != 4 {
        return Err(Error::format(
            path,
            format!(
                "NRRD has dimension {dimension}; lacuna reads 1- to 3-D volumes, with channels or time as a 4th axis"
            ),
        ));
    }
    let kinds: Vec<String> = kinds.unwrap_or("").split_whitespace().map(str::to_lowercase).collect();
    if kinds.len() != 4 {
        return Err(Error::format(
            path,
            "a 4-D NRRD needs 'kinds' naming its component axis (first) or time axis (last)",
        ));
    }
    if let Some(i) = kinds.iter().position(|k| k == "time") {
        if i != 3 {
            return Err(Error::format(
                path,
                format!("NRRD time axis is not contiguous: it is axis {i} of 4, and lacuna reads time as the slowest (last) axis"),
            ));
        }
        return Ok(Axes {
            spatial: [0, 1, 2],
            channels: 1,
            steps: sizes[3] as u32,
        });
    }
    let spatial = |k: &str| matches!(k, "domain" | "space");
    if !spatial(&kinds[0]) && kinds[1..].iter().all(|k| spatial(k)) {
        let channels = sizes[0] as u32;
        if !(1..=super::MAX_CHANNELS as u32).contains(&channels) {
            return Err(Error::format(
                path,
                format!(
                    "NRRD component axis has {channels} channels: a volume has 1 to {}",
                    super::MAX_CHANNELS
                ),
            ));
        }
        return Ok(Axes {
            spatial: [1, 2, 3],
            channels,
            steps: 1,
        });
    }
    Err(Error::format(
        path,
        format!(
            "NRRD kinds '{}': expected a component axis first (vector, list, RGB-color, ...) or a time axis last",
            kinds.join(" ")
        ),
    ))
}

/// What a NRRD header says: the voxels' type, grid and axes, and where its
/// data lies.
struct Header {
    ty: VoxelType,
    dims: [u32; 3],
    axes: Axes,
    little: bool,
    spacing: [f32; 3],
    /// Bytes before the data (`byte skip`), inflated bytes for gzip.
    skip: u64,
    gzip: bool,
    /// A detached header's data file; None: attached, from `offset` on.
    data_file: Option<PathBuf>,
    offset: usize,
    /// Whether the header's blank line was found (it ends the header).
    ended: bool,
}

impl Header {
    /// Bytes of one step (every channel).
    fn block(&self) -> u64 {
        let voxels = self.dims.iter().fold(1u64, |n, &d| n.saturating_mul(d as u64));
        voxels.saturating_mul(self.ty.bytes() as u64 * self.axes.channels as u64)
    }
}

/// A header field's name as fields are compared: lower case, no spaces.
fn field_key(name: &str) -> String {
    name.chars()
        .filter(|c| !c.is_whitespace())
        .flat_map(char::to_lowercase)
        .collect()
}

/// Parses the header of `bytes` (a detached data file is allowed where
/// `detached` says so).
fn header(path: &Path, bytes: &[u8], detached: bool) -> Result<Header> {
    if !bytes.starts_with(b"NRRD000") {
        return Err(Error::format(path, "not a NRRD file (no NRRD000x magic)"));
    }
    // The header ends at the first empty line (attached data follows it).
    let mut fields: HashMap<String, String> = HashMap::new();
    let mut pos = 0usize;
    let mut first = true;
    let mut ended = false;
    while pos < bytes.len() {
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| pos + i);
        let line = String::from_utf8_lossy(&bytes[pos..end])
            .trim_end_matches('\r')
            .to_string();
        pos = end + 1;
        if first {
            first = false;
            continue;
        }
        if line.is_empty() {
            ended = true;
            break;
        }
        if line.starts_with('#') || line.contains(":=") {
            continue;
        }
        let Some((k, v)) = line.split_once(':') else {
            return Err(Error::format(path, format!("NRRD header line without ':': '{line}'")));
        };
        // Field names compare without case and spaces, so the format's
        // spellings ("byte skip" and "byteskip", "data file" and
        // "datafile") are one field; each may be given once.
        let name = k.trim().to_lowercase();
        // The lines after it name the files, so it is refused here, by name.
        if field_key(&name) == field_key("data file") && is_list(v.trim()) {
            return Err(Error::format(
                path,
                "NRRD 'data file: LIST' (data split over listed files) is not supported: join them into one file",
            ));
        }
        if fields.insert(field_key(&name), v.trim().to_string()).is_some() {
            return Err(Error::format(
                path,
                format!("NRRD header gives the field '{name}' twice (a field may be given once)"),
            ));
        }
    }
    let get = |k: &str| fields.get(&field_key(k)).map(String::as_str);
    let require = |k: &str| get(k).ok_or_else(|| Error::format(path, format!("NRRD header has no '{k}' field")));

    let ty_name = require("type")?;
    let ty =
        nrrd_type(ty_name).ok_or_else(|| Error::format(path, format!("NRRD type '{ty_name}' is not supported")))?;
    let dimension: usize = require("dimension")?
        .parse()
        .map_err(|_| Error::format(path, "NRRD 'dimension' is not an integer"))?;
    let sizes = numbers(path, "sizes", require("sizes")?)?;
    for &size in &sizes {
        if !(size.fract() == 0.0 && (1.0..=u32::MAX as f64).contains(&size)) {
            return Err(Error::format(
                path,
                format!(
                    "NRRD size '{}' is not a positive 32-bit integer",
                    crate::error::number(size)
                ),
            ));
        }
    }
    // A slice (or a row) is a volume one voxel thick, as a 2-D NIfTI is:
    // its missing axes have size 1 and spacing 1.
    let flat = (1..3).contains(&dimension) && sizes.len() == dimension;
    let (dimension, sizes) = match flat {
        true => (3, [sizes.clone(), vec![1.0; 3 - sizes.len()]].concat()),
        false => (dimension, sizes),
    };
    let axes = axes(path, dimension, &sizes, get("kinds"))?;
    let dims = axes.spatial.map(|a| sizes[a] as u32);
    let little = match get("endian") {
        // Multi-byte voxels are read in the byte order the file states, as
        // teem requires; a guess would read a big-endian file as noise.
        // (An encoding lacuna does not read is named below instead.)
        None if ty.bytes() > 1 && matches!(get("encoding"), Some("raw" | "gzip" | "gz")) => {
            return Err(Error::format(
                path,
                format!("NRRD header has no 'endian' field, which {ty} voxels need (little or big)"),
            ))
        }
        None | Some("little") => true,
        Some("big") => false,
        Some(e) => return Err(Error::format(path, format!("NRRD endian '{e}' is not little or big"))),
    };
    let spacings = get("spacings").map(|s| numbers(path, "spacings", s)).transpose()?;
    // Per axis, `none` for one without a direction (a component or time axis).
    let directions = get("space directions")
        .map(|d| direction_lengths(path, d))
        .transpose()?;
    // The format gives an axis one of the two: an axis with both, its
    // spacing not nan, would have one ignored without a word.
    if let (Some(spacings), Some(directions)) = (&spacings, &directions) {
        let both = spacings
            .iter()
            .zip(directions)
            .position(|(s, d)| d.is_some() && !s.is_nan());
        if let Some(axis) = both {
            return Err(Error::format(
                path,
                format!(
                    "NRRD axis {axis} has both a spacing ({}) and a space direction, which the format does not allow: keep one (or make its spacing nan)",
                    crate::error::number(spacings[axis])
                ),
            ));
        }
    }
    let lengths: Option<Vec<f64>> = directions
        .map(|d| d.into_iter().flatten().collect::<Vec<f64>>())
        .filter(|l| !l.is_empty());
    let (spacing, field) = match (lengths, &spacings) {
        (Some(lengths), _) => (lengths, "space directions' lengths"),
        (None, Some(all)) if all.len() == sizes.len() => (axes.spatial.iter().map(|&a| all[a]).collect(), "spacings"),
        (None, Some(all)) => (all.clone(), "spacings"),
        (None, None) => (vec![1.0; 3], "spacings"),
    };
    let spacing = match flat && spacing.len() < 3 {
        true => [spacing.clone(), vec![1.0; 3 - spacing.len()]].concat(),
        false => spacing,
    };
    // Checked as f32, as the volume keeps them (1e-300 would be 0, 1e308 inf).
    let spacing = match spacing.as_slice() {
        [x, y, z] if [x, y, z].iter().all(|v| (**v as f32).is_finite() && **v as f32 > 0.0) => {
            [*x as f32, *y as f32, *z as f32]
        }
        other => {
            let given: Vec<String> = other.iter().map(|v| crate::error::number(*v)).collect();
            return Err(Error::format(
                path,
                format!(
                    "NRRD {field} must be three positive numbers within f32's range, not {}",
                    given.join(" ")
                ),
            ));
        }
    };

    let skip: u64 = get("byte skip").map_or(Ok(0), |s| match s.parse::<i64>() {
        Ok(n) if n >= 0 => Ok(n as u64),
        Ok(-1) => Err(Error::format(
            path,
            "NRRD 'byte skip: -1' (the data at the file's end) is not supported: give the data's byte offset",
        )),
        _ => Err(Error::format(path, format!("NRRD 'byte skip' must be >= 0, not '{s}'"))),
    })?;
    // Lines of the data file before its data (a foreign header): its bytes
    // would have to be scanned for line ends; refused, never ignored.
    match get("line skip").map(str::parse::<u64>) {
        None | Some(Ok(0)) => {}
        Some(_) => {
            return Err(Error::format(
                path,
                "NRRD 'line skip' is not supported: give the data's offset as 'byte skip'",
            ))
        }
    }
    let gzip = match require("encoding")? {
        "raw" => false,
        "gzip" | "gz" => true,
        other => {
            return Err(Error::format(
                path,
                format!("NRRD encoding '{other}' is not supported (raw, gzip)"),
            ))
        }
    };
    let data_file = match get("data file") {
        Some(name) => {
            if !detached {
                return Err(Error::format(
                    path,
                    format!("NRRD data file '{name}' is detached; load the header from its path"),
                ));
            }
            if is_list(name) || name.contains('%') {
                return Err(Error::format(
                    path,
                    "NRRD multi-file data ('LIST' or format patterns) is not supported",
                ));
            }
            Some(path.parent().unwrap_or(Path::new(".")).join(name))
        }
        None if !ended => return Err(Error::format(path, "NRRD header has no blank line before the data")),
        None => None,
    };
    Ok(Header {
        ty,
        dims,
        axes,
        little,
        spacing,
        skip,
        gzip,
        data_file,
        offset: pos.min(bytes.len()),
        ended,
    })
}

/// Parses the header of `bytes`, checks the volume's size, then reads step
/// `step`'s data (None: the header only): attached, or (when `detached`
/// allows) from the named file. Returns the volume and the time steps.
fn parse(
    path: &Path,
    bytes: &[u8],
    detached: bool,
    device: Option<&DeviceInfo>,
    step: Option<u32>,
) -> Result<(Option<Volume>, u32)> {
    let h = header(path, bytes, detached)?;
    let Some(step) = step else {
        return Ok((None, h.axes.steps));
    };
    super::check_file_step(path, step, h.axes.steps)?;
    let (ty, dims, axes, little, spacing) = (h.ty, h.dims, &h.axes, h.little, h.spacing);
    for _ in 0..axes.channels {
        super::check_size(dims, ty, &path.display().to_string(), device)?;
    }
    // The bytes the header describes: nothing reads or inflates beyond them
    // (one more tells a longer input), so no input expands without bound.
    let block = h.block();
    let wanted = h.skip.saturating_add(block * axes.steps as u64);
    let (source, raw): (PathBuf, Cow<[u8]>) = match &h.data_file {
        Some(data_path) => {
            // Deflate's worst case grows data by well under 1 %.
            let limit = if h.gzip {
                wanted.saturating_mul(2).saturating_add(1 << 16)
            } else {
                wanted
            };
            (data_path.clone(), Cow::Owned(read_at_most(data_path, limit)?))
        }
        None => (path.to_path_buf(), Cow::Borrowed(&bytes[h.offset..])),
    };
    let inflated;
    let data: &[u8] = if h.gzip {
        super::check_gzip_holds(&source, raw.len() as u64, wanted)?;
        inflated = inflate(&source, &raw, wanted)?;
        &inflated
    } else {
        &raw
    };
    let payload = data.get(h.skip.min(usize::MAX as u64) as usize..).unwrap_or_default();
    if payload.len() as u64 != block * axes.steps as u64 {
        return Err(short_data(&source, &h, payload.len() as u64));
    }
    // This step's block: voxels with their channels interleaved, fastest.
    let at = (block * step as u64) as usize;
    let payload = &payload[at..at + block as usize];
    let name = path.display().to_string();
    if axes.channels == 1 {
        let mut volume = decode(&source, payload, ty, little, dims, spacing)?;
        volume.name = name;
        return Ok((Some(volume), axes.steps));
    }
    let (c_all, b) = (axes.channels as usize, ty.bytes());
    let channels = (0..c_all)
        .map(|c| {
            let bytes: Vec<u8> = payload
                .chunks_exact(b * c_all)
                .flat_map(|v| &v[c * b..(c + 1) * b])
                .copied()
                .collect();
            let mut v = decode(&source, &bytes, ty, little, dims, spacing)?;
            v.name = format!("{name}[{c}]");
            Ok(v)
        })
        .collect::<Result<Vec<_>>>()?;
    Volume::join(channels).map(|mut v| {
        v.name = name;
        (Some(v), axes.steps)
    })
}

/// The error for data of `len` bytes where `h` needs another length.
fn short_data(source: &Path, h: &Header, len: u64) -> Error {
    let [w, ht, d] = h.dims;
    Error::format(
        source,
        format!(
            "holds {len} bytes of voxel data but {w}x{ht}x{d} {} ({} channels, {} steps) needs {}",
            h.ty,
            h.axes.channels,
            h.axes.steps,
            h.block() * h.axes.steps as u64
        ),
    )
}

/// The first 64 KiB of `path`, where a header is read from (headers are short).
fn head(path: &Path) -> Result<Vec<u8>> {
    first_bytes(path, HEAD_BYTES as u64)
}

/// The first `n` bytes of `path` (all of a shorter file).
fn first_bytes(path: &Path, n: u64) -> Result<Vec<u8>> {
    let (file, _) = crate::limits::open_input(path)?;
    let mut head = Vec::new();
    file.take(n).read_to_end(&mut head).map_err(|e| Error::io(path, e))?;
    Ok(head)
}

const HEAD_BYTES: usize = 1 << 16;

/// The grid and type of a one-channel NRRD whose data can stream (raw, or
/// gzip with the `loaders` feature; a header within 64 KiB); None else.
pub fn streamed_layout(path: &Path) -> Option<([u32; 3], VoxelType)> {
    let head = head(path).ok()?;
    let h = header(path, &head, true).ok()?;
    // A detached header without its blank line is whole only if the head
    // holds the whole file.
    let whole = h.ended || head.len() < HEAD_BYTES;
    (whole && h.axes.channels == 1 && (!h.gzip || cfg!(feature = "loaders"))).then_some((h.dims, h.ty))
}

/// Reads `path`, or fails (without reading on) when it holds more than
/// `limit` bytes; its exact length is then checked by `decode`.
fn read_at_most(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let (file, len) = crate::limits::open_input(path)?;
    if len > limit {
        return Err(Error::format(
            path,
            format!("holds {len} bytes, more than the {limit} bytes the NRRD header allows for"),
        ));
    }
    crate::limits::check_host(format_args!("NRRD file {}", path.display()), len, 1)?;
    let mut out = Vec::new();
    file.take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| Error::io(path, e))?;
    if out.len() as u64 > limit {
        return Err(Error::format(
            path,
            format!("holds more than the {limit} bytes the NRRD header describes"),
        ));
    }
    Ok(out)
}

/// Inflates gzip data, no further than `wanted` bytes and one more.
#[cfg(feature = "loaders")]
fn inflate(source: &Path, raw: &[u8], wanted: u64) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(raw)
        .take(wanted.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| Error::format(source, format!("corrupt gzip data: {e}")))?;
    Ok(out)
}

#[cfg(not(feature = "loaders"))]
fn inflate(source: &Path, _: &[u8], _: u64) -> Result<Vec<u8>> {
    Err(Error::format(
        source,
        "gzip-encoded NRRD needs lacuna's `loaders` cargo feature",
    ))
}
