//! Havran's comparison: one configuration (scene, mode, maximum depth) is
//! built once and rendered by the Whitted tracer with one or more
//! traversals; rows are printed in his layout (statistics down, maximum
//! depths across, per scene and mode).

use super::whitted::{self, RayCounts, Tracer, TraversalTotals, WhittedOptions};
use super::{BuildStats, CpuTracer, GpuTracer, Mode, Octree, OctreeOptions, TraceKernels, TraceScene, Traversal};
use crate::error::Result;
use crate::frame::Frame;
use crate::scene::{Scene, SpdScene};
use std::fmt::Write as _;

/// One configuration's results.
#[derive(Clone, Debug)]
pub struct Row {
    pub scene: SpdScene,
    pub mode: Mode,
    pub max_depth: u32,
    pub build: BuildStats,
    pub counts: RayCounts,
    pub totals: Vec<TraversalTotals>,
    pub disagreements: u64,
}

/// Where rays are traced: the GPU (pipelines created once, shared by every
/// configuration) or the CPU reference.
pub enum Backend<'a> {
    Gpu(&'a TraceKernels),
    Cpu,
}

/// Builds the octree for (`mode`, `max_depth`) within `max_bytes`
/// (`Octree::build_within`) and renders `scene` with every traversal in
/// `traversals` (the first one's image is returned).
#[allow(clippy::too_many_arguments)]
pub fn run(
    backend: &Backend,
    max_bytes: u64,
    scene: &Scene,
    traced: &TraceScene,
    mode: Mode,
    max_depth: u32,
    traversals: &[Traversal],
    options: &WhittedOptions,
) -> Result<(Row, Option<Frame>)> {
    let build = OctreeOptions {
        mode,
        max_depth,
        max_objects: 1,
    };
    let tree = Octree::for_scene_within(traced, build, max_bytes)?;
    let stats = match backend {
        Backend::Gpu(kernels) => {
            let mut gpu = GpuTracer::new(kernels, &tree, traced)?;
            // Lavapipe compiles a pipeline on its first dispatch: warm each up.
            for &t in traversals {
                let probe = [super::Ray {
                    org: [0.0; 3],
                    tmin: 0.0,
                    dir: [0.0, 0.0, 1.0],
                    tmax: 1.0,
                }];
                gpu.trace(t, &probe, false)?;
            }
            whitted::render(scene, &mut gpu as &mut dyn Tracer, traversals, options)?
        }
        Backend::Cpu => {
            let mut cpu = CpuTracer {
                tree: &tree,
                scene: traced,
            };
            whitted::render(scene, &mut cpu, traversals, options)?
        }
    };
    let mut stats = stats;
    let image = stats.image.take().map(|mut f| {
        f.metadata.insert("scene".into(), scene.kind.to_string());
        f.metadata.insert("size_factor".into(), scene.size_factor.to_string());
        f.metadata.insert("octree".into(), format!("{mode}{max_depth}"));
        f.metadata.insert("traversal".into(), traversals[0].to_string());
        f
    });
    Ok((
        Row {
            scene: scene.kind,
            mode,
            max_depth,
            build: tree.stats,
            counts: stats.counts,
            totals: stats.totals,
            disagreements: stats.disagreements,
        },
        image,
    ))
}

/// Havran's ray counts for the SPD at default size (his grid statistics),
/// for comparison: eye hits, shadow rays, shadow hits, secondary, secondary hits.
pub fn havran_counts(scene: SpdScene) -> [u64; 5] {
    match scene {
        SpdScene::Balls => [263169, 959244, 285178, 179884, 134368],
        SpdScene::Gears => [245332, 2088012, 1057557, 494338, 365338],
        SpdScene::Lattice => [261170, 1180774, 943159, 243210, 178786],
        SpdScene::Mount => [173685, 361037, 74555, 710436, 472351],
        SpdScene::Rings => [263169, 1077336, 510719, 312879, 175688],
        SpdScene::Teapot => [161546, 406340, 34757, 226235, 67688],
        SpdScene::Tetra => [49950, 46262, 5538, 0, 0],
        SpdScene::Tree => [169907, 1110323, 47506, 0, 0],
    }
}

/// The ray counts against Havran's, one line.
pub fn format_counts(scene: SpdScene, c: &RayCounts, default_size: bool) -> String {
    let ours = [
        c.eye_hits,
        c.shadow_rays,
        c.shadow_hits,
        c.secondary_rays,
        c.secondary_hits,
    ];
    let names = ["eye hits", "shadow rays", "shadow hits", "secondary", "secondary hits"];
    let mut s = format!("rays: {} eye", c.eye_rays);
    for (i, n) in names.iter().enumerate() {
        let _ = write!(s, ", {n} {}", ours[i]);
        if default_size {
            let h = havran_counts(scene)[i];
            if h > 0 {
                let _ = write!(s, " ({:+.2} % vs Havran)", (ours[i] as f64 / h as f64 - 1.0) * 100.0);
            }
        }
    }
    s
}

/// One configuration as a small table: build statistics, then a line per traversal.
pub fn format_row(r: &Row) -> String {
    let mut s = String::new();
    let b = &r.build;
    let _ = writeln!(
        s,
        "{} octree {}{}: N_IN {}  N_V {}  N_EV {}  N_OIV {}  T_B {:.3} s",
        r.scene, r.mode, r.max_depth, b.interior, b.leaves, b.empty_leaves, b.references, b.build_s
    );
    let _ = writeln!(
        s,
        "{:<10} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "traversal", "N_IT", "N_TS", "N_ETS", "N_EETS", "T_TR [s]"
    );
    for t in &r.totals {
        let [it, ts, ets, eets] = t.per_ray();
        let _ = writeln!(
            s,
            "{:<10} {:>10.2} {:>10.2} {:>10.2} {:>10.2} {:>10.3}",
            format!("O{}", t.traversal),
            it,
            ts,
            ets,
            eets,
            t.trace_ms / 1e3
        );
    }
    s
}

/// Every row in Havran's layout as Markdown: per scene and mode, statistics
/// down and maximum depths across.
pub fn format_all(rows: &[Row]) -> String {
    let mut s = String::new();
    let mut scenes: Vec<SpdScene> = rows.iter().map(|r| r.scene).collect();
    scenes.dedup();
    for scene in scenes {
        let _ = writeln!(s, "### {scene}\n");
        if let Some(r) = rows.iter().find(|r| r.scene == scene) {
            let _ = writeln!(s, "{}\n", format_counts(scene, &r.counts, true));
            let differing: u64 = rows.iter().filter(|r| r.scene == scene).map(|r| r.disagreements).sum();
            let _ = writeln!(
                s,
                "Rays whose hit differs between traversals, all configurations: {differing}.\n"
            );
        }
        for mode in [Mode::Center, Mode::Adaptive] {
            let these: Vec<&Row> = rows.iter().filter(|r| r.scene == scene && r.mode == mode).collect();
            if these.is_empty() {
                continue;
            }
            let _ = write!(s, "| {scene} {mode} |");
            for r in &these {
                let _ = write!(s, " depth {} |", r.max_depth);
            }
            let _ = write!(s, "\n|---|");
            for _ in &these {
                let _ = write!(s, "---:|");
            }
            s.push('\n');
            let mut line = |name: &str, f: &dyn Fn(&Row) -> String| {
                let _ = write!(s, "| {name} |");
                for r in &these {
                    let _ = write!(s, " {} |", f(r));
                }
                s.push('\n');
            };
            line("N_IN", &|r| r.build.interior.to_string());
            line("N_V", &|r| r.build.leaves.to_string());
            line("N_EV", &|r| r.build.empty_leaves.to_string());
            line("N_OIV", &|r| r.build.references.to_string());
            line("T_B [s]", &|r| format!("{:.3}", r.build.build_s));
            let traversals: Vec<Traversal> = these[0].totals.iter().map(|t| t.traversal).collect();
            for (k, t) in traversals.iter().enumerate() {
                let per = |r: &Row, i: usize| r.totals.get(k).map(|x| x.per_ray()[i]).unwrap_or(f64::NAN);
                line(&format!("O{t} N_IT"), &|r| format!("{:.2}", per(r, 0)));
                line(&format!("O{t} N_TS"), &|r| format!("{:.2}", per(r, 1)));
                line(&format!("O{t} N_ETS"), &|r| format!("{:.2}", per(r, 2)));
                line(&format!("O{t} N_EETS"), &|r| format!("{:.2}", per(r, 3)));
                line(&format!("O{t} T_TR [s]"), &|r| {
                    format!("{:.3}", r.totals.get(k).map(|x| x.trace_ms / 1e3).unwrap_or(f64::NAN))
                });
            }
            let _ = writeln!(s);
        }
    }
    s
}
