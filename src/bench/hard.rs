//! The DESIGN hard cases as a suite: every skipping structure must render
//! each case exactly as naive marching does with the same sample filter (bit
//! for bit, under each filter the volume's format supports), with no
//! validation message and no NaN or infinity in the frame.

use crate::accel::{Accel, BuildInput, Builder, Params, Structure};
use crate::desc::Mode;
use crate::error::Result;
use crate::frame::{diff, Frame};
use crate::gpu::Context;
use crate::render::{Camera, Filter, FrameDesc, Projection, Rays, Renderer, Scene};
use crate::tf::TransferFunction;
use crate::volume::{GpuVolume, LoadOptions, VoxelData, VoxelType};
use crate::Volume;

pub struct HardCase {
    pub name: &'static str,
    pub volume: Volume,
    pub tf: &'static str,
    /// The views (each rendered under every sample filter the volume's
    /// format supports).
    pub views: Vec<FrameDesc>,
}

/// The structures the suite checks: every registry entry but naive, with
/// each entry's parameter variants (the paper's k-d sets).
pub fn structures() -> Result<Vec<(String, Accel, Params)>> {
    let mut out = Vec::new();
    for a in Accel::skipping() {
        for (label, params) in a.method().variants()? {
            out.push((label, a, params));
        }
    }
    Ok(out)
}

/// An orbit camera view (orthographic or perspective).
pub fn cam(size: u32, az: f64, el: f64, projection: Projection, step: f32, ert: Option<f32>) -> Result<FrameDesc> {
    FrameDesc::builder(size, size)
        .orbit(az, el, projection)
        .step(step)
        .ert(ert)
        .build()
}

const ORTHO: Projection = Projection::Orthographic;

/// Orthographic rays laid out by hand: pixel (i, j) starts at start + i * du
/// + j * dv and travels along dir.
pub fn lattice(size: u32, start: [f32; 3], du: [f32; 3], dv: [f32; 3], dir: [f32; 3], step: f32) -> Result<FrameDesc> {
    let base = [0, 1, 2].map(|a| start[a] - 0.5 * (du[a] + dv[a]));
    FrameDesc::builder(size, size)
        .camera(Camera::Rays(Rays::orthographic(base, du, dv, dir)))
        .step(step)
        .build()
}

fn gen(spec: &str) -> Result<Volume> {
    Volume::load(spec, &LoadOptions::default())
}

/// The cases, at sizes a CPU driver renders in seconds.
pub fn cases() -> Result<Vec<HardCase>> {
    let persp = |d: Option<f64>, fov: f64| Projection::Perspective {
        fov_deg: fov,
        distance: d,
    };
    let mut dot = vec![0u8; 40 * 40 * 40];
    dot[16 + 40 * (16 + 40 * 16)] = 255;
    let halves: Vec<u8> = (0..24 * 24 * 24).map(|i| if (i % 24) < 12 { 0 } else { 255 }).collect();
    let long: Vec<u8> = (0..4 * 4 * 3000)
        .map(|i| if (i / 16) % 97 < 3 { 255 } else { 0 })
        .collect();
    Ok(vec![
        HardCase {
            name: "rays parallel to an axis",
            volume: gen("turbulence:33x29x31")?,
            tf: "ramp:0.5:1:0.3",
            views: vec![
                cam(32, 0.0, 0.0, ORTHO, 0.5, None)?,
                cam(32, 90.0, 0.0, ORTHO, 0.5, None)?,
                cam(32, 0.0, 90.0, ORTHO, 0.5, None)?,
            ],
        },
        HardCase {
            name: "rays through brick faces and edges",
            volume: gen("turbulence:32")?,
            tf: "ramp:0.55:1:0.5",
            views: vec![lattice(
                33,
                [0.0, 0.0, -5.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                0.5,
            )?],
        },
        HardCase {
            name: "rays through brick corners",
            volume: gen("turbulence:32")?,
            tf: "band:0.7:1",
            views: vec![lattice(
                17,
                [-4.0, -4.0, -4.0],
                [2.0, -2.0, 0.0],
                [1.0, 1.0, -2.0],
                [1.0, 1.0, 1.0],
                0.5,
            )?],
        },
        HardCase {
            name: "grazing rays",
            volume: gen("turbulence:32")?,
            tf: "ramp:0.55:1:0.5",
            views: vec![
                lattice(
                    33,
                    [40.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    [0.0, 0.0, 1.0],
                    [-1.0, 0.0, 0.0],
                    1.0,
                )?,
                lattice(
                    33,
                    [8.0, -3.0, 0.0],
                    [0.0, 0.0, 1.0],
                    [1.0, 0.0, 0.0],
                    [0.0, 1.0, 1.0],
                    0.5,
                )?,
            ],
        },
        HardCase {
            name: "camera inside the volume",
            volume: gen("menger:27")?,
            tf: "ramp:0.3:1:0.5",
            views: vec![cam(32, 10.0, 5.0, persp(Some(0.1), 70.0), 0.5, None)?],
        },
        HardCase {
            name: "camera inside an empty region",
            volume: gen("shells:48")?,
            tf: "ramp:0.2:1:0.8",
            views: vec![
                cam(32, 0.0, 0.0, persp(Some(0.0), 90.0), 0.5, None)?,
                cam(32, 33.0, 12.0, persp(Some(0.0), 90.0), 0.3, None)?,
            ],
        },
        HardCase {
            name: "dims not multiples of the brick size",
            volume: gen("nbody:13x37x21")?,
            tf: "ramp:0.2:1:0.6",
            views: vec![
                cam(32, 30.0, 20.0, ORTHO, 0.5, None)?,
                cam(32, -140.0, -25.0, persp(None, 50.0), 0.5, None)?,
            ],
        },
        HardCase {
            name: "degenerate dims 1 x 1 x N",
            volume: gen("shells:1x1x40")?,
            tf: "ramp:0.2:1:0.6",
            views: vec![cam(24, 30.0, 20.0, ORTHO, 0.5, None)?],
        },
        HardCase {
            name: "transparent transfer function",
            volume: gen("vessels:40")?,
            tf: "band:0:1:0",
            views: vec![cam(32, 30.0, 20.0, ORTHO, 0.5, None)?],
        },
        HardCase {
            name: "opaque transfer function",
            volume: gen("vessels:40")?,
            tf: "band:0:1:0.05",
            views: vec![
                cam(32, 30.0, 20.0, ORTHO, 0.5, None)?,
                cam(32, 30.0, 20.0, ORTHO, 0.5, Some(0.95))?,
            ],
        },
        HardCase {
            name: "a single active voxel",
            volume: Volume::new("dot", [40; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(dot))?,
            tf: "band:0.02:1:1",
            views: vec![
                cam(32, 0.0, 0.0, ORTHO, 0.5, None)?,
                cam(32, 45.0, 35.264389682754654, ORTHO, 0.37, None)?,
            ],
        },
        HardCase {
            name: "spike narrower than the gap between voxel values",
            volume: Volume::new("halves", [24; 3], [1.0; 3], VoxelType::U8, VoxelData::U8(halves))?,
            tf: "spike:0.5:0.0005",
            views: vec![
                cam(24, 90.0, 0.0, ORTHO, 0.5, None)?,
                cam(24, 80.0, 10.0, ORTHO, 0.25, None)?,
            ],
        },
        HardCase {
            name: "steps that do not divide the box",
            volume: gen("nbody:40")?,
            tf: "ramp:0.3:1",
            views: vec![
                cam(32, 17.0, 23.0, ORTHO, 0.3, None)?,
                cam(32, 17.0, 23.0, ORTHO, 0.77, None)?,
                cam(32, 17.0, 23.0, ORTHO, 1.9, None)?,
            ],
        },
        HardCase {
            name: "large t (a 4 x 4 x 3000 volume)",
            volume: Volume::new("long", [4, 4, 3000], [1.0; 3], VoxelType::U8, VoxelData::U8(long))?,
            tf: "band:0.5:1:0.01",
            views: vec![
                cam(16, 0.0, 0.0, ORTHO, 0.5, None)?,
                cam(16, 0.3, 0.2, ORTHO, 0.7, None)?,
                cam(16, 180.0, 0.0, persp(Some(1.2), 1.0), 0.5, None)?,
            ],
        },
    ])
}

/// One case against one structure under one filter.
pub struct Outcome {
    pub case: &'static str,
    pub filter: Filter,
    pub structure: String,
    pub identical: bool,
    pub validation_messages: usize,
    pub finite: bool,
    /// What marched it, when not its own kernel (`auto`'s choice, a tree of
    /// one leaf marched naively).
    pub marched_as: Option<String>,
    pub detail: String,
}

impl Outcome {
    pub fn passed(&self) -> bool {
        self.identical && self.validation_messages == 0 && self.finite
    }
}

/// Renders `view` of `s` sampling with `filter`.
pub fn render_view(renderer: &Renderer, scene: Scene, view: &FrameDesc, filter: Filter) -> Result<Frame> {
    let view = view.to_builder().filter(filter).build()?;
    Ok(renderer.render(scene, &view)?.0)
}

/// Runs every case for every structure and filter on a validated context.
pub fn run(ctx: &Context, mut on_case: impl FnMut(&str)) -> Result<Vec<Outcome>> {
    let builder = Builder::new(ctx)?;
    let renderer = Renderer::new(ctx)?;
    let mut out = Vec::new();
    ctx.take_validation_messages();
    for case in cases()? {
        on_case(case.name);
        let v = &case.volume;
        let tf = TransferFunction::parse(case.tf)?;
        let gv = GpuVolume::upload(ctx, v)?;
        let lut = tf.upload(ctx)?;
        let scene = BuildInput {
            volume: v,
            gpu_volume: &gv,
            tf: &tf,
            gpu_tf: &lut,
            mode: Mode::Composite,
        };
        // The ranges every variant reads, each kind computed once.
        let variants = structures()?;
        let with: Vec<(Accel, &Params)> = variants.iter().map(|(_, a, p)| (*a, p)).collect();
        let (ranges, _) = builder.ranges_for(&with, &gv)?;
        let mut built = Vec::new();
        for (label, accel, params) in &variants {
            built.push((label.clone(), builder.build(*accel, &scene, &ranges, params)?.0));
        }
        let structures = built;
        for filter in Filter::ALL.into_iter().filter(|&f| gv.sampler_for(f).is_ok()) {
            let render = |s: &Structure, view: &FrameDesc| {
                let scene = Scene {
                    structure: s,
                    volume: &gv,
                    tf: &lut,
                };
                render_view(&renderer, scene, view, filter)
            };
            let naive: Vec<Frame> = case
                .views
                .iter()
                .map(|view| render(&Structure::naive(), view))
                .collect::<Result<_>>()?;
            let baseline = ctx.take_validation_messages().len();
            for (label, s) in &structures {
                let (mut identical, mut finite, mut detail) = (true, true, String::new());
                for (i, view) in case.views.iter().enumerate() {
                    let f = render(s, view)?;
                    let d = diff(&naive[i], &f)?;
                    if d.differing > 0 {
                        identical = false;
                        detail = format!("view {i}: {d}");
                    }
                    finite &= f.pixels.iter().all(|p| p.iter().all(|c| c.is_finite()));
                }
                let messages = ctx.take_validation_messages();
                if let Some(m) = messages.first() {
                    detail = format!("{m}");
                }
                out.push(Outcome {
                    case: case.name,
                    filter,
                    structure: label.clone(),
                    identical,
                    validation_messages: messages.len() + baseline,
                    finite,
                    marched_as: s.marched_as_reason().map(|m| m.label),
                    detail,
                });
            }
        }
    }
    Ok(out)
}

/// The pass/fail table: a row per case and filter, a column per structure.
/// A cell reads `pass` (`pass (naive)` when another kernel marched it).
pub fn table(outcomes: &[Outcome]) -> String {
    let mut labels: Vec<&str> = Vec::new();
    for o in outcomes {
        if !labels.contains(&o.structure.as_str()) {
            labels.push(&o.structure);
        }
    }
    let mut s = format!(
        "| hard case | filter | {} |\n|---|---|{}\n",
        labels.join(" | "),
        "---|".repeat(labels.len())
    );
    let mut rows: Vec<(&str, Filter)> = Vec::new();
    for o in outcomes {
        if !rows.contains(&(o.case, o.filter)) {
            rows.push((o.case, o.filter));
        }
    }
    for (c, f) in rows {
        let cells: Vec<String> = labels
            .iter()
            .map(|l| {
                match outcomes
                    .iter()
                    .find(|o| o.case == c && o.filter == f && o.structure == *l)
                {
                    Some(o) if o.passed() => match &o.marched_as {
                        Some(m) => format!("pass ({m})"),
                        None => "pass".into(),
                    },
                    Some(_) => "FAIL".into(),
                    None => "-".into(),
                }
            })
            .collect();
        s += &format!("| {c} | {f} | {} |\n", cells.join(" | "));
    }
    s
}
