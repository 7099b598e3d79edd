//! The registry is the one place a structure is added: every entry is
//! complete and reachable from every listing that must name it (the bench
//! configs, `--help`, the README), parameters shared between structures
//! agree, and a structure written outside the crate (a toy here) is built,
//! recorded and rendered through the same Builder and Renderer with only
//! its own code: its `Method`, its parameters, its bindings.

use crate::common;
use crate::common::{assert_clean, gpu};
use lacuna::accel::params::{Param, Value};
use lacuna::accel::table::{params_for, shared_params};
use lacuna::accel::{Accel, BuildInput, Builder, Built, March, Method, Params, RangeKind, Ranges, Stats, TABLE};
use lacuna::bench::{config, BenchConfig};
use lacuna::frame::diff;
use lacuna::gpu::record::Access;
use lacuna::gpu::shaders::{self, march_grid};
use lacuna::gpu::{vk, Binding, Bound, Buffer, MemoryLocation, OptionalTimer, Recording, TexelBuffer, Timer};
use lacuna::render::Mode;
use lacuna::render::Octants;
use lacuna::render::{Filter, FrameDesc, Projection, Renderer, Scene};
use lacuna::volume::{GpuVolume, LoadOptions};
use lacuna::{Result, TransferFunction, Volume};

#[test]
fn every_entry_is_complete_and_named_wherever_structures_are_listed() {
    let ctx = gpu();
    let renderer = Renderer::new(&ctx).unwrap();
    let probe_volume = GpuVolume::upload(&ctx, &Volume::load("menger:9", &LoadOptions::default()).unwrap()).unwrap();
    let mut names: Vec<&str> = TABLE.iter().map(|a| a.name()).collect();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), TABLE.len(), "registry names are unique");
    assert!(TABLE[0].is_naive(), "naive comes first: the bench times it first");
    let configs = [
        BenchConfig::parse(config::QUICK, "quick").unwrap(),
        BenchConfig::parse(config::PAPER, "paper").unwrap(),
    ];
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    for &accel in TABLE {
        let m = accel.method();
        assert!(!m.description().is_empty(), "{accel}: description");
        // Its march kernel is created for each filter (the common bindings
        // are checked by name at creation).
        for filter in Filter::ALL {
            let desc = FrameDesc::builder(8, 8).filter(filter).build().unwrap();
            let kernel = renderer.kernel(m.march(), &desc, &probe_volume).unwrap();
            assert!(kernel.local_size().iter().product::<u32>() > 0);
        }
        // Every variant the exactness checks build is a valid parameter set.
        let variants = m.variants().unwrap();
        assert!(!variants.is_empty(), "{accel}: variants");
        for (label, params) in &variants {
            m.check(params).unwrap_or_else(|e| panic!("{label}: {e}"));
            m.ranges(params).unwrap();
        }
        for c in &configs {
            assert!(
                c.structures.iter().any(|s| s.accel == accel.name()),
                "bench config {} lacks {accel}",
                c.name
            );
        }
        assert!(readme.contains(&format!("`{accel}`")), "README names no `{accel}`");
    }
    assert_clean(&ctx);
}

#[test]
fn shared_parameters_agree_and_every_listing_takes_them() {
    let params = shared_params(TABLE).unwrap();
    // The flags the command line always had, each generated from a schema.
    for flag in ["cell", "kd", "max-leaf", "bins", "classify", "apron", "collapse"] {
        let p = params.iter().find(|p| p.param.name == flag).unwrap();
        assert!(p.help().contains(&p.param.values()), "{flag}: {}", p.help());
    }
    // `cell` has a default per structure, and its help lists them.
    let cell = params.iter().find(|p| p.param.name == "cell").unwrap();
    assert!(
        cell.help().contains("grid 16") && cell.help().contains("distance 8"),
        "{}",
        cell.help()
    );
    // Two structures declaring one name differently is refused by name.
    struct Clash;
    // SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
    unsafe impl Method for Clash {
        fn name(&self) -> &'static str {
            "clash"
        }
        fn description(&self) -> &'static str {
            "test-only: a cell that is a word"
        }
        fn params(&self) -> &'static [Param] {
            const P: &[Param] = &[Param::choice("cell", &["big", "small"], "big", "Cells")];
            P
        }
        fn ranges(&self, _: &Params) -> Result<RangeKind> {
            Ok(RangeKind::None)
        }
        fn march(&self) -> March {
            March::plain(shaders::MARCH_NAIVE)
        }
    }
    let err = shared_params(&[TABLE[2], Accel(&Clash)]).unwrap_err().to_string();
    assert!(err.contains("cell") && err.contains("clash"), "{err}");

    // The bench TOML takes every parameter (with `_` for `-`), applies each
    // to the structures that have it, and refuses a name no structure has.
    let toml = |extra: &str| {
        format!(
            "name = \"t\"\nsize = [8, 8]\nframes = 1\nwarmup = 1\nbuilds = 1\nstep = 0.5\nelevation = 0.0\n\
             [[dataset]]\nvolume = \"nbody:8\"\n[[structure]]\nlabel = \"s\"\naccel = \"kd-gpu\"\n{extra}"
        )
    };
    let c = BenchConfig::parse(&toml("max_leaf = 128\nbins = 8\ncollapse = true\ncell = 4"), "t").unwrap();
    let p = c.structures[0].resolve().unwrap().params;
    assert_eq!(p.get("max-leaf").unwrap(), Value::Int(128));
    assert_eq!(p.get("bins").unwrap(), Value::Int(8));
    assert_eq!(p.get("collapse").unwrap(), Value::Switch(true));
    assert!(p.get("cell").is_err(), "kd-gpu has no cell: it is another structure's");
    let err = BenchConfig::parse(&toml("cells = 4"), "t").unwrap_err().to_string();
    assert!(err.contains("cells") && err.contains("no structure has it"), "{err}");
    let err = BenchConfig::parse(&toml("bins = 1"), "t").unwrap_err().to_string();
    assert!(err.contains("bins") && err.contains("2..=64"), "{err}");
    // A value for another structure's parameter is checked too.
    let err = BenchConfig::parse(&toml("classify = \"all\""), "t")
        .unwrap_err()
        .to_string();
    assert!(err.contains("classify") && err.contains("range or voxel"), "{err}");
    // The library is strict: a structure refuses a name it does not have.
    let grid = TABLE.iter().find(|a| a.name() == "grid").unwrap();
    let err = grid.params(&[("max_leaf", "128")]).unwrap_err().to_string();
    assert!(err.contains("max_leaf") && err.contains("it has: cell"), "{err}");
    assert_eq!(params_for(*grid, &[("max-leaf", "128")]).unwrap(), grid.defaults());
    assert!(params_for(*grid, &[("kd", "bogus")]).is_err());
}

#[test]
fn the_command_line_lists_every_structure_and_parameter_from_the_table() {
    let r = common::lacuna(&["render", "--help"], &[]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    for a in TABLE {
        assert!(r.stdout.contains(a.name()), "--help lacks {a}");
        for p in a.method().params() {
            assert!(r.stdout.contains(&format!("--{}", p.name)), "--help lacks --{}", p.name);
        }
    }
}

/// A structure written outside the crate: a macro-cell grid whose every cell
/// is active (exact, and skipping nothing), recorded by its own code into
/// the caller's command buffer and marched by the grid kernel.
struct FullGrid;

/// Its one parameter, with a default of its own.
const EDGE: Param = Param::power_of_two("edge", 32, 4, 64, "Toy cell edge in voxels");

struct FullGridData {
    counts: [u32; 3],
    edge: u32,
    flags: TexelBuffer,
}

// SAFETY: `march` is the kernel its builds' `Built` bindings and push constants are made for.
unsafe impl Method for FullGrid {
    fn name(&self) -> &'static str {
        "toy-full-grid"
    }
    fn description(&self) -> &'static str {
        "test-only: a macro-cell grid with every cell active"
    }
    fn params(&self) -> &'static [Param] {
        &[EDGE]
    }
    fn ranges(&self, _: &Params) -> Result<RangeKind> {
        Ok(RangeKind::None)
    }
    fn march(&self) -> March {
        March::plain(shaders::MARCH_GRID)
    }
    /// The grid kernel reads value ranges in MIP and MinIP frames, which
    /// this toy does not build.
    fn marches(&self, mode: &Mode) -> bool {
        matches!(mode, Mode::Composite | Mode::Iso(_))
    }
    fn record_build(
        &self,
        builder: &Builder,
        cmd: Recording<'_>,
        mut timer: Option<&mut Timer>,
        input: &BuildInput,
        _: &Ranges,
        params: &Params,
    ) -> Result<Box<dyn Built>> {
        let edge = params.int("edge")?;
        let counts = input.gpu_volume.dims().map(|d| d.div_ceil(edge));
        let cells = counts.iter().map(|&c| c as u64).product::<u64>();
        // The grid kernel reads a cell's flag as a texel (R32UI).
        let usage = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let flags = Buffer::new(
            builder.context(),
            "toy flags",
            cells * 4,
            usage,
            MemoryLocation::GpuOnly,
        )?;
        let flags = TexelBuffer::new(builder.context(), flags, vk::Format::R32_UINT)?;
        let pass = timer.begin(cmd, "fill")?;
        unsafe {
            builder
                .context()
                .device()
                .cmd_fill_buffer(cmd.raw(), flags.buffer().raw(), 0, vk::WHOLE_SIZE, 1)
        };
        // ALL_TRANSFER, not CLEAR, as the source stage (see the README's validation notes).
        cmd.barrier(Access::TRANSFER_WRITE, Access::COMPUTE_READ);
        timer.end(cmd, pass);
        Ok(Box::new(FullGridData { counts, edge, flags }))
    }
}

// SAFETY: binds only buffers it owns, made and sized by its build for the kernel that marches it.
unsafe impl Built for FullGridData {
    fn bindings(&self) -> Vec<Bound<'_>> {
        march_grid::Own {
            cell_texels: Binding::TexelBuffer(self.flags.view()),
        }
        .list()
    }
    fn push(&self) -> Vec<u8> {
        let push = march_grid::Push {
            counts: self.counts,
            cell: self.edge,
        };
        bytemuck::bytes_of(&push).to_vec()
    }
    fn stats(&self) -> Result<Option<Stats>> {
        let cells = self.counts.iter().map(|&c| c as u64).product();
        Ok(Some(Stats {
            unit: "toy cells",
            total_bricks: cells,
            active_bricks: cells,
            nodes: cells,
            leaves: cells,
            height: 1,
            bytes: cells * 4,
        }))
    }
}

#[test]
fn a_structure_outside_the_table_builds_records_and_renders_exactly() {
    let ctx = gpu();
    let toy = Accel(&FullGrid);
    let volume = Volume::load("nbody:48", &LoadOptions::default()).unwrap();
    let tf = TransferFunction::parse(volume.default_tf.as_deref().unwrap()).unwrap();
    let gv = GpuVolume::upload(&ctx, &volume).unwrap();
    let lut = tf.upload(&ctx).unwrap();
    let builder = Builder::new(&ctx).unwrap();
    // Its parameters resolve like a built-in's: defaults, given values, checks.
    assert_eq!(toy.defaults().get("edge").unwrap(), Value::Int(32));
    let params = toy.params(&[("edge", "16")]).unwrap();
    assert!(toy.params(&[("cell", "4")]).is_err(), "not one of its parameters");
    assert_eq!(params.describe(), [("edge", "16".to_string())]);
    assert!(toy.params(&[("edge", "12")]).is_err());
    let (ranges, t) = builder.ranges_for(&[(toy, &params)], &gv).unwrap();
    assert!(t.phases.is_empty(), "it reads no ranges: {t}");
    let input = BuildInput {
        volume: &volume,
        gpu_volume: &gv,
        tf: &tf,
        gpu_tf: &lut,
        mode: Mode::Composite,
        frames: &[],
        octants: Octants::ALL,
    };
    // Submitted by the default `Method::build`, and recorded into ours.
    let (built, timings) = builder.build(toy, &input, &ranges, &params).unwrap();
    assert!(timings.get("fill").is_some(), "{timings}");
    let mut timer = Timer::new(&ctx, 2).unwrap();
    let recorded = ctx
        .submit_and_wait(|cmd| {
            timer.reset(cmd);
            builder.record_build(toy, cmd, Some(&mut timer), &input, &ranges, &params)
        })
        .unwrap();
    let renderer = Renderer::new(&ctx).unwrap();
    let desc = FrameDesc::builder(64, 48)
        .orbit(25.0, 15.0, Projection::Orthographic)
        .build()
        .unwrap();
    let frame = |s: &lacuna::accel::Structure| {
        let scene = Scene {
            structure: s,
            volume: &gv,
            tf: &lut,
        };
        renderer.render(scene, &desc).unwrap().0
    };
    let naive = frame(&lacuna::accel::Structure::naive());
    assert!(naive.pixels.iter().any(|p| p[3] > 0.0), "the view shows the volume");
    for s in [&built, &recorded] {
        assert_eq!(diff(&naive, &frame(s)).unwrap().differing, 0);
    }
    let stats = built.stats().unwrap().unwrap();
    assert_eq!(stats.total_bricks, 27, "3 x 3 x 3 cells of 16^3");
    assert!(built.built_as::<FullGridData>().is_some());
    // Host-driven entries say so instead of recording.
    let kd: Accel = "kd-cpu".parse().unwrap();
    assert!(!kd.method().recordable());
    let err = ctx
        .submit_and_wait(|cmd| builder.record_build(kd, cmd, Some(&mut timer), &input, &ranges, &kd.defaults()))
        .err()
        .unwrap();
    assert!(err.to_string().contains("kd-cpu is built by the host"), "{err}");
    assert_clean(&ctx);
}
