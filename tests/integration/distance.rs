//! The GPU distance maps (cube and octant) against a brute-force CPU
//! transform and against the host's sweeps (`build_on_host`), and the
//! extremes: no active cell, every cell active, one active cell.

use crate::common::{assert_clean, gpu};
use lacuna::accel::distance::{self, DistanceMap};
use lacuna::accel::{BuildInput, Builder, RangeKind};
use lacuna::gpu::{Context, Timer};
use lacuna::render::Mode;
use lacuna::render::Octants;
use lacuna::tf::GpuTransferFunction;
use lacuna::volume::{GpuVolume, VoxelData, VoxelType};
use lacuna::{TransferFunction, Volume};

fn rng(seed: u64) -> impl FnMut() -> u32 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 33) as u32
    }
}

/// A volume with a bright voxel at random positions (`per_mille` of voxels).
fn speckles(dims: [u32; 3], per_mille: u32, seed: u64) -> Volume {
    let mut r = rng(seed);
    let data: Vec<u8> = (0..dims.iter().product::<u32>())
        .map(|_| if r() % 1000 < per_mille { 255 } else { 0 })
        .collect();
    Volume::new("speckles", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(data)).unwrap()
}

struct Built {
    map: DistanceMap,
    flags: Vec<bool>,
    distances: Vec<u32>,
    /// Active cells, and cells.
    active: usize,
    cells: usize,
    phases: Vec<String>,
}

/// The phase `build_on_host` classifies in: on the host where it sees the
/// cells' ranges (lavapipe), else on the device.
fn classify_phase(cells: &lacuna::accel::GpuBricks) -> &'static str {
    match cells.ranges().is_host_coherent() {
        true => "classify (host)",
        false => "classify",
    }
}

/// What a composite frame's build reads.
fn composite_input<'a>(
    volume: &'a Volume,
    gpu_volume: &'a GpuVolume,
    tf: &'a TransferFunction,
    gpu_tf: &'a GpuTransferFunction,
    octants: Octants,
) -> BuildInput<'a> {
    BuildInput {
        volume,
        gpu_volume,
        tf,
        gpu_tf,
        mode: Mode::Composite,
        frames: &[],
        octants,
    }
}

/// The map of `v` under `tf` (`built`: the octants an octant map computes).
fn build_for(ctx: &Context, v: &Volume, tf: &TransferFunction, cell: u32, octants: bool, built: Octants) -> Built {
    let builder = Builder::new(ctx).unwrap();
    let gv = GpuVolume::upload(ctx, v).unwrap();
    let lut = tf.upload(ctx).unwrap();
    let (ranges, _) = builder.ranges(&[RangeKind::Cells(cell)], &gv).unwrap();
    let mut timer = Timer::new(ctx, 8).unwrap();
    let input = composite_input(v, &gv, tf, &lut, built);
    let map = ctx
        .submit_and_wait(|cmd| {
            timer.reset(cmd);
            distance::record(&builder, cmd, Some(&mut timer), &input, ranges.cells(cell)?, octants)
        })
        .unwrap();
    let total = map.counts.iter().product::<u32>() as usize;
    let flags: Vec<bool> = flag_words(&map.flags, total).iter().map(|&f| f != 0).collect();
    let distances = map.download().unwrap();
    // The host's transform of the device's classification (what
    // `Builder::build` makes on a CPU device) holds the same bytes.
    let (host, host_timings) = distance::build_on_host(&builder, &input, ranges.cells(cell).unwrap(), octants).unwrap();
    assert_eq!(host.built, map.built, "{}: octants built on the host", v.name);
    // Classified on the host too (lavapipe's ranges are host visible).
    assert_eq!(
        flag_words(&host.flags, total),
        flag_words(&map.flags, total),
        "{}: host classification differs from the kernel's",
        v.name
    );
    assert_eq!(
        host.download().unwrap(),
        distances,
        "{}: host transform differs from the device's",
        v.name
    );
    assert!(host_timings.get(classify_phase(ranges.cells(cell).unwrap())).is_some());
    assert!(host_timings.get("distance (host)").is_some());
    let timings = timer.results().unwrap();
    let phases = ["classify", "distance x", "distance y", "distance z"]
        .into_iter()
        .filter(|p| timings.get(p).is_some())
        .map(String::from)
        .collect();
    assert_clean(ctx);
    Built {
        map,
        distances,
        active: flags.iter().filter(|&&f| f).count(),
        cells: flags.len(),
        flags,
        phases,
    }
}

/// A map's first `total` flag words.
fn flag_words(flags: &lacuna::gpu::Buffer, total: usize) -> Vec<u32> {
    let words: Vec<u32> = bytemuck::pod_collect_to_vec(&flags.download(0, flags.size()).unwrap());
    words[..total].to_vec()
}

/// The host's classification (`build_on_host` on lavapipe) against the
/// kernel's, for two float channels each with its own transfer function
/// and with regions of NaN (no data: left out of the ranges, and a cell of
/// only NaN has an empty range): the same flags wherever a cell's ranges
/// are numbers, and never fewer active cells. Each channel alone
/// makes cells active the other leaves empty, so a classifier that read
/// one channel, or one channel's TF for both, would differ.
#[test]
fn host_classification_equals_the_kernels_per_channel_and_around_no_data() {
    let ctx = gpu();
    let dims = [36u32, 28, 20];
    let n = dims.iter().product::<u32>() as usize;
    let at = |i: usize| [i % 36, i / 36 % 28, i / (36 * 28)];
    let channel = |name: &str, f: &dyn Fn([usize; 3]) -> f32| {
        let data: Vec<f32> = (0..n).map(|i| f(at(i))).collect();
        Volume::new(name, dims, [1.0; 3], VoxelType::F32, VoxelData::F32(data)).unwrap()
    };
    // Channel 1 rises along x, with a slab of NaN; channel 2 is bright in
    // a ball, with NaN in one corner block.
    let a = channel("x ramp", &|[x, _, z]| {
        if (8..12).contains(&z) {
            f32::NAN
        } else {
            x as f32 / 35.0
        }
    });
    let b = channel("ball", &|[x, y, z]| {
        let d = ((x as f32 - 24.0).powi(2) + (y as f32 - 10.0).powi(2) + (z as f32 - 12.0).powi(2)).sqrt();
        if x < 6 && y < 6 {
            f32::NAN
        } else {
            (1.0 - d / 10.0).max(0.0)
        }
    });
    let v = Volume::join(vec![a, b]).unwrap();
    let tf = TransferFunction::parse_channels("ramp:0.8:1 | band:0.5:0.6").unwrap();
    let builder = Builder::new(&ctx).unwrap();
    let gv = GpuVolume::upload(&ctx, &v).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    for cell in [2, 4] {
        let (ranges, _) = builder.ranges(&[RangeKind::Cells(cell)], &gv).unwrap();
        let cells = ranges.cells(cell).unwrap();
        let input = composite_input(&v, &gv, &tf, &lut, Octants::ALL);
        let device = ctx
            .submit_and_wait(|cmd| distance::record(&builder, cmd, None, &input, cells, false))
            .unwrap();
        let (host, timings) = distance::build_on_host(&builder, &input, cells, false).unwrap();
        assert!(
            timings.get(classify_phase(cells)).is_some(),
            "cell {cell}: classified elsewhere"
        );
        let total = cells.total() as usize;
        let (d, h) = (flag_words(&device.flags, total), flag_words(&host.flags, total));
        let r: Vec<f32> = bytemuck::pod_collect_to_vec(&cells.ranges().download(0, cells.ranges().size()).unwrap());
        let numbers = |b: usize| r[4 * b..4 * b + 4].iter().all(|x| !x.is_nan());
        let mut by_channel = [0usize; 2];
        for i in 0..total {
            assert!(h[i] >= d[i], "cell {cell}: cell {i} active on the device only");
            if numbers(i) {
                assert_eq!(h[i], d[i], "cell {cell}: cell {i} ({:?})", &r[4 * i..4 * i + 4]);
            }
            for (c, count) in by_channel.iter_mut().enumerate() {
                *count += (tf.channel(c).max_alpha(r[4 * i + 2 * c], r[4 * i + 2 * c + 1]) > 0.0) as usize;
            }
        }
        let active = h.iter().filter(|&&f| f != 0).count();
        assert!(
            active > by_channel[0] && active > by_channel[1],
            "cell {cell}: {active} active, by channel {by_channel:?}"
        );
        assert!(active < total, "cell {cell}: every cell active");
    }
    assert_clean(&ctx);
}

fn build(ctx: &Context, v: &Volume, tf: &TransferFunction, cell: u32, octants: bool) -> Built {
    build_for(ctx, v, tf, cell, octants, Octants::ALL)
}

fn check(what: &str, b: &Built, octants: bool) {
    let reference = distance::reference(b.map.counts, &b.flags, octants, b.map.built);
    assert_eq!(b.distances.len(), reference.len(), "{what}: map size");
    if let Some(i) = (0..reference.len()).find(|&i| b.distances[i] != reference[i]) {
        let per = distance::channels(octants);
        panic!(
            "{what}: cell {} channel {}: GPU {} CPU {}",
            i / per,
            i % per,
            b.distances[i],
            reference[i]
        );
    }
    for phase in ["classify", "distance x", "distance y", "distance z"] {
        assert!(b.phases.iter().any(|p| p == phase), "{what}: phase {phase} not timed");
    }
}

#[test]
fn maps_match_the_brute_force_transform() {
    let ctx = gpu();
    let tf = TransferFunction::parse("ramp:0.5:1").unwrap();
    // The 140-voxel axes are rows of 70 cells at cell 2: longer than
    // distance_rows.comp and distance_octant_rows.comp keep in private
    // arrays, so they use the storage stack (deque), along each axis in
    // turn (the octant kernel runs 1, 1 and 2 tasks a row along x, y and
    // z, each sweeping both kinds). The 128-voxel axis is rows of exactly 64 cells at cell 2, the
    // longest kept in private arrays.
    for (dims, per_mille, seed) in [
        ([40, 36, 44], 1, 1),
        ([64, 24, 32], 4, 2),
        ([33, 47, 20], 20, 3),
        ([140, 12, 10], 8, 4),
        ([12, 140, 10], 8, 5),
        ([10, 12, 140], 8, 6),
        ([10, 128, 12], 8, 7),
    ] {
        let v = speckles(dims, per_mille, seed);
        for cell in [2, 4, 8] {
            for octants in [false, true] {
                let b = build(&ctx, &v, &tf, cell, octants);
                assert!(b.active > 0, "{dims:?} cell {cell}: some cells active");
                if cell < 8 {
                    assert!(b.active < b.cells, "{dims:?} cell {cell}: some cells empty");
                }
                check(&format!("{dims:?} cell {cell} octants {octants}"), &b, octants);
            }
        }
    }
}

#[test]
fn octant_maps_of_some_octants_hold_exactly_those() {
    let ctx = gpu();
    let tf = TransferFunction::parse("ramp:0.5:1").unwrap();
    // One octant, two opposite ones, the two of one z sign and one y sign,
    // and two that differ only in z: each pass's tasks (the x signs, the
    // xy classes copied to the z signs needed, the octants) in turn; in
    // private arrays and in the storage deque (rows of 70 cells; along y,
    // pass y writes only the z-negative words for the sets without a
    // z-positive octant).
    let sets = [
        Octants::one(5),
        Octants::from_bits(0b1000_0001),
        Octants::from_bits(0b0011_0000),
        Octants::from_bits(0b0100_0100),
    ];
    for (dims, seed) in [
        ([40, 36, 44], 11),
        ([140, 12, 10], 12),
        ([12, 140, 10], 14),
        ([10, 12, 140], 13),
    ] {
        let v = speckles(dims, 8, seed);
        for built in sets {
            let b = build_for(&ctx, &v, &tf, 2, true, built);
            assert_eq!(b.map.built, built);
            assert!(
                b.active > 0 && b.active < b.cells,
                "{dims:?}: some cells active, some empty"
            );
            // The octants not built read as 1: the march walks them cell by cell.
            check(&format!("{dims:?} octants {built}"), &b, true);
        }
    }
    // A cube map holds every direction whatever was asked.
    let b = build_for(&ctx, &speckles([40, 36, 44], 8, 11), &tf, 2, false, Octants::one(3));
    assert_eq!(b.map.built, Octants::ALL);
}

#[test]
fn empty_full_and_single_cell_maps() {
    let ctx = gpu();
    let dims = [32, 32, 32];
    let zeros = Volume::new(
        "zeros",
        dims,
        [1.0; 3],
        VoxelType::U8,
        VoxelData::U8(vec![0; 32 * 32 * 32]),
    )
    .unwrap();
    let visible = TransferFunction::parse("ramp:0:1").unwrap();
    let invisible = TransferFunction::parse("ramp:0.5:1").unwrap();
    let mut one = vec![0u8; 32 * 32 * 32];
    one[17 + 32 * (9 + 32 * 25)] = 255;
    let one = Volume::new("one", dims, [1.0; 3], VoxelType::U8, VoxelData::U8(one)).unwrap();
    for octants in [false, true] {
        // No active cell: every distance is the cap (a cap only shortens jumps).
        let b = build(&ctx, &zeros, &invisible, 4, octants);
        assert_eq!(b.active, 0);
        let half = distance::channels(octants) / 2;
        assert!(b
            .distances
            .chunks(2 * half)
            .all(|c| c[..half].iter().all(|&d| d == distance::CAP)));
        check("empty", &b, octants);
        // Every cell active: a TF visible at the volume's one value.
        let b = build(
            &ctx,
            &zeros,
            &TransferFunction::parse("band:0:0.1").unwrap(),
            4,
            octants,
        );
        assert_eq!(b.active, b.cells, "all active");
        check("full", &b, octants);
        let b = build(&ctx, &one, &visible, 8, octants);
        check("one voxel", &b, octants);
    }
}
