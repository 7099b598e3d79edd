//! `--accel auto`: a distance map on sparse data (octant maps on small
//! grids, the cube map on large ones), naive marching on dense data, the
//! choice re-made on a TF change, and the image of every choice equal to
//! naive's (the identity tests cover auto with every other entry).

mod common;
use common::{assert_clean, gpu};
use lacuna::accel::{auto, BuildInput, Builder, Structure};
use lacuna::frame::diff;
use lacuna::render::Mode;
use lacuna::render::{FrameDesc, Renderer};
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::{TransferFunction, Volume};

fn load(spec: &str) -> Volume {
    Volume::load(spec, &LoadOptions::default()).unwrap()
}

fn build(builder: &Builder, v: &Volume, gv: &GpuVolume, tf: &TransferFunction, cell: u32) -> Structure {
    let lut = tf.upload(builder.context()).unwrap();
    let auto = common::accel("auto");
    let params = auto.params(&[("cell", &cell.to_string())]).unwrap();
    let (ranges, _) = builder.ranges_for(&[(auto, &params)], gv).unwrap();
    let input = BuildInput {
        volume: v,
        gpu_volume: gv,
        tf,
        gpu_tf: &lut,
        mode: Mode::Composite,
    };
    builder.build(auto, &input, &ranges, &params).unwrap().0
}

#[test]
fn sparse_data_gets_the_distance_map_and_dense_data_naive_marching() {
    let ctx = gpu();
    let builder = Builder::new(&ctx).unwrap();
    let renderer = Renderer::new(&ctx).unwrap();
    let desc = FrameDesc::builder(64, 64).build().unwrap();
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
        let choice = &s.built_as::<auto::Chosen>().expect("auto's build is its choice").choice;
        // Frames are marched with the chosen structure's kernel.
        assert_eq!(s.marched_as().name(), expect, "{}: {}", tf.spec, choice.reason());
        assert_eq!(choice.accel, s.marched_as());
        assert_eq!(s.march().shader.name, choice.accel.method().march().shader.name);
        let reported = s.marched_as_reason().expect("auto says what it chose");
        assert_eq!(reported.label, choice.describe());
        assert_eq!(reported.reason, choice.reason());
        assert!(choice.predicted.is_finite() && choice.predicted > 0.0);
        if expect == "naive" {
            assert_eq!(choice.summary.active, choice.summary.cells);
            assert!(choice.predicted >= 1.0);
        } else {
            assert!(choice.summary.active_fraction() < 0.5, "{}", choice.reason());
            assert_eq!(choice.describe(), format!("{expect} (cell {cell})"));
        }
        let lut = tf.upload(&ctx).unwrap();
        let frame = common::frame(&renderer, &s, &gv, &lut, &desc);
        let naive = common::frame(&renderer, &Structure::naive(), &gv, &lut, &desc);
        assert_eq!(diff(&naive, &frame).unwrap().differing, 0, "{}", tf.spec);
        assert!(
            frame.pixels.iter().any(|p| p[3] > 0.0),
            "{}: something visible",
            tf.spec
        );
    }
    assert_clean(&ctx);
}
