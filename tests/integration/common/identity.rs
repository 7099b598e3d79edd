//! The identity harness: every skipping structure against naive marching,
//! bit for bit, over views that share one frame mode (the structures are
//! built for it), under each sample filter.

use super::assert_clean;
use lacuna::accel::table::params_for;
use lacuna::accel::{Accel, BuildInput, Builder, MarchedKind, Params, Ranges, Structure};
use lacuna::bench::hard::{self, lattice};
use lacuna::frame::{diff, Frame};
use lacuna::render::Octants;
use lacuna::render::{Filter, FrameDesc, Mode, Projection, Renderer, Scene};
use lacuna::tf::GpuTransferFunction;
use lacuna::volume::GpuVolume;
use lacuna::{TransferFunction, Volume};

/// Parameter values given to every structure (each takes those of its own
/// parameters), as `lacuna render --cell 8 --kd shallow` does.
pub type Given = &'static [(&'static str, &'static str)];

/// The defaults of every structure.
pub const DEFAULTS: Given = &[];

/// Which kernel each structure must have marched with.
#[derive(Clone, Copy, PartialEq)]
pub enum Kernels {
    /// Its own (sparse data: every tree of the paper's has empty space to
    /// skip; with cost-driven leaves, `Reported`); `auto` names the
    /// structure it chose and marches with that one's kernel.
    Own,
    /// Its own, or another one it names with a reason (a tree that is one
    /// leaf covering the volume is marched naively).
    Reported,
}

/// `accel`'s parameters for `given`, and with the other setting of
/// cost-driven leaves for the structures that have them.
pub fn parameter_sets(accel: Accel, given: Given) -> Vec<Params> {
    let p = params_for(accel, given).unwrap();
    let mut sets = vec![p.clone()];
    if let Ok(on) = p.switch("collapse") {
        let flipped = if on { "off" } else { "on" };
        let mut given = given.to_vec();
        given.push(("collapse", flipped));
        sets.push(params_for(accel, &given).unwrap());
    }
    sets
}

pub struct Fixture {
    pub renderer: Renderer,
    pub builder: Builder,
    /// Volumes go up in bricks of this edge (bricked storage), each pool
    /// image within these limits; None: dense.
    pub bricks: Option<(u32, lacuna::volume::PoolLimits)>,
    /// Last: given back to the pool after the renderer's and builder's
    /// buffers are freed, so their messages are this test's.
    pub ctx: super::Gpu,
}

/// A volume and TF uploaded, with the volume's ranges.
pub struct Prepared<'a> {
    pub volume: &'a Volume,
    pub tf: &'a TransferFunction,
    pub gv: GpuVolume,
    pub lut: GpuTransferFunction,
    pub ranges: Ranges,
    /// The frame mode the structures are built for.
    pub mode: Mode,
}

impl Fixture {
    pub fn new() -> Self {
        let ctx = super::gpu();
        let builder = super::builder(&ctx);
        Fixture {
            // auto's probe kernels are the context's: the frames reuse them.
            renderer: Renderer::new(builder.context()).unwrap(),
            builder,
            ctx,
            bricks: None,
        }
    }

    /// As `new`, uploading volumes in bricks of `edge` voxels.
    pub fn with_bricks(edge: u32) -> Self {
        let fx = Self::new();
        let limits = lacuna::volume::PoolLimits::of(fx.ctx.info());
        Fixture {
            bricks: Some((edge, limits)),
            ..fx
        }
    }

    /// As `with_bricks`, each pool image also within `limits`.
    pub fn with_bricks_within(edge: u32, limits: lacuna::volume::PoolLimits) -> Self {
        Fixture {
            bricks: Some((edge, limits)),
            ..Self::new()
        }
    }

    /// Uploads the volume and TF and computes the ranges every structure
    /// reads with the `given` values.
    pub fn prepare<'a>(&self, volume: &'a Volume, tf: &'a TransferFunction, given: Given) -> Prepared<'a> {
        let mut gv = match self.bricks {
            Some((edge, limits)) => GpuVolume::upload_bricks_within(&self.ctx, volume, edge, limits).unwrap(),
            None => GpuVolume::upload(&self.ctx, volume).unwrap(),
        };
        // Shaded and iso views read the gradient; the manual filter reads
        // the cells copy (tests/integration/cells.rs: the same samples as without).
        gv.prepare(volume, volume.channel_count() == 1, Some(Filter::Manual))
            .unwrap();
        let lut = tf.upload(&self.ctx).unwrap();
        let sets: Vec<(Accel, Params)> = lacuna::accel::TABLE
            .iter()
            .flat_map(|&a| parameter_sets(a, given).into_iter().map(move |p| (a, p)))
            .collect();
        let reads: Vec<(Accel, &Params)> = sets.iter().map(|(a, p)| (*a, p)).collect();
        let (ranges, _) = self.builder.ranges_for(&reads, &gv).unwrap();
        Prepared {
            volume,
            tf,
            gv,
            lut,
            ranges,
            mode: Mode::Composite,
        }
    }

    pub fn build(&self, p: &Prepared, accel: Accel, params: &Params) -> Structure {
        self.build_for(p, accel, params, Octants::ALL)
    }

    /// As `build`, for frames of the ray direction `octants` only.
    pub fn build_for(&self, p: &Prepared, accel: Accel, params: &Params, octants: Octants) -> Structure {
        let scene = BuildInput {
            volume: p.volume,
            gpu_volume: &p.gv,
            tf: p.tf,
            gpu_tf: &p.lut,
            mode: p.mode,
            frames: &[],
            octants,
        };
        self.builder.build(accel, &scene, &p.ranges, params).unwrap().0
    }

    pub fn frame(&self, s: &Structure, p: &Prepared, view: &FrameDesc, filter: Filter) -> Frame {
        let scene = Scene {
            structure: s,
            volume: &p.gv,
            tf: &p.lut,
        };
        hard::render_view(&self.renderer, scene, view, filter).unwrap()
    }

    /// Renders every view with naive and with every skipping structure under
    /// each set of given values (and cost-driven leaves on and off), with
    /// each filter; asserts bit-identical frames, and that each structure
    /// marched with the kernel `kernels` asks for. Returns the naive frames
    /// of the manual filter.
    ///
    /// auto is left out: its frame is marched by the structure it chose,
    /// with that structure's kernel and data, and every candidate is in
    /// this matrix; its own pricing (a counting kernel per candidate, look
    /// and volume kind) would add about a fifth to these checks.
    /// `auto::auto_equals_naive_in_every_look_storage_and_channel_count`
    /// checks auto's frames in every look on sparse data, and in composite
    /// and MIP frames over bricks, NaN-masked floats and two channels.
    pub fn check_with(
        &self,
        what: &str,
        v: &Volume,
        tf: &TransferFunction,
        views: &[FrameDesc],
        given: &[Given],
        kernels: Kernels,
    ) -> Vec<Frame> {
        let mut naive: Option<Vec<Vec<Frame>>> = None;
        let mut own_kernels = 0;
        for &g in given {
            let mut p = self.prepare(v, tf, g);
            p.mode = *views[0].mode();
            assert!(
                views.iter().all(|view| view.mode().same_classification(&p.mode)),
                "{what}: views of one check share a mode"
            );
            let filters: Vec<Filter> = Filter::ALL
                .into_iter()
                .filter(|&f| p.gv.sampler_for(f).is_ok())
                .collect();
            assert!(
                // Unless the texels are wider, hold NaN or sit in bricks
                // (manual only).
                filters.contains(&Filter::Hardware)
                    || p.gv.pool().is_some()
                    || lacuna::volume::common_kind(v) != lacuna::volume::TexelKind::Unorm8
                    || v.no_data_total() > 0,
                "R8 UNORM must filter linearly (Vulkan requires it)"
            );
            let reference = naive.get_or_insert_with(|| {
                filters
                    .iter()
                    .map(|&filter| {
                        views
                            .iter()
                            .map(|view| self.frame(&Structure::naive(), &p, view, filter))
                            .collect()
                    })
                    .collect()
            });
            for accel in Accel::skipping().filter(|a| a.name() != "auto") {
                for params in parameter_sets(accel, g) {
                    let s = self.build(&p, accel, &params);
                    // Cost-driven leaves may make a tree one leaf where the
                    // measured model prices that cheaper: it says so.
                    let collapsed = params.switch("collapse").unwrap_or(false);
                    own_kernels += usize::from(check_kernel(
                        what,
                        &s,
                        &p.mode,
                        if collapsed { Kernels::Reported } else { kernels },
                    ));
                    for (filter, naive) in filters.iter().zip(reference.iter()) {
                        for (i, view) in views.iter().enumerate() {
                            let f = self.frame(&s, &p, view, *filter);
                            let d = diff(&naive[i], &f).unwrap();
                            assert!(d.differing == 0, "{what}, view {i}, {accel} ({params}), {filter}: {d}");
                            assert!(
                                f.pixels.iter().all(|px| px.iter().all(|c| c.is_finite())),
                                "{what}: non-finite pixel"
                            );
                        }
                    }
                }
            }
        }
        // Even where a structure may fall back, some skipping kernel ran:
        // equality with naive would prove nothing otherwise (unless no
        // structure skips in the mode: average).
        let mode = *views[0].mode();
        if Accel::skipping().any(|a| a.method().marches(&mode)) {
            assert!(own_kernels > 0, "{what}: no structure marched with its own kernel");
        }
        assert_clean(&self.ctx);
        naive.and_then(|n| n.into_iter().next()).unwrap()
    }

    /// Every structure at its defaults; each marches with its own kernel.
    pub fn check(&self, what: &str, v: &Volume, tf: &TransferFunction, views: &[FrameDesc]) -> Vec<Frame> {
        self.check_with(what, v, tf, views, &[DEFAULTS], Kernels::Own)
    }

    /// As `check`, for dense or tiny data where a tree may be one leaf
    /// covering the volume (marched naively, and saying so).
    pub fn check_dense(&self, what: &str, v: &Volume, tf: &TransferFunction, views: &[FrameDesc]) -> Vec<Frame> {
        self.check_with(what, v, tf, views, &[DEFAULTS], Kernels::Reported)
    }
}

/// What marched `s` (the renderer dispatches the kernel of
/// `s.marched_as()`): its own kernel, the structure it chose (`auto`), the
/// naive kernel in a mode the structure does not skip in (`Method::marches`
/// says which), or, under `Reported` only, the naive kernel where its build
/// found nothing to skip, saying so. Returns whether its own kernel marched.
pub fn check_kernel(what: &str, s: &Structure, mode: &Mode, kernels: Kernels) -> bool {
    match s.marched_as_reason() {
        None => true,
        Some(m) => {
            let fallback = m.kind == MarchedKind::ModeFallback && !s.accel().method().marches(mode);
            assert!(
                m.kind == MarchedKind::Choice || fallback || kernels == Kernels::Reported,
                "{what}: {} marched as {} ({}) where its own kernel should have",
                s.accel(),
                m.label,
                m.reason
            );
            false
        }
    }
}

/// Every look: composite unshaded and shaded, MIP, MinIP, average, iso.
pub fn every_look() -> Vec<(Mode, Option<lacuna::render::Shading>)> {
    vec![
        (Mode::Composite, None),
        (Mode::Composite, Some(lacuna::render::Shading::default())),
        (Mode::Mip, None),
        (Mode::MinIp, None),
        (Mode::Average, None),
        (Mode::Iso(lacuna::render::Iso::new(&[0.4]).unwrap()), None),
    ]
}

pub fn cam(size: u32, az: f64, el: f64, projection: Projection, step: f32) -> FrameDesc {
    hard::cam(size, az, el, projection, step, None).unwrap()
}

pub fn standard_views() -> Vec<FrameDesc> {
    let persp = Projection::Perspective {
        fov_deg: 50.0,
        distance: None,
    };
    vec![
        cam(48, 30.0, 20.0, Projection::Orthographic, 0.5),
        cam(40, 0.0, 0.0, Projection::Orthographic, 0.5),
        cam(40, 90.0, 0.0, Projection::Orthographic, 1.0),
        cam(40, 0.0, 90.0, Projection::Orthographic, 0.5),
        cam(40, 45.0, 35.264389682754654, Projection::Orthographic, 0.37),
        cam(40, -140.0, -25.0, persp, 0.5),
        cam(
            40,
            200.0,
            10.0,
            Projection::Perspective {
                fov_deg: 80.0,
                distance: Some(0.3),
            },
            0.5,
        ),
    ]
}

/// Rays exactly through brick faces, edges and corners, and grazing the
/// volume's faces.
pub fn lattice_views() -> Vec<FrameDesc> {
    vec![
        hard::along_z_through_brick_faces().unwrap(),
        // Along -x, grazing the y = 0 and y = 32 faces.
        lattice(
            33,
            [40.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [-1.0, 0.0, 0.0],
            1.0,
        )
        .unwrap(),
        // Diagonals through brick corners (8k, 8k, 8k).
        lattice(
            17,
            [-4.0, -4.0, -4.0],
            [2.0, -2.0, 0.0],
            [1.0, 1.0, -2.0],
            [1.0, 1.0, 1.0],
            0.5,
        )
        .unwrap(),
        // In the plane x = 8 (a brick face), diagonal in y-z.
        lattice(
            33,
            [8.0, -3.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 1.0],
            0.5,
        )
        .unwrap(),
    ]
}
