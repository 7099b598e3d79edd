//! The cells copies (src/volume/cells.rs): the manual filter reading one
//! texel per sample from the volume's, and three per lit sample from the
//! gradient's, gives the frames it gives from eight texel fetches each, bit
//! for bit, for every texel kind (unorm8, unorm16, float32 with NaN), odd
//! dimensions, cameras along axes and inside the volume, and every mode
//! (shaded composite and iso read the gradient); and a copy the device
//! cannot hold is refused by the limit.

use crate::common::{assert_clean, gpu};
use lacuna::accel::{Accel, BuildInput, Builder};
use lacuna::desc::Iso;
use lacuna::frame::Frame;
use lacuna::gpu::Context;
use lacuna::render::Octants;
use lacuna::render::{Filter, FrameDesc, Mode, Projection, Renderer, Scene, Shading};
use lacuna::volume::{
    cells_words, check_cells, check_gradient_cells, record_pack_cells, GpuVolume, TexelKind, VoxelData, VoxelType,
};
use lacuna::{TransferFunction, Volume};

/// A lumpy field on odd dims in each texel kind, values over the whole range.
fn volumes() -> Vec<Volume> {
    let dims = [13u32, 9, 7];
    let n = (dims[0] * dims[1] * dims[2]) as usize;
    let field: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y, z) = (i % 13, i / 13 % 9, i / 117);
            (((x * 7 + y * 5 + z * 11) % 17) as f32 / 16.0 * 0.8 + 0.1 * (x % 3) as f32).min(1.0)
        })
        .collect();
    let u8s = field.iter().map(|v| (v * 255.0) as u8).collect();
    let u16s = field.iter().map(|v| (v * 65535.0) as u16).collect();
    // Float data with no-data holes: some beside others, one on a face.
    let mut f32s = field.clone();
    for i in [0, 14, 15, 200, 201, 330, n - 1] {
        f32s[i] = f32::NAN;
    }
    vec![
        Volume::new("cells u8", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(u8s)).unwrap(),
        Volume::new("cells u16", dims, [1.0, 0.5, 2.0], VoxelType::U16, VoxelData::U16(u16s)).unwrap(),
        Volume::new("cells f32", dims, [1.0; 3], VoxelType::F32, VoxelData::F32(f32s)).unwrap(),
    ]
}

fn frame(
    ctx: &Context,
    renderer: &Renderer,
    gv: &GpuVolume,
    v: &Volume,
    tf: &TransferFunction,
    desc: &FrameDesc,
) -> Frame {
    let lut = tf.upload(ctx).unwrap();
    let builder = Builder::new(ctx).unwrap();
    let accel = Accel::naive();
    let (ranges, _) = builder.ranges_for(&[(accel, &accel.defaults())], gv).unwrap();
    let input = BuildInput {
        volume: v,
        gpu_volume: gv,
        tf,
        gpu_tf: &lut,
        mode: *desc.mode(),
        frames: &[],
        octants: Octants::ALL,
    };
    let (structure, _) = builder.build(accel, &input, &ranges, &accel.defaults()).unwrap();
    let scene = Scene {
        structure: &structure,
        volume: gv,
        tf: &lut,
    };
    renderer.render(scene, desc).unwrap().0
}

#[test]
fn cells_give_the_manual_filters_samples_bit_for_bit() {
    let ctx = gpu();
    let renderer = Renderer::new(&ctx).unwrap();
    let tf = TransferFunction::parse("ramp:0.2:0.9").unwrap();
    let views = [
        (30.0, 20.0, Projection::Orthographic),
        (0.0, 0.0, Projection::Orthographic),
        (90.0, 90.0, Projection::Orthographic),
        (
            45.0,
            30.0,
            Projection::Perspective {
                fov_deg: 60.0,
                distance: Some(0.3),
            },
        ),
    ];
    // (mode, shaded)
    let modes = [
        (Mode::Composite, false),
        (Mode::Composite, true),
        (Mode::Mip, false),
        (Mode::Iso(Iso::new(&[0.45]).unwrap()), false),
    ];
    for v in volumes() {
        let mut plain = GpuVolume::upload(&ctx, &v).unwrap();
        plain.add_gradient(&v).unwrap();
        let mut cells = GpuVolume::upload(&ctx, &v).unwrap();
        cells.prepare(&v, true, Some(Filter::Manual)).unwrap();
        assert!(cells.cells().is_some(), "{}: no cells copy", v.name);
        assert!(cells.gradient_cells().is_some(), "{}: no gradient cells copy", v.name);
        assert!(plain.gradient_cells().is_none());
        assert_eq!(cells.default_filter(), Filter::Manual);
        for (mode, shaded) in &modes {
            for &(az, el, projection) in &views {
                let desc = FrameDesc::builder(40, 32)
                    .orbit(az, el, projection)
                    .filter(Filter::Manual)
                    .mode(*mode)
                    .shading(shaded.then(Shading::default))
                    .build()
                    .unwrap();
                let a = frame(&ctx, &renderer, &plain, &v, &tf, &desc);
                let b = frame(&ctx, &renderer, &cells, &v, &tf, &desc);
                let visible = a.pixels.iter().filter(|p| p[3] > 0.0).count();
                assert!(
                    visible > 50,
                    "{} {mode:?} {az},{el}: only {visible} visible pixels",
                    v.name
                );
                for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
                    let bits = |c: &[f32; 4]| c.map(f32::to_bits);
                    assert_eq!(
                        bits(p),
                        bits(q),
                        "{} {mode:?} view {az},{el}: pixel {i} differs with the cells copy",
                        v.name
                    );
                }
            }
        }
    }
    assert_clean(&ctx);
}

#[test]
fn a_cells_copy_past_the_devices_limits_is_refused_by_name() {
    let ctx = gpu();
    let info = ctx.info();
    let err = check_cells(info, [4000, 4000, 4000], TexelKind::Unorm8)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("maxTexelBufferElements") && err.contains("cells copy of volume 4000x4000x4000"),
        "{err}"
    );
    assert!(check_cells(info, [64, 64, 64], TexelKind::Float32).is_ok());
    let err = check_gradient_cells(info, [2000, 2000, 2000]).unwrap_err().to_string();
    assert!(
        err.contains("maxTexelBufferElements") && err.contains("gradient cells copy of volume 2000x2000x2000"),
        "{err}"
    );
    assert_eq!(TexelKind::Float32.bytes_per_voxel(), 32);
}

/// The copy the device makes from the volume image (`record_pack_cells`,
/// the path of devices whose memory is not the host's) and the one the
/// host packs in shared memory (`add_cells` on this CPU device) are the
/// host's words, bit for bit, for every kind (NaN included), also when the
/// copy is made in several dispatches of a few rows each.
#[test]
fn the_devices_cells_copy_is_the_hosts_bit_for_bit() {
    let ctx = gpu();
    for v in volumes() {
        let want: Vec<u8> = bytemuck::cast_slice(&cells_words(&v)).to_vec();
        let kind = TexelKind::of(&v.data);
        let mut gv = GpuVolume::upload(&ctx, &v).unwrap();
        // One binding for the whole copy, and one of about three rows.
        let row = (v.dims[0] as u64 + 1) * kind.bytes_per_voxel();
        for range in [u64::MAX, 3 * row + 1] {
            let image = (gv.image().view(), gv.sampler());
            let mut timer = lacuna::gpu::Timer::new(&ctx, 1).unwrap();
            let got = ctx
                .submit_and_wait(|cmd| {
                    timer.reset(cmd);
                    // SAFETY: the volume's own image and sampler, alive past the wait.
                    unsafe { record_pack_cells(cmd, Some(&mut timer), image, v.dims, kind, range) }
                })
                .unwrap()
                .0;
            // The pass is timed.
            assert!(timer.results().unwrap().phase("cells").unwrap() >= 0.0);
            let got = got.buffer().download(0, want.len() as u64).unwrap();
            assert!(
                got == want,
                "{}: the device's copy differs (binding of {range} bytes)",
                v.name
            );
        }
        gv.add_cells(&v).unwrap();
        let shared = gv.cells().unwrap().buffer().download(0, want.len() as u64).unwrap();
        assert!(shared == want, "{}: add_cells's copy differs", v.name);
    }
    assert_clean(&ctx);
}

/// Another step of `v`'s series: its voxels in reverse order, floats
/// doubled (another normalisation) and without NaN, on another spacing,
/// so every texel, copy and flag changes.
fn step_before(v: &Volume) -> Volume {
    let data = match &v.data {
        VoxelData::U8(d) => VoxelData::U8(d.iter().rev().copied().collect()),
        VoxelData::U16(d) => VoxelData::U16(d.iter().rev().copied().collect()),
        VoxelData::F32(d) => VoxelData::F32(d.iter().rev().map(|x| if x.is_nan() { 0.5 } else { 2.0 * x }).collect()),
        VoxelData::Bricks(_) => unreachable!("volumes() are dense"),
    };
    let spacing = v.spacing.map(|s| 1.5 * s);
    Volume::new("step before", v.dims, spacing, v.source_type, data).unwrap()
}

/// `v` with its middle z plane changed (every voxel of it, NaN too).
fn plane_changed(v: &Volume) -> Volume {
    let [w, h, d] = v.dims.map(|n| n as usize);
    let plane = w * h * (d / 2)..w * h * (d / 2 + 1);
    let mut data = v.data.clone();
    match &mut data {
        VoxelData::U8(x) => x[plane].iter_mut().for_each(|x| *x = 255 - *x),
        VoxelData::U16(x) => x[plane].iter_mut().for_each(|x| *x = 65535 - *x),
        VoxelData::F32(x) => x[plane]
            .iter_mut()
            .for_each(|x| *x = if x.is_nan() { 0.25 } else { 1.0 - *x }),
        VoxelData::Bricks(_) => unreachable!("volumes() are dense"),
    }
    Volume::new("plane changed", v.dims, v.spacing, v.source_type, data).unwrap()
}

/// `v` with a few voxels changed: the last of a row (a segment of one
/// voxel), and a block of 2x2x2 in the middle.
fn voxels_changed(v: &Volume) -> Volume {
    let [w, h, d] = v.dims.map(|n| n as usize);
    let at = |x: usize, y: usize, z: usize| x + w * (y + h * z);
    let mut places = vec![at(w - 1, h / 2, d / 2)];
    for (x, y, z) in [
        (0, 0, 0),
        (1, 0, 0),
        (0, 1, 0),
        (1, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (0, 1, 1),
        (1, 1, 1),
    ] {
        places.push(at(w / 2 + x, h / 2 + y, d / 2 + z));
    }
    let mut data = v.data.clone();
    match &mut data {
        VoxelData::U8(x) => places.iter().for_each(|&i| x[i] = 255 - x[i]),
        VoxelData::U16(x) => places.iter().for_each(|&i| x[i] = 65535 - x[i]),
        VoxelData::F32(x) => places
            .iter()
            .for_each(|&i| x[i] = if x[i].is_nan() { 0.25 } else { 1.0 - x[i] }),
        VoxelData::Bricks(_) => unreachable!("volumes() are dense"),
    }
    Volume::new("voxels changed", v.dims, v.spacing, v.source_type, data).unwrap()
}

/// A step put in place of the one before (`GpuVolume::replace`, as `view`
/// and `bench` play a series) renders as a fresh upload of it, bit for
/// bit, cells and gradient copies included, in every kind and mode; a
/// volume on another grid, of another kind or bricked is not put in place.
#[test]
fn a_step_put_in_place_renders_as_its_fresh_upload() {
    let ctx = gpu();
    let renderer = Renderer::new(&ctx).unwrap();
    let tf = TransferFunction::parse("ramp:0.2:0.9").unwrap();
    let modes = [
        (Mode::Composite, false),
        (Mode::Composite, true),
        (Mode::Mip, false),
        (Mode::Iso(Iso::new(&[0.45]).unwrap()), false),
    ];
    let volumes = volumes();
    for v in &volumes {
        let before = step_before(v);
        let mut placed = GpuVolume::upload(&ctx, &before).unwrap();
        placed.prepare(&before, true, Some(Filter::Manual)).unwrap();
        let desc = FrameDesc::builder(40, 32).filter(Filter::Manual).build().unwrap();
        let old = frame(&ctx, &renderer, &placed, &before, &tf, &desc);
        assert!(
            placed.replace(v, Some(&before)).unwrap(),
            "{}: not put in place",
            v.name
        );
        placed.prepare(v, true, Some(Filter::Manual)).unwrap();
        let mut fresh = GpuVolume::upload(&ctx, v).unwrap();
        fresh.prepare(v, true, Some(Filter::Manual)).unwrap();
        assert_eq!(
            (placed.norm(), placed.has_nan()),
            (fresh.norm(), fresh.has_nan()),
            "{}",
            v.name
        );
        assert_eq!(
            (placed.spacing(), placed.has_nan()),
            (v.spacing, v.no_data_total() > 0),
            "{}",
            v.name
        );
        let words = |g: &GpuVolume| {
            g.cells()
                .unwrap()
                .buffer()
                .download(0, g.cells().unwrap().buffer().size())
        };
        assert!(
            words(&placed).unwrap() == words(&fresh).unwrap(),
            "{}: cells copies differ",
            v.name
        );
        for (mode, shaded) in &modes {
            let desc = FrameDesc::builder(40, 32)
                .orbit(30.0, 20.0, Projection::Orthographic)
                .filter(Filter::Manual)
                .mode(*mode)
                .shading(shaded.then(Shading::default))
                .build()
                .unwrap();
            let a = frame(&ctx, &renderer, &placed, v, &tf, &desc);
            let b = frame(&ctx, &renderer, &fresh, v, &tf, &desc);
            let bits = |f: &Frame| f.pixels.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
            assert!(bits(&a) == bits(&b), "{} {mode:?} shaded {shaded}: differs", v.name);
            if matches!(mode, Mode::Composite) && !shaded {
                assert!(bits(&a) != bits(&old), "{}: the step before looks the same", v.name);
            }
        }
        // The image alone (no cells copy: the manual filter's eight fetches
        // read it), put in place through the mirror of its texels that
        // `replace` keeps from step to step: whole (no step before at
        // hand, or no mirror yet), then only where a plane changed.
        let touched = plane_changed(v);
        let bits = |f: &Frame| f.pixels.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
        let mut plain = GpuVolume::upload(&ctx, &before).unwrap();
        let steps: [(&Volume, Option<&Volume>); 4] =
            [(v, None), (&before, None), (v, Some(&before)), (&touched, Some(v))];
        for (step, previous) in steps {
            assert!(plain.replace(step, previous).unwrap(), "{}: not put in place", v.name);
        }
        assert!(plain.cells().is_none());
        let mut fresh_touched = GpuVolume::upload(&ctx, &touched).unwrap();
        fresh_touched.prepare(&touched, true, Some(Filter::Manual)).unwrap();
        let a = frame(&ctx, &renderer, &plain, &touched, &tf, &desc);
        let b = frame(&ctx, &renderer, &fresh_touched, &touched, &tf, &desc);
        assert!(
            bits(&a) == bits(&b),
            "{}: the changed plane put in place differs",
            v.name
        );
        let unchanged = frame(&ctx, &renderer, &fresh, v, &tf, &desc);
        assert!(
            bits(&a) != bits(&unchanged),
            "{}: the changed plane does not show",
            v.name
        );
        assert!(plain.replace(v, Some(&touched)).unwrap());
        let a = frame(&ctx, &renderer, &plain, v, &tf, &desc);
        assert!(
            bits(&a) == bits(&unchanged),
            "{}: the image put in place differs",
            v.name
        );
        // A few voxels: one in a row's short last segment (13 voxels a row).
        let sparse = voxels_changed(v);
        assert!(plain.replace(&sparse, Some(v)).unwrap());
        let mut fresh_sparse = GpuVolume::upload(&ctx, &sparse).unwrap();
        fresh_sparse.prepare(&sparse, true, Some(Filter::Manual)).unwrap();
        let a = frame(&ctx, &renderer, &plain, &sparse, &tf, &desc);
        let b = frame(&ctx, &renderer, &fresh_sparse, &sparse, &tf, &desc);
        assert!(bits(&a) == bits(&b), "{}: a few voxels put in place differ", v.name);
        assert!(
            bits(&a) != bits(&unchanged),
            "{}: the changed voxels do not show",
            v.name
        );
    }
    // Not in place: other dims, another kind, bricked storage.
    let mut u8s = GpuVolume::upload(&ctx, &volumes[0]).unwrap();
    let smaller = lacuna::Volume::load("nbody:13x9x6", &Default::default()).unwrap();
    assert!(!u8s.replace(&smaller, None).unwrap());
    assert!(!u8s.replace(&volumes[1], Some(&volumes[0])).unwrap());
    let mut bricked = GpuVolume::upload_bricks(&ctx, &volumes[0], 4).unwrap();
    assert!(!bricked.replace(&volumes[0], None).unwrap());
    assert_clean(&ctx);
}

/// A ramp (each brick's range narrow, so a changed voxel changes it) on
/// dims past two blocks of cells along x, in each kind.
fn wide_volumes() -> Vec<Volume> {
    let dims = [37u32, 21, 19];
    let n = (dims[0] * dims[1] * dims[2]) as usize;
    let field: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y, z) = (i % 37, i / 37 % 21, i / (37 * 21));
            (x + 2 * y + 3 * z) as f32 / 130.0
        })
        .collect();
    vec![
        Volume::new(
            "wide u8",
            dims,
            [1.0; 3],
            VoxelType::U8,
            VoxelData::U8(field.iter().map(|v| (v * 255.0) as u8).collect()),
        )
        .unwrap(),
        Volume::new(
            "wide u16",
            dims,
            [1.0; 3],
            VoxelType::U16,
            VoxelData::U16(field.iter().map(|v| (v * 65535.0) as u16).collect()),
        )
        .unwrap(),
        Volume::new("wide f32", dims, [1.0; 3], VoxelType::F32, VoxelData::F32(field)).unwrap(),
    ]
}

/// `v` changed in a few places only: a voxel inside, a run along x across
/// a block of cells, the first and last voxel of a row (the edge cells),
/// voxels 16 and 32 of rows (each read by two blocks of 16 cells), a voxel
/// on the top face; floats also get a NaN (no data).
fn changed_in_places(v: &Volume) -> Volume {
    let [w, h, _] = v.dims.map(|n| n as usize);
    let at = |x: usize, y: usize, z: usize| x + w * (y + h * z);
    let mut places = vec![
        at(9, 10, 8),
        at(0, 3, 4),
        at(36, 3, 4),
        at(16, 7, 2),
        at(32, 11, 6),
        at(20, 20, 18),
    ];
    places.extend((13..=21).map(|x| at(x, 5, 12)));
    // A segment's last voxel alone, read by the next brick's apron.
    places.push(at(27, 15, 9));
    let data = match &v.data {
        VoxelData::U8(d) => VoxelData::U8(with(d, &places, |x| x ^ 0x5a)),
        VoxelData::U16(d) => VoxelData::U16(with(d, &places, |x| x ^ 0x5a5a)),
        VoxelData::F32(d) => {
            let mut f = with(d, &places, |x| 1.0 - x);
            f[at(9, 10, 9)] = f32::NAN;
            VoxelData::F32(f)
        }
        VoxelData::Bricks(_) => unreachable!("dense volumes"),
    };
    Volume::new("changed in places", v.dims, v.spacing, v.source_type, data).unwrap()
}

fn with<T: Copy>(d: &[T], places: &[usize], change: impl Fn(T) -> T) -> Vec<T> {
    let mut out = d.to_vec();
    for &i in places {
        out[i] = change(out[i]);
    }
    out
}

/// A series step put in place with the step before at hand rewrites only
/// what changed (the image's changed bricks, the cells copy around the
/// changed voxels, the ranges of the bricks whose apron holds one), and its
/// cells copy and ranges (read from the cells copy, or from the image
/// where there is none) equal a fresh upload's bit for bit, in every kind, for ranges of 4^3 cells
/// and 8^3 bricks computed alone or together, on the device or (given the
/// step's voxels, on a CPU device, for unorm texels with a cells copy) on
/// the host; the same step's ranges asked again are the kept ones.
#[test]
fn a_step_rewritten_where_it_changed_equals_its_fresh_upload() {
    use lacuna::accel::builder::RangeKind;
    use lacuna::prims::brick_minmax::coarsens_exactly;
    use lacuna::volume::Storage;
    let ctx = gpu();
    let bits = |b: &lacuna::gpu::Buffer| b.download(0, b.size()).unwrap();
    let sets: [&[RangeKind]; 3] = [
        &[RangeKind::Cells(4)],
        &[RangeKind::Bricks],
        &[RangeKind::Cells(4), RangeKind::Bricks],
    ];
    // The manual filter's volumes have their cells copy, which the ranges
    // read; the hardware filter's have none: the ranges read the image.
    for (before, filter) in wide_volumes()
        .into_iter()
        .flat_map(|v| [(v.clone(), Filter::Manual), (v, Filter::Hardware)])
    {
        let manual = Some(filter);
        let after = changed_in_places(&before);
        let unorm = matches!(before.data, VoxelData::U8(_) | VoxelData::U16(_));
        let host_made = ctx.info().is_cpu() && unorm && filter == Filter::Manual;
        for (kinds, host) in sets.into_iter().flat_map(|k| [(k, None), (k, Some(&after))]) {
            let builder = Builder::new(&ctx).unwrap();
            let mut placed = GpuVolume::upload_step(&ctx, None, &before, Storage::Dense, false, manual).unwrap();
            builder.ranges(kinds, &placed).unwrap();
            // Only the image's changed bricks copied, or all of it (as on
            // a CPU device by default).
            placed.upload_changed = filter == Filter::Hardware;
            let placed = GpuVolume::upload_step(
                &ctx,
                Some((placed, Some(&before))),
                &after,
                Storage::Dense,
                false,
                manual,
            )
            .unwrap();
            let mark = placed.step_mark().unwrap();
            let (_, delta) = mark.since.as_ref().expect("the step before was at hand");
            assert!(
                delta.any() && delta.fraction() < 0.2,
                "{}: {}",
                before.name,
                delta.fraction()
            );
            let fresh = GpuVolume::upload_step(&ctx, None, &after, Storage::Dense, false, manual).unwrap();
            let words = |g: &GpuVolume| g.cells().map(|c| bits(c.buffer()));
            assert_eq!(placed.cells().is_some(), filter == Filter::Manual, "{}", before.name);
            assert!(words(&placed) == words(&fresh), "{}: cells copies differ", before.name);
            let (want, _) = Builder::new(&ctx).unwrap().ranges(kinds, &fresh).unwrap();
            // From the step before's (the finest from its changed bricks
            // only, a coarser one with it coarsened from the finest where
            // the normalisation allows), then the same step's again (none
            // computed).
            for round in 0..2 {
                let (got, timings) = builder.ranges_with(kinds, &placed, host).unwrap();
                let on_host = timings.phases.iter().any(|(n, _)| n.ends_with("(host)"));
                assert_eq!(
                    on_host,
                    host.is_some() && host_made,
                    "{}: made on the host",
                    before.name
                );
                for (i, kind) in kinds.iter().enumerate() {
                    let pick = |r: &lacuna::accel::builder::Ranges| match kind {
                        RangeKind::Cells(c) => r.cells(*c).unwrap().computed(),
                        _ => r.bricks().unwrap().computed(),
                    };
                    let range_bits = |r: &lacuna::accel::builder::Ranges| match kind {
                        RangeKind::Cells(c) => bits(r.cells(*c).unwrap().ranges()),
                        _ => bits(r.bricks().unwrap().ranges()),
                    };
                    let name = &before.name;
                    assert!(
                        range_bits(&got) == range_bits(&want),
                        "{name} {kind:?} round {round}: ranges differ"
                    );
                    let (computed, total) = (pick(&got), pick(&want));
                    let coarsened = i > 0 && coarsens_exactly(&placed);
                    match (round, coarsened) {
                        (_, true) => assert_eq!(computed, 0, "{name} {kind:?}: not coarsened"),
                        (0, false) => assert!(
                            computed > 0 && computed < total / 2,
                            "{name} {kind:?}: {computed} of {total}"
                        ),
                        _ => assert_eq!(computed, 0, "{name} {kind:?}: the same step's computed again"),
                    }
                }
            }
        }
    }
    assert_clean(&ctx);
}

/// A series played step after step, each put in place of the one before
/// (`upload_step`), has its cells copy and ranges (made on the device or
/// the host) equal to a fresh upload's at every step. A CPU device, which
/// keeps a staging mirror of the last step's texels, finds what changed
/// without the step before at hand (given here on odd steps only).
#[test]
fn a_played_series_keeps_its_step_ranges_exact() {
    use lacuna::accel::builder::RangeKind;
    use lacuna::volume::{LoadOptions, Series, Storage};
    let ctx = gpu();
    let bits = |b: &lacuna::gpu::Buffer| b.download(0, b.size()).unwrap();
    let words = |g: &GpuVolume| g.cells().map(|c| bits(c.buffer()));
    let series = Series::open("nbody:64", &LoadOptions::default()).unwrap();
    let manual = Some(Filter::Manual);
    let mirrored = ctx.info().is_cpu();
    for cell in [4, 16] {
        let kinds = [RangeKind::Cells(cell)];
        for host in [false, true] {
            let builder = Builder::new(&ctx).unwrap();
            let mut last: Option<(GpuVolume, Volume)> = None;
            for k in 0..8 {
                let v = series.load(k, None).unwrap();
                let (gv, before) = last.take().unzip();
                let before = before.filter(|_| k % 2 == 1);
                let gv = GpuVolume::upload_step(
                    &ctx,
                    gv.map(|g| (g, before.as_ref())),
                    &v,
                    Storage::Dense,
                    false,
                    manual,
                )
                .unwrap();
                let found = gv.step_mark().unwrap().since.is_some();
                assert_eq!(found, k % 2 == 1 || (mirrored && k >= 2), "step {k}: what changed");
                let (got, timings) = builder.ranges_with(&kinds, &gv, host.then_some(&v)).unwrap();
                let on_host = timings.phases.iter().any(|(n, _)| n.ends_with("(host)"));
                assert_eq!(on_host, found && host && mirrored, "step {k}: {timings:?}");
                let fresh = GpuVolume::upload_step(&ctx, None, &v, Storage::Dense, false, manual).unwrap();
                assert!(words(&gv) == words(&fresh), "step {k}: cells copies differ");
                let (want, _) = Builder::new(&ctx).unwrap().ranges(&kinds, &fresh).unwrap();
                assert!(
                    bits(got.cells(cell).unwrap().ranges()) == bits(want.cells(cell).unwrap().ranges()),
                    "step {k} cell {cell} host {host}: ranges differ"
                );
                last = Some((gv, v));
            }
        }
    }
    assert_clean(&ctx);
}

#[test]
fn a_recorded_gradient_submits_nothing_and_lights_as_the_uploaded_one() {
    let ctx = gpu();
    let renderer = Renderer::new(&ctx).unwrap();
    let tf = TransferFunction::parse("ramp:0.2:0.9").unwrap();
    let v = &volumes()[0];
    let mut uploaded = GpuVolume::upload(&ctx, v).unwrap();
    uploaded.prepare(v, true, Some(Filter::Manual)).unwrap();
    let mut recorded = GpuVolume::upload(&ctx, v).unwrap();
    recorded.prepare(v, false, Some(Filter::Manual)).unwrap();
    assert!(recorded.gradient_view().is_none());
    // One submission, this test's own.
    let before = ctx.submissions();
    let staging = ctx.submit_and_wait(|cmd| recorded.record_add_gradient(cmd, v)).unwrap();
    assert!(staging.is_some(), "the gradient image was recorded");
    assert_eq!(ctx.submissions(), before + 1);
    // On a device that shares the host's memory (lavapipe) the cells copy
    // is made as add_gradient makes it; elsewhere it would need a copy.
    let shared = lacuna::volume::host_shared(&ctx);
    assert_eq!(
        recorded.gradient_cells().is_some(),
        uploaded.gradient_cells().is_some() && shared
    );
    assert!(!shared || recorded.gradient_cells().is_some(), "lavapipe: made");
    for mode in [Mode::Composite, Mode::Iso(Iso::new(&[0.45]).unwrap())] {
        let desc = FrameDesc::builder(40, 32)
            .orbit(30.0, 20.0, Projection::Orthographic)
            .filter(Filter::Manual)
            .mode(mode)
            .shading(matches!(mode, Mode::Composite).then(Shading::default))
            .build()
            .unwrap();
        let a = frame(&ctx, &renderer, &uploaded, v, &tf, &desc);
        let b = frame(&ctx, &renderer, &recorded, v, &tf, &desc);
        assert!(a.pixels.iter().filter(|p| p[3] > 0.0).count() > 50, "{mode:?}: visible");
        let bits = |f: &Frame| f.pixels.iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
        assert!(bits(&a) == bits(&b), "{mode:?}: the recorded gradient lights otherwise");
    }
    // Once there, nothing more to record.
    assert!(ctx
        .submit_and_wait(|cmd| recorded.record_add_gradient(cmd, v))
        .unwrap()
        .is_none());
    assert_clean(&ctx);
}
