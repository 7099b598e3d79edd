//! `--accel auto`: the structure for this volume and transfer function,
//! chosen without a trial render. It builds the cube distance map (the
//! candidate itself), reads its summary (active fraction, the mean
//! distances of empty and active cells, the active-empty faces), predicts the
//! frame time of the distance march against naive marching with the
//! device's measured cost model, and keeps the map (replaced by the octant
//! map on grids of fewer than [`OCTANT_CELLS`] cells) or drops to naive.
//! Re-made on every build, i.e. every transfer-function change. The model is
//! documented in `docs/structures.md`.

use super::builder::{Builder, RangeKind, Ranges};
use super::cost::{self, CostModel};
use super::distance::{self, DistanceKernels, DistanceMap, DistanceMethod, Summary};
use super::method::{Accel, BuildInput, Built, March, MarchedAs, MarchedKind, Method};
use super::naive::{NoData, NAIVE};
use super::params::{self, Param, Params, Value};
use super::stats::Stats;
use crate::error::Result;
use crate::gpu::{Bound, Timer, Timings};

/// The cell edge auto plans with when `--cell` is not given: the finest
/// cell whose map rebuild stays cheap (`docs/results/distance.md`).
pub const CELL: u32 = 4;

/// Grids of fewer cells than this (32^3) get octant maps, which march
/// faster (their boxes reach further ahead) but whose transform costs
/// several times the cube map's, growing past a quarter of a frame from
/// here on lavapipe (`docs/results/auto.md`); larger grids get the cube map.
pub const OCTANT_CELLS: u64 = 1 << 15;

/// Predicted distance-march time over naive time above which auto marches naively.
pub const THRESHOLD: f64 = 1.0;

const CUBE: Accel = Accel(&DistanceMethod { octants: false });
const OCTANT: Accel = Accel(&DistanceMethod { octants: true });

/// What auto chose and why.
#[derive(Clone, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct Choice {
    /// The structure the frames are marched with.
    pub accel: Accel,
    pub cell: u32,
    /// The distance march's predicted frame time over naive's.
    pub predicted: f64,
    pub summary: Summary,
    pub model: CostModel,
}

impl Choice {
    /// `distance-octant (cell 4)`, `distance (cell 4)` or `naive`.
    pub fn describe(&self) -> String {
        if self.accel == NAIVE {
            NAIVE.name().into()
        } else {
            format!("{} (cell {})", self.accel, self.cell)
        }
    }

    /// One line with the statistics behind the choice.
    pub fn reason(&self) -> String {
        let s = &self.summary;
        format!(
            "active cells {:.2} %, faces per active cell {:.2}, mean distance empty {:.2} active {:.2} cells; predicted distance/naive {:.3}",
            100.0 * s.active_fraction(),
            s.faces as f64 / s.active.max(1) as f64,
            s.empty_distance,
            s.active_distance,
            self.predicted
        )
    }
}

/// The predicted frame time of the distance march over naive marching's, at
/// the renderer's default step. Per cell of ray length, naive takes
/// `cell / step` samples; the distance march takes those of the active
/// fraction plus one walk step per box, a box spanning about its cell's
/// distance in cells: `(1 - a) / d_empty + a / d_active` steps per cell.
pub fn predict(s: &Summary, cell: u32, model: &CostModel) -> f64 {
    let a = s.active_fraction();
    let steps_per_cell = (1.0 - a) / s.empty_distance.max(1.0) + a / s.active_distance.max(1.0);
    let samples_per_cell = cell as f64 / cost::STEP as f64;
    // A walk step costs a traversal step and a region entry (span + skip).
    let walk = model.step_ns + model.entry_ns;
    a + steps_per_cell * walk / (samples_per_cell * model.sample_ns)
}

/// The built structure and the choice behind it
/// (`Structure::built_as::<Chosen>()`).
pub struct Chosen {
    pub choice: Choice,
    inner: Box<dyn Built>,
}

impl Built for Chosen {
    fn bindings(&self) -> Vec<Bound<'_>> {
        self.inner.bindings()
    }
    fn push(&self) -> Vec<u8> {
        self.inner.push()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        self.inner.stats()
    }
    fn marched_as(&self) -> Option<MarchedAs> {
        Some(MarchedAs {
            accel: self.choice.accel,
            label: self.choice.describe(),
            reason: self.choice.reason(),
            kind: MarchedKind::Choice,
        })
    }
}

/// `--accel auto`.
pub struct AutoMethod;

impl Method for AutoMethod {
    fn name(&self) -> &'static str {
        "auto"
    }
    fn description(&self) -> &'static str {
        "chooses naive or a distance map for this volume and TF from the map's statistics and the device's cost model"
    }
    fn params(&self) -> &'static [Param] {
        const CELL_PARAM: Param = params::CELL.with_default(Value::Int(CELL));
        &[CELL_PARAM]
    }
    fn ranges(&self, p: &Params) -> Result<RangeKind> {
        Ok(RangeKind::Cells(p.int("cell")?))
    }
    /// The kernel of the cube map; frames use the chosen structure's
    /// (`Structure::marched_as`).
    fn march(&self) -> March {
        CUBE.method().march()
    }
    fn variants(&self) -> Result<Vec<(String, Params)>> {
        [CELL, 8]
            .into_iter()
            .map(|cell| {
                let p = Params::resolve(self.params(), &[("cell", &cell.to_string())])?;
                Ok((format!("auto cell {cell}"), p))
            })
            .collect()
    }
    /// Host-driven: the choice reads the map's summary back.
    fn recordable(&self) -> bool {
        false
    }
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        ranges: &Ranges,
        p: &Params,
    ) -> Result<(Box<dyn Built>, Timings)> {
        let ctx = builder.context();
        let model = builder.cost_model()?;
        let kernels = builder.shared::<DistanceKernels>()?;
        let cell = p.int("cell")?;
        let cells = ranges.cells(cell)?;
        let out = DistanceMap::summary_buffer(ctx)?;
        // Records a map, and the summary of the first one.
        let build_map = |octants: bool, summary: bool| -> Result<(DistanceMap, Timings)> {
            let mut timer = Timer::new(ctx, 8)?;
            let map = ctx.submit_and_wait(|cmd| {
                timer.reset(cmd);
                let map = distance::record(builder, cmd, Some(&mut timer), input, cells, octants)?;
                if summary {
                    map.record_summary(ctx, &kernels, cmd, Some(&mut timer), &out)?;
                }
                Ok(map)
            })?;
            Ok((map, timer.results()?))
        };
        // The model is calibrated on the cube map's statistics, so the
        // choice reads those; the octant map, never slower to march, is
        // built only once the map has won.
        let (cube, mut timings) = build_map(false, true)?;
        let (summary, predicted) = timings.cpu("choose", || -> Result<(Summary, f64)> {
            let summary = cube.read_summary(&out)?;
            Ok((summary, predict(&summary, cell, &model)))
        })?;
        let (accel, inner): (Accel, Box<dyn Built>) = if predicted >= THRESHOLD {
            (NAIVE, Box::new(NoData))
        } else if cells.total < OCTANT_CELLS {
            let (octant, octant_timings) = build_map(true, false)?;
            for (name, ms) in octant_timings.phases {
                timings.push(format!("octant {name}"), ms);
            }
            (OCTANT, Box::new(octant))
        } else {
            (CUBE, Box::new(cube))
        };
        let choice = Choice {
            accel,
            cell,
            predicted,
            summary,
            model,
        };
        Ok((Box::new(Chosen { choice, inner }), timings))
    }
}
