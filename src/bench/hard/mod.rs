//! The DESIGN hard cases as a suite: every skipping structure must render
//! each case exactly as naive marching does with the same sample filter (bit
//! for bit, under each filter the volume's format supports), in every look
//! (`looks`: each frame mode, shading, jitter; clip planes and crop boxes
//! are cases of their own), with no validation message and no NaN or
//! infinity in the frame.

mod cases;

pub use cases::{along_z_through_brick_faces, cam, cases, lattice, looks, masked, series_steps, HardCase, HardLook};

use crate::accel::{Accel, BuildInput, Builder, MarchedKind, Params, Structure};
use crate::error::{Error, Result};
use crate::frame::{diff, Frame};
use crate::gpu::Context;
use crate::render::{Filter, FrameDesc, Renderer, Scene};
use crate::tf::TransferFunction;
use crate::volume::GpuVolume;

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

/// One case in one look against one structure under one filter.
pub struct Outcome {
    pub case: &'static str,
    pub look: &'static str,
    pub filter: Filter,
    pub structure: String,
    pub identical: bool,
    pub validation_messages: usize,
    pub finite: bool,
    /// What marched it, when not its own kernel (`auto`'s choice, a tree of
    /// one leaf marched naively, naive in a mode it does not skip in).
    pub marched_as: Option<String>,
    /// Marched by the naive kernel because it does not skip in the look's
    /// mode: nothing to compare.
    pub mode_fallback: bool,
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

/// `case`'s views in `look` (over the case's own): early termination only
/// where the look is composite.
fn views_in(case: &HardCase, look: &HardLook) -> Result<Vec<FrameDesc>> {
    let spec = look.spec.over(&case.look);
    let composite = spec.mode.as_deref().is_none_or(|m| m == "composite");
    case.views
        .iter()
        .map(|v| {
            let ert = if composite { v.ert() } else { None };
            spec.apply(v.to_builder().ert(ert))?.build()
        })
        .collect()
}

/// Which cases and looks a run covers: those named, or all where none is.
#[derive(Clone, Debug, Default)]
pub struct Selection {
    pub looks: Vec<String>,
    pub cases: Vec<String>,
}

impl Selection {
    /// Refuses a look or case the suite does not have, naming those it has.
    pub fn check(&self) -> Result<()> {
        let looks: Vec<&str> = looks("0.5").iter().map(|l| l.name).collect();
        let cases: Vec<&str> = cases()?.iter().map(|c| c.name).collect();
        for (what, asked, known) in [("look", &self.looks, looks), ("case", &self.cases, cases)] {
            if let Some(bad) = asked.iter().find(|a| !known.contains(&a.as_str())) {
                return Err(Error::invalid(
                    what,
                    bad,
                    format!("expected one of: {}", known.join("; ")),
                ));
            }
        }
        Ok(())
    }

    fn has(named: &[String], name: &str) -> bool {
        named.is_empty() || named.iter().any(|n| n == name)
    }
}

/// Runs every case in every look that `only` selects for every structure
/// and filter on a validated context.
pub fn run(ctx: &Context, only: &Selection, mut on_case: impl FnMut(&str)) -> Result<Vec<Outcome>> {
    only.check()?;
    let builder = Builder::new(ctx)?;
    // What is checked is that every structure equals naive; which exact
    // structure auto marches does not change that, so its candidates are
    // priced with nominal constants rather than measured ones.
    builder.set_kernel_costs(Some(crate::accel::auto::KernelCost::NOMINAL))?;
    // Frames share the march kernels auto's probes created.
    let renderer = Renderer::new(builder.context())?;
    let mut out = Vec::new();
    ctx.take_validation_messages();
    let variants = structures()?;
    for case in cases()?.into_iter().filter(|c| Selection::has(&only.cases, c.name)) {
        let v = &case.volume;
        let tf = TransferFunction::parse_channels(case.tf)?;
        let mut gv = GpuVolume::upload(ctx, v)?;
        // The shaded and iso looks read the gradient; the manual filter
        // reads the cells copy where the device holds it, as frames do by
        // default on a CPU device. Several channels are not lit (README,
        // "Channels").
        let one_channel = v.channel_count() == 1;
        gv.prepare(v, one_channel, Some(Filter::Manual))?;
        let lut = tf.upload(ctx)?;
        // The ranges every variant reads, each kind computed once.
        let with: Vec<(Accel, &Params)> = variants.iter().map(|(_, a, p)| (*a, p)).collect();
        let (ranges, _) = builder.ranges_for(&with, &gv)?;
        for look in looks(case.iso)
            .into_iter()
            .filter(|l| Selection::has(&only.looks, l.name))
            .filter(|l| one_channel || !(l.spec.shade == Some(true) || l.spec.mode.as_deref() == Some("iso")))
        {
            on_case(&format!("{} ({})", case.name, look.name));
            let views = views_in(&case, &look)?;
            let input = BuildInput {
                volume: v,
                gpu_volume: &gv,
                tf: &tf,
                gpu_tf: &lut,
                mode: *views[0].mode(),
                frames: &views[..1],
                octants: FrameDesc::octants_of(&views, v.dims, v.spacing)?,
            };
            let mut structures = Vec::new();
            for (label, accel, params) in &variants {
                structures.push((label.clone(), builder.build(*accel, &input, &ranges, params)?.0));
            }
            let filters = Filter::ALL
                .into_iter()
                .filter(|&f| gv.sampler_for(f).is_ok() && (look.all_filters || f == Filter::Manual));
            for filter in filters {
                let render = |s: &Structure, view: &FrameDesc| {
                    let scene = Scene {
                        structure: s,
                        volume: &gv,
                        tf: &lut,
                    };
                    render_view(&renderer, scene, view, filter)
                };
                let naive: Vec<Frame> = views
                    .iter()
                    .map(|view| render(&Structure::naive(), view))
                    .collect::<Result<_>>()?;
                let baseline = ctx.take_validation_messages().len();
                for (label, s) in &structures {
                    let marched = s.marched_as_reason();
                    let mode_fallback = marched.as_ref().is_some_and(|m| m.kind == MarchedKind::ModeFallback);
                    let (mut identical, mut finite, mut detail) = (true, true, String::new());
                    // A structure marched naively in this mode renders
                    // naive's frames by construction: nothing to compare.
                    for (i, view) in views.iter().enumerate().filter(|_| !mode_fallback) {
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
                        look: look.name,
                        filter,
                        structure: label.clone(),
                        identical,
                        validation_messages: messages.len() + baseline,
                        finite,
                        marched_as: marched.map(|m| m.label),
                        mode_fallback,
                        detail,
                    });
                }
            }
        }
    }
    // Asked for cases only in looks they are not run in (several channels
    // are not lit): passing nothing would read as a pass.
    if out.is_empty() {
        return Err(Error::invalid(
            "case",
            only.cases.join("; "),
            "runs in none of the looks named (cases of several channels are not shaded or iso)",
        ));
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
        "| hard case | look | filter | {} |\n|---|---|---|{}\n",
        labels.join(" | "),
        "---|".repeat(labels.len())
    );
    let mut rows: Vec<(&str, &str, Filter)> = Vec::new();
    for o in outcomes {
        if !rows.contains(&(o.case, o.look, o.filter)) {
            rows.push((o.case, o.look, o.filter));
        }
    }
    for (c, look, f) in rows {
        let cells: Vec<String> = labels
            .iter()
            .map(|l| {
                match outcomes
                    .iter()
                    .find(|o| o.case == c && o.look == look && o.filter == f && o.structure == *l)
                {
                    Some(o) if o.mode_fallback => "naive".into(),
                    Some(o) if o.passed() => match &o.marched_as {
                        Some(m) => format!("pass ({m})"),
                        None => "pass".into(),
                    },
                    Some(_) => "FAIL".into(),
                    None => "-".into(),
                }
            })
            .collect();
        s += &format!("| {c} | {look} | {f} | {} |\n", cells.join(" | "));
    }
    s
}
