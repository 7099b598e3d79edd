//! Havran's octrees on reduced SPD scenes: the GPU traversals against the CPU
//! reference on every ray's hit and counters (through the whole Whitted ray
//! tree: eye, shadow, reflected and refracted rays), the four traversals
//! against each other, the octree against brute force, and the builder's
//! invariants. Every GPU run is validated (synchronization included).

use crate::common;
use lacuna::octree::whitted::{self, Tracer, WhittedOptions};
use lacuna::octree::{
    trace_ray, Box3, CpuTracer, GpuTracer, Mode, Octree, OctreeOptions, Ray, TraceKernels, TraceResult, TraceScene,
    Traversal, MISS,
};
use lacuna::scene::{Scene, SpdScene};

/// Scene sizes small enough for lavapipe, every primitive kind present.
fn reduced(kind: SpdScene) -> Scene {
    let sf = match kind {
        SpdScene::Balls => 2,
        SpdScene::Gears => 1,
        SpdScene::Lattice => 3,
        SpdScene::Mount => 3,
        SpdScene::Rings => 2,
        SpdScene::Teapot => 3,
        SpdScene::Tetra => 3,
        SpdScene::Tree => 5,
    };
    Scene::generate(kind, Some(sf)).unwrap()
}

fn options(mode: Mode, max_depth: u32) -> OctreeOptions {
    OctreeOptions {
        mode,
        max_depth,
        max_objects: 1,
    }
}

/// Traces every batch on the GPU and on the CPU and requires identical results.
struct Compare<'a> {
    gpu: GpuTracer<'a>,
    cpu: CpuTracer<'a>,
    rays: u64,
    hits: u64,
}

impl Tracer for Compare<'_> {
    fn trace(&mut self, kind: Traversal, rays: &[Ray], any_hit: bool) -> lacuna::Result<(Vec<TraceResult>, f64)> {
        let (g, ms) = self.gpu.trace(kind, rays, any_hit)?;
        let (c, _) = self.cpu.trace(kind, rays, any_hit)?;
        for (i, (a, b)) in g.iter().zip(&c).enumerate() {
            assert_eq!(
                a, b,
                "ray {i} {:?} with traversal {kind} (any hit: {any_hit}): GPU vs CPU",
                rays[i]
            );
        }
        self.rays += rays.len() as u64;
        self.hits += g.iter().filter(|r| r.hit()).count() as u64;
        Ok((g, ms))
    }
}

#[test]
fn gpu_traversals_match_the_cpu_reference_on_every_ray_and_counter() {
    let ctx = common::gpu();
    let kernels = TraceKernels::new(&ctx).unwrap();
    let opts = WhittedOptions {
        resolution: 20,
        max_depth: 5,
        image: false,
    };
    for kind in SpdScene::ALL {
        let scene = reduced(kind);
        let traced = TraceScene::new(&scene);
        for (mode, depth) in [(Mode::Center, 5), (Mode::Adaptive, 4)] {
            let tree = Octree::for_scene(&traced, options(mode, depth));
            let mut cmp = Compare {
                gpu: GpuTracer::new(&kernels, &tree, &traced).unwrap(),
                cpu: CpuTracer {
                    tree: &tree,
                    scene: &traced,
                },
                rays: 0,
                hits: 0,
            };
            let stats = whitted::render(&scene, &mut cmp, &Traversal::ALL, &opts).unwrap();
            assert_eq!(
                stats.disagreements, 0,
                "{kind} {mode}{depth}: traversals disagree on hits"
            );
            assert!(stats.counts.eye_hits > 0, "{kind}: the view sees the scene");
            assert!(cmp.hits > 0 && cmp.rays >= 4 * stats.counts.total());
            // Every traversal visits leaves; the per-traversal step counts differ by design.
            for t in &stats.totals {
                assert!(t.leaves > 0 && t.tests > 0, "{kind} {mode}{depth} {:?}", t.traversal);
            }
            common::assert_clean(&ctx);
        }
    }
}

#[test]
fn the_four_traversals_render_identical_images() {
    let ctx = common::gpu();
    let scene = reduced(SpdScene::Mount);
    let traced = TraceScene::new(&scene);
    let tree = Octree::for_scene(&traced, options(Mode::Adaptive, 5));
    let kernels = TraceKernels::new(&ctx).unwrap();
    let mut gpu = GpuTracer::new(&kernels, &tree, &traced).unwrap();
    let opts = WhittedOptions {
        resolution: 32,
        max_depth: 5,
        image: true,
    };
    let frames: Vec<_> = Traversal::ALL
        .iter()
        .map(|&t| whitted::render(&scene, &mut gpu, &[t], &opts).unwrap().image.unwrap())
        .collect();
    assert!(
        frames[0].pixels.iter().any(|p| p[0] != frames[0].pixels[0][0]),
        "a non-trivial image"
    );
    for f in &frames[1..] {
        assert_eq!(f.pixels, frames[0].pixels);
    }
    common::assert_clean(&ctx);
}

/// Nearest hit over every primitive, no octree.
fn brute_force(traced: &TraceScene, ray: &Ray) -> (u32, f32) {
    let mut best = (MISS, ray.tmax);
    for (k, p) in traced.prims.iter().enumerate() {
        if let Some(t) = lacuna::octree::prims::intersect(traced, p, ray, ray.tmin, best.1) {
            best = (k as u32, t);
        }
    }
    best
}

#[test]
fn octree_hits_equal_brute_force_nearest_hits() {
    for kind in SpdScene::ALL {
        let scene = reduced(kind);
        let traced = TraceScene::new(&scene);
        for mode in [Mode::Center, Mode::Adaptive] {
            let tree = Octree::for_scene(&traced, options(mode, 6));
            let mut hits = 0;
            for ray in whitted::eye_rays(&scene.view, 39) {
                let (prim, t) = brute_force(&traced, &ray);
                for kind_t in Traversal::ALL {
                    let r = trace_ray(&tree, &traced, kind_t, &ray, false);
                    // Ties in t may resolve to either primitive.
                    assert!(
                        r.prim == prim || (r.hit() && r.t() == t),
                        "{kind} {mode} {kind_t}: octree {:?} vs brute force ({prim}, {t}) for {ray:?}",
                        r
                    );
                    // Shadow rays: any hit exactly when the nearest exists.
                    let s = trace_ray(&tree, &traced, kind_t, &ray, true);
                    assert_eq!(s.hit(), prim != MISS, "{kind} {mode} {kind_t}: any-hit");
                }
                hits += u32::from(prim != MISS);
            }
            assert!(hits > 0, "{kind}: the rays hit something");
        }
    }
}

fn overlaps(a: &Box3, b: &Box3) -> bool {
    (0..3).all(|k| b.lo[k] <= a.hi[k] && b.hi[k] >= a.lo[k])
}

#[test]
fn octree_builds_follow_havrans_rules_and_statistics() {
    for kind in [SpdScene::Tree, SpdScene::Gears, SpdScene::Lattice] {
        let traced = TraceScene::new(&reduced(kind));
        for mode in [Mode::Center, Mode::Adaptive] {
            for depth in 1..=5 {
                let tree = Octree::for_scene(&traced, options(mode, depth));
                let s = tree.stats;
                assert_eq!(s.leaves, 7 * s.interior + 1, "all eight children allocated");
                assert_eq!(tree.nodes.len() as u64, s.leaves + s.interior);
                assert_eq!(s.references, tree.refs.len() as u64);
                let root = &tree.nodes[0];
                for b in &traced.boxes {
                    for k in 0..3 {
                        assert!(
                            root.lo[k] < b.lo[k] && root.hi[k] > b.hi[k],
                            "root encloses every object"
                        );
                    }
                }
                let mut empty = 0;
                for (i, n) in tree.nodes.iter().enumerate() {
                    let nb = Box3 {
                        lo: [n.lo[0], n.lo[1], n.lo[2]],
                        hi: [n.hi[0], n.hi[1], n.hi[2]],
                    };
                    if n.is_leaf() {
                        let mut held: Vec<u32> =
                            tree.refs[n.first() as usize..(n.first() + n.count()) as usize].to_vec();
                        held.sort_unstable();
                        // The parent's objects that overlap this leaf, exactly.
                        let parent = &tree.nodes[n.parent() as usize];
                        let candidates: Vec<u32> = (0..traced.boxes.len() as u32)
                            .filter(|&k| overlaps(&nb, &traced.boxes[k as usize]))
                            .filter(|&k| {
                                let pb = Box3 {
                                    lo: [parent.lo[0], parent.lo[1], parent.lo[2]],
                                    hi: [parent.hi[0], parent.hi[1], parent.hi[2]],
                                };
                                i == 0 || overlaps(&pb, &traced.boxes[k as usize])
                            })
                            .collect();
                        assert!(held.iter().all(|k| candidates.contains(k)));
                        if n.depth() < depth {
                            assert!(n.count() <= 1, "a leaf above the depth limit holds at most one object");
                        }
                        empty += u64::from(n.count() == 0);
                    } else {
                        for a in 0..3 {
                            assert!(n.split[a] > n.lo[a] && n.split[a] < n.hi[a], "split inside the node");
                            if mode == Mode::Center {
                                assert_eq!(n.split[a], (n.lo[a] + n.hi[a]) * 0.5);
                            }
                        }
                        for c in 0..8 {
                            let child = &tree.nodes[(n.first() + c) as usize];
                            assert_eq!(child.parent() as usize, i);
                            assert_eq!(child.depth(), n.depth() + 1);
                        }
                    }
                }
                assert_eq!(empty, s.empty_leaves);
            }
        }
    }
}

/// A build past its byte budget stops as it goes and is an error naming
/// the depth; within it, the tree is `build`'s. The CLI budgets a GPU tree
/// by `maxStorageBufferRange`, so a depth whose tree would take gigabytes
/// of host memory (tetra's four overlapping objects split to the last
/// level) is one line, not an abort.
#[test]
fn an_octree_past_its_budget_is_an_error_not_an_abort() {
    let traced = TraceScene::new(&reduced(SpdScene::Tree));
    let whole = Octree::for_scene(&traced, options(Mode::Center, 5));
    let within = Octree::for_scene_within(&traced, options(Mode::Center, 5), u64::MAX).unwrap();
    assert_eq!((within.nodes, within.refs), (whole.nodes.clone(), whole.refs));
    let bytes = (whole.nodes.len() * std::mem::size_of::<lacuna::octree::Node>()) as u64;
    let err = Octree::for_scene_within(&traced, options(Mode::Center, 5), bytes / 2)
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("invalid max depth '5': the octree of "), "{err}");
    assert!(err.ends_with("take a smaller max depth"), "{err}");
    common::fails(
        &[
            "octree",
            "tetra",
            "--size",
            "1",
            "--resolution",
            "16",
            "--max-depth",
            "9",
            "--validate",
        ],
        &[],
        "invalid max depth '9': the octree of 4 objects outgrew",
    );
}
