//! Cost-driven leaves: the measured cost model, and collapsed trees against
//! their CPU reference and their plain counterparts.

mod common;
use common::{assert_clean, gpu};
use lacuna::accel::cost::{self, FLOOR_NS};
use lacuna::accel::Builder;
use lacuna::render::RenderSettings;

#[test]
fn the_cost_model_is_measured_once_with_positive_finite_constants() {
    let ctx = gpu();
    let builder = Builder::new(&ctx).unwrap();
    let m = builder.cost_model().unwrap();
    for (name, v) in [("sample", m.sample_ns), ("step", m.step_ns), ("entry", m.entry_ns)] {
        assert!(v.is_finite() && v >= FLOOR_NS, "{name}_ns = {v}");
    }
    // Kept per builder: the second call returns the same constants.
    assert_eq!(builder.cost_model().unwrap(), m);
    // A brick leaf marches several samples, so it costs more than one.
    let (brick, _) = m.leaf([0; 3], [8; 3]);
    assert!(brick as f64 > m.sample_ns, "{m:?}");
    assert_clean(&ctx);
}

#[test]
fn the_collapse_plans_for_the_renderers_default_step() {
    assert_eq!(RenderSettings::default().step, cost::STEP);
}
