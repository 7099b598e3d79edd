//! k-d trees: the CPU occupancy tables against brute force, and both builders'
//! trees checked for quality: every leaf box is tight (shrinking any face
//! loses an active footprint), leaves are disjoint and cover every active
//! footprint, and the halting rules hold.

use crate::common;
use crate::common::{assert_clean, gpu};
use lacuna::accel::kd::occupancy::Occupancy;
use lacuna::accel::kd::{cheaper_as_leaf, leaf_boxes, volume, Depth, IBox, KdParams};
use lacuna::accel::{Accel, BuildInput, Builder, Params};
use lacuna::render::Mode;
use lacuna::render::Octants;
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::{TransferFunction, Volume};

/// Brute-force footprint activity: max alpha over the 27 voxels it reads.
fn brute(v: &Volume, tf: &TransferFunction) -> Vec<bool> {
    let d = v.dims.map(|x| x as i64);
    let mut out = Vec::new();
    for z in 0..d[2] {
        for y in 0..d[1] {
            for x in 0..d[0] {
                let (mut lo, mut hi) = (f32::MAX, f32::MIN);
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let c = [x + dx, y + dy, z + dz];
                            let c = [0, 1, 2].map(|a| c[a].clamp(0, d[a] - 1) as u32);
                            let val = v.value(c[0], c[1], c[2]);
                            lo = lo.min(val);
                            hi = hi.max(val);
                        }
                    }
                }
                out.push(tf.max_alpha(lo, hi) > 0.0);
            }
        }
    }
    out
}

#[test]
fn occupancy_tables_match_brute_force() {
    for (spec, t) in [
        ("vessels:45x33x70", "ramp:0.3:1"),
        ("nbody:40", "ramp:0.35:1"),
        ("shells:1x1x37", "band:0.5:1"),
    ] {
        let v = Volume::load(spec, &LoadOptions::default()).unwrap();
        let tf = TransferFunction::parse(t).unwrap();
        let occ = Occupancy::new(&v, &tf);
        let flags = brute(&v, &tf);
        assert_eq!(
            occ.active,
            flags.iter().filter(|f| **f).count() as u64,
            "{spec}: active count"
        );
        let d = v.dims.map(|x| x as i32);
        let at = |x: i32, y: i32, z: i32| flags[(x + d[0] * (y + d[1] * z)) as usize];
        // Random boxes: count and tight box against brute force.
        let mut s = 7u64;
        let mut r = |n: i32| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 33) % n as u64) as i32
        };
        for _ in 0..200 {
            let a = [r(d[0]), r(d[1]), r(d[2])];
            let b = [r(d[0]), r(d[1]), r(d[2])];
            let bx: IBox = [[0, 1, 2].map(|i| a[i].min(b[i])), [0, 1, 2].map(|i| a[i].max(b[i]) + 1)];
            let (mut n, mut lo, mut hi) = (0i64, [i32::MAX; 3], [i32::MIN; 3]);
            for z in bx[0][2]..bx[1][2] {
                for y in bx[0][1]..bx[1][1] {
                    for x in bx[0][0]..bx[1][0] {
                        if at(x, y, z) {
                            n += 1;
                            lo = [lo[0].min(x), lo[1].min(y), lo[2].min(z)];
                            hi = [hi[0].max(x + 1), hi[1].max(y + 1), hi[2].max(z + 1)];
                        }
                    }
                }
            }
            assert_eq!(occ.count(&bx), n, "{spec}: count of {bx:?}");
            assert_eq!(
                occ.tight(&bx),
                (n > 0).then_some([lo, hi]),
                "{spec}: tight box of {bx:?}"
            );
        }
    }
}

/// Tight, disjoint, covering leaves; deep leaves obey the size rules unless
/// cost-driven leaves are on (a region cheaper as one leaf stays whole).
fn check_tree(what: &str, occ: &Occupancy, leaves: &[IBox], params: &KdParams, collapse: bool) {
    let mut sum = 0;
    for (i, l) in leaves.iter().enumerate() {
        let n = occ.count(l);
        assert!(n > 0, "{what}: leaf {i} {l:?} is empty");
        sum += n;
        for a in 0..3 {
            let mut lo = *l;
            lo[0][a] += 1;
            let mut hi = *l;
            hi[1][a] -= 1;
            assert!(
                occ.count(&lo) < n,
                "{what}: leaf {l:?} is not tight at its low {a} face"
            );
            assert!(
                occ.count(&hi) < n,
                "{what}: leaf {l:?} is not tight at its high {a} face"
            );
        }
        if params.depth == Depth::Deep && !collapse {
            let longest = (0..3).map(|a| l[1][a] - l[0][a]).max().unwrap();
            assert!(
                longest <= params.max_leaf as i32 || volume(l) <= 512,
                "{what}: leaf {l:?} exceeds max leaf {}",
                params.max_leaf
            );
        }
        for m in &leaves[i + 1..] {
            let overlap = (0..3).all(|a| l[0][a].max(m[0][a]) < l[1][a].min(m[1][a]));
            assert!(!overlap, "{what}: leaves {l:?} and {m:?} overlap");
        }
    }
    assert_eq!(
        sum as u64, occ.active,
        "{what}: leaves do not cover every active footprint"
    );
}

#[test]
fn cpu_and_gpu_trees_are_tight_disjoint_and_covering() {
    let ctx = gpu();
    let builder = Builder::new(&ctx).unwrap();
    let params = [
        KdParams {
            depth: Depth::Shallow,
            max_leaf: 32,
            bins: 4,
        },
        KdParams {
            depth: Depth::Deep,
            max_leaf: 32,
            bins: 4,
        },
        KdParams {
            depth: Depth::Deep,
            max_leaf: 128,
            bins: 4,
        },
        KdParams {
            depth: Depth::Deep,
            max_leaf: 16,
            bins: 8,
        },
    ];
    for (spec, t) in [
        ("vessels:64", "ramp:0.3:1"),
        ("nbody:64", "ramp:0.35:1"),
        ("menger:54", "ramp:0.3:1:0.2"),
        ("turbulence:37x29x41", "ramp:0.6:1"),
    ] {
        let v = Volume::load(spec, &LoadOptions::default()).unwrap();
        let tf = TransferFunction::parse(t).unwrap();
        let occ = Occupancy::new(&v, &tf);
        let gv = GpuVolume::upload(&ctx, &v).unwrap();
        let lut = tf.upload(&ctx).unwrap();
        let (ranges, _) = builder.ranges(&[], &gv).unwrap();
        let scene = BuildInput {
            volume: &v,
            gpu_volume: &gv,
            tf: &tf,
            gpu_tf: &lut,
            mode: Mode::Composite,
            frames: &[],
            octants: Octants::ALL,
        };
        for (kd, collapse) in params.into_iter().flat_map(|kd| [(kd, false), (kd, true)]) {
            for accel in [common::accel("kd-cpu"), common::accel("kd-gpu")] {
                let (s, timings) = builder
                    .build(accel, &scene, &ranges, &kd_params(accel, &kd, collapse))
                    .unwrap();
                let tree = s.tree().unwrap();
                let nodes = tree.read_nodes().unwrap();
                let what = format!("{spec} {accel} {kd:?} collapse {collapse}");
                check_tree(&what, &occ, &leaf_boxes(&nodes), &kd, collapse);
                if collapse {
                    // Every split kept is one the cost model prefers.
                    let model = builder.cost_model().unwrap();
                    for n in nodes.iter().filter(|n| !n.is_leaf()) {
                        let b = |i: i32| {
                            let (lo, hi) = nodes[i as usize].bounds();
                            [lo, hi]
                        };
                        let (lo, hi) = n.bounds();
                        assert!(
                            !cheaper_as_leaf(&model, &[lo, hi], &b(n.lo[3]), &b(n.hi[3])),
                            "{what}: {n:?} is cheaper as a leaf"
                        );
                    }
                }
                let stats = tree.stats().unwrap();
                assert_eq!(stats.nodes as usize, nodes.len());
                assert_eq!(stats.leaves as usize, leaf_boxes(&nodes).len());
                assert!(stats.height >= 1);
                let phases: &[&str] = if accel == common::accel("kd-cpu") {
                    &["svt", "tree", "upload"]
                } else {
                    &["bricks", "sort", "queries", "upload"]
                };
                for ph in phases {
                    assert!(timings.get(ph).is_some(), "{what}: phase {ph} missing");
                }
                if kd.depth == Depth::Shallow {
                    // Shallow trees stay small (the paper: 19 to 35 nodes).
                    assert!(stats.nodes < 200, "{what}: {} nodes", stats.nodes);
                }
            }
        }
    }
    assert_clean(&ctx);
}

/// A k-d structure's parameters for `kd` and `collapse`.
fn kd_params(accel: Accel, kd: &KdParams, collapse: bool) -> Params {
    let depth = if kd.depth == Depth::Shallow { "shallow" } else { "deep" };
    let (max_leaf, bins) = (kd.max_leaf.to_string(), kd.bins.to_string());
    let collapse = if collapse { "on" } else { "off" };
    let given = [
        ("kd", depth),
        ("max-leaf", max_leaf.as_str()),
        ("bins", bins.as_str()),
        ("collapse", collapse),
    ];
    let p = lacuna::accel::table::params_for(accel, &given).unwrap();
    assert_eq!(KdParams::from_params(&p).unwrap().depth, kd.depth);
    p
}

#[test]
fn kd_parameters_are_validated_by_their_schemas() {
    let kd = common::accel("kd-gpu");
    for (given, needle) in [
        (("kd", "medium"), "expected shallow or deep"),
        (("max-leaf", "4"), "an integer >= 8"),
        (("bins", "1"), "an integer in 2..=64"),
    ] {
        let err = kd.params(&[given]).unwrap_err().to_string();
        assert!(err.contains(given.0) && err.contains(needle), "{err}");
    }
    assert!(lacuna::accel::check_cell(12)
        .unwrap_err()
        .to_string()
        .contains("power of two"));
}
