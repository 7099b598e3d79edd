//! The embedding example (`examples/embed`) as a test: a host engine with its
//! own instance, device and queue rasterizes a cube, then records lacuna's
//! build (grid, and the LBVH) and render into the same command buffer. Where the cube is, the
//! frame shows the cube and none of the volume behind it; everywhere else it
//! equals lacuna's own render of the same camera bit for bit; validation
//! (with synchronization validation) reports nothing.

use crate::common;
#[path = "../../examples/embed/engine.rs"]
mod engine;
use crate::host;

use crate::common::{assert_clean, gpu};
use lacuna::accel::{BuildInput, Builder};
use lacuna::render::Mode;
use lacuna::render::Octants;
use lacuna::render::{Camera, Filter, FrameDesc, Renderer, Scene};
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::{TransferFunction, Volume};

#[test]
fn the_engines_cube_occludes_the_volume_and_the_rest_is_lacunas_render() {
    // The grid, and the LBVH whose recorded build has no CPU round trip.
    for accel in ["grid", "lbvh"] {
        occludes_with(accel);
    }
}

fn occludes_with(accel: &str) {
    let settings = engine::Settings {
        size: 96,
        validate: true,
        accel: accel.into(),
        ..engine::Settings::default()
    };
    let r = engine::run(&settings).unwrap();
    assert!(r.validation.is_empty(), "{}", r.validation.join("\n"));
    // Nothing submitted behind the engine's back: creating lacuna's
    // objects, uploading, building and marching were only recorded.
    assert_eq!(
        r.lacuna_submissions, 0,
        "{accel}: lacuna submitted on the engine's queue"
    );
    assert!(r.timings.phase("march").is_ok());

    // lacuna's own render (its own context, naive marching) of the same camera.
    let ctx = gpu();
    let volume = Volume::load(&settings.volume, &LoadOptions::default()).unwrap();
    let tf = TransferFunction::parse(volume.default_tf.as_deref().unwrap()).unwrap();
    let gv = GpuVolume::upload(&ctx, &volume).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let builder = Builder::new(&ctx).unwrap();
    let (ranges, _) = builder.ranges(&[], &gv).unwrap();
    let input = BuildInput {
        volume: &volume,
        gpu_volume: &gv,
        tf: &tf,
        gpu_tf: &lut,
        mode: Mode::Composite,
        frames: &[],
        octants: Octants::ALL,
    };
    let naive_accel = common::accel("naive");
    let naive = builder
        .build(naive_accel, &input, &ranges, &naive_accel.defaults())
        .unwrap()
        .0;
    let size = settings.size;
    let m = settings.camera.matrices(gv.dims(), gv.spacing(), size, size).unwrap();
    let view = FrameDesc::builder(size, size)
        .camera(Camera::Matrices(m))
        .filter(Filter::Manual)
        .build()
        .unwrap();
    let scene = Scene {
        structure: &naive,
        volume: &gv,
        tf: &lut,
    };
    let (own, _) = Renderer::new(&ctx).unwrap().render(scene, &view).unwrap();
    assert_clean(&ctx);

    let bits = |p: &[f32; 4]| p.map(f32::to_bits);
    let (mut covered, mut hidden, mut open) = (0, 0, 0);
    for i in 0..r.depth.len() {
        let (c, own) = (&r.composite.pixels[i], &own.pixels[i]);
        if r.depth[i] < 1.0 {
            // The cube is drawn here: the frame shows the cube, nothing of the volume.
            covered += 1;
            assert_eq!(
                r.volume.pixels[i], [0.0; 4],
                "{accel} pixel {i}: volume in front of the cube"
            );
            assert_eq!(bits(c), bits(&r.mesh.pixels[i]), "pixel {i}");
            assert_eq!(c[3], 1.0);
            hidden += usize::from(own[3] > 0.1);
        } else {
            open += usize::from(own[3] > 0.1);
            assert_eq!(bits(c), bits(own), "{accel} pixel {i}: not lacuna's own render");
        }
    }
    // The test means something: the cube hides volume that is there, and
    // the volume shows around it.
    assert!(
        covered > 200 && hidden > 100 && open > 1000,
        "{accel}: {covered} {hidden} {open}"
    );
}
