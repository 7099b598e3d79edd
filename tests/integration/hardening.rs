//! Hardening: inputs that ask for too much memory, too much GPU work, or are
//! hostile files give one `error:` line and a non-zero exit, with no panic,
//! no backtrace and no output file; the error names the check that refused
//! the input, so nothing was allocated or marched first.

use crate::common;

use std::path::Path;
use std::process::{Command, Stdio};

/// Runs `lacuna args` with RUST_BACKTRACE=1 (a panic would show one);
/// returns (exit code, stderr). That it refused before allocating is shown
/// by the error naming the size check, not by a clock.
fn run(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_lacuna"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// `args` (plus `--out DIR/out.exr` when `out`) fail with exactly one
/// `error:` line containing every needle, and `dir` stays empty.
fn fails(dir: &Path, args: &[&str], out: bool, needles: &[&str]) {
    let target = dir.join("out.exr");
    let target = target.to_str().unwrap();
    let mut all = args.to_vec();
    if out {
        all.extend(["--out", target]);
    }
    let (code, stderr) = run(&all);
    assert!(code.is_some_and(|c| c != 0), "{all:?}: exit {code:?}\n{stderr}");
    let lines: Vec<&str> = stderr.trim_end().lines().collect();
    assert_eq!(lines.len(), 1, "{all:?}: expected one line:\n{stderr}");
    assert!(lines[0].starts_with("error: "), "{all:?}: {}", lines[0]);
    for n in needles {
        assert!(lines[0].contains(n), "{all:?}: '{}' lacks '{n}'", lines[0]);
    }
    assert!(
        !stderr.contains("panicked") && !stderr.contains("backtrace"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_dir(dir).unwrap().count(), 0, "{all:?} left a file");
}

#[test]
fn sizes_are_checked_before_allocation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 10^15 voxels: the host check, from the spec alone.
    fails(
        d,
        &["render", "nbody:100000", "--validate"],
        true,
        &[
            "volume nbody:100000x100000x100000",
            "bytes of host memory",
            "MemAvailable",
        ],
    );
    fails(d, &["info", "menger:100000"], false, &["bytes of host memory"]);
    fails(
        d,
        &["export", "turbulence:60000", d.join("x.raw").to_str().unwrap()],
        false,
        &["bytes of host memory"],
    );
    // A frame side over the bound, before any memory is sought for it.
    fails(
        d,
        &["render", "menger:16", "--size", "100000x100000", "--validate"],
        true,
        &["invalid size '100000x100000'", "1..=16384 pixels"],
    );
    let bench_out = d.join("bench");
    fails(
        d,
        &[
            "bench",
            "--quick",
            "--frames",
            "100000",
            "--rounds",
            "100000",
            "--out",
            bench_out.to_str().unwrap(),
            "--quiet",
        ],
        false,
        &["100000 frames x 100000 rounds", "bytes of host memory"],
    );
    // Past the cap of runs a field may ask for, before any work.
    for flag in ["--frames", "--warmup", "--builds", "--rounds"] {
        let what = flag.trim_start_matches('-');
        fails(
            d,
            &[
                "bench",
                "--quick",
                flag,
                "4000000000",
                "--out",
                bench_out.to_str().unwrap(),
            ],
            false,
            &[&format!("{what} 4000000000 must be at most 100000")],
        );
    }
    // The device's limits, from the spec, before the volume is generated:
    // a volume of one image dimension's maximum squared, deep enough to
    // pass maxMemoryAllocationSize, stored dense (auto would store it in
    // bricks and render it).
    let ctx = common::gpu();
    let info = ctx.info().clone();
    drop(ctx);
    let side = info.max_image_dimension_3d as u64;
    let depth = (info.max_memory_allocation_size / (side * side) + 1).min(side);
    let spec = format!("menger:{side}x{side}x{depth}");
    if side * side * depth > info.max_memory_allocation_size {
        let (code, stderr) = run(&["render", &spec, "--storage", "dense", "--validate"]);
        assert_eq!(code, Some(2), "{stderr}");
        assert!(
            stderr.contains("exceeds the device limit") || stderr.contains("bytes of host memory"),
            "{stderr}"
        );
    }
    // Headers: a NRRD and a NIfTI of 10^15 voxels hold a few bytes.
    let nrrd = d.join("huge.nrrd");
    std::fs::write(
        &nrrd,
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 100000 100000 100000\nencoding: gzip\n\n",
    )
    .unwrap();
    let nrrd_s = nrrd.to_str().unwrap().to_string();
    let nii = d.join("huge.nii");
    std::fs::write(&nii, nifti_header([32767, 32767, 32767])).unwrap();
    let nii_s = nii.to_str().unwrap().to_string();
    let files = tempfile::tempdir().unwrap();
    for input in [&nrrd_s, &nii_s] {
        fails(files.path(), &["info", input], false, &["bytes of host memory"]);
    }
    // Rendering streams them into bricks, one slab at a time; a slab of
    // one 32767^2 double layer is 8 GiB, so a gzip file too small to hold
    // the grid is refused before it (deflate inflates at most 1032:1).
    let gz_nrrd = d.join("huge_gz.nrrd");
    let mut bytes =
        b"NRRD0004\ntype: double\ndimension: 3\nsizes: 32767 32767 32767\nendian: little\nencoding: gzip\n\n".to_vec();
    bytes.extend(common::gzip(&[0; 4096]));
    std::fs::write(&gz_nrrd, bytes).unwrap();
    let mut nii = nifti_header([32767, 32767, 32767]);
    nii[70..72].copy_from_slice(&64i16.to_le_bytes());
    nii[72..74].copy_from_slice(&64i16.to_le_bytes());
    let gz_nii = d.join("huge.nii.gz");
    std::fs::write(&gz_nii, common::gzip(&[&nii[..], &[0; 4096]].concat())).unwrap();
    for input in [&gz_nrrd, &gz_nii] {
        let input = input.to_str().unwrap();
        fails(
            files.path(),
            &["render", input, "--size", "8x8"],
            true,
            &["which inflate to at most"],
        );
    }
}

/// A NIfTI-1 header of `dims` uint8 voxels and no data.
fn nifti_header(dims: [i16; 3]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (i, d) in [3, dims[0], dims[1], dims[2], 1, 1, 1, 1].iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&2i16.to_le_bytes());
    h[72..74].copy_from_slice(&8i16.to_le_bytes());
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    h
}

#[test]
fn samples_per_ray_are_capped_before_any_dispatch() {
    let dir = tempfile::tempdir().unwrap();
    fails(
        dir.path(),
        &["render", "menger:16", "--size", "8x8", "--step", "1e-9", "--validate"],
        true,
        &["invalid step", "cap of 1048576 samples per ray"],
    );
    // The bench's error sweep renders with its steps too.
    let config = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiny-bench.toml"))
        .unwrap()
        .replace("step = 0.5", "step = 0.0000001");
    assert!(
        config.contains("step = 0.0000001"),
        "tiny-bench.toml has no 'step = 0.5'"
    );
    let cfg_dir = tempfile::tempdir().unwrap();
    let cfg = cfg_dir.path().join("tiny.toml");
    std::fs::write(&cfg, config).unwrap();
    let out = dir.path().join("bench");
    fails(
        dir.path(),
        &[
            "bench",
            cfg.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
            "--validate",
        ],
        false,
        &["samples per ray"],
    );
}

#[test]
fn hostile_files_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let inputs = tempfile::tempdir().unwrap();
    let p = |name: &str| inputs.path().join(name).to_str().unwrap().to_string();
    // A NRRD whose gzip data inflates far past what its header describes.
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    std::io::Write::write_all(&mut gz, &vec![0u8; 1 << 24]).unwrap();
    let mut nrrd = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: gzip\n\n".to_vec();
    nrrd.extend(gz.finish().unwrap());
    std::fs::write(p("bomb.nrrd"), nrrd).unwrap();
    fails(dir.path(), &["render", &p("bomb.nrrd"), "--validate"], true, &["holds"]);
    // A NIfTI header of 1000^3 voxels with no data behind it (the old
    // loader allocated the volume before reading).
    std::fs::write(p("empty.nii"), nifti_header([1000, 1000, 1000])).unwrap();
    fails(dir.path(), &["info", &p("empty.nii")], false, &["bytes of voxel data"]);
    // A rank of 9 (dim[0]), invalid either way round: named as stored.
    let mut rank9 = nifti_header([4, 4, 4]);
    rank9[40..42].copy_from_slice(&9i16.to_le_bytes());
    // int16, whose code swapped (1024) is a type lacuna does not read: the
    // rank is checked first.
    rank9[70..72].copy_from_slice(&4i16.to_le_bytes());
    rank9[72..74].copy_from_slice(&16i16.to_le_bytes());
    rank9.extend([0u8; 64]);
    std::fs::write(p("rank9.nii"), rank9).unwrap();
    fails(
        dir.path(),
        &["info", &p("rank9.nii")],
        false,
        &["NIfTI dim[0] is 9 read little-endian and 2304 big-endian"],
    );
    // Spacings past f32's range (0 or inf as the volume keeps them), and
    // a zero direction: named by the field the file gives them in.
    for (name, field, needle) in [
        (
            "tiny.nrrd",
            "spacings: 1e-300 1 1",
            "NRRD spacings must be three positive numbers within f32's range, not 1e-300 1 1",
        ),
        ("huge.nrrd", "spacings: 1 1e308 1", "within f32's range, not 1 1e308 1"),
        (
            "flat.nrrd",
            "space directions: (0,0,0) (0,1,0) (0,0,1)",
            "NRRD space directions' lengths must be three positive numbers within f32's range, not 0 1 1",
        ),
    ] {
        let mut bytes =
            format!("NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\n{field}\nencoding: raw\n\n").into_bytes();
        bytes.extend([0u8; 64]);
        std::fs::write(p(name), bytes).unwrap();
        fails(dir.path(), &["info", &p(name)], false, &[needle]);
    }
    // Data split over a list of files: named, not a puzzling header line.
    std::fs::write(
        p("list.nhdr"),
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: LIST\na.raw\nb.raw\n",
    )
    .unwrap();
    fails(dir.path(), &["info", &p("list.nhdr")], false, &["'data file: LIST'"]);
    // A file whose name starts so is a file.
    std::fs::write(p("LISTING.raw"), [7u8; 64]).unwrap();
    std::fs::write(
        p("listing.nhdr"),
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: LISTING.raw\n",
    )
    .unwrap();
    let (code, stderr) = run(&["info", &p("listing.nhdr")]);
    assert_eq!(code, Some(0), "{stderr}");
    // Text encodings need no byte order: the encoding is what is named.
    std::fs::write(
        p("ascii.nrrd"),
        "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n1 2 3 4 5 6 7 8\n",
    )
    .unwrap();
    fails(
        dir.path(),
        &["info", &p("ascii.nrrd")],
        false,
        &["NRRD encoding 'ascii' is not supported"],
    );
    // Multi-byte voxels without a byte order: refused, not guessed.
    let mut bytes = b"NRRD0004\ntype: short\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n".to_vec();
    bytes.extend([0u8; 128]);
    std::fs::write(p("endian.nrrd"), bytes).unwrap();
    fails(
        dir.path(),
        &["info", &p("endian.nrrd")],
        false,
        &["no 'endian' field, which int16 voxels need"],
    );
    // An attached NRRD far longer than its header describes: refused
    // from its length, before its data is read.
    let long = p("long.nrrd");
    std::fs::write(
        &long,
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n",
    )
    .unwrap();
    std::fs::OpenOptions::new()
        .write(true)
        .open(&long)
        .unwrap()
        .set_len(1 << 42) // 4 TiB, sparse: past any host's memory, so reading it would fail
        .unwrap();
    fails(
        dir.path(),
        &["info", &long],
        false,
        &["bytes of voxel data but 4x4x4 uint8", "needs 64"],
    );
    // A NRRD naming /dev/zero as its detached data.
    std::fs::write(
        p("zero.nhdr"),
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\ndata file: /dev/zero\n\n",
    )
    .unwrap();
    fails(
        dir.path(),
        &["info", &p("zero.nhdr")],
        false,
        &["/dev/zero: is not a regular file"],
    );
    // Fewer sizes than the dimension says: the count is named.
    std::fs::write(
        p("sizes.nrrd"),
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4\nencoding: raw\n\n",
    )
    .unwrap();
    fails(
        dir.path(),
        &["info", &p("sizes.nrrd")],
        false,
        &["NRRD 'sizes' gives 2 numbers but 'dimension' is 3"],
    );
    // A header line of 1 MB is named, not echoed whole.
    let long = format!(
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: {}\n\n",
        "x".repeat(1 << 20)
    );
    std::fs::write(p("long.nrrd"), long).unwrap();
    let (code, stderr) = run(&["info", &p("long.nrrd")]);
    assert_eq!(code, Some(2), "{}", &stderr[..stderr.len().min(300)]);
    assert!(
        stderr.len() < 2500 && stderr.contains("bytes in all"),
        "{} bytes",
        stderr.len()
    );
    // diff of a file that is not an EXR.
    std::fs::write(p("junk.exr"), b"v/1\x01junk").unwrap();
    let (code, stderr) = run(&["diff", &p("junk.exr"), &p("junk.exr")]);
    assert_eq!(code, Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("EXR") && !stderr.contains("panicked"), "{stderr}");
}

/// `lacuna args` with its standard output's reading end closed at once (and
/// standard error's too, with `stderr_too`), before it has printed.
fn with_closed_pipes(args: &[&str], stderr_too: bool) -> std::process::Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_lacuna"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    if stderr_too {
        drop(child.stderr.take());
    }
    child.wait_with_output().unwrap()
}

#[test]
fn a_closed_pipe_ends_output_quietly() {
    let out = with_closed_pipes(&["info", "menger:16"], false);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.is_empty(), "{stderr}");
    assert!(!out.status.success(), "lacuna wrote to a closed pipe and succeeded");
}

#[test]
fn render_writes_its_frame_after_the_reader_of_its_output_has_gone() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.exr");
    // As `| grep -m1 device` does: gone before the frame is written.
    let run = with_closed_pipes(
        &["render", "menger:16", "--size", "16x16", "--out", out.to_str().unwrap()],
        false,
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success() && stderr.is_empty(), "{:?}: {stderr}", run.status);
    let frame = lacuna::frame::Frame::read_exr(&out).unwrap();
    assert!(frame.pixels.iter().any(|p| p[3] > 0.0), "an empty frame");
    // Its error line with both pipes closed: dropped, and exit code 2, not
    // a panic.
    let run = with_closed_pipes(
        &[
            "render",
            "no_such_4x4x4_uint8.raw",
            "--size",
            "8x8",
            "--out",
            out.to_str().unwrap(),
        ],
        true,
    );
    assert_eq!(run.status.code(), Some(2));
}

#[cfg(target_os = "linux")]
#[test]
fn output_to_a_full_disk_is_one_error_line_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.exr");
    let out = out.to_str().unwrap();
    for args in [
        &["info", "menger:16"][..],
        &["render", "menger:16", "--size", "16x16", "--out", out][..],
        &["devices"][..],
    ] {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let run = Command::new(env!("CARGO_BIN_EXE_lacuna"))
            .args(args)
            .stdout(full)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(
            stderr.trim_end(),
            "error: standard output: No space left on device (os error 28)",
            "{args:?}"
        );
    }
}

/// A perspective frame is the same at any physical scale: its rays were
/// formed one world unit from the eye, which at 1e7 units a voxel lay
/// within f32's rounding of the eye, so no ray had a direction and the
/// march ran into llvmpipe's loop cap ("take a coarser step").
#[test]
fn a_perspective_frame_is_the_same_at_every_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<u8> = (0..16u32 * 16 * 16).map(|i| ((i * 37) % 251) as u8).collect();
    let frame = |spacing: f32, accel: &str| {
        let volume = dir.path().join(format!("v{spacing:e}.nii"));
        std::fs::write(&volume, common::nifti_bytes(&[16, 16, 16], 2, 8, [spacing; 3], &data)).unwrap();
        let out = dir.path().join(format!("f{spacing:e}-{accel}.exr"));
        let args = ["--perspective", "40", "--camera", "35,25", "--accel", accel];
        common::render_ok(volume.to_str().unwrap(), &out, &args);
        lacuna::frame::Frame::read_exr(&out).unwrap()
    };
    let unit = frame(1.0, "naive");
    assert!(unit.pixels.iter().any(|p| p[3] > 0.1), "the volume is not in view");
    for spacing in [1e-10, 1e-3, 1e3, 1e7, 1e25] {
        for accel in ["naive", "grid"] {
            let d = lacuna::frame::diff(&unit, &frame(spacing, accel)).unwrap();
            assert_eq!(d.differing, 0, "spacing {spacing}, {accel}: {d}");
        }
    }
}

/// An orthographic frame, unlit and lit, is the same at every uniform
/// spacing within f32 rounding: its eye plane sat a fixed unit in front of
/// the volume, 1e9 voxels out at 1e-9 a voxel (the frame went transparent),
/// and the lit view direction's square overflowed at 1e20 (shading went flat).
#[test]
fn an_orthographic_frame_is_the_same_at_every_spacing() {
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<u8> = (0..16u32 * 16 * 16).map(|i| ((i * 37) % 251) as u8).collect();
    let frame = |spacing: f32, shade: &str| {
        let volume = dir.path().join(format!("v{spacing:e}.nii"));
        std::fs::write(&volume, common::nifti_bytes(&[16, 16, 16], 2, 8, [spacing; 3], &data)).unwrap();
        let out = dir.path().join(format!("o{spacing:e}-{shade}.exr"));
        let args = ["--camera", "35,25", "--accel", "naive", "--shade", shade];
        common::render_ok(volume.to_str().unwrap(), &out, &args);
        lacuna::frame::Frame::read_exr(&out).unwrap()
    };
    for shade in ["off", "on"] {
        let unit = frame(1.0, shade);
        assert!(unit.pixels.iter().any(|p| p[3] > 0.1), "the volume is not in view");
        for spacing in [1e-9, 1e-5, 1e5, 1e20] {
            let d = lacuna::frame::diff(&unit, &frame(spacing, shade)).unwrap();
            assert!(d.max_abs < 1e-5, "spacing {spacing}, shade {shade}: {d}");
        }
    }
}

/// A spacing past f32 once multiplied by the dims is an error naming the
/// spacing and the volume; a very uneven one loads, and where a camera
/// forms no finite rays from it, that frame's error says so in a line.
#[test]
fn spacings_past_f32_are_errors_and_uneven_ones_load() {
    let data = [7u8; 8 * 8 * 8];
    let bytes = common::nifti_bytes(&[8, 8, 8], 2, 8, [1e38, 1e-38, 1.0], &data);
    let err = lacuna::Volume::from_nifti_bytes("s.nii", &bytes)
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "invalid spacing '1e38 x 1e-38 x 1': s.nii: the volume's physical size (dims x spacing) is past f32"
    );
    let bytes = common::nifti_bytes(&[8, 8, 8], 2, 8, [1e7, 1.0, 1.0], &data);
    assert!(lacuna::Volume::from_nifti_bytes("s.nii", &bytes).is_ok());
    let dir = tempfile::tempdir().unwrap();
    let flat = dir.path().join("flat.nii");
    std::fs::write(&flat, common::nifti_bytes(&[8, 8, 8], 2, 8, [1e30, 1e-30, 1.0], &data)).unwrap();
    common::fails(
        &["render", flat.to_str().unwrap(), "--size", "8x8"],
        &[],
        "form no finite rays for a volume of spacing",
    );
}
