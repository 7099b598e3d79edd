//! Limits on what input may ask for: host memory checked before anything
//! sized from input is allocated, and the cap on samples per ray that keeps
//! every GPU submission short (a driver watchdog resets the device when one
//! runs for seconds). The device's own limits are checked by `gpu`.

use crate::error::{Error, Result};
use std::path::Path;

/// Most samples one ray may take (longest ray through the box / step):
/// 2^20, a million, ~2000x the default step's count on a 1024^3 volume.
pub const MAX_SAMPLES_PER_RAY: u64 = 1 << 20;

/// Most samples (rays x the longest ray's samples) one submission of
/// `Renderer::render` marches: a frame over it is marched in bands of rows,
/// one submission each, so none runs long enough to trip a driver's watchdog
/// (2^30 samples take well under a second on a mid-range GPU).
pub const MAX_SAMPLES_PER_SUBMIT: u64 = 1 << 30;

/// Bytes of host memory available to new allocations: `MemAvailable` from
/// `/proc/meminfo`, or unlimited where that cannot be read (the allocator
/// then still fails with an error, not an abort, through `try_reserve`).
pub fn available_memory() -> u64 {
    let text = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    text.lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(u64::MAX, |kib| kib.saturating_mul(1024))
}

/// Checks that `count` items of `item_bytes` each fit the host's available
/// memory; returns the bytes. `what` names the input (e.g. `volume 4096x4096x4096`).
pub fn check_host(what: impl std::fmt::Display, count: u64, item_bytes: u64) -> Result<u64> {
    let available = available_memory();
    match count.checked_mul(item_bytes) {
        Some(bytes) if bytes <= available => Ok(bytes),
        bytes => Err(Error::HostMemory {
            what: what.to_string(),
            bytes: bytes.map_or_else(|| format!("more than {}", u64::MAX), |b| b.to_string()),
            available,
        }),
    }
}

/// A zeroed vector of `count` items, after `check_host`; an allocation the
/// check could not foresee (memory taken meanwhile) is an error too.
pub fn zeroed<T: Clone + Default>(what: impl std::fmt::Display, count: u64) -> Result<Vec<T>> {
    let item = std::mem::size_of::<T>().max(1) as u64;
    let bytes = check_host(&what, count, item)?;
    let mut v = Vec::new();
    v.try_reserve_exact(count as usize).map_err(|_| Error::HostMemory {
        what: what.to_string(),
        bytes: bytes.to_string(),
        available: available_memory(),
    })?;
    v.resize(count as usize, T::default());
    Ok(v)
}

/// The longest side of a frame, in pixels: larger is a mistake, refused
/// before any memory is sought for it.
pub const MAX_FRAME_SIDE: u32 = 16384;

/// The most frames, builds, rounds or warm-up runs a command or a bench
/// protocol asks for: each is a frame or a build, and more is a typo.
pub const MAX_RUNS: u32 = 100_000;

/// Checks that rays through a `dims` box sampled every `step` voxels take
/// at most `MAX_SAMPLES_PER_RAY` samples, and that the step is no longer
/// than the box's diagonal (a longer one samples a ray at most once);
/// returns the longest ray's count.
pub fn check_samples_per_ray(dims: [u32; 3], step: f32) -> Result<u64> {
    let diagonal = dims.iter().map(|&d| (d as f64).powi(2)).sum::<f64>().sqrt();
    if step as f64 > diagonal {
        return Err(Error::invalid(
            "step",
            step.to_string(),
            format!(
                "is longer than the diagonal of the {}x{}x{} box ({diagonal:.1} voxels): a ray would take at most one sample",
                dims[0], dims[1], dims[2]
            ),
        ));
    }
    let samples = (diagonal / step as f64).ceil();
    if !(samples.is_finite() && samples <= MAX_SAMPLES_PER_RAY as f64) {
        return Err(Error::invalid(
            "step",
            step.to_string(),
            format!(
                "the longest ray through the {}x{}x{} box would take {samples:.0} samples, over the cap of {MAX_SAMPLES_PER_RAY} samples per ray (MAX_SAMPLES_PER_RAY)",
                dims[0], dims[1], dims[2]
            ),
        ));
    }
    Ok(samples as u64)
}

/// Loop passes a SIMD group's march runs on rays of `samples` samples
/// through a box whose diagonal is `diagonal` voxels: one per sample, a
/// second per sample of a lit frame (its group leaves the sample loop to
/// light a visible one), 8 per voxel of the ray for a structure's traversal
/// (a few small loops per region entered, regions at least 2 voxels wide),
/// and the ray's set-up. A bound for naive marching, whose lanes march one
/// span each. Not for every structure: where a group's lanes march spans
/// of different lengths, each pass of the sample loop waits for the longest
/// one, so a group can run more sample passes than any one ray has samples;
/// such a march finds out itself (`Renderer::check_whole`, `Error::LoopCap`).
pub fn march_loop_passes(samples: u64, diagonal: f64, lit: bool) -> u64 {
    let per_sample = 1 + lit as u64;
    samples
        .saturating_mul(per_sample)
        .saturating_add(8 * diagonal.ceil() as u64)
        .saturating_add(256)
}

/// Checks that a march through a `dims` box every `step` voxels fits
/// `limit` loop passes (`DeviceInfo::loop_pass_limit`, on a device that
/// caps them; `device` names it): past it the device would end the march
/// early and the frame would be wrong without a word.
pub fn check_loop_passes(device: &str, limit: Option<u64>, dims: [u32; 3], step: f32, lit: bool) -> Result<()> {
    let Some(limit) = limit else {
        return Ok(());
    };
    let samples = check_samples_per_ray(dims, step)?;
    let diagonal = dims.iter().map(|&d| (d as f64).powi(2)).sum::<f64>().sqrt();
    if march_loop_passes(samples, diagonal, lit) <= limit {
        return Ok(());
    }
    // The least step that fits, rounded up to three significant digits.
    let fixed = march_loop_passes(0, diagonal, lit);
    let most = (limit.saturating_sub(fixed) / (1 + lit as u64)).max(1);
    let least = diagonal / most as f64;
    let scale = 10f64.powi(2 - least.log10().floor() as i32);
    Err(Error::invalid(
        "step",
        step.to_string(),
        format!(
            "the longest ray through the {}x{}x{} box would take {samples} samples; {device} ends a SIMD group's loops after {limit} passes in all, so a{} frame of this volume needs a step of at least {} here",
            dims[0],
            dims[1],
            dims[2],
            if lit { " lit" } else { "n unlit" },
            (least * scale).ceil() / scale
        ),
    ))
}

/// Opens an input file after checking that it is a regular file (a FIFO
/// would block the open, a device never end), and gives its length, so a
/// caller checks sizes before reading anything.
pub fn open_input(path: &Path) -> Result<(std::fs::File, u64)> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(Error::format(
            path,
            "is not a regular file (a folder, device or pipe): lacuna reads input from regular files",
        ));
    }
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    Ok((file, meta.len()))
}

/// Reads a whole input file of at most `max` bytes: `what` (e.g. "bench
/// config") names what it should be where it is longer. The read stops
/// past `max` even if the file grows meanwhile.
pub fn read_input(path: &Path, what: &str, max: u64) -> Result<Vec<u8>> {
    let (file, len) = open_input(path)?;
    let too_long = |len: u64| Error::format(path, format!("is {len} bytes, more than a {what} can be ({max} bytes)"));
    if len > max {
        return Err(too_long(len));
    }
    check_host(format_args!("{what} {}", path.display()), len, 1)?;
    let mut out = Vec::new();
    std::io::Read::read_to_end(&mut std::io::Read::take(file, max.saturating_add(1)), &mut out)
        .map_err(|e| Error::io(path, e))?;
    match out.len() as u64 > max {
        true => Err(too_long(out.len() as u64)),
        false => Ok(out),
    }
}

/// `read_input` of a UTF-8 text file.
pub fn read_input_text(path: &Path, what: &str, max: u64) -> Result<String> {
    String::from_utf8(read_input(path, what, max)?).map_err(|e| Error::format(path, format!("is not UTF-8 text: {e}")))
}

/// The longest text input lacuna reads whole (a bench config, a transfer
/// function, a results.json): far past any real one, and parsed within a
/// few hundred MB.
pub const MAX_TEXT_INPUT: u64 = 16 << 20;

/// Channels a volume can have (one texel of up to four components per
/// voxel on the GPU), and so transfer functions per frame.
pub const MAX_CHANNELS: usize = 4;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn host_check_names_the_bytes_and_the_limit() {
        assert_eq!(check_host("x", 10, 4).unwrap(), 40);
        let e = check_host("volume 100000x100000x100000", 1_000_000_000_000_000, 1).unwrap_err();
        let text = e.to_string();
        assert!(text.contains("volume 100000x100000x100000"), "{text}");
        assert!(text.contains("1000000000000000 bytes"), "{text}");
        assert!(text.contains("MemAvailable"), "{text}");
        assert!(check_host("overflow", u64::MAX, 2)
            .unwrap_err()
            .to_string()
            .contains("more than"));
        assert_eq!(zeroed::<u32>("v", 3).unwrap(), vec![0; 3]);
    }

    #[test]
    fn loop_passes_bound_lit_frames_twice_and_name_the_least_step() {
        let dims = [32, 32, 32];
        assert!(check_loop_passes("x", None, dims, 1e-4, true).is_ok());
        assert!(check_loop_passes("x", Some(65535), dims, 0.5, true).is_ok());
        // 55.4 voxels of diagonal: about 110852 samples at 0.0005.
        let e = check_loop_passes("llvmpipe", Some(65535), dims, 0.0005, false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("llvmpipe ends a SIMD group's loops after 65535"), "{e}");
        assert!(e.contains("step of at least 0.000855"), "{e}");
        let lit = check_loop_passes("llvmpipe", Some(65535), dims, 0.0015, true)
            .unwrap_err()
            .to_string();
        assert!(
            lit.contains("lit frame") && lit.contains("step of at least 0.00171"),
            "{lit}"
        );
        assert!(check_loop_passes("llvmpipe", Some(65535), dims, 0.0015, false).is_ok());
        // The step it names fits.
        assert!(check_loop_passes("llvmpipe", Some(65535), dims, 0.00171, true).is_ok());
    }

    #[test]
    fn inputs_are_regular_files_read_up_to_their_cap() {
        let dir = std::env::temp_dir().join(format!("lacuna-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("c.toml");
        std::fs::write(&file, "name = 1\n").unwrap();
        assert_eq!(read_input_text(&file, "bench config", 9).unwrap(), "name = 1\n");
        let long = read_input(&file, "bench config", 8).unwrap_err().to_string();
        assert!(
            long.contains("is 9 bytes, more than a bench config can be (8 bytes)"),
            "{long}"
        );
        let folder = read_input(&dir, "bench config", 8).unwrap_err().to_string();
        assert!(folder.contains("is not a regular file"), "{folder}");
        let device = read_input(Path::new("/dev/zero"), "bench config", 8)
            .unwrap_err()
            .to_string();
        assert!(device.contains("is not a regular file"), "{device}");
        std::fs::write(&file, [0xff, 0xfe]).unwrap();
        assert!(read_input_text(&file, "x", 8)
            .unwrap_err()
            .to_string()
            .contains("not UTF-8"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn samples_per_ray_cap() {
        assert_eq!(check_samples_per_ray([3, 4, 0], 0.5).unwrap(), 10);
        assert!(check_samples_per_ray([1024; 3], 1.0 / 512.0).is_ok());
        let e = check_samples_per_ray([64; 3], 1e-9).unwrap_err().to_string();
        assert!(e.contains("1048576 samples per ray"), "{e}");
    }
}
