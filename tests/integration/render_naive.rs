//! The naive marcher against the CPU reference of the same integral on the
//! same lattice, under each sample filter within its tolerance (README,
//! "Sample filter"), and against the analytic transmittance of a homogeneous
//! medium.

use crate::common;
use crate::common::{gpu, max_abs, render};
use lacuna::accel::Accel;
use lacuna::render::reference;
use lacuna::render::Octants;
use lacuna::render::{Filter, FrameBuilder, FrameDesc, Projection};
use lacuna::volume::{VoxelData, VoxelType};
use lacuna::{TransferFunction, Volume};

/// A square frame of an orbit camera, sampled with the manual filter.
fn settings(size: u32, az: f64, el: f64, projection: Projection) -> FrameBuilder {
    FrameDesc::builder(size, size)
        .orbit(az, el, projection)
        .filter(Filter::Manual)
}

/// Max abs GPU-vs-CPU difference allowed per filter. Manual: the same f32
/// arithmetic, apart from the device's `pow` in the corrected LUT. Hardware:
/// Vulkan lets filtering weights carry only `subTexelPrecisionBits` (>= 4)
/// fractional bits; lavapipe has 8, so a sample may move by up to 2^-9 of the
/// local value difference, and a steep TF turns that into colour.
fn tolerance(filter: Filter) -> f64 {
    match filter {
        Filter::Manual => 1e-4,
        Filter::Hardware => 0.05,
    }
}

const PERSP: Projection = Projection::Perspective {
    fov_deg: 40.0,
    distance: None,
};

/// Each filter's GPU frame against the CPU reference.
fn check_against_reference(volume: &Volume, tf: &TransferFunction, s: FrameBuilder) {
    check_filters(volume, tf, s, &Filter::ALL)
}

fn check_filters(volume: &Volume, tf: &TransferFunction, s: FrameBuilder, filters: &[Filter]) {
    let ctx = gpu();
    let desc = s.build().unwrap();
    let params = desc.params_for(volume.dims, volume.spacing, volume.norm).unwrap();
    let cpu = reference::render(volume, tf, &params);
    for &filter in filters {
        let frame = render(&ctx, volume, tf, &s.filter(filter).build().unwrap(), Accel::naive());
        let err = max_abs(&frame, &cpu);
        assert!(
            err <= tolerance(filter),
            "{} {}, {filter}: GPU vs CPU max abs {err}",
            volume.name,
            desc.camera().describe()
        );
        // The frame is not trivially empty.
        assert!(frame.pixels.iter().any(|p| p[3] > 0.01), "{}: empty frame", volume.name);
    }
}

#[test]
fn generators_match_the_cpu_reference_orthographic_and_perspective() {
    for spec in ["menger:27", "nbody:48", "vessels:40", "turbulence:32", "shells:36"] {
        let v = Volume::load(spec, &Default::default()).unwrap();
        let tf = TransferFunction::parse(v.default_tf.as_ref().unwrap()).unwrap();
        check_against_reference(&v, &tf, settings(64, 30.0, 20.0, Projection::Orthographic));
        check_against_reference(&v, &tf, settings(48, -115.0, 35.0, PERSP));
    }
}

#[test]
fn axis_aligned_views_and_odd_dims_match_the_reference() {
    // Dims that are not multiples of 8, anisotropic spacing, and rays with
    // direction components exactly 0 passing through voxel faces.
    let mut v = Volume::load("turbulence:37x29x41", &Default::default()).unwrap();
    v.spacing = [1.0, 1.5, 0.75];
    let tf = TransferFunction::parse("ramp:0.4:1:0.3").unwrap();
    for (az, el) in [
        (0.0, 0.0),
        (90.0, 0.0),
        (180.0, 0.0),
        (0.0, 90.0),
        (0.0, -90.0),
        (45.0, 35.264),
    ] {
        check_against_reference(&v, &tf, settings(40, az, el, Projection::Orthographic));
    }
}

#[test]
fn camera_inside_the_volume_and_early_termination_match_the_reference() {
    let v = Volume::load("menger:27", &Default::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.3:1:0.5").unwrap();
    let inside = Projection::Perspective {
        fov_deg: 70.0,
        distance: Some(0.1),
    };
    check_against_reference(&v, &tf, settings(48, 10.0, 5.0, inside));
    let s = settings(48, 30.0, 20.0, Projection::Orthographic).ert(Some(0.9));
    check_against_reference(&v, &tf, s);
    // ERT only truncates rays that reached the threshold; others are untouched.
    let ctx = gpu();
    let cut = render(&ctx, &v, &tf, &s.build().unwrap(), Accel::naive());
    let full = render(&ctx, &v, &tf, &s.ert(None).build().unwrap(), Accel::naive());
    let mut truncated = 0;
    for (c, f) in cut.pixels.iter().zip(&full.pixels) {
        if c[3] < 0.9 {
            assert_eq!(c, f, "a ray below the ERT threshold changed");
        } else {
            assert!(c[3] <= f[3]);
            truncated += (c != f) as u32;
        }
    }
    assert!(truncated > 0, "ERT at 0.9 should cut some rays of an opaque sponge");
}

#[test]
fn a_spike_visible_only_through_interpolation_is_rendered() {
    // Two voxel values, 0 and 1; the spike at 0.5 is narrower than their gap,
    // so only interpolated samples between them can hit it.
    let dims = [16, 16, 16];
    let data: Vec<u8> = (0..16 * 16 * 16).map(|i| if (i % 16) < 8 { 0 } else { 255 }).collect();
    let v = Volume::new("halves", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
    let tf = TransferFunction::parse("spike:0.5:0.001").unwrap();
    assert_eq!(tf.lookup(0.0)[3], 0.0);
    assert_eq!(tf.lookup(1.0)[3], 0.0);
    // Looking down -x with step 0.5, every ray samples x = 8.0 exactly, where
    // the interpolated value is 0.5. Manual filtering only: lavapipe filters
    // R8 UNORM to an 8-bit result (127/255 or 128/255 here), which misses a
    // spike narrower than 1/255 (README, "Sample filter").
    let s = settings(32, 90.0, 0.0, Projection::Orthographic);
    check_filters(&v, &tf, s, &[Filter::Manual]);
}

#[test]
fn hardware_filtering_moves_the_image_by_a_bounded_amount() {
    // The filter reaches the kernel (the images differ), and the difference
    // stays within the hardware tolerance of the manual image.
    let v = Volume::load("nbody:48", &Default::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.2:1").unwrap();
    let ctx = gpu();
    let s = settings(64, 12.0, 34.0, PERSP);
    let manual = render(&ctx, &v, &tf, &s.build().unwrap(), Accel::naive());
    let hardware = render(
        &ctx,
        &v,
        &tf,
        &s.filter(Filter::Hardware).build().unwrap(),
        Accel::naive(),
    );
    let d = lacuna::frame::diff(&manual, &hardware).unwrap();
    assert!(d.differing > 0, "the hardware filter changed nothing: {d}");
    assert!(d.max_abs <= tolerance(Filter::Hardware), "{d}");
}

#[test]
fn the_frame_lut_is_corrected_for_the_step_on_the_gpu() {
    // The first LUT_SIZE entries: alpha 1 - (1 - a)^dt, rgb as is; then the
    // raw LUT. Against the CPU's correction (the device's pow may round
    // differently from Rust's powf).
    let ctx = gpu();
    let v = Volume::load("nbody:16", &Default::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.1:0.9:0.7").unwrap();
    let renderer = lacuna::render::Renderer::new(&ctx).unwrap();
    let gv = lacuna::volume::GpuVolume::upload(&ctx, &v).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    for step in [0.37f32, 1.0, 2.5] {
        let s = settings(8, 0.0, 0.0, Projection::Orthographic)
            .step(step)
            .build()
            .unwrap();
        let target = lacuna::render::RenderTarget::new(&ctx, 8, 8).unwrap();
        let naive = lacuna::accel::Structure::naive();
        let scene = lacuna::render::Scene {
            structure: &naive,
            volume: &gv,
            tf: &lut,
        };
        let out = lacuna::render::Output::Buffer;
        ctx.submit_and_wait(|cmd| renderer.record(cmd, None, &target, scene, &s, out))
            .unwrap();
        let gpu_lut: Vec<[f32; 4]> =
            bytemuck::pod_collect_to_vec(&target.lut().buffer().download(0, target.lut().buffer().size()).unwrap());
        // One channel's two tables (the buffer has room for every channel's).
        let (corrected, raw) = gpu_lut[..2 * lacuna::tf::LUT_SIZE].split_at(lacuna::tf::LUT_SIZE);
        assert_eq!(raw, tf.lut(), "the raw half");
        let expected = tf.corrected_lut(step);
        for (i, (g, c)) in corrected.iter().zip(&expected).enumerate() {
            assert_eq!(g[..3], c[..3], "entry {i}: rgb");
            assert!(
                (g[3] - c[3]).abs() <= 1e-6,
                "step {step} entry {i}: {} vs {}",
                g[3],
                c[3]
            );
            // Transparent stays exactly transparent (classification relies on it).
            assert_eq!(g[3] == 0.0, c[3] == 0.0, "entry {i}");
        }
        assert!(expected.iter().any(|e| e[3] > 0.0 && e[3] < 1.0));
    }
    common::assert_clean(&ctx);
}

/// Chord length of a ray through the box [0, dims], in f64.
fn chord(org: [f64; 3], dir: [f64; 3], dims: [u32; 3]) -> f64 {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if dir[a] == 0.0 {
            if org[a] < 0.0 || org[a] > dims[a] as f64 {
                return 0.0;
            }
            continue;
        }
        let ta = (0.0 - org[a]) / dir[a];
        let tb = (dims[a] as f64 - org[a]) / dir[a];
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t1 - t0.max(0.0)).max(0.0)
}

#[test]
fn homogeneous_box_transmittance_is_exp_minus_sigma_length() {
    let dims = [24, 20, 28];
    let n = dims.iter().product::<u32>() as usize;
    let v = Volume::new("constant", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(vec![77; n])).unwrap();
    let alpha = 0.05f64;
    let sigma = -(1.0 - alpha).ln();
    let tf = TransferFunction::parse(&format!("band:0:1:{alpha}")).unwrap();
    let ctx = gpu();
    for (az, el, step) in [(0.0, 0.0, 0.5), (33.0, 21.0, 0.37), (60.0, -40.0, 1.3)] {
        let s = settings(48, az, el, Projection::Orthographic)
            .step(step)
            .build()
            .unwrap();
        let frame = render(&ctx, &v, &tf, &s, Accel::naive());
        let p = s.params_for(v.dims, v.spacing, v.norm).unwrap();
        let dir = [p.eye_or_dir[0] as f64, p.eye_or_dir[1] as f64, p.eye_or_dir[2] as f64];
        let len = (dir.iter().map(|c| c * c).sum::<f64>()).sqrt();
        let dir = dir.map(|c| c / len);
        let mut hits = 0;
        for y in 0..48 {
            for x in 0..48 {
                let org = [0, 1, 2]
                    .map(|a| p.base[a] as f64 + (x as f64 + 0.5) * p.du[a] as f64 + (y as f64 + 0.5) * p.dv[a] as f64);
                let l = chord(org, dir, dims);
                let expected = 1.0 - (-sigma * l).exp();
                let got = frame.pixel(x, y)[3] as f64;
                assert!(
                    (got - expected).abs() <= 1e-3,
                    "az {az} el {el} step {step} pixel ({x},{y}): alpha {got} vs 1-exp(-sigma L) {expected} (L {l})"
                );
                hits += (l > 1.0) as u32;
            }
        }
        assert!(hits > 100, "the box should cover many pixels");
    }
}

#[test]
fn rendering_is_deterministic_bit_for_bit() {
    let v = Volume::load("nbody:40", &Default::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.2:1").unwrap();
    let s = settings(64, 12.0, 34.0, PERSP).build().unwrap();
    let ctx = gpu();
    let a = render(&ctx, &v, &tf, &s, Accel::naive());
    let b = render(&ctx, &v, &tf, &s, Accel::naive());
    assert_eq!(lacuna::frame::diff(&a, &b).unwrap().differing, 0);
}

#[test]
fn degenerate_volumes_render() {
    // 1 x 1 x N and a single voxel.
    for dims in [[1, 1, 20], [1, 1, 1], [3, 1, 2]] {
        let n = dims.iter().product::<u32>() as usize;
        let data: Vec<u8> = (0..n).map(|i| (i * 37 % 256) as u8).collect();
        let v = Volume::new("tiny", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap();
        let tf = TransferFunction::parse("band:0:1:0.5").unwrap();
        check_against_reference(&v, &tf, settings(16, 20.0, 10.0, Projection::Orthographic));
    }
}

/// A frame over the per-submission sample budget is marched in bands of
/// rows, one submission each; the bands tile the frame exactly, so the image
/// equals the one-submission frame bit for bit, for naive and a skipping
/// structure alike.
#[test]
fn frames_split_into_bands_equal_the_whole_frame() {
    use lacuna::accel::{BuildInput, Builder};
    use lacuna::frame::diff;
    use lacuna::render::{Renderer, Scene};
    use lacuna::volume::{GpuVolume, LoadOptions};
    let ctx = gpu();
    let v = Volume::load("nbody:48", &LoadOptions::default()).unwrap();
    let tf = TransferFunction::parse("ramp:0.3:1").unwrap();
    let gv = GpuVolume::upload(&ctx, &v).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let builder = Builder::new(&ctx).unwrap();
    let renderer = Renderer::new(&ctx).unwrap();
    // 72 x 40: the last band of 8-row workgroups is partial.
    let s = settings(72, 30.0, 20.0, Projection::Orthographic)
        .size(72, 40)
        .build()
        .unwrap();
    let per_ray = lacuna::limits::check_samples_per_ray(v.dims, s.step()).unwrap();
    for name in ["naive", "grid"] {
        let accel: Accel = name.parse().unwrap();
        let params = accel.defaults();
        let (ranges, _) = builder.ranges_for(&[(accel, &params)], &gv).unwrap();
        let input = BuildInput {
            volume: &v,
            gpu_volume: &gv,
            tf: &tf,
            gpu_tf: &lut,
            mode: lacuna::render::Mode::Composite,
            frames: &[],
            octants: Octants::ALL,
        };
        let (structure, _) = builder.build(accel, &input, &ranges, &params).unwrap();
        assert_eq!(structure.marched_as(), accel, "its own kernel marches");
        let scene = Scene {
            structure: &structure,
            volume: &gv,
            tf: &lut,
        };
        let (whole, _, one) = renderer.render_in_bands(scene, &s, u64::MAX).unwrap();
        assert_eq!(one, 1);
        // One row of workgroups (72 x 8 rays) per band: 5 bands.
        let budget = 72 * 8 * per_ray;
        let (banded, timings, bands) = renderer.render_in_bands(scene, &s, budget).unwrap();
        assert_eq!(bands, 5, "{name}");
        // Each pass is timed once, summed over the bands.
        let names: Vec<&str> = timings.phases.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["march", "readback"], "{name}");
        assert!(whole.pixels.iter().any(|p| p[3] > 0.0), "{name}: something visible");
        assert_eq!(diff(&whole, &banded).unwrap().differing, 0, "{name}");
        // A host's bands: each recorded and submitted on its own.
        let bands = renderer.bands(scene, &s, budget).unwrap();
        let rows: Vec<(u32, u32)> = bands.iter().map(|b| (b.first_row, b.rows)).collect();
        assert_eq!(rows, [(0, 8), (8, 8), (16, 8), (24, 8), (32, 8)], "{name}");
        let target = lacuna::render::RenderTarget::new(&ctx, 72, 40).unwrap();
        for band in bands {
            ctx.submit_and_wait(|cmd| {
                renderer.record_band(cmd, None, &target, scene, &s, lacuna::render::Output::Buffer, band)
            })
            .unwrap();
        }
        ctx.submit_and_wait(|cmd| renderer.record_readback(cmd, &target))
            .unwrap();
        assert_eq!(
            diff(&whole, &target.read().unwrap()).unwrap().differing,
            0,
            "{name}: host bands"
        );
        // A band off the workgroup rows, or past the frame, is an error.
        for (first_row, rows) in [(4, 8), (32, 16), (0, 0)] {
            let band = lacuna::render::Band { first_row, rows };
            let err = ctx
                .submit_and_wait(|cmd| {
                    renderer.record_band(cmd, None, &target, scene, &s, lacuna::render::Output::Buffer, band)
                })
                .unwrap_err();
            assert!(err.to_string().contains("Renderer::bands"), "{err}");
        }
    }
    common::assert_clean(&ctx);
}

#[test]
fn a_structure_renders_only_the_volume_grid_it_was_built_over() {
    use lacuna::accel::{BuildInput, Builder, Structure};
    use lacuna::render::{Renderer, Scene};
    use lacuna::volume::{GpuVolume, LoadOptions};
    let ctx = gpu();
    let load = |spec: &str| Volume::load(spec, &LoadOptions::default()).unwrap();
    let (small, large) = (load("vessels:32"), load("vessels:40"));
    let tf = TransferFunction::parse("ramp:0.3:1").unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let (gv_small, gv_large) = (
        GpuVolume::upload(&ctx, &small).unwrap(),
        GpuVolume::upload(&ctx, &large).unwrap(),
    );
    let builder = Builder::new(&ctx).unwrap();
    let accel: Accel = "grid".parse().unwrap();
    let params = accel.defaults();
    let (ranges, _) = builder.ranges_for(&[(accel, &params)], &gv_small).unwrap();
    let input = BuildInput {
        volume: &small,
        gpu_volume: &gv_small,
        tf: &tf,
        gpu_tf: &lut,
        mode: lacuna::render::Mode::Composite,
        frames: &[],
        octants: Octants::ALL,
    };
    let (grid, _) = builder.build(accel, &input, &ranges, &params).unwrap();
    let renderer = Renderer::new(&ctx).unwrap();
    let desc = settings(32, 30.0, 20.0, Projection::Orthographic).build().unwrap();
    let scene = |structure, volume| Scene {
        structure,
        volume,
        tf: &lut,
    };
    // Its own volume renders; another grid is refused, naming both.
    renderer.render(scene(&grid, &gv_small), &desc).unwrap();
    let err = renderer.render(scene(&grid, &gv_large), &desc).unwrap_err();
    assert!(
        err.to_string().contains("40x40x40") && err.to_string().contains("built over 32x32x32"),
        "{err}"
    );
    // Naive marching has no structure: any volume.
    renderer.render(scene(&Structure::naive(), &gv_large), &desc).unwrap();
    common::assert_clean(&ctx);
}
