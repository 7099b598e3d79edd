//! Data-parallel rendering without MPI (`lacuna::parallel`): the k-d blocks
//! tile the bricks and come in visibility order; each rank's part (its
//! bricks and ghosts, its segment of every ray) is rendered by every
//! structure exactly as naive marching renders it; the parts blended
//! front to back are the one-process frame within 1e-5 (the blend
//! reassociates the float sums), and MIP/MinIP parts picked by their ray
//! values are it bit for bit. tests/integration/mpi.rs does the same through `mpirun`,
//! IceT and MPI reductions.

use crate::common;
use crate::common::identity::cam;
use crate::common::{accel, assert_clean, builder, gpu};
use lacuna::accel::{Accel, BuildInput, Params};
use lacuna::desc::Rays;
use lacuna::frame::{diff, Frame};
use lacuna::parallel::{blend, pick, Decomposition};
use lacuna::render::Octants;
use lacuna::render::{Camera, Filter, FrameDesc, Mode, Projection, Renderer, Scene, Shading};
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::{TransferFunction, Volume};

#[test]
fn blocks_tile_the_bricks_and_each_rank_has_one() {
    for (dims, edge) in [
        ([64, 64, 64], 16),
        ([37, 29, 45], 16),
        ([100, 7, 9], 8),
        ([5, 5, 5], 1),
        ([48, 48, 16], 16),
    ] {
        let counts = dims.map(|d: u32| d.div_ceil(edge));
        let total = counts.iter().product::<u32>();
        for ranks in 1..=total.min(11) {
            let d = Decomposition::new(dims, edge, ranks).unwrap();
            assert_eq!(d.blocks.len(), ranks as usize);
            // Every brick in exactly one block, every block non-empty.
            let mut owner = vec![0u32; total as usize];
            for b in &d.blocks {
                assert!(b.bricks_count() > 0);
                for z in b.bricks[0][2]..b.bricks[1][2] {
                    for y in b.bricks[0][1]..b.bricks[1][1] {
                        for x in b.bricks[0][0]..b.bricks[1][0] {
                            owner[(x + counts[0] * (y + counts[1] * z)) as usize] += 1;
                        }
                    }
                }
                assert_eq!(b.lo, b.bricks[0].map(|c| c * edge));
                assert_eq!(b.hi, [0, 1, 2].map(|a| (b.bricks[1][a] * edge).min(dims[a])));
            }
            assert!(owner.iter().all(|&n| n == 1), "{dims:?}/{edge} in {ranks}");
        }
        let e = Decomposition::new(dims, edge, total + 1).unwrap_err().to_string();
        assert!(
            e.starts_with("invalid rank count") && e.contains("each rank needs one"),
            "{e}"
        );
    }
}

/// Where the ray `org + t dir`, t >= 0, enters box [lo, hi], if it
/// crosses it.
fn entry(org: [f32; 3], dir: [f32; 3], lo: [u32; 3], hi: [u32; 3]) -> Option<f32> {
    let (mut t0, mut t1) = (0.0f32, f32::INFINITY);
    for a in 0..3 {
        let (ta, tb) = ((lo[a] as f32 - org[a]) / dir[a], (hi[a] as f32 - org[a]) / dir[a]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0 < t1 - 1e-3).then_some(t0)
}

#[test]
fn the_order_puts_every_ray_s_blocks_front_to_back() {
    let dims = [64, 48, 80];
    for ranks in [2, 3, 5, 8] {
        let d = Decomposition::new(dims, 16, ranks).unwrap();
        // Eyes around and inside the volume, and orthographic directions.
        let mut seed = 7u32;
        let mut next = || {
            seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
            (seed >> 8) as f32 / 16777216.0
        };
        for case in 0..200 {
            let perspective = case % 2 == 0;
            let eye = [0, 1, 2].map(|a| (next() * 2.0 - 0.5) * dims[a] as f32);
            let dir = [0, 1, 2].map(|_| next() * 2.0 - 1.0);
            let rays = Rays {
                perspective,
                eye_or_dir: if perspective { eye } else { dir },
                ..Rays::orthographic([0.0; 3], [0.0; 3], [0.0; 3], dir)
            };
            let order = d.order(&rays);
            let rank_at: Vec<usize> = (0..ranks)
                .map(|r| order.iter().position(|&o| o == r).unwrap())
                .collect();
            for _ in 0..20 {
                let target = [0, 1, 2].map(|a| next() * dims[a] as f32);
                let (org, ray) = if perspective {
                    (eye, [0, 1, 2].map(|a| target[a] - eye[a]))
                } else {
                    ([0, 1, 2].map(|a| target[a] - 1000.0 * dir[a]), dir)
                };
                let mut hits: Vec<(f32, usize)> = d
                    .blocks
                    .iter()
                    .enumerate()
                    .filter_map(|(r, b)| entry(org, ray, b.lo, b.hi).map(|t| (t, rank_at[r])))
                    .collect();
                hits.sort_by(|a, b| a.0.total_cmp(&b.0));
                let places: Vec<usize> = hits.iter().map(|h| h.1).collect();
                assert!(
                    places.windows(2).all(|w| w[0] < w[1]),
                    "{ranks} ranks, case {case}: blocks met in order places {places:?}"
                );
            }
        }
    }
}

fn load(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

/// Renders `desc` over `volume` as `ranks` ranks would: each part with
/// naive and the structures given, asserting them identical; returns the
/// blend of the naive parts.
fn rendered_in_parts(
    volume: &Volume,
    tf: &TransferFunction,
    desc: &FrameDesc,
    ranks: u32,
    structures: &[Accel],
) -> Frame {
    let ctx = gpu();
    let renderer = Renderer::new(&ctx).unwrap();
    let builder = builder(&ctx);
    let lut = tf.upload(&ctx).unwrap();
    let split = Decomposition::new(volume.dims, 16, ranks).unwrap();
    let mut parts = Vec::new();
    for block in &split.blocks {
        let mut gv = GpuVolume::upload_bricks_kept(&ctx, volume, 16, block.with_ghosts(split.counts)).unwrap();
        gv.prepare(volume, desc.lighting().is_some(), Some(Filter::Manual))
            .unwrap();
        let (lo, hi) = block.bounds();
        let part_desc = desc.to_builder().segment(Some([lo, hi])).build().unwrap();
        let input = BuildInput {
            volume,
            gpu_volume: &gv,
            tf,
            gpu_tf: &lut,
            mode: *desc.mode(),
            frames: std::slice::from_ref(&part_desc),
            octants: Octants::ALL,
        };
        let mut frames: Vec<(Accel, Frame)> = Vec::new();
        for &a in [accel("naive")].iter().chain(structures) {
            let params: Params = a.defaults();
            let (ranges, _) = builder.ranges_for(&[(a, &params)], &gv).unwrap();
            let (s, _) = builder.build(a, &input, &ranges, &params).unwrap();
            let scene = Scene {
                structure: &s,
                volume: &gv,
                tf: &lut,
            };
            frames.push((a, renderer.render(scene, &part_desc).unwrap().0));
        }
        for (a, f) in &frames[1..] {
            let d = diff(&frames[0].1, f).unwrap();
            assert_eq!(d.differing, 0, "{a} differs from naive on block {block:?}: {d:?}");
        }
        parts.push(frames.swap_remove(0).1);
    }
    assert_clean(&ctx);
    let (w, h) = desc.size();
    let rays = desc.camera().rays(volume.dims, volume.spacing, w, h).unwrap();
    let pixels: Vec<&[[f32; 4]]> = parts.iter().map(|f| f.pixels.as_slice()).collect();
    let joined = match desc.mode() {
        Mode::Composite => blend(&pixels, &split.order(&rays)),
        mode => {
            let values: Vec<&[f32]> = parts
                .iter()
                .map(|f| f.depth.as_deref().expect("a part carries its ray values or depths"))
                .collect();
            pick(&pixels, &values, *mode == Mode::Mip)
        }
    };
    Frame::new(w, h, joined)
}

fn iso(values: &str) -> Mode {
    Mode::Iso(lacuna::render::Iso::parse(values).unwrap())
}

#[test]
fn mip_minip_and_iso_parts_picked_by_ray_value_or_depth_are_the_one_process_frame_bit_for_bit() {
    let ctx = gpu();
    let cases = [
        (
            "nbody:48",
            "ramp:0.1:1",
            Mode::Mip,
            30.0,
            20.0,
            Projection::Orthographic,
        ),
        (
            "turbulence:37x29x45",
            "ramp:0.3:0.9",
            Mode::Mip,
            200.0,
            -30.0,
            Projection::Perspective {
                fov_deg: 40.0,
                distance: None,
            },
        ),
        (
            "turbulence:37x29x45",
            "band:0.05:0.45",
            Mode::MinIp,
            90.0,
            10.0,
            Projection::Orthographic,
        ),
        // Iso surfaces crossing the blocks' faces: a crossing between two
        // blocks' samples is the later block's (it pairs its first sample
        // with the one before), and the nearest surface wins.
        ("nbody:48", "ramp:0:1", iso("0.3"), 30.0, 20.0, Projection::Orthographic),
        (
            "turbulence:37x29x45",
            "ramp:0:1",
            iso("0.45,0.6"),
            200.0,
            -30.0,
            Projection::Perspective {
                fov_deg: 40.0,
                distance: None,
            },
        ),
    ];
    for (spec, tf, mode, az, el, projection) in cases {
        let volume = load(spec);
        let tf = TransferFunction::parse(tf).unwrap();
        let desc = cam(64, az, el, projection, 0.5)
            .to_builder()
            .mode(mode)
            .filter(Filter::Manual)
            .build()
            .unwrap();
        let whole = common::render(&ctx, &volume, &tf, &desc, accel("naive"));
        let shown = whole.pixels.iter().filter(|p| p[3] > 0.01).count();
        assert!(
            shown > 100 && shown < 64 * 64,
            "{spec} {mode:?} shows the volume ({shown})"
        );
        for ranks in [2, 3] {
            let structures = [accel("auto"), accel("grid"), accel("distance"), accel("octree-rev")];
            let picked = rendered_in_parts(&volume, &tf, &desc, ranks, &structures);
            let d = diff(&whole, &picked).unwrap();
            assert_eq!(d.differing, 0, "{spec} {mode:?} in {ranks} parts: {d:?}");
        }
        // Each iso part against the CPU reference of the same part.
        if matches!(mode, Mode::Iso(_)) {
            let split = Decomposition::new(volume.dims, 16, 3).unwrap();
            for block in &split.blocks {
                let (lo, hi) = block.bounds();
                let part = desc.to_builder().segment(Some([lo, hi])).build().unwrap();
                let gpu_part = common::render(&ctx, &volume, &tf, &part, accel("naive"));
                let cpu_part = lacuna::render::reference::render_frame(&volume, &tf, &part).unwrap();
                let d = diff(&gpu_part, &cpu_part).unwrap();
                assert!(d.max_abs <= 1e-4, "{spec} block {block:?}: {d:?}");
            }
        }
    }
}

#[test]
fn parts_blended_front_to_back_are_the_one_process_frame() {
    let ctx = gpu();
    let cases: Vec<(&str, Option<&str>, FrameDesc)> = vec![
        ("nbody:48", None, cam(64, 30.0, 20.0, Projection::Orthographic, 0.5)),
        (
            "turbulence:37x29x45",
            Some("ramp:0.3:0.9"),
            cam(
                64,
                200.0,
                -30.0,
                Projection::Perspective {
                    fov_deg: 40.0,
                    distance: None,
                },
                0.7,
            ),
        ),
        (
            "vessels:40",
            Some("ramp:0.1:0.6"),
            cam(64, 90.0, 0.0, Projection::Orthographic, 0.5),
        ),
        // Rays along z, pixel column 32 lying in the plane x = 32 that the
        // two blocks share: the block above it takes them, the other not.
        (
            "turbulence:64",
            Some("ramp:0.3:0.9"),
            FrameDesc::builder(64, 64)
                .camera(Camera::Rays(Rays::orthographic(
                    [-0.5, -0.5, -1.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                )))
                .step(0.5)
                .build()
                .unwrap(),
        ),
    ];
    for (i, (spec, tf, desc)) in cases.into_iter().enumerate() {
        let volume = load(spec);
        let tf = TransferFunction::parse(tf.or(volume.default_tf.as_deref()).unwrap()).unwrap();
        // The second case shaded: gradients read across the blocks' faces.
        let desc = match i {
            1 => desc.to_builder().shading(Some(Shading::default())).build().unwrap(),
            _ => desc,
        };
        let desc = desc.to_builder().filter(Filter::Manual).build().unwrap();
        let whole = common::render(&ctx, &volume, &tf, &desc, accel("naive"));
        assert!(
            whole.pixels.iter().filter(|p| p[3] > 0.001).count() > 20,
            "{spec} shows the volume"
        );
        for ranks in [2, 3] {
            let structures = [accel("auto"), accel("distance"), accel("lbvh")];
            let blended = rendered_in_parts(&volume, &tf, &desc, ranks, &structures);
            let d = diff(&whole, &blended).unwrap();
            assert!(d.max_abs < 1e-5, "{spec} in {ranks} parts: {d:?}");
        }
    }
}

#[test]
fn a_cube_s_first_cut_parts_its_layers() {
    // z first among equal sides: each side streams only its own layers.
    for (dims, ranks) in [([64, 64, 64], 2), ([48, 48, 48], 3), ([80, 64, 80], 2)] {
        let d = Decomposition::new(dims, 16, ranks).unwrap();
        let counts = dims.map(|v| v / 16);
        let first = &d.blocks[0];
        assert_eq!(
            (first.bricks[0][2], first.bricks[1][0], first.bricks[1][1]),
            (0, counts[0], counts[1]),
            "{dims:?} in {ranks}: {first:?}"
        );
        assert!(first.bricks[1][2] < counts[2]);
    }
}

#[test]
fn mpirun_without_the_feature_is_one_error() {
    use lacuna::parallel::across_ranks;
    let e = across_ranks(Some(3), false).unwrap_err().to_string();
    assert!(
        e.starts_with("invalid launch 'mpirun with 3 ranks'") && e.contains("--features mpi"),
        "{e}"
    );
    assert!(!across_ranks(Some(1), false).unwrap());
    assert!(!across_ranks(None, false).unwrap());
    assert!(across_ranks(Some(2), true).unwrap());
    assert!(!across_ranks(None, true).unwrap());
}

#[test]
fn segments_under_a_crop_clip_planes_and_jitter_join_to_the_frame_and_match_the_cpu() {
    use lacuna::render::{reference, Clip};
    let ctx = gpu();
    let volume = load("turbulence:37x29x45");
    let tf = TransferFunction::parse("ramp:0.3:0.9").unwrap();
    // The crop box misses part of every block; the plane cuts across the
    // volume, and some rays pass beside the crop entirely.
    let clip = Clip::default()
        .crop([4.0, 3.0, 6.0], [30.0, 25.0, 40.0])
        .unwrap()
        .plane([1.0, 0.4, -0.2, -9.0])
        .unwrap();
    let desc = cam(64, 200.0, -30.0, Projection::Orthographic, 0.7)
        .to_builder()
        .clip(clip)
        .jitter(true)
        .filter(Filter::Manual)
        .build()
        .unwrap();
    // Composite, and iso: a clipped ray's first sample has no sample
    // before it in any part, and a jittered lattice's crossing between two
    // parts is the later part's.
    let iso = desc.to_builder().mode(iso("0.5,0.62")).build().unwrap();
    for desc in [desc, iso] {
        let whole = common::render(&ctx, &volume, &tf, &desc, accel("naive"));
        assert!(whole.pixels.iter().filter(|p| p[3] > 0.001).count() > 20);
        for ranks in [2, 3] {
            let joined = rendered_in_parts(&volume, &tf, &desc, ranks, &[accel("auto"), accel("grid")]);
            let d = diff(&whole, &joined).unwrap();
            match desc.mode() {
                Mode::Composite => assert!(d.max_abs < 1e-5, "{ranks} parts: {d:?}"),
                _ => assert_eq!(d.differing, 0, "iso in {ranks} parts: {d:?}"),
            }
        }
        // Each part against the CPU reference of the same part.
        let split = Decomposition::new(volume.dims, 16, 3).unwrap();
        for block in &split.blocks {
            let (lo, hi) = block.bounds();
            let part = desc.to_builder().segment(Some([lo, hi])).build().unwrap();
            let gpu_part = common::render(&ctx, &volume, &tf, &part, accel("naive"));
            let cpu_part = reference::render_frame(&volume, &tf, &part).unwrap();
            let d = diff(&gpu_part, &cpu_part).unwrap();
            assert!(d.max_abs <= 1e-4, "{:?} block {block:?}: {d:?}", desc.mode());
        }
    }
}

#[test]
fn a_segment_is_a_composite_mip_or_minip_frame_s_part_only() {
    use lacuna::render::Mode;
    let part = |mode: Mode| {
        cam(16, 30.0, 20.0, Projection::Orthographic, 0.5)
            .to_builder()
            .mode(mode)
            .segment(Some([[0.0; 3], [8.0; 3]]))
            .build()
    };
    let e = part(Mode::Average).unwrap_err().to_string();
    assert!(
        e.starts_with("invalid segment 'average'") && e.contains("composite, mip, minip and iso modes only"),
        "{e}"
    );
    for mode in [Mode::Composite, Mode::Mip, Mode::MinIp, iso("0.5")] {
        let desc = part(mode).unwrap();
        assert_eq!(desc.writes_ray_values(), matches!(mode, Mode::Mip | Mode::MinIp));
        assert_eq!(desc.writes_depth(), mode != Mode::Composite);
    }
    let e = FrameDesc::builder(8, 8)
        .segment(Some([[4.0, 0.0, 0.0], [2.0, 8.0, 8.0]]))
        .build()
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("invalid segment"), "{e}");
}
