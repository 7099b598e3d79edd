//! `--accel auto`: its candidates (what the device holds), the counts its
//! probe frames take (against the lattice), its choice under given kernel
//! constants (skipping on sparse data, naive on dense data and in average
//! frames, every candidate timed with `trial always`), the frame of every
//! choice equal to naive's (in every look, over bricks, NaN-masked floats
//! and two channels: the other structures' identity matrices leave auto
//! out), and the kernel constants measured once and read back from the
//! cache (again with `recalibrate`).

use crate::common;
use crate::common::identity::{check_kernel, every_look, standard_views, Fixture, Kernels, DEFAULTS};
use crate::common::{assert_clean, gpu, masked};
use lacuna::accel::auto::{self, choose, Chosen, KernelCost};
use lacuna::accel::probe::FrameProbe;
use lacuna::accel::{BuildInput, Builder, Structure};
use lacuna::bench::hard::lattice;
use lacuna::frame::diff;
use lacuna::render::Octants;
use lacuna::render::{Filter, FrameDesc, Mode, Renderer};
use lacuna::volume::{GpuVolume, LoadOptions, POOL_BRICK};
use lacuna::{TransferFunction, Volume};

fn load(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

fn build(
    builder: &Builder,
    v: &Volume,
    gv: &GpuVolume,
    tf: &TransferFunction,
    desc: &FrameDesc,
    trial: &str,
) -> Structure {
    build_with(builder, v, gv, tf, desc, &[("trial", trial)])
}

fn build_with(
    builder: &Builder,
    v: &Volume,
    gv: &GpuVolume,
    tf: &TransferFunction,
    desc: &FrameDesc,
    given: &[(&str, &str)],
) -> Structure {
    let lut = tf.upload(builder.context()).unwrap();
    let auto = common::accel("auto");
    let params = auto.params(given).unwrap();
    let (ranges, _) = builder.ranges_for(&[(auto, &params)], gv).unwrap();
    let input = BuildInput {
        volume: v,
        gpu_volume: gv,
        tf,
        gpu_tf: &lut,
        mode: *desc.mode(),
        frames: std::slice::from_ref(desc),
        octants: Octants::ALL,
    };
    builder.build(auto, &input, &ranges, &params).unwrap().0
}

fn choice(s: &Structure) -> &auto::Choice {
    &s.built_as::<Chosen>().expect("auto's build is its choice").choice
}

#[test]
fn candidates_are_what_the_device_holds() {
    let ctx = gpu();
    let info = ctx.info();
    // 64^3: 16^3 cells of 4 and 8^3 of 8, both octant maps; grids of 8 and 16.
    let (c, notes) = choose::candidates(info, [64; 3], &Mode::Composite, false).unwrap();
    let labels: Vec<&str> = c.iter().map(|c| c.label.as_str()).collect();
    assert_eq!(
        labels,
        [
            "naive",
            "distance-octant (cell 4)",
            "distance-octant (cell 8)",
            "grid (cell 8)",
            "grid (cell 16)"
        ]
    );
    assert!(notes.is_empty());
    // 512^3: 128^3 cells of 4 are past the octant bound: the cube map;
    // 64^3 of 8 are within it.
    let (c, _) = choose::candidates(info, [512; 3], &Mode::Mip, false).unwrap();
    assert_eq!(c[1].label, "distance (cell 4)");
    assert_eq!(c[2].label, "distance-octant (cell 8)");
    assert!(128u64.pow(3) > auto::OCTANT_CELLS && 64u64.pow(3) <= auto::OCTANT_CELLS);
    // Past the device's buffer range (lavapipe: 128 MiB) a candidate is
    // left out with the limit named, never a failure.
    let huge = [4096, 4096, 2048];
    let (c, notes) = choose::candidates(info, huge, &Mode::Composite, false).unwrap();
    assert_eq!(c[0].label, "naive");
    let range = info.max_storage_buffer_range;
    if 1024u64 * 1024 * 512 * 12 > range {
        assert!(
            notes
                .iter()
                .any(|n| n == "no distance map at cell 4: over maxStorageBufferRange (536870912 cells)"),
            "{notes:?}"
        );
    }
    // Where neither cell 4 nor 8 fits (2048^3 in cells of 8 is 256^3
    // cells, 201 MB of row stacks), the finest coarser map that fits.
    let (c, notes) = choose::candidates(info, [2048; 3], &Mode::Composite, false).unwrap();
    if 256u64.pow(3) * 12 > range && 128u64.pow(3) * 12 <= range {
        assert_eq!(c[1].label, "distance (cell 16)", "{notes:?}");
        assert!(notes
            .iter()
            .any(|n| n == "a distance map at cell 16: the finest that fits"));
    }
    // Average frames read every sample: naive only.
    let (c, _) = choose::candidates(info, [64; 3], &Mode::Average, true).unwrap();
    assert_eq!(c.len(), 1);
    // The k-d tree: last, where asked for and the volume is within the
    // voxels its build is priced for; by default on GPUs only.
    let (c, notes) = choose::candidates(info, [64; 3], &Mode::Mip, true).unwrap();
    assert_eq!(c.len(), 6);
    assert_eq!(c[5].label, "kd-gpu (MLS=32, collapsed)");
    assert!(c[5].is_tree() && !c[..5].iter().any(|c| c.is_tree()));
    assert!(notes.is_empty(), "{notes:?}");
    // Past the voxels its build is priced for, or (within them) past the
    // Morton codes' 1024 bricks on an axis: left out with a note.
    for (dims, note) in [
        (
            [1024, 512, 512],
            "no k-d tree: 268435456 voxels, over the 134217728 its build is priced for",
        ),
        (
            [9000, 120, 120],
            "no k-d tree: [1125, 15, 15] bricks of 8^3, over the 1024 per axis its Morton codes address",
        ),
    ] {
        let (c, notes) = choose::candidates(info, dims, &Mode::Composite, true).unwrap();
        assert!(!c.iter().any(|c| c.is_tree()), "{dims:?}");
        assert!(notes.iter().any(|n| n == note), "{notes:?}");
    }
    assert!(choose::prices_tree(info, "on") && !choose::prices_tree(info, "off"));
    assert_eq!(choose::prices_tree(info, "auto"), !info.is_cpu());
}

#[test]
fn probe_counts_are_the_lattices_samples() {
    let ctx = gpu();
    let builder = common::builder(&ctx);
    let v = load("menger:64");
    let gv = GpuVolume::upload(&ctx, &v).unwrap();
    // 16x16 rays along +z from z = -1 through the whole box: each takes
    // every lattice point of [1, 65) at step 0.5, 128 samples.
    let desc = lattice(
        16,
        [0.5, 0.5, -1.0],
        [4.0, 0.0, 0.0],
        [0.0, 4.0, 0.0],
        [0.0, 0.0, 1.0],
        0.5,
    )
    .unwrap();
    // Peak alpha 0.1: no ray comes near opacity 1, so none ends early.
    let tf = TransferFunction::parse("ramp:0.3:1:0.1").unwrap();
    let probe = FrameProbe::new(&builder, &gv, &tf, &desc, 256).unwrap();
    assert_eq!(probe.scale(), 1.0, "a small frame is probed whole");
    let c = probe.count(&Structure::naive()).unwrap();
    let group = ctx.info().subgroup_size as u64;
    assert_eq!(c.rays, 256);
    assert_eq!(c.ray_samples, 256 * 128);
    // Every ray of a group takes as many samples: a group iteration each.
    assert_eq!(c.samples, 256 / group * 128);
    assert_eq!((c.steps, c.regions), (0, 0));
    // Opaque matter (alpha 1 at the solid value) ends rays even with ERT
    // off, and the probe counts what they skip behind it.
    let opaque = TransferFunction::parse("ramp:0.3:1").unwrap();
    let probe = FrameProbe::new(&builder, &gv, &opaque, &desc, 256).unwrap();
    let c = probe.count(&Structure::naive()).unwrap();
    assert!(c.ray_samples < 256 * 128, "{c:?}");
    // A distance map over nothing visible: no sample, no region, a walk.
    let empty = TransferFunction::parse("band:0:1:0").unwrap();
    let lut = empty.upload(&ctx).unwrap();
    let distance = common::accel("distance");
    let params = distance.defaults();
    let (ranges, _) = builder.ranges_for(&[(distance, &params)], &gv).unwrap();
    let input = BuildInput {
        volume: &v,
        gpu_volume: &gv,
        tf: &empty,
        gpu_tf: &lut,
        mode: Mode::Composite,
        frames: &[],
        octants: Octants::ALL,
    };
    let (map, _) = builder.build(distance, &input, &ranges, &params).unwrap();
    let probe = FrameProbe::new(&builder, &gv, &empty, &desc, 256).unwrap();
    let c = probe.count(&map).unwrap();
    assert_eq!((c.samples, c.regions, c.ray_samples), (0, 0, 0));
    assert!(c.steps >= 256 / group, "{c:?}");
    assert_clean(&ctx);
}

#[test]
fn auto_marches_what_it_chose_and_equals_naive() {
    let ctx = gpu();
    let builder = common::builder(&ctx);
    let renderer = Renderer::new(builder.context()).unwrap();
    let v = load("nbody:64");
    let gv = GpuVolume::upload(&ctx, &v).unwrap();
    let sparse = TransferFunction::parse("ramp:0.3:1").unwrap();
    // Every voxel visible: nothing to skip.
    let dense = TransferFunction::parse("band:0:1").unwrap();
    let frame = |mode: Mode| FrameDesc::builder(64, 64).mode(mode).build().unwrap();
    // (TF, mode, trial, tree, whether naive is expected)
    let cases = [
        (&sparse, Mode::Composite, "off", "off", Some(false)),
        (&dense, Mode::Composite, "off", "off", Some(true)),
        (&sparse, Mode::Mip, "off", "off", None),
        (&dense, Mode::Average, "near", "off", Some(true)),
        (&sparse, Mode::Composite, "always", "off", None),
        // The k-d tree priced, counted and timed beside the others.
        (&sparse, Mode::Composite, "always", "on", None),
        (&sparse, Mode::Mip, "off", "on", None),
        (&sparse, Mode::Mip, "near", "on", None),
    ];
    for (tf, mode, trial, tree, naive) in cases {
        let desc = frame(mode);
        let s = build_with(&builder, &v, &gv, tf, &desc, &[("trial", trial), ("tree", tree)]);
        if matches!(mode, Mode::Average) {
            // Average reads every sample: auto, like every structure, is
            // marched naively and says so.
            assert!(s.built_as::<Chosen>().is_none());
            assert!(s.marched_as().is_naive());
            let why = s.marched_as_reason().unwrap();
            assert_eq!(why.kind, lacuna::accel::MarchedKind::ModeFallback, "{}", why.reason);
            continue;
        }
        let c = choice(&s);
        // Frames are marched with the chosen structure's kernel and data.
        assert_eq!(c.accel, s.marched_as());
        assert_eq!(s.march().shader().name(), c.accel.method().march().shader().name());
        let reported = s.marched_as_reason().expect("auto says what it chose");
        assert_eq!(reported.label, c.describe());
        assert_eq!(reported.reason, c.reason());
        if let Some(naive) = naive {
            assert_eq!(c.accel.is_naive(), naive, "{} {mode:?}: {}", tf.spec, c.reason());
        }
        assert_eq!(c.priced[0].label, "naive", "naive comes first");
        assert_eq!(c.priced.len(), if tree == "on" { 6 } else { 5 }, "{}", c.reason());
        assert!(c.priced.iter().all(|p| p.predicted.is_finite() && p.predicted > 0.0));
        assert!(c.model.iter().all(|m| m == "given"), "{:?}", c.model);
        if tree == "on" && trial == "near" {
            // The model prices the tree poorly on GPUs: it is timed against
            // the best prediction, unless it is that and clear of the rest.
            let t = &c.priced[5];
            assert!(
                t.trial.is_some() || (!c.timed && c.describe() == t.label),
                "{}",
                c.reason()
            );
        }
        if trial == "always" {
            assert!(c.timed && c.priced.iter().all(|p| p.trial.is_some()));
            assert_eq!(c.priced[choose::pick(&c.priced)].label, c.describe(), "{}", c.reason());
        }
        if trial == "off" {
            assert!(!c.timed);
            // The cheapest prediction wins.
            let least = c
                .priced
                .iter()
                .min_by(|a, b| a.predicted.total_cmp(&b.predicted))
                .unwrap();
            assert_eq!(least.label, c.describe());
        }
        let lut = tf.upload(&ctx).unwrap();
        let frame = common::frame(&renderer, &s, &gv, &lut, &desc);
        let naive = common::frame(&renderer, &Structure::naive(), &gv, &lut, &desc);
        assert_eq!(diff(&naive, &frame).unwrap().differing, 0, "{} {mode:?}", tf.spec);
        assert!(
            frame.pixels.iter().any(|p| p[3] > 0.0),
            "{}: something visible",
            tf.spec
        );
    }
    assert_clean(&ctx);
}

/// auto in every look on sparse data, and in composite and MIP frames (by
/// the transfer function's opacity and by the running maximum) over bricked
/// storage, NaN-masked floats and two channels (lit looks and iso read one
/// channel), each priced on the frame it renders:
/// its frame equals naive's, marched with the kernel of the structure it
/// chose (or naive's, saying why). The identity matrices of the other
/// structures leave auto out (`Fixture::check_with`).
#[test]
fn auto_equals_naive_in_every_look_storage_and_channel_count() {
    let cases = [
        ("sparse", load("nbody:40"), None, "ramp:0.3:1"),
        ("bricked", load("nbody:45x37x51"), Some(POOL_BRICK), "ramp:0.3:1"),
        ("masked float", masked("nbody:36"), None, "ramp:0.3:1"),
        // A transfer function per channel; vessels shows only its brightest voxels.
        (
            "two channels",
            load("nbody:40+vessels:40"),
            None,
            "ramp:0.3:1 | ramp:0.97:1",
        ),
    ];
    let auto = common::accel("auto");
    // Priced by the given constants alone, so the choice does not move with
    // a timing (`auto_marches_what_it_chose_and_equals_naive` times trials).
    let untimed = auto.params(&[("trial", "off")]).unwrap();
    for (what, v, bricks, tf) in &cases {
        let fx = match bricks {
            Some(edge) => Fixture::with_bricks(*edge),
            None => Fixture::new(),
        };
        let tf = TransferFunction::parse_channels(tf).unwrap();
        let p = fx.prepare(v, &tf, DEFAULTS);
        let mut skipped = 0;
        let looks = every_look().into_iter().filter(|(mode, shading)| {
            *what == "sparse" || shading.is_none() && matches!(mode, Mode::Composite | Mode::Mip)
        });
        for (mode, shading) in looks {
            let view = standard_views()[0]
                .to_builder()
                .mode(mode)
                .shading(shading)
                .build()
                .unwrap();
            let input = BuildInput {
                volume: v,
                gpu_volume: &p.gv,
                tf: &tf,
                gpu_tf: &p.lut,
                mode,
                frames: std::slice::from_ref(&view),
                octants: Octants::ALL,
            };
            let s = fx.builder.build(auto, &input, &p.ranges, &untimed).unwrap().0;
            let what = format!("{what} {}", mode.name());
            check_kernel(&what, &s, &mode, Kernels::Reported);
            skipped += usize::from(!s.marched_as().is_naive());
            let naive = fx.frame(&Structure::naive(), &p, &view, Filter::Manual);
            let frame = fx.frame(&s, &p, &view, Filter::Manual);
            let d = diff(&naive, &frame).unwrap();
            assert_eq!(d.differing, 0, "{what}: auto ({}) against naive: {d}", s.marched_as());
        }
        // Equality with naive proves something only where auto skipped.
        assert!(skipped > 0, "{what}: auto marched every look naively");
        assert_clean(&fx.ctx);
    }
}

#[test]
fn kernel_constants_are_measured_once_then_read_from_the_cache() {
    let ctx = gpu();
    let dir = tempfile::tempdir().unwrap();
    let v = load("vessels:48");
    let mut gv = GpuVolume::upload(&ctx, &v).unwrap();
    gv.prepare(&v, false, None).unwrap();
    let tf = TransferFunction::parse("ramp:0.3:1").unwrap();
    let desc = FrameDesc::builder(64, 64).build().unwrap();
    let measured = {
        let builder = Builder::new(&ctx).unwrap();
        builder.use_cost_cache(Some(dir.path().to_path_buf())).unwrap();
        let s = build(&builder, &v, &gv, &tf, &desc, "off");
        let c = choice(&s);
        assert_eq!(c.model, ["measured now"], "{}", c.reason());
        c.priced.iter().map(|p| p.predicted).collect::<Vec<_>>()
    };
    let files: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(files.len(), 1, "one file per device: {files:?}");
    let text = std::fs::read_to_string(&files[0]).unwrap();
    assert!(text.starts_with("lacuna kernel cost model 1\n"), "{text}");
    // One line per kernel priced: naive, the octant map, the grid.
    let keys: Vec<&str> = text.lines().filter(|l| l.starts_with("march/")).collect();
    assert_eq!(keys.len(), 3, "{text}");
    for line in &keys {
        let values: Vec<f64> = line.split_whitespace().skip(1).map(|x| x.parse().unwrap()).collect();
        let cost = KernelCost::from_array(values.try_into().unwrap());
        assert!(cost.is_valid() && cost.sample_ns > 0.0, "{line}");
    }
    // A second builder (a later run) reads them: the same predictions.
    let builder = Builder::new(&ctx).unwrap();
    builder.use_cost_cache(Some(dir.path().to_path_buf())).unwrap();
    let s = build(&builder, &v, &gv, &tf, &desc, "off");
    let c = choice(&s);
    assert_eq!(c.model, [format!("cached in {}", files[0].display())]);
    assert_eq!(c.priced.iter().map(|p| p.predicted).collect::<Vec<_>>(), measured);
    // Recalibrating measures again (and rewrites the file).
    builder.recalibrate().unwrap();
    let s = build(&builder, &v, &gv, &tf, &desc, "off");
    assert_eq!(choice(&s).model, ["measured now"]);
    // A file of another format is measured over, never an error.
    std::fs::write(&files[0], "something else\n").unwrap();
    let builder = Builder::new(&ctx).unwrap();
    builder.use_cost_cache(Some(dir.path().to_path_buf())).unwrap();
    let s = build(&builder, &v, &gv, &tf, &desc, "off");
    assert_eq!(choice(&s).model, ["measured now"]);
    assert!(std::fs::read_to_string(&files[0])
        .unwrap()
        .starts_with("lacuna kernel cost model 1"));
    assert_clean(&ctx);
}

/// Naive's counts derived from another structure's counting frame (what
/// auto prices naive by) are naive's own counting frame's, exactly: in
/// every mode that ends rays early, with ERT on and off, clipped and
/// jittered, in perspective, on a frame whose probe skips tiles, for every
/// kind of walk (grid, cube and octant distance maps, the k-d tree).
#[test]
fn naive_counts_derived_from_a_structures_march_are_naives_own() {
    let ctx = gpu();
    let builder = common::builder(&ctx);
    let clip = lacuna::desc::Clip::default().plane([0.3, 1.0, 0.2, -14.0]).unwrap();
    let persp = lacuna::render::Projection::Perspective {
        fov_deg: 50.0,
        distance: None,
    };
    let ortho = lacuna::render::Projection::Orthographic;
    let mut checked = 0;
    for (spec, tf) in [
        ("nbody:40", "ramp:0.3:1"),
        ("menger:27", "ramp:0.2:0.9"),
        ("vessels:36", "band:0.4:1"),
        ("vessels:36+nbody:36", "ramp:0.1:0.6"),
    ] {
        let v = match spec.split_once('+') {
            Some((a, b)) => Volume::join(vec![load(a), load(b)]).unwrap(),
            None => load(spec),
        };
        let gv = GpuVolume::upload(&ctx, &v).unwrap();
        let tf = TransferFunction::parse(tf).unwrap();
        let lut = tf.upload(&ctx).unwrap();
        let iso = Mode::Iso(lacuna::desc::Iso::new(&[0.5]).unwrap());
        let descs = [
            FrameDesc::builder(48, 40).orbit(30.0, 20.0, ortho).build().unwrap(),
            FrameDesc::builder(48, 40)
                .orbit(30.0, 20.0, ortho)
                .ert(None)
                .build()
                .unwrap(),
            FrameDesc::builder(48, 40)
                .orbit(-60.0, 35.0, persp)
                .ert(Some(0.5))
                .build()
                .unwrap(),
            FrameDesc::builder(48, 40)
                .orbit(200.0, -10.0, ortho)
                .clip(clip)
                .jitter(true)
                .build()
                .unwrap(),
            FrameDesc::builder(48, 40)
                .orbit(30.0, 20.0, ortho)
                .mode(Mode::Mip)
                .build()
                .unwrap(),
            FrameDesc::builder(48, 40)
                .orbit(30.0, 20.0, persp)
                .mode(Mode::MinIp)
                .build()
                .unwrap(),
            FrameDesc::builder(48, 40)
                .orbit(80.0, 10.0, ortho)
                .mode(iso)
                .build()
                .unwrap(),
            // Probed in blocks of tiles, not whole.
            FrameDesc::builder(256, 200).orbit(30.0, 20.0, ortho).build().unwrap(),
        ];
        // Several channels: composite, MIP and MinIP (no iso).
        let descs: Vec<FrameDesc> = descs
            .into_iter()
            .filter(|d| v.channel_count() == 1 || !matches!(d.mode(), Mode::Iso(_)))
            .collect();
        for desc in descs {
            // A probe of 16 tiles where a 48x40 frame has 30; 64 of 800.
            let wanted = if desc.size().0 > 48 { 64 } else { 16 };
            let probe = FrameProbe::new(&builder, &gv, &tf, &desc, wanted).unwrap();
            assert!(probe.scale() > 1.0, "{spec} {desc:?}: probed whole");
            let want = probe.count(&Structure::naive()).unwrap();
            assert!(want.ray_samples > 0, "{spec} {desc:?}: no samples");
            for name in ["grid", "distance", "distance-octant", "kd-gpu"] {
                let accel = common::accel(name);
                let params = accel.defaults();
                let (ranges, _) = builder.ranges_for(&[(accel, &params)], &gv).unwrap();
                let input = BuildInput {
                    volume: &v,
                    gpu_volume: &gv,
                    tf: &tf,
                    gpu_tf: &lut,
                    mode: *desc.mode(),
                    frames: std::slice::from_ref(&desc),
                    octants: Octants::ALL,
                };
                let (s, _) = builder.build(accel, &input, &ranges, &params).unwrap();
                let (_, derived) = probe.count_both(&s).unwrap();
                let derived = derived.expect("the probe holds naive's half");
                assert_eq!(derived, want, "{spec} {name} {desc:?}");
                checked += 1;
            }
        }
    }
    assert_eq!(checked, (3 * 8 + 7) * 4);
    assert_clean(&ctx);
}

#[test]
fn an_orbit_is_priced_as_the_mean_of_its_views_and_timed_on_each() {
    let ctx = gpu();
    // Nominal constants: a prediction is a function of the counts alone.
    let builder = common::builder(&ctx);
    let v = load("vessels:48");
    let tf = TransferFunction::parse(v.default_tf.as_deref().unwrap()).unwrap();
    let gv = GpuVolume::upload(&ctx, &v).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let auto = common::accel("auto");
    let view = |az: f64| {
        FrameDesc::builder(64, 64)
            .orbit(az, 20.0, lacuna::render::Projection::Orthographic)
            .build()
            .unwrap()
    };
    let views = [view(30.0), view(210.0)];
    let priced = |frames: &[FrameDesc], trial: &str| -> auto::Choice {
        let params = auto.params(&[("trial", trial)]).unwrap();
        let (ranges, _) = builder.ranges_for(&[(auto, &params)], &gv).unwrap();
        let input = BuildInput {
            volume: &v,
            gpu_volume: &gv,
            tf: &tf,
            gpu_tf: &lut,
            mode: Mode::Composite,
            frames,
            octants: Octants::ALL,
        };
        choice(&builder.build(auto, &input, &ranges, &params).unwrap().0).clone()
    };
    let (a, b) = (priced(&views[..1], "off"), priced(&views[1..], "off"));
    let both = priced(&views, "off");
    assert_eq!((a.views, both.views), (1, 2));
    assert_eq!(both.priced.len(), a.priced.len());
    // Each candidate's counts are its two views' counts, its prediction
    // their mean: no view's counts went to another candidate.
    for ((pa, pb), p) in a.priced.iter().zip(&b.priced).zip(&both.priced) {
        assert_eq!((&pa.label, &pb.label), (&p.label, &p.label));
        assert_eq!(p.counts.samples, pa.counts.samples + pb.counts.samples, "{}", p.label);
        assert_eq!(p.counts.steps, pa.counts.steps + pb.counts.steps, "{}", p.label);
        assert_eq!(p.counts.rays, pa.counts.rays + pb.counts.rays, "{}", p.label);
        let mean = (pa.predicted + pb.predicted) / 2.0;
        assert!(
            (p.predicted - mean).abs() <= 1e-9 * mean,
            "{}: {} against {mean}",
            p.label,
            p.predicted
        );
    }
    // The views differ, so the test tells them apart.
    assert!(a
        .priced
        .iter()
        .zip(&b.priced)
        .any(|(x, y)| x.counts.samples != y.counts.samples));
    // Timed: every candidate on both views, said so.
    let timed = priced(&views, "always");
    assert!(timed.priced.iter().all(|p| p.trial.is_some_and(|t| t > 0.0)));
    assert!(timed.reason().contains("of 2 views, summed"), "{}", timed.reason());
    assert_clean(&ctx);
}
