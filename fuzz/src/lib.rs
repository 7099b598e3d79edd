//! The fuzz targets' bodies: each feeds one parser bytes from libFuzzer and
//! checks that bad input is a one-line error; each returns whether the
//! input parsed. `tests/integration/fuzz_inputs.rs` in the
//! main package includes this file and runs the seeds and every crash found
//! through the same functions on stable.

use lacuna::bench::BenchConfig;
use lacuna::frame::Frame;
use lacuna::volume::{parse_dims, parse_type, LoadOptions, VolumeSpec};
use lacuna::{TransferFunction, Volume};
use std::path::Path;

/// Errors are one line (the CLI prints them after `error: `); true when parsed.
fn one_line<T>(result: lacuna::Result<T>) -> bool {
    match result {
        Ok(_) => true,
        Err(e) => {
            let text = e.to_string();
            assert!(!text.contains('\n'), "multi-line error: {text}");
            false
        }
    }
}

/// Splits `data` at its first newline: (first line as text, the rest).
fn split_line(data: &[u8]) -> (String, &[u8]) {
    let end = data.iter().position(|&b| b == b'\n').unwrap_or(data.len());
    let rest = data.get(end + 1..).unwrap_or_default();
    (String::from_utf8_lossy(&data[..end]).into_owned(), rest)
}

/// The volume spec parser (`NAME:SIZE[:PARAM]` or a path), dims and types;
/// specs of up to 4096 voxels are generated.
pub fn volume_spec(data: &[u8]) -> bool {
    let text = String::from_utf8_lossy(data);
    // Specs naming real files would read them: only procedural-looking ones.
    if text.contains(['/', '\\', '\0']) {
        return false;
    }
    one_line(parse_dims(&text));
    one_line(parse_type(&text));
    // Procedural specs only (a path is not this target's); small ones are
    // generated too, which checks their parameters.
    match VolumeSpec::parse(&text, &LoadOptions::default()) {
        Ok(VolumeSpec::Procedural { generator, dims, param }) => {
            dims.iter().map(|&d| d as u64).product::<u64>() > 4096 || one_line(generator.generate(dims, param))
        }
        Ok(VolumeSpec::File(_)) => false,
        // Joined channels of small generators: the join checks their grids.
        Ok(spec @ VolumeSpec::Channels(_)) => {
            let small = |s: &VolumeSpec| match s {
                VolumeSpec::Procedural { dims, .. } => dims.iter().map(|&d| d as u64).product::<u64>() <= 4096,
                _ => false,
            };
            match &spec {
                VolumeSpec::Channels(parts) if parts.iter().all(small) => one_line(spec.load(&LoadOptions::default())),
                _ => false,
            }
        }
        Err(e) => one_line::<()>(Err(e)),
    }
}

/// The raw loader: the first line is the file name (its layout), the rest the bytes.
pub fn raw(data: &[u8]) -> bool {
    let (name, bytes) = split_line(data);
    one_line(Volume::from_raw_bytes(&name, bytes, None))
}

/// NRRD with attached data (raw or gzip).
pub fn nrrd(data: &[u8]) -> bool {
    one_line(Volume::from_nrrd_bytes("fuzz.nrrd", data))
}

/// NIfTI-1 single files, plain or gzip.
pub fn nifti(data: &[u8]) -> bool {
    one_line(Volume::from_nifti_bytes("fuzz.nii", data))
}

/// Transfer-function specs (first byte `s`) or ParaView JSON (anything else).
pub fn tf(data: &[u8]) -> bool {
    match data.split_first() {
        Some((b's', rest)) => {
            let spec = String::from_utf8_lossy(rest);
            // A spec naming a file reads it: only inline specs here.
            !spec.to_lowercase().ends_with(".json")
                && !Path::new(spec.as_ref()).exists()
                && one_line(TransferFunction::parse(&spec))
        }
        _ => {
            let text = String::from_utf8_lossy(data);
            one_line(TransferFunction::from_paraview_json_str(&text, Path::new("fuzz.json")))
        }
    }
}

/// Bench configurations (TOML).
pub fn bench_toml(data: &[u8]) -> bool {
    one_line(BenchConfig::parse(&String::from_utf8_lossy(data), "fuzz.toml"))
}

/// EXR frames as `lacuna diff` reads them.
pub fn exr(data: &[u8]) -> bool {
    one_line(Frame::read_exr_bytes(data, Path::new("fuzz.exr")))
}
