//! The registry is the one place a structure is added: every entry is
//! complete (name, kernel, variants) and is covered by the identity matrix,
//! the hard-case suite and both bench configs; and a structure written
//! outside the crate (a toy grid here) builds and renders through the same
//! Builder and Renderer with no other change.

mod common;
use common::{assert_clean, gpu};
use lacuna::accel::grid::{self, GridMethod};
use lacuna::accel::{
    Accel, BuildInput, BuildOptions, Builder, Built, Classifier, March, Method, RangeKind, Ranges, Structure, TABLE,
};
use lacuna::bench::{config, hard, BenchConfig};
use lacuna::frame::diff;
use lacuna::gpu::{vk, Timer};
use lacuna::render::{Camera, RenderSettings, Renderer};
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::{Result, TransferFunction, Volume};

#[test]
fn every_entry_is_complete_and_covered_everywhere() {
    let ctx = gpu();
    let renderer = Renderer::new(&ctx).unwrap();
    let mut names: Vec<&str> = TABLE.iter().map(|a| a.name()).collect();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), TABLE.len(), "registry names are unique");
    assert!(TABLE[0].is_naive());
    let hard = hard::structures();
    let configs = [
        BenchConfig::parse(config::QUICK, "quick").unwrap(),
        BenchConfig::parse(config::PAPER, "paper").unwrap(),
    ];
    for &accel in TABLE {
        let m = accel.method();
        assert_eq!(m.name().parse::<Accel>().unwrap(), accel);
        assert!(!m.description().is_empty(), "{accel}: description");
        assert!(!m.variants().is_empty(), "{accel}: variants");
        // Its march kernel exists for each filter and takes the four common bindings first.
        for filter in lacuna::render::Filter::ALL {
            let kernel = renderer.kernel(accel, filter).unwrap();
            assert!(kernel.local_size().iter().product::<u32>() > 0);
        }
        for c in &configs {
            assert!(
                c.structures.iter().any(|s| s.accel == accel.name()),
                "bench config {} lacks {accel}",
                c.name
            );
        }
        if !accel.is_naive() {
            // The identity tests and the hard suite iterate Accel::skipping().
            assert!(Accel::skipping().any(|a| a == accel));
            assert!(hard.iter().any(|(_, a, _)| *a == accel), "hard suite lacks {accel}");
        }
    }
    assert_clean(&ctx);
}

/// A structure defined outside the crate: the macro-cell grid with 32^3
/// cells under its own name, recorded into the caller's command buffer.
struct ToyGrid;

impl Method for ToyGrid {
    fn name(&self) -> &'static str {
        "toy-grid32"
    }
    fn description(&self) -> &'static str {
        "test-only: the macro-cell grid at 32^3 cells"
    }
    fn ranges(&self) -> RangeKind {
        RangeKind::Cells
    }
    fn params(&self, _: &BuildOptions) -> Vec<(&'static str, String)> {
        vec![("cell", "32".into())]
    }
    fn march(&self) -> March {
        GridMethod.march()
    }
    fn record_build(
        &self,
        builder: &Builder,
        cmd: vk::CommandBuffer,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        _: &BuildOptions,
    ) -> Result<Box<dyn Built>> {
        let classifier = builder.kernels::<Classifier>()?;
        let cells = ranges.cells(32)?;
        let g = grid::record(
            builder.context(),
            &classifier,
            cmd,
            timer,
            input.gpu_volume,
            cells,
            input.gpu_tf,
        )?;
        Ok(Box::new(g))
    }
}

#[test]
fn a_structure_outside_the_table_builds_records_and_renders_exactly() {
    let ctx = gpu();
    let toy = Accel(&ToyGrid);
    let volume = Volume::load("nbody:48", &LoadOptions::default()).unwrap();
    let tf = TransferFunction::parse(volume.default_tf.as_deref().unwrap()).unwrap();
    let gv = GpuVolume::upload(&ctx, &volume).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let builder = Builder::new(&ctx).unwrap();
    let (ranges, t) = builder.ranges_for(&[toy], &gv, 32).unwrap();
    assert!(t.get("cell ranges").is_some() && t.get("ranges").is_none(), "{t}");
    let input = BuildInput {
        volume: &volume,
        gpu_volume: &gv,
        tf: &tf,
        gpu_tf: &lut,
    };
    let options = BuildOptions {
        cell: 32,
        ..Default::default()
    };
    let (built, timings) = builder.build(toy, &input, &ranges, &options).unwrap();
    assert!(timings.get("classify").is_some());
    // The recorded form, into one command buffer of ours.
    let mut timer = Timer::new(&ctx, 2).unwrap();
    let recorded = ctx
        .submit_and_wait(|cmd| {
            timer.reset(cmd);
            builder.record_build(toy, cmd, Some(&mut timer), &input, &ranges, &options)
        })
        .unwrap();
    let renderer = Renderer::new(&ctx).unwrap();
    let settings = RenderSettings {
        width: 64,
        height: 48,
        camera: Camera {
            azimuth_deg: 25.0,
            elevation_deg: 15.0,
            ..Camera::default()
        },
        ..Default::default()
    };
    let (naive, _) = renderer.render(&Structure::naive(), &gv, &lut, &settings).unwrap();
    assert!(naive.pixels.iter().any(|p| p[3] > 0.0), "the view shows the volume");
    for s in [&built, &recorded] {
        let (f, _) = renderer.render(s, &gv, &lut, &settings).unwrap();
        assert_eq!(diff(&naive, &f).unwrap().differing, 0);
    }
    let stats = built.stats().unwrap().unwrap();
    assert_eq!(stats.total_bricks, 8, "2 x 2 x 2 cells of 32^3");
    // Host-driven entries say so instead of recording.
    let kd: Accel = "kd-cpu".parse().unwrap();
    assert!(!kd.method().recordable());
    let err = ctx
        .submit_and_wait(|cmd| builder.record_build(kd, cmd, Some(&mut timer), &input, &ranges, &options))
        .err()
        .unwrap();
    assert!(err.to_string().contains("kd-cpu is built by the host"), "{err}");
    assert_clean(&ctx);
}
