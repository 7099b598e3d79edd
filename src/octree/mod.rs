//! Octrees after Havran's "Comparison of octree traversal algorithms" (1999):
//! CPU construction in modes C and A, the four traversals (Glassner 1984,
//! Samet 1989, Gargantini & Atkinson 1993, Revelles et al. 2000) in GLSL with
//! a CPU reference that mirrors them, a GPU batch tracer, and the SPD's
//! Whitted ray tracer that drives them and counts Havran's statistics.

pub mod build;
mod gpu;
pub mod prims;
pub mod report;
pub mod whitted;

pub use crate::spatial::octree_node as node;
pub use crate::spatial::octree_traverse as traverse;

pub use build::{Box3, BuildStats, Mode, Octree, OctreeOptions, MAX_DEPTH_LIMIT};
pub use gpu::{GpuTracer, TraceKernels};
pub use node::Node;
pub use prims::{Prim, Ray, TraceResult, TraceScene, MISS};
pub use traverse::{Counters, Traversal};
pub use whitted::CpuTracer;

use rayon::prelude::*;

impl Octree {
    /// Havran's octree over a surface scene.
    pub fn for_scene(scene: &TraceScene, options: OctreeOptions) -> Octree {
        Octree::build(scene.root_box(), &scene.boxes, options)
    }

    /// As `for_scene`, an error once the build would take more than `max_bytes`.
    pub fn for_scene_within(
        scene: &TraceScene,
        options: OctreeOptions,
        max_bytes: u64,
    ) -> crate::error::Result<Octree> {
        Octree::build_within(scene.root_box(), &scene.boxes, options, max_bytes)
    }
}

/// Traces one ray on the CPU: the reference the GPU tracer must match.
pub fn trace_ray(tree: &Octree, scene: &TraceScene, kind: Traversal, ray: &Ray, any_hit: bool) -> TraceResult {
    let mut best = ray.tmax;
    let mut prim = MISS;
    let mut tests = 0u32;
    let c = traverse::traverse(&tree.nodes, kind, ray.org, ray.dir, ray.tmin, ray.tmax, |n, _t0, t1| {
        if n.count() == 0 {
            return false;
        }
        let limit = t1 + 1e-5 * t1.abs().max(1.0);
        for &k in &tree.refs[n.first() as usize..(n.first() + n.count()) as usize] {
            tests += 1;
            if let Some(t) = prims::intersect(scene, &scene.prims[k as usize], ray, ray.tmin, best) {
                if any_hit {
                    best = t;
                    prim = k;
                    return true;
                }
                if t <= limit {
                    best = t;
                    prim = k;
                }
            }
        }
        prim != MISS
    });
    TraceResult {
        t_bits: if prim == MISS { 0 } else { best.to_bits() },
        prim,
        tests,
        steps: c.steps,
        leaves: c.leaves,
        empty_leaves: c.empty_leaves,
        pad: [0; 2],
    }
}

/// Traces a batch on the CPU (rayon).
pub fn trace_cpu(tree: &Octree, scene: &TraceScene, kind: Traversal, rays: &[Ray], any_hit: bool) -> Vec<TraceResult> {
    rays.par_iter()
        .map(|r| trace_ray(tree, scene, kind, r, any_hit))
        .collect()
}
