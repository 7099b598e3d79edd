//! `--accel auto`: a distance map on sparse data (octant maps on small
//! grids, the cube map on large ones), naive marching on dense data, the
//! choice re-made on a TF change, and the image of every choice equal to
//! naive's (the identity tests cover auto with every other entry).

mod common;
use common::{assert_clean, gpu};
use lacuna::accel::{auto, Accel, BuildInput, BuildOptions, Builder, Structure};
use lacuna::frame::diff;
use lacuna::render::{RenderSettings, Renderer};
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::{TransferFunction, Volume};

fn load(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

fn build(builder: &Builder, v: &Volume, gv: &GpuVolume, tf: &TransferFunction, cell: u32) -> Structure {
    let lut = tf.upload(builder.context()).unwrap();
    let options = BuildOptions {
        cell,
        ..Default::default()
    };
    let (ranges, _) = builder.ranges(gv, options.cell).unwrap();
    let input = BuildInput {
        volume: v,
        gpu_volume: gv,
        tf,
        gpu_tf: &lut,
    };
    builder
        .build(common::accel("auto"), &input, &ranges, &options)
        .unwrap()
        .0
}

#[test]
fn sparse_data_gets_the_distance_map_and_dense_data_naive_marching() {
    let ctx = gpu();
    let builder = Builder::new(&ctx).unwrap();
    let renderer = Renderer::new(&ctx).unwrap();
    let settings = RenderSettings {
        width: 64,
        height: 64,
        ..Default::default()
    };
    let v = load("nbody:64");
    let gv = GpuVolume::upload(&ctx, &v).unwrap();
    let sparse = TransferFunction::parse("ramp:0.3:1").unwrap();
    // Every voxel visible: no empty cell, nothing to skip.
    let dense = TransferFunction::parse("band:0:1").unwrap();
    // nbody:64 has 16^3 cells of 4 voxels (octant maps) and 32^3 of 2 (the
    // cube map: auto::OCTANT_CELLS).
    assert!(16u64.pow(3) < auto::OCTANT_CELLS && 32u64.pow(3) >= auto::OCTANT_CELLS);
    let cases = [
        (&sparse, 4, "distance-octant"),
        (&dense, 4, "naive"),
        (&sparse, 4, "distance-octant"),
        (&sparse, 2, "distance"),
        (&dense, 2, "naive"),
    ];
    for (tf, cell, expect) in cases {
        let s = build(&builder, &v, &gv, tf, cell);
        let choice = s.choice().expect("auto reports its choice");
        assert_eq!(s.accel().name(), expect, "{}: {}", tf.spec, choice.reason());
        assert_eq!(choice.accel, s.accel());
        assert!(choice.predicted.is_finite() && choice.predicted > 0.0);
        if expect == "naive" {
            assert_eq!(choice.summary.active, choice.summary.cells);
            assert!(choice.predicted >= 1.0);
        } else {
            assert!(choice.summary.active_fraction() < 0.5, "{}", choice.reason());
            assert_eq!(choice.describe(), format!("{expect} (cell {cell})"));
        }
        let lut = tf.upload(&ctx).unwrap();
        let (frame, _) = renderer.render(&s, &gv, &lut, &settings).unwrap();
        let (naive, _) = renderer.render(&Structure::naive(), &gv, &lut, &settings).unwrap();
        assert_eq!(diff(&naive, &frame).unwrap().differing, 0, "{}", tf.spec);
        assert!(
            frame.pixels.iter().any(|p| p[3] > 0.0),
            "{}: something visible",
            tf.spec
        );
    }
    assert!(Accel::ALL.iter().any(|a| a.name() == "auto"));
    assert_clean(&ctx);
}
