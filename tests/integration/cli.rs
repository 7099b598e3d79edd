//! The `lacuna` binary end to end: render to EXR (read back with the `exr`
//! crate, metadata checked) and PNG (decoded with the `png` crate), info, diff exit codes, devices, and every bad
//! input as a one-line error with a non-zero exit and no output file.

use crate::common;
use crate::common::{fails, lacuna, render_ok, render_ok_with};
use lacuna::frame::Frame;
use std::path::Path;

#[test]
fn render_prints_pass_timings_and_writes_an_exr_with_metadata() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("frame.exr");
    let r = render_ok("menger:24", &out, &["--camera", "-20,15", "--step", "0.75"]);
    assert!(
        r.stdout.contains("march") && r.stdout.contains("readback") && r.stdout.contains("total"),
        "{}",
        r.stdout
    );
    assert!(r.stderr.is_empty(), "{}", r.stderr);
    let frame = Frame::read_exr(&out).unwrap();
    assert_eq!((frame.width, frame.height), (40, 32));
    assert!(frame.pixels.iter().any(|p| p[3] > 0.1));
    for key in [
        "volume", "tf", "accel", "camera", "step", "ert", "filter", "device", "gpu_ms",
    ] {
        assert!(
            frame.metadata.contains_key(key),
            "missing metadata {key}: {:?}",
            frame.metadata
        );
    }
    // The default structure is auto, which records what it chose.
    assert_eq!(frame.metadata["accel"], "auto");
    let chosen = &frame.metadata["marched_as"];
    let structure = chosen.split([' ', '(']).next().unwrap();
    let found = lacuna::accel::Accel::find(structure);
    assert!(found.is_some_and(|a| a.name() != "auto"), "{chosen}");
    assert!(r.stdout.contains(&format!("auto -> {chosen}")), "{}", r.stdout);
    assert_eq!(frame.metadata["step"], "0.75");
    assert_eq!(frame.metadata["volume"], "menger:24x24x24");
    // The default filter: manual from the cells copy on a CPU device (one
    // fetch per sample), else hardware (Vulkan requires R8 to filter linearly).
    let cpu = common::gpu().info().device_type == lacuna::gpu::vk::PhysicalDeviceType::CPU;
    let faster = if cpu { "manual" } else { "hardware" };
    assert_eq!(frame.metadata["filter"], faster);
    assert!(
        r.stdout.contains(&format!("filter {faster} (device default)")),
        "{}",
        r.stdout
    );
    // The march time recorded is the one printed (to its three decimals:
    // at most half a unit of the third apart, as 2.8545 printed 2.855 is,
    // give or take the binary rounding of the two decimals).
    let gpu_ms = frame.metadata["gpu_ms"].parse::<f64>().unwrap();
    let printed = r
        .stdout
        .lines()
        .skip_while(|l| !l.starts_with("render GPU time"))
        .find_map(|l| l.trim().strip_prefix("march"))
        .and_then(|v| v.trim().trim_end_matches(" ms").parse::<f64>().ok())
        .unwrap();
    assert!(
        gpu_ms > 0.0 && (gpu_ms - printed).abs() <= 0.0005 + 1e-9,
        "{gpu_ms} vs {printed}"
    );
    // Only the frame is in the folder: no temporary left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

/// The sRGB encoding of a linear value, written here from IEC 61966-2-1
/// rather than taken from the library.
fn srgb(linear: f64) -> f64 {
    if linear <= 0.0031308 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

#[test]
fn render_to_png_matches_the_exr_in_8_bit_srgb_with_straight_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let (exr, png) = (dir.path().join("frame.exr"), dir.path().join("frame.png"));
    let args = ["--camera", "-20,35", "--tf", "ramp:0.2:1:0.3"];
    render_ok("menger:27", &exr, &args);
    render_ok("menger:27", &png, &args);
    let frame = Frame::read_exr(&exr).unwrap();

    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let info = reader.info();
    assert_eq!((info.width, info.height), (40, 32));
    assert_eq!(
        (info.color_type, info.bit_depth),
        (png::ColorType::Rgba, png::BitDepth::Eight)
    );
    assert!(info.srgb.is_some(), "no sRGB chunk");
    let text: Vec<(String, String)> = info
        .utf8_text
        .iter()
        .map(|t| (t.keyword.clone(), t.get_text().unwrap()))
        .collect();
    assert!(
        text.contains(&("lacuna.volume".into(), "menger:27x27x27".into())),
        "{text:?}"
    );
    let mut rgba = vec![0u8; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut rgba).unwrap();

    // Row 0 at the top in both: the frame is not symmetric top to bottom,
    // so a flipped PNG could not match.
    let (w, h) = (frame.width, frame.height);
    assert!((0..w).any(|x| frame.pixel(x, 0) != frame.pixel(x, h - 1) || frame.pixel(x, 5) != frame.pixel(x, h - 6)));
    let (mut partial, mut opaque_ish) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let p = frame.pixel(x, y).map(f64::from);
            let i = 4 * (y * w + x) as usize;
            let got = &rgba[i..i + 4];
            // Straight alpha: colour / alpha, sRGB-encoded; alpha linear.
            let a = p[3].clamp(0.0, 1.0);
            let want_a = (a * 255.0).round();
            assert_eq!(got[3] as f64, want_a, "alpha at ({x},{y}): {p:?}");
            for c in 0..3 {
                let want = if a == 0.0 {
                    0.0
                } else {
                    (srgb((p[c] / a).clamp(0.0, 1.0)) * 255.0).round()
                };
                assert!(
                    (got[c] as f64 - want).abs() <= 1.0,
                    "channel {c} at ({x},{y}): {} vs {want} from {p:?}",
                    got[c]
                );
            }
            partial += (a > 0.02 && a < 0.98) as u32;
            opaque_ish += (a > 0.5) as u32;
        }
    }
    assert!(partial > 50 && opaque_ish > 0, "{partial} partial, {opaque_ish} > 0.5");
    // Only the two frames: no temporary left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

/// The sRGB decoding of an 8-bit value, from IEC 61966-2-1.
fn srgb_decode(encoded: u8) -> f64 {
    let v = encoded as f64 / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn render_to_png_over_a_background_is_the_exr_composited_in_linear_light() {
    let dir = tempfile::tempdir().unwrap();
    let (exr, png) = (dir.path().join("frame.exr"), dir.path().join("frame.png"));
    let args = ["--camera", "-20,35", "--tf", "ramp:0.2:1:0.3"];
    render_ok("menger:27", &exr, &args);
    render_ok("menger:27", &png, &[&args[..], &["--background", "#3366cc"]].concat());
    let frame = Frame::read_exr(&exr).unwrap();

    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let info = reader.info();
    assert_eq!((info.width, info.height), (40, 32));
    assert_eq!(
        (info.color_type, info.bit_depth),
        (png::ColorType::Rgb, png::BitDepth::Eight)
    );
    let mut rgb = vec![0u8; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut rgb).unwrap();
    let background = [0x33, 0x66, 0xcc].map(srgb_decode);
    let (mut bare, mut mixed) = (0, 0);
    for (i, p) in frame.pixels.iter().enumerate() {
        let a = (p[3] as f64).clamp(0.0, 1.0);
        for c in 0..3 {
            let want = (srgb((p[c] as f64 + (1.0 - a) * background[c]).clamp(0.0, 1.0)) * 255.0).round();
            let got = rgb[3 * i + c] as f64;
            assert!(
                (got - want).abs() <= 1.0,
                "pixel {i} channel {c}: {got} vs {want} from {p:?}"
            );
        }
        bare += (a == 0.0 && rgb[3 * i..3 * i + 3] == [0x33, 0x66, 0xcc]) as u32;
        mixed += (a > 0.05 && a < 0.95) as u32;
    }
    assert!(
        bare > 0 && mixed > 50,
        "{bare} background pixels, {mixed} partly covered"
    );
}

#[test]
fn a_background_is_refused_for_an_exr_frame_or_when_malformed() {
    let dir = tempfile::tempdir().unwrap();
    for (name, colour, message) in [
        (
            "frame.exr",
            "102030",
            "invalid background '102030': only a .png frame is composited",
        ),
        (
            "frame.png",
            "12345",
            "invalid background '12345': expected an sRGB colour",
        ),
    ] {
        let out = dir.path().join(name);
        let r = lacuna(
            &[
                "render",
                "menger:8",
                "--out",
                out.to_str().unwrap(),
                "--background",
                colour,
            ],
            &[],
        );
        assert_eq!(r.code, 2, "{name}: {}{}", r.stdout, r.stderr);
        let lines: Vec<&str> = r.stderr.lines().collect();
        assert_eq!(lines.len(), 1, "{name}: {}", r.stderr);
        assert!(
            lines[0].starts_with("error: ") && lines[0].contains(message),
            "{name}: {}",
            lines[0]
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn a_frame_name_that_is_not_exr_or_png_fails_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["frame.tiff", "frame.jpg", "frame", "frame.exr.tmp"] {
        let out = dir.path().join(name);
        // A missing volume and no Vulkan driver: the name is refused first.
        let r = lacuna(
            &[
                "render",
                "/no/such/volume_8x8x8_uint8.raw",
                "--out",
                out.to_str().unwrap(),
            ],
            &[
                ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
                ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
            ],
        );
        assert_eq!(r.code, 2, "{name}: {}{}", r.stdout, r.stderr);
        assert!(r.stdout.is_empty(), "{name}: {}", r.stdout);
        let lines: Vec<&str> = r.stderr.lines().collect();
        assert_eq!(lines.len(), 1, "{name}: {}", r.stderr);
        assert!(
            lines[0].starts_with("error: invalid frame output") && lines[0].contains("expected a .exr"),
            "{name}: {}",
            lines[0]
        );
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn render_perspective_with_ert_and_a_json_tf() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("tf.json");
    std::fs::write(
        &json,
        r#"[{"RGBPoints":[0,0,0,1, 1,1,0,0],"Points":[0,0,0.5,0, 0.5,0,0.5,0, 1,0.6,0.5,0]}]"#,
    )
    .unwrap();
    let out = dir.path().join("p.exr");
    render_ok(
        "nbody:32",
        &out,
        &[
            "--perspective",
            "45",
            "--distance",
            "1.5",
            "--ert",
            "0.95",
            "--tf",
            json.to_str().unwrap(),
        ],
    );
    let frame = Frame::read_exr(&out).unwrap();
    assert!(frame.metadata["camera"].starts_with("persp"));
    assert_eq!(frame.metadata["ert"], "0.95");
}

#[test]
fn info_describes_the_volume_and_its_occupancy() {
    let r = lacuna(&["info", "menger:27", "--tf", "band:0.5:1"], &[]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    for needle in [
        "dims     27x27x27",
        "type     uint8",
        "spacing  1 x 1 x 1",
        "values   0 .. 250",
        "histogram",
        "visible",
        "active",
    ] {
        assert!(r.stdout.contains(needle), "'{needle}' missing from:\n{}", r.stdout);
    }
    // 8000 of 19683 voxels are solid in a level-3 sponge at 27^3.
    assert!(r.stdout.contains("visible  40.644 %"), "{}", r.stdout);
}

#[test]
fn diff_reports_metrics_and_exit_codes() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        dir.path().join("a.exr"),
        dir.path().join("b.exr"),
        dir.path().join("c.exr"),
    );
    render_ok("shells:24", &a, &[]);
    render_ok("shells:24", &b, &[]);
    render_ok("shells:24", &c, &["--camera", "50,10"]);
    let same = lacuna(
        &["diff", a.to_str().unwrap(), b.to_str().unwrap(), "--max-abs", "0"],
        &[],
    );
    assert_eq!(same.code, 0, "{}{}", same.stdout, same.stderr);
    assert!(
        same.stdout.contains("max_abs 0.000000e0") && same.stdout.contains("differing 0 of 1280"),
        "{}",
        same.stdout
    );
    let heat = dir.path().join("heat.png");
    let differ = lacuna(
        &[
            "diff",
            a.to_str().unwrap(),
            c.to_str().unwrap(),
            "--max-abs",
            "0",
            "--heatmap",
            heat.to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(differ.code, 1, "{}{}", differ.stdout, differ.stderr);
    assert!(differ.stdout.contains("rmse") && differ.stdout.contains("psnr"));
    let png = std::fs::read(&heat).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let loose = lacuna(
        &["diff", a.to_str().unwrap(), c.to_str().unwrap(), "--max-abs", "1"],
        &[],
    );
    assert_eq!(loose.code, 0);
    // Bad input exits 2 with one line.
    let small = dir.path().join("small.exr");
    let r = lacuna(
        &[
            "render",
            "shells:24",
            "--size",
            "8x8",
            "--validate",
            "--out",
            small.to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(r.code, 0, "{}", r.stderr);
    // A sparse 4 TiB file of zeros, past any host's memory: refused by its
    // first bytes, so nothing more of it is read.
    let not_exr = dir.path().join("zeros.exr");
    std::fs::File::create(&not_exr).unwrap().set_len(1 << 42).unwrap();
    for args in [
        vec!["diff", a.to_str().unwrap(), small.to_str().unwrap()],
        vec!["diff", a.to_str().unwrap(), "/no/such.exr"],
        vec!["diff", a.to_str().unwrap(), heat.to_str().unwrap()],
        // A heatmap is a PNG; a name that says otherwise is refused first.
        vec!["diff", a.to_str().unwrap(), c.to_str().unwrap(), "--heatmap", "h.exr"],
        // Input is checked before it is read: a device would never end, and
        // a large file that is no EXR is refused by its first bytes.
        vec!["diff", "/dev/zero", a.to_str().unwrap()],
        vec!["diff", a.to_str().unwrap(), not_exr.to_str().unwrap()],
    ] {
        let r = lacuna(&args, &[]);
        assert_eq!(r.code, 2, "{args:?}: {}", r.stderr);
        assert_eq!(r.stderr.trim().lines().count(), 1, "{args:?}: {}", r.stderr);
        let needle = match args.as_slice() {
            [.., "h.exr"] => "a heatmap is a PNG: name it .png",
            [_, "/dev/zero", _] => "/dev/zero: is not a regular file",
            [_, _, b] if *b == not_exr.to_str().unwrap() => "not an EXR file",
            _ => "",
        };
        assert!(r.stderr.contains(needle), "{args:?}: {}", r.stderr);
    }
    let r = lacuna(&["diff", a.to_str().unwrap(), small.to_str().unwrap()], &[]);
    assert!(r.stderr.contains("sizes differ"), "{}", r.stderr);
    // Iso frames' depth (Z) is compared too: colour alike, one depth moved.
    let iso = dir.path().join("iso.exr");
    render_ok("shells:24", &iso, &["--mode", "iso", "--iso", "0.5"]);
    let mut moved = lacuna::frame::Frame::read_exr(&iso).unwrap();
    let z = moved.depth.as_mut().unwrap();
    let hit = z.iter().position(|d| d.is_finite()).unwrap();
    z[hit] += 5.0;
    let moved_path = dir.path().join("moved.exr");
    moved.write_exr(&moved_path).unwrap();
    moved.depth = None;
    let flat = dir.path().join("flat.exr");
    moved.write_exr(&flat).unwrap();
    // A depth in one frame only (a viewer's screenshot) is named; the
    // colours decide.
    for (other, code, needle) in [
        (&moved_path, 1, "the depth (Z) differs by 5.000000e0 at 1 pixels"),
        (&flat, 0, "depth (Z): only in the first frame"),
    ] {
        let r = lacuna(
            &["diff", iso.to_str().unwrap(), other.to_str().unwrap(), "--max-abs", "0"],
            &[],
        );
        assert_eq!(r.code, code, "{}{}", r.stdout, r.stderr);
        assert!(
            r.stderr.contains(needle) || r.stdout.contains(needle),
            "{}{}",
            r.stdout,
            r.stderr
        );
    }
    // A bound past the depth's difference passes it.
    let r = lacuna(
        &[
            "diff",
            iso.to_str().unwrap(),
            moved_path.to_str().unwrap(),
            "--max-abs",
            "6",
        ],
        &[],
    );
    assert_eq!(r.code, 0, "{}{}", r.stdout, r.stderr);
    let r = lacuna(&["diff", iso.to_str().unwrap(), moved_path.to_str().unwrap()], &[]);
    assert!(
        r.stdout.contains("differing 1 of 1280 pixels") && r.stdout.contains("depth (Z): max_abs 5.000000e0"),
        "{}",
        r.stdout
    );
}

#[test]
fn lbvh_from_the_cli_is_bit_identical_to_naive() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        dir.path().join("naive.exr"),
        dir.path().join("lbvh.exr"),
        dir.path().join("paper.exr"),
    );
    render_ok("vessels:40", &a, &["--camera", "15,25"]);
    let r = render_ok(
        "vessels:40",
        &b,
        &["--camera", "15,25", "--accel", "lbvh", "--repeat", "2", "--warmup", "1"],
    );
    for needle in [
        "ranges",
        "classify",
        "compact",
        "morton",
        "sort",
        "emit",
        "refit",
        "structure active",
        "8^3 bricks",
        "height",
        "medians of 2 runs",
    ] {
        assert!(r.stdout.contains(needle), "'{needle}' missing:\n{}", r.stdout);
    }
    let d = lacuna(
        &["diff", a.to_str().unwrap(), b.to_str().unwrap(), "--max-abs", "0"],
        &[],
    );
    assert_eq!(d.code, 0, "{}", d.stdout);
    assert!(d.stdout.contains("differing 0 of"), "{}", d.stdout);
    assert_eq!(Frame::read_exr(&b).unwrap().metadata["accel"], "lbvh");
    render_ok(
        "vessels:40",
        &c,
        &[
            "--camera",
            "15,25",
            "--accel",
            "lbvh",
            "--classify",
            "voxel",
            "--apron",
            "off",
        ],
    );
    let meta = Frame::read_exr(&c).unwrap().metadata;
    assert_eq!((meta["classify"].as_str(), meta["apron"].as_str()), ("voxel", "off"));
}

#[test]
fn every_structure_from_the_cli_is_bit_identical_to_naive() {
    let dir = tempfile::tempdir().unwrap();
    let naive = dir.path().join("naive.exr");
    render_ok("nbody:40", &naive, &["--camera", "-35,15"]);
    for (accel, extra, needles) in [
        ("grid", vec!["--cell", "8"], vec!["cell 8", "cell ranges", "classify"]),
        (
            "kd-cpu",
            vec!["--kd", "shallow"],
            vec!["kd shallow", "svt", "tree", "upload"],
        ),
        (
            "kd-gpu",
            vec!["--max-leaf", "128", "--bins", "6"],
            vec!["kd deep", "max-leaf 128", "bins 6", "bricks", "queries", "host"],
        ),
        (
            "hybrid",
            vec![],
            vec!["k-d tree over the macro-cell grid", "cell 16", "svt", "classify"],
        ),
    ] {
        let out = dir.path().join(format!("{accel}.exr"));
        let mut args = vec!["--camera", "-35,15", "--accel", accel];
        args.extend(extra);
        let r = render_ok("nbody:40", &out, &args);
        for n in needles.iter().chain(&["structure active", "height"]) {
            assert!(r.stdout.contains(n), "{accel}: '{n}' missing:\n{}", r.stdout);
        }
        let d = lacuna(
            &["diff", naive.to_str().unwrap(), out.to_str().unwrap(), "--max-abs", "0"],
            &[],
        );
        assert_eq!(d.code, 0, "{accel}: {}", d.stdout);
        assert_eq!(Frame::read_exr(&out).unwrap().metadata["accel"], accel);
    }
}

/// Kernels are created from SPIR-V pruned of the code their specialization
/// constants rule out (`gpu/prune`); `LACUNA_SPIRV_PRUNE=0` creates them
/// from the whole modules. The frames are the same bit for bit, and both
/// modules pass the validation layer's SPIR-V checks (`--validate`).
#[test]
fn kernels_pruned_by_their_constants_render_what_whole_ones_render() {
    let dir = tempfile::tempdir().unwrap();
    for (accel, look) in [
        ("octree-93", vec!["--shade", "on"]),
        ("distance", vec!["--mode", "iso", "--iso", "0.4", "--filter", "manual"]),
        ("naive", vec!["--mode", "mip", "--filter", "hardware"]),
    ] {
        let (pruned, whole) = (dir.path().join("pruned.exr"), dir.path().join("whole.exr"));
        let mut args = vec!["--camera", "30,20", "--accel", accel];
        args.extend(&look);
        render_ok("nbody:40", &pruned, &args);
        render_ok_with("nbody:40", &whole, &args, &[("LACUNA_SPIRV_PRUNE", "0")]);
        let bits = |path: &Path| -> Vec<u32> {
            let frame = Frame::read_exr(path).unwrap();
            frame.pixels.iter().flatten().map(|v| v.to_bits()).collect()
        };
        let (a, b) = (bits(&pruned), bits(&whole));
        assert!(a == b, "{accel} {look:?}: the pruned kernel's frame differs");
        assert!(
            a.chunks(4).any(|p| f32::from_bits(p[3]) > 0.0),
            "{accel} {look:?}: an empty frame"
        );
    }
}

#[test]
fn devices_lists_at_least_one() {
    let r = lacuna(&["devices"], &[]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.starts_with("0: "), "{}", r.stdout);
}

#[test]
fn bad_input_is_one_line_nonzero_and_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    std::fs::write(p("short_4x4x4_uint8.raw"), [0u8; 60]).unwrap();
    std::fs::write(p("bad_4x4x4_uint9.raw"), [0u8; 64]).unwrap();
    std::fs::write(p("bad.nii.gz"), b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03garbage").unwrap();
    let mut nii = vec![0u8; 352];
    nii[0..4].copy_from_slice(&348i32.to_le_bytes());
    for (i, d) in [3i16, 2, 2, 2, 1, 1, 1, 1].iter().enumerate() {
        nii[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    nii[70..72].copy_from_slice(&32i16.to_le_bytes()); // complex64
    nii[72..74].copy_from_slice(&64i16.to_le_bytes());
    nii[108..112].copy_from_slice(&352f32.to_le_bytes());
    nii[344..348].copy_from_slice(b"n+1\0");
    nii.extend([0u8; 64]);
    std::fs::write(p("complex.nii"), &nii).unwrap();
    std::fs::write(p("bad.json"), "{\"RGBPoints\": [0, 1,").unwrap();

    let ctx = common::gpu();
    let too_long = format!("menger:{}x1x1", ctx.info().max_image_dimension_3d + 1);
    drop(ctx);

    fails(&["render", "/no/such/volume_8x8x8_uint8.raw"], &[], "No such file");
    fails(
        &["render", "menger:8", "--filter", "linear"],
        &[],
        "expected manual or hardware",
    );
    fails(
        &["render", &p("short_4x4x4_uint8.raw")],
        &[],
        "holds 60 bytes of voxel data but 4x4x4 uint8 needs 64",
    );
    fails(
        &["render", &p("bad_4x4x4_uint9.raw")],
        &[],
        "unknown voxel type 'uint9'",
    );
    fails(&["render", &p("bad.nii.gz")], &[], "corrupt gzip");
    fails(&["render", &p("complex.nii")], &[], "datatype");
    fails(&["render", "menger:0"], &[], "zero dimension");
    fails(&["render", "menger:4x0x4"], &[], "dimensions");
    // Dense storage is refused past the 3D image limit (auto takes bricks
    // there: tests/integration/volumes.rs).
    fails(&["render", &too_long, "--storage", "dense"], &[], "maxImageDimension3D");
    fails(&["render", "menger:16", "--tf", "ramp:1"], &[], "expected ramp:LO:HI");
    fails(
        &["render", "menger:16", "--tf", "spike:0.5:-1"],
        &[],
        "WIDTH must be > 0",
    );
    fails(&["render", "menger:16", "--tf", &p("bad.json")], &[], "invalid JSON");
    let huge_json = p("huge.json");
    std::fs::File::create(&huge_json).unwrap().set_len(17 << 20).unwrap();
    fails(
        &["render", "menger:16", "--tf", &huge_json],
        &[],
        "more than a ParaView JSON transfer function can be (16777216 bytes)",
    );
    fails(
        &["render", "menger:16", "--size", "0x0"],
        &[],
        "width and height must be > 0",
    );
    fails(&["render", "menger:16", "--size", "big"], &[], "expected WxH");
    // Negative numbers reach their own checks, not "unexpected argument".
    fails(
        &["render", "menger:16", "--size", "-64x64"],
        &[],
        "invalid size '-64x64'",
    );
    fails(
        &["render", "menger:16", "--time", "-1"],
        &[],
        "invalid value '-1' for '--time <TIME>'",
    );
    fails(
        &["render", "menger:16", "--accel", "grid", "--cell", "-4"],
        &[],
        "invalid cell '-4'",
    );
    // --dims and --type describe one raw file: '+' joins no channels then.
    fails(
        &["info", "a.nii+b.raw", "--dims", "8x8x8", "--type", "uint8"],
        &[],
        "invalid volume 'a.nii+b.raw': is no file, and with --dims and --type a spec names one raw file",
    );
    // A newline in a file name is escaped: the error stays one line.
    fails(
        &["info", "/no/such\nvolume_8x8x8_uint8.raw"],
        &[],
        "/no/such\\nvolume_8x8x8_uint8.raw: No such file",
    );
    // Checked before auto's probes, which named their own buffer.
    fails(
        &["render", "menger:16", "--size", "16384x16384"],
        &[],
        "error: frame 16384x16384 (4294967296 bytes) exceeds the device limit maxStorageBufferRange",
    );
    fails(&["render", "menger:16", "--step", "0"], &[], "invalid step '0'");
    fails(&["render", "menger:16", "--step", "-1"], &[], "invalid step '-1'");
    fails(&["render", "menger:16", "--step", "NaN"], &[], "invalid step 'NaN'");
    fails(&["render", "menger:16", "--step", "x"], &[], "--step");
    fails(&["render", "menger:16", "--ert", "1.5"], &[], "invalid ert");
    fails(&["render", "menger:16", "--repeat", "0"], &[], "invalid repeat '0'");
    fails(&["info", ""], &[], "invalid volume '': is empty");
    // --dims and --type are a raw file's: refused with a generator, a file
    // whose header gives them, or a pattern of such files.
    let raw = ["--dims", "4x4x4", "--type", "uint8"];
    for (volume, why) in [
        ("menger:27", "this names a generator"),
        (
            "/usr/share/mricron/templates/ch2.nii.gz",
            "this file's header gives its grid and type",
        ),
        ("t_%02d.nii.gz", "this file's header gives its grid and type"),
    ] {
        let args = [&["info", volume][..], &raw].concat();
        fails(&args, &[], &format!("--dims and --type describe a raw file, and {why}"));
    }
    // A raw file's name is its layout: the flags may repeat it, not
    // replace it (the file itself need not exist to be refused).
    let named = "/no/such/v_12x10x8_uint8.raw";
    fails(
        &["info", named, "--dims", "10x12x8", "--type", "uint8"],
        &[],
        "its name gives 12x10x8 uint8, and --dims and --type say 10x12x8 uint8",
    );
    fails(
        &["info", named, "--dims", "12x10x8", "--type", "uint8"],
        &[],
        "v_12x10x8_uint8.raw: No such file",
    );
    for (flag, n) in [("--repeat", "4000000000"), ("--warmup", "100001")] {
        let needle = format!("invalid {} '{n}': at most 100000", &flag[2..]);
        fails(&["render", "menger:16", flag, n], &[], &needle);
    }
    fails(
        &["render", "menger:16", "--accel", "magic"],
        &[],
        "expected one of: naive",
    );
    fails(&["render", "menger:16", "--camera", "10"], &[], "AZIMUTH,ELEVATION");
    // Finite but absurd: no float reduces 1e40 degrees to a turn.
    fails(
        &["render", "menger:16", "--camera", "1e40,0"],
        &[],
        "azimuth must be in [-360, 360]",
    );
    fails(
        &["render", "menger:16", "--camera", "0,95"],
        &[],
        "elevation in [-90, 90]",
    );
    fails(
        &["render", "menger:16", "--shade", "on", "--light", "0,-1e9"],
        &[],
        "invalid light '0,-1000000000'",
    );
    fails(&["render", "menger:16", "--perspective", "0"], &[], "field of view");
    fails(
        &["render", "menger:16", "--perspective", "1e-30"],
        &[],
        "past the 1000 a camera may stand",
    );
    fails(
        &["render", "menger:16", "--perspective", "40", "--distance", "1e9"],
        &[],
        "bounding-sphere radii",
    );
    // A step longer than the box's diagonal (27.7 voxels) samples a ray once.
    fails(
        &["render", "menger:16", "--step", "1e30"],
        &[],
        "longer than the diagonal",
    );
    fails(
        &["render", "menger:16", "--step", "28"],
        &[],
        "longer than the diagonal",
    );
    fails(&["render", "menger:16", "--size", "20000x8"], &[], "1..=16384 pixels");
    fails(&["info", "blob:16"], &[], "not a generator");
    // More transfer functions than channels: the error before any report.
    let too_many = ["info", "menger:16", "--tf", "ramp:0.3:1", "--tf", "ramp:0.5:1"];
    fails(&too_many, &[], "2 transfer functions for a volume of 1 channel");
    assert_eq!(lacuna(&too_many, &[]).stdout, "", "no report before the error");
    fails(&["render", "menger:16", "--unknown-flag"], &[], "--unknown-flag");
    // A missing required argument is named on the one line.
    fails(
        &["render", "menger:16", "--dims", "8x8x8"],
        &[],
        "required arguments were not provided: --type <TYPE>",
    );
    // No Vulkan driver at all: the loader finds no ICD.
    let none = [
        ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
        ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
    ];
    fails(&["render", "menger:8"], &none, "apt install mesa-vulkan-drivers");
    fails(&["devices"], &none, "apt install mesa-vulkan-drivers");
}

#[test]
fn output_into_a_missing_folder_fails_cleanly() {
    let r = lacuna(
        &[
            "render",
            "menger:8",
            "--size",
            "8x8",
            "--validate",
            "--out",
            "/no/such/dir/f.exr",
        ],
        &[],
    );
    assert_eq!(r.code, 2);
    assert_eq!(r.stderr.trim().lines().count(), 1, "{}", r.stderr);
    assert!(r.stderr.contains("/no/such/dir/f.exr"), "{}", r.stderr);
}

#[test]
fn scene_prints_counts_and_writes_nff() {
    let dir = tempfile::tempdir().unwrap();
    let nff = dir.path().join("tetra.nff");
    let r = lacuna(&["scene", "tetra", "--nff", nff.to_str().unwrap()], &[]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("4096 primitives"), "{}", r.stdout);
    let text = std::fs::read_to_string(&nff).unwrap();
    assert!(text.contains("\nv\nfrom 1.022846 -3.177154 -2.174512\n"), "view block");
    assert_eq!(text.lines().filter(|l| *l == "p 3").count(), 4096);
    assert_eq!(text.lines().filter(|l| l.starts_with("l ")).count(), 1);
    let r = lacuna(&["scene", "gears", "--size", "1"], &[]);
    assert!(r.stdout.contains("147 primitives"), "{}", r.stdout);
}

#[test]
fn octree_prints_havrans_table_and_writes_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tree.exr");
    let r = lacuna(
        &[
            "octree",
            "tree",
            "--size",
            "4",
            "--mode",
            "A",
            "--max-depth",
            "5",
            "--traversal",
            "all",
            "--resolution",
            "24",
            "--validate",
            "--out",
            out.to_str().unwrap(),
        ],
        &[],
    );
    assert_eq!(r.code, 0, "{}\n{}", r.stdout, r.stderr);
    for needle in [
        "N_IN", "N_OIV", "T_B", "N_IT", "N_EETS", "T_TR", "O84", "O89", "O93", "Orev", "eye hits",
    ] {
        assert!(r.stdout.contains(needle), "{needle} missing:\n{}", r.stdout);
    }
    assert!(
        r.stdout.contains("rays whose hit differs between traversals: 0"),
        "{}",
        r.stdout
    );
    let frame = Frame::read_exr(&out).unwrap();
    assert_eq!((frame.width, frame.height), (24, 24));
    assert_eq!(frame.metadata.get("octree").map(String::as_str), Some("A5"));
    assert_eq!(frame.metadata.get("scene").map(String::as_str), Some("tree"));
    // The extension picks the format, as render's --out.
    let png = dir.path().join("tree.png");
    let args = [
        "octree",
        "tree",
        "--size",
        "4",
        "--resolution",
        "8",
        "--validate",
        "--out",
    ];
    let r = lacuna(&[&args[..], &[png.to_str().unwrap()]].concat(), &[]);
    assert_eq!(r.code, 0, "{}\n{}", r.stdout, r.stderr);
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
}

#[test]
fn bad_octree_and_scene_input_is_one_line() {
    fails(&["scene", "teapots"], &[], "invalid scene 'teapots'");
    fails(&["scene", "mount", "--size", "9"], &[], "mount supports 1..=7");
    fails(&["octree", "tetra", "--mode", "B"], &[], "invalid octree mode 'B'");
    fails(
        &["octree", "tetra", "--traversal", "85"],
        &[],
        "invalid octree traversal '85'",
    );
    fails(&["octree", "tetra", "--max-depth", "20"], &[], "invalid max depth '20'");
    fails(&["octree", "tetra", "--resolution", "0"], &[], "invalid resolution '0'");
    fails(&["octree"], &[], "name a scene, or use --all");
    fails(&["octree", "tetra", "--out", "t.tiff"], &[], "expected a .exr");
    fails(&["octree", "tetra", "--report", "r.md"], &[], "give --all with it");
    // Checked before the (long) comparison starts.
    fails(
        &["octree", "--all", "--report", "/no/such/dir/t.md"],
        &[],
        "/no/such/dir/t.md",
    );
    fails(
        &["scene", "tree", "--nff", "/no/such/dir/t.nff"],
        &[],
        "/no/such/dir/t.nff",
    );
}
