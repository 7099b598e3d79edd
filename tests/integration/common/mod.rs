//! Shared test helpers: every GPU context runs with validation and
//! synchronization validation, and tests fail on any message.
#![allow(dead_code)]

pub mod identity;

use lacuna::accel::{Accel, BuildInput, Builder, Params, Structure};
use lacuna::frame::Frame;
use lacuna::gpu::{Context, ContextOptions};
use lacuna::render::Octants;
use lacuna::render::{FrameDesc, Renderer, Scene};
use lacuna::volume::GpuVolume;
use lacuna::{TransferFunction, Volume};
use std::path::Path;
use std::process::Command;
use std::sync::Mutex;

/// A fresh validated context (LACUNA_DEVICE still selects the device), for
/// tests about contexts themselves; others take one from the pool (`gpu`).
pub fn fresh_gpu() -> Context {
    Context::new(&ContextOptions {
        validation: true,
        device: None,
    })
    .expect("validated Vulkan context (lavapipe + vulkan-validationlayers)")
}

/// Validated contexts that tests have given back: the kernels a context
/// made stay in it, so the next test's identical kernels cost no compile.
static POOL: Mutex<Vec<Context>> = Mutex::new(Vec::new());

/// A validated context lent to one test at a time, so the validation
/// messages it collects are that test's. Given back when dropped, if the
/// test left no message in it; a test that panicked drops its context.
pub struct Gpu(Option<Context>);

/// A context from the pool, or a fresh one when every pooled one is lent.
pub fn gpu() -> Gpu {
    let pooled = POOL.lock().unwrap_or_else(|p| p.into_inner()).pop();
    Gpu(Some(pooled.unwrap_or_else(fresh_gpu)))
}

impl std::ops::Deref for Gpu {
    type Target = Context;
    fn deref(&self) -> &Context {
        self.0.as_ref().expect("lent until dropped")
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        let Some(ctx) = self.0.take() else { return };
        if std::thread::panicking() {
            return;
        }
        assert_clean(&ctx);
        // A clone still held (a renderer outliving its guard) could record
        // while another test holds the context: such a context is dropped.
        if ctx.handle_count() == 1 {
            POOL.lock().unwrap_or_else(|p| p.into_inner()).push(ctx);
        }
    }
}

/// Panics with every validation message collected so far.
pub fn assert_clean(ctx: &Context) {
    let messages = ctx.take_validation_messages();
    assert!(
        messages.is_empty(),
        "{} validation message(s):\n{}",
        messages.len(),
        messages.iter().map(|m| m.to_string()).collect::<Vec<_>>().join("\n")
    );
}

/// Renders on the GPU with validation, asserting no validation message.
pub fn render(ctx: &Context, volume: &Volume, tf: &TransferFunction, desc: &FrameDesc, accel: Accel) -> Frame {
    render_with(ctx, volume, tf, desc, accel, &accel.defaults())
}

/// As `render`, with the structure's parameters.
pub fn render_with(
    ctx: &Context,
    volume: &Volume,
    tf: &TransferFunction,
    desc: &FrameDesc,
    accel: Accel,
    params: &Params,
) -> Frame {
    let frame = try_render_with(ctx, volume, tf, desc, accel, params).unwrap();
    assert_clean(ctx);
    frame
}

/// As `render_with`, the frame's error returned (a frame the renderer
/// refuses); only setting the scene up may panic.
pub fn try_render_with(
    ctx: &Context,
    volume: &Volume,
    tf: &TransferFunction,
    desc: &FrameDesc,
    accel: Accel,
    params: &Params,
) -> lacuna::Result<Frame> {
    let renderer = Renderer::new(ctx).unwrap();
    let mut gv = GpuVolume::upload(ctx, volume).unwrap();
    gv.prepare(volume, desc.lighting().is_some(), desc.filter()).unwrap();
    let lut = tf.upload(ctx).unwrap();
    let builder = builder(ctx);
    let (ranges, _) = builder.ranges_for(&[(accel, params)], &gv).unwrap();
    let input = BuildInput {
        volume,
        gpu_volume: &gv,
        tf,
        gpu_tf: &lut,
        mode: *desc.mode(),
        frames: &[],
        octants: Octants::ALL,
    };
    let (structure, _) = builder.build(accel, &input, &ranges, params).unwrap();
    let scene = Scene {
        structure: &structure,
        volume: &gv,
        tf: &lut,
    };
    renderer.render(scene, desc).map(|(frame, _)| frame)
}

/// Renders `structure` (built for `lut` over `gv`) with `desc`.
pub fn frame(
    renderer: &Renderer,
    structure: &Structure,
    gv: &GpuVolume,
    lut: &lacuna::tf::GpuTransferFunction,
    desc: &FrameDesc,
) -> Frame {
    let scene = Scene {
        structure,
        volume: gv,
        tf: lut,
    };
    renderer.render(scene, desc).unwrap().0
}

/// A builder whose auto prices candidates with nominal constants (what is
/// tested of auto's choice is in tests/integration/auto.rs; elsewhere only that it is
/// exact).
pub fn builder(ctx: &Context) -> Builder {
    let b = Builder::new(ctx).unwrap();
    b.set_kernel_costs(Some(lacuna::accel::auto::KernelCost::NOMINAL))
        .unwrap();
    b
}

/// Per-channel max abs difference.
pub fn max_abs(a: &Frame, b: &Frame) -> f64 {
    lacuna::frame::diff(a, b).unwrap().max_abs
}

/// The registry entry named `name`.
pub fn accel(name: &str) -> Accel {
    name.parse().unwrap()
}

/// What a run of the `lacuna` binary printed and returned.
pub struct Run {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

pub fn lacuna(args: &[&str], env: &[(&str, &str)]) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_lacuna"));
    cmd.args(args);
    // auto's measured kernel constants, shared by every test's runs (the
    // first run of a kind measures them) and kept out of the user's cache.
    cmd.env(
        "XDG_CACHE_HOME",
        Path::new(env!("CARGO_TARGET_TMPDIR")).join("xdg-cache"),
    );
    for (k, v) in env {
        cmd.env(k, v);
    }
    let out = cmd.output().unwrap();
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into(),
        stderr: String::from_utf8_lossy(&out.stderr).into(),
    }
}

/// Renders `spec` at a small size with validation on; panics on failure.
pub fn render_ok(spec: &str, out: &Path, extra: &[&str]) -> Run {
    render_ok_with(spec, out, extra, &[])
}

/// `render_ok` with `env` set for the process.
pub fn render_ok_with(spec: &str, out: &Path, extra: &[&str], env: &[(&str, &str)]) -> Run {
    let mut args = vec![
        "render",
        spec,
        "--size",
        "40x32",
        "--validate",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let r = lacuna(&args, env);
    assert_eq!(r.code, 0, "stdout: {}\nstderr: {}", r.stdout, r.stderr);
    r
}

/// Asserts a one-line `error:` on stderr naming `needle`, a non-zero exit,
/// and that no output file (or temporary) was created.
pub fn fails(args: &[&str], env: &[(&str, &str)], needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let mut all: Vec<&str> = args.to_vec();
    let out_s = out.to_str().unwrap().to_string();
    if args[0] == "render" {
        all.extend(["--out", &out_s, "--validate"]);
    }
    let r = lacuna(&all, env);
    assert_ne!(r.code, 0, "{all:?} succeeded: {}", r.stdout);
    let lines: Vec<&str> = r.stderr.trim().lines().collect();
    assert_eq!(lines.len(), 1, "{all:?}: expected one line, got:\n{}", r.stderr);
    assert!(lines[0].contains(needle), "{all:?}: '{}' lacks '{needle}'", lines[0]);
    assert!(!r.stderr.contains("panicked"));
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        0,
        "{all:?} left a file behind"
    );
}

/// `spec`'s volume as float32 with voxels without data (`bench::hard::masked`:
/// NaN in a central ball, +inf and -inf on two planes), with the
/// generator's default TF.
pub fn masked(spec: &str) -> Volume {
    let mut m = lacuna::bench::hard::masked(spec).unwrap();
    m.default_tf = Volume::load(spec, &Default::default()).unwrap().default_tf;
    m
}

/// `values` as voxels of `ty` (spread over the type's range: signed types
/// shifted below zero, wide types scaled), little- or big-endian.
pub fn encode(values: &[f64], ty: lacuna::volume::VoxelType, little: bool) -> Vec<u8> {
    use lacuna::volume::VoxelType;
    let mut out = Vec::new();
    for &v in values {
        let mut b: Vec<u8> = match ty {
            VoxelType::U8 => vec![v as u8],
            VoxelType::I8 => vec![(v as i64 - 100) as i8 as u8],
            VoxelType::U16 => (v as u16 * 300).to_le_bytes().to_vec(),
            VoxelType::I16 => ((v as i16 - 100) * 300).to_le_bytes().to_vec(),
            VoxelType::U32 => (v as u32 * 70000).to_le_bytes().to_vec(),
            VoxelType::I32 => ((v as i32 - 100) * 70000).to_le_bytes().to_vec(),
            VoxelType::F32 => ((v as f32) * 0.25 - 3.0).to_le_bytes().to_vec(),
            VoxelType::F64 => (v * 0.25 - 3.0).to_le_bytes().to_vec(),
        };
        if !little {
            b.reverse();
        }
        out.extend(b);
    }
    out
}

/// `bytes` gzip-compressed.
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

/// A NIfTI-1 single file (.nii) of `datatype`, written by hand: `dims`
/// x, y, z and, when given, time (its rank is their count).
pub fn nifti_bytes(dims: &[u32], datatype: i16, bitpix: i16, pixdim: [f32; 3], data: &[u8]) -> Vec<u8> {
    let mut h = vec![0u8; 352];
    h[0..4].copy_from_slice(&348i32.to_le_bytes());
    let mut dim = [1i16; 8];
    dim[0] = dims.len() as i16;
    for (i, d) in dims.iter().enumerate() {
        dim[i + 1] = *d as i16;
    }
    for (i, d) in dim.iter().enumerate() {
        h[40 + 2 * i..42 + 2 * i].copy_from_slice(&d.to_le_bytes());
    }
    h[70..72].copy_from_slice(&datatype.to_le_bytes());
    h[72..74].copy_from_slice(&bitpix.to_le_bytes());
    let pd = [1.0f32, pixdim[0], pixdim[1], pixdim[2], 1.0, 1.0, 1.0, 1.0];
    for (i, p) in pd.iter().enumerate() {
        h[76 + 4 * i..80 + 4 * i].copy_from_slice(&p.to_le_bytes());
    }
    h[108..112].copy_from_slice(&352f32.to_le_bytes());
    h[112..116].copy_from_slice(&1f32.to_le_bytes());
    h[344..348].copy_from_slice(b"n+1\0");
    h.extend_from_slice(data);
    h
}
