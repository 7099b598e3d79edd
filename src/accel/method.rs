//! The contract between lacuna and a skipping structure, knowing no
//! structure: the [`Method`] trait a structure implements, what a build
//! returns ([`Built`]), the handle [`Accel`] and a built [`Structure`]. The
//! table of lacuna's structures lives above them all (`table.rs`); a
//! structure written outside the crate implements [`Method`] and is used
//! through `Accel(&MyStructure)` exactly as the built-in ones.

use super::builder::{Builder, RangeKind, Ranges};
use super::params::{Param, Params};
use super::stats::Stats;
use crate::desc::{FrameDesc, Mode, Octants};
use crate::error::{Error, Result};
use crate::gpu::Recording;
use crate::gpu::{Bound, DeviceInfo, Shader, Timer, Timings};
use crate::tf::{GpuTransferFunction, TransferFunction};
use crate::volume::{GpuVolume, Volume};
use std::any::Any;

/// The march kernel that renders a structure: a shader of `glsl/march/`
/// and its specialization constants (constant_id 0, 1, ...).
#[derive(Clone, Copy, Debug)]
pub struct March {
    pub(crate) shader: Shader,
    pub(crate) constants: &'static [u32],
}

impl March {
    /// The kernel of `shader` with `constants` at constant_id 0, 1, ...
    ///
    /// # Safety
    /// As `Kernel::specialized`: the constants are values the shader was
    /// written to take there.
    pub const unsafe fn new(shader: Shader, constants: &'static [u32]) -> Self {
        March { shader, constants }
    }

    /// Its shader.
    pub fn shader(&self) -> Shader {
        self.shader
    }

    /// Its specialization constants (constant_id 0, 1, ...).
    pub fn constants(&self) -> &'static [u32] {
        self.constants
    }

    /// A kernel without specialization.
    pub const fn plain(shader: Shader) -> Self {
        March { shader, constants: &[] }
    }
}

/// What a build reads: the volume and transfer function on the host (for
/// host-built structures) and on the GPU, the mode of the frames it is
/// for (what "empty" means: `accel::mode`), optionally such frames
/// themselves (camera, step, early termination, filter, size), which `auto`
/// prices its candidates on, and the ray direction octants of the frames it
/// will serve (octant distance maps compute only those: `Octants::ALL`
/// where unknown).
#[derive(Clone, Copy)]
pub struct BuildInput<'a> {
    pub volume: &'a Volume,
    pub gpu_volume: &'a GpuVolume,
    pub tf: &'a TransferFunction,
    pub gpu_tf: &'a GpuTransferFunction,
    pub mode: Mode,
    /// The frames the structure will march (camera, size, step, early
    /// termination, filter, mode), each of a mode that classifies as `mode`
    /// does (else the build is an error); auto prices its candidates on up
    /// to four of them, evenly spread (`auto::choose::PRICED_VIEWS`).
    /// Empty: none named (auto prices on the default orbit at 512x512).
    pub frames: &'a [FrameDesc],
    /// The ray direction octants the frames marched with the structure
    /// will have (`FrameDesc::octants`). An octant map marches a frame with
    /// other octants exactly, cell by cell on those (`DistanceMap`).
    pub octants: Octants,
}

impl BuildInput<'_> {
    /// The grid and channel count a structure built from this is for.
    pub(crate) fn built_over(&self) -> ([u32; 3], u32) {
        (self.gpu_volume.dims, self.gpu_volume.channels)
    }

    /// The texels and the opacities a structure built from this skips for
    /// (None: naive, which skips nothing; no opacities: iso, whose values
    /// classify, not the TF).
    pub(crate) fn built_for(&self, accel: Accel) -> Option<(u64, Option<u64>)> {
        let alpha = (!matches!(self.mode, Mode::Iso(_))).then(|| self.gpu_tf.alpha_key());
        accel.method().skips().then(|| (self.gpu_volume.content_id(), alpha))
    }

    /// Its parts agree: made on `ctx` (the builder's), the transfer
    /// function classified on the host is the one uploaded, and holds the
    /// volume's channels.
    pub(crate) fn check(&self, ctx: &crate::gpu::Context) -> Result<()> {
        ctx.check_is(self.gpu_volume.context(), "volume")?;
        ctx.check_is(self.gpu_tf.context(), "transfer function")?;
        // Classification reads the opacities of the host's TF.
        if self.tf.alpha_key() != self.gpu_tf.alpha_key() {
            return Err(Error::invalid(
                "build input",
                self.tf.spec.clone(),
                "is not the transfer function gpu_tf was uploaded from: give both the same one",
            ));
        }
        // Host-side builds read the volume's voxels at the device's dims.
        self.volume.check()?;
        if self.volume.dims != self.gpu_volume.dims || self.volume.channel_count() as u32 != self.gpu_volume.channels {
            return Err(Error::invalid(
                "build input",
                self.volume.name.clone(),
                "is not the volume gpu_volume was uploaded from: give both the same one",
            ));
        }
        self.tf.check_channels(self.gpu_volume.channels as usize)
    }
}

/// When a built structure is marched by another entry's kernel: which, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct MarchedAs {
    /// The entry whose kernel (and, unless naive, whose built data) marches.
    pub accel: Accel,
    /// What it is, as printed: `distance-octant (cell 4)`, `naive`.
    pub label: String,
    /// One line on why.
    pub reason: String,
    pub kind: MarchedKind,
}

/// Why a structure is marched by another entry's kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MarchedKind {
    /// Choosing is what the structure does (`auto`).
    Choice,
    /// The build found nothing to skip (a tree that is one leaf covering
    /// the volume is marched by the naive kernel: the same samples, no
    /// traversal).
    NothingToSkip,
    /// The structure does not skip in the frame's mode (`Method::marches`):
    /// naive marching.
    ModeFallback,
}

/// A built structure: what its march kernel reads beyond the bindings
/// every march kernel has (`glsl/common/march.glsl`: the render parameters,
/// volume, LUT and frame, which the renderer binds).
///
/// # Safety
/// The renderer dispatches the march kernel with these bindings and push
/// constants as they are: every binding is a live object of the context
/// the structure was built on, of the type, usage and size the kernel
/// (`Method::march` of the entry that built it, or `marched_as`) reads
/// given `push`, and stays alive and unchanged while frames recorded with
/// it are pending. lacuna's own structures keep that by construction.
/// It is `Send + Sync` so a `Structure` can be built on a loader thread
/// and recorded from several (every binding is a Vulkan handle).
pub unsafe trait Built: Any + Send + Sync {
    /// The kernel's own bindings, by name (`shaders::march_NAME::Own::list`).
    fn bindings(&self) -> Vec<Bound<'_>>;
    /// The march kernel's push constants (empty for none).
    fn push(&self) -> Vec<u8> {
        Vec::new()
    }
    /// The paper's Table 1 statistics (None: nothing built). May read the
    /// structure back once.
    fn stats(&self) -> Result<Option<Stats>>;
    /// Set when another entry's kernel marches this structure: `auto`'s
    /// choice, or a tree that is one leaf covering the volume (marched by
    /// the naive kernel). None: the entry's own kernel (`Method::march`).
    fn marched_as(&self) -> Option<MarchedAs> {
        None
    }
    /// The ray direction octants it skips for (all but a partly built
    /// octant map: `BuildInput::octants`).
    fn octants(&self) -> Octants {
        Octants::ALL
    }
}

/// A skipping structure: its parameters, what it reads, how it is built,
/// how it is marched. Implement it in the structure's module and add one
/// line to the table (`table.rs`).
///
/// # Safety
/// `march` names the kernel that reads what `record_build` / `build`
/// return, and those obey `Built`'s contract for it.
pub unsafe trait Method: Sync {
    /// The CLI name (`--accel NAME`).
    fn name(&self) -> &'static str;
    /// One line for listings: what it is and who it is after.
    fn description(&self) -> &'static str;
    /// Its parameters (`params.rs`); the command line, the bench TOML,
    /// records and frame metadata list them from here.
    fn params(&self) -> &'static [Param] {
        &[]
    }
    /// Checks a combination of values the schema alone cannot (called by
    /// [`Accel::params`]).
    fn check(&self, params: &Params) -> Result<()> {
        let _ = params;
        Ok(())
    }
    /// The per-volume ranges its build reads with these parameters.
    fn ranges(&self, params: &Params) -> Result<RangeKind>;
    /// Whether its frames skip by what it was built for (a volume's
    /// texels, a transfer function): all but naive, which reads neither.
    fn skips(&self) -> bool {
        true
    }
    /// Every kind of ranges its build reads on `volume` and `info`'s device
    /// (default: `ranges`; a structure that builds others, `auto`, lists
    /// theirs).
    fn range_kinds(&self, params: &Params, volume: &GpuVolume, info: &DeviceInfo) -> Result<Vec<RangeKind>> {
        let _ = (volume, info);
        Ok(vec![self.ranges(params)?])
    }
    /// Its march kernel.
    fn march(&self) -> March;
    /// Whether `Builder::build` hands it the mode's classification (the
    /// activity function of `accel::mode` in place of the frame's TF in
    /// MIP, MinIP and iso frames; default). A structure that builds others
    /// through the builder (`auto`) says no and reads the frame's TF.
    fn classifies(&self) -> bool {
        true
    }
    /// Whether its kernel marches frames of `mode` skipping exactly
    /// (`accel::mode`); in other modes it is marched naively. Default:
    /// every mode but average, each classifying by its activity function.
    fn marches(&self, mode: &Mode) -> bool {
        !matches!(mode, Mode::Average)
    }
    /// The parameter sets the exactness checks (the identity tests and
    /// `bench --suite hard`) build it with: (label, values).
    fn variants(&self) -> Result<Vec<(String, Params)>> {
        Ok(vec![(self.name().to_string(), Params::defaults(self.params()))])
    }
    /// Whether `record_build` records the whole build into one command
    /// buffer. Host-driven builders (a CPU build, a readback, one submission
    /// per tree level) return false and implement `build` instead.
    fn recordable(&self) -> bool {
        true
    }
    /// Records the build for the input's transfer function into `cmd`,
    /// timing its passes with `timer`. Barriers: begins with the `prims`
    /// entry barrier (earlier compute and transfer writes visible) and ends
    /// with compute writes; order the march after it with a barrier from
    /// `Access::COMPUTE_WRITE` to `Access::COMPUTE_READ`.
    fn record_build(
        &self,
        builder: &Builder,
        cmd: Recording<'_>,
        timer: Option<&mut Timer>,
        input: &BuildInput,
        ranges: &Ranges,
        params: &Params,
    ) -> Result<Box<dyn Built>> {
        let _ = (builder, cmd, timer, input, ranges, params);
        Err(Error::Unsupported(format!(
            "{} is built by the host (it reads results back between passes): call build, not record_build",
            self.name()
        )))
    }
    /// Builds and waits: the path a transfer-function change takes. Returns
    /// the structure and the time of each phase. The default submits
    /// `record_build` once.
    fn build(
        &self,
        builder: &Builder,
        input: &BuildInput,
        ranges: &Ranges,
        params: &Params,
    ) -> Result<(Box<dyn Built>, Timings)> {
        submit_build(self, builder, input, ranges, params)
    }
}

/// `method`'s `record_build` submitted once and waited for, with its
/// passes' timings: `Method::build`'s default.
pub fn submit_build(
    method: &(impl Method + ?Sized),
    builder: &Builder,
    input: &BuildInput,
    ranges: &Ranges,
    params: &Params,
) -> Result<(Box<dyn Built>, Timings)> {
    let ctx = builder.context();
    let mut timer = Timer::new(ctx, 16)?;
    let built = ctx.submit_and_wait(|cmd| {
        timer.reset(cmd);
        method.record_build(builder, cmd, Some(&mut timer), input, ranges, params)
    })?;
    Ok((built, timer.results()?))
}

/// A handle to a structure: cheap to copy, compared by name.
#[derive(Clone, Copy)]
pub struct Accel(pub &'static dyn Method);

impl Accel {
    pub fn method(self) -> &'static dyn Method {
        self.0
    }

    pub fn name(self) -> &'static str {
        self.0.name()
    }

    /// Its parameters at their defaults, with `given` (name, text) values
    /// parsed in, and checked; a name it does not have is an error (for
    /// values given to every structure, as the command line's flags are,
    /// see `table::params_for`).
    pub fn params(self, given: &[(&str, &str)]) -> Result<Params> {
        let p = Params::resolve(self.0.params(), given)?;
        self.0.check(&p)?;
        Ok(p)
    }

    /// Its parameters at their defaults.
    pub fn defaults(self) -> Params {
        Params::defaults(self.0.params())
    }
}

impl PartialEq for Accel {
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Accel {}

impl std::hash::Hash for Accel {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.name().hash(state)
    }
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::fmt::Display for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(feature = "serde")]
impl serde::Serialize for Accel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

/// A built structure with the entry that built it. Read through its
/// methods: its kernel, bindings and mode must stay those it was built with.
pub struct Structure {
    pub(crate) accel: Accel,
    pub(crate) params: Params,
    /// The mode of the frames it was built for (None: any, as naive).
    pub(crate) mode: Option<Mode>,
    /// The grid and channel count of the volume it was built over (None:
    /// any, as naive).
    pub(crate) volume: Option<([u32; 3], u32)>,
    /// The volume's `content_id` and the transfer function's `alpha_key`
    /// it skips for (None: any, as naive and a mode's naive fallback; no
    /// key: any TF, as iso).
    pub(crate) built_for: Option<(u64, Option<u64>)>,
    /// The context its buffers were made on (None: it holds none).
    pub(crate) made_on: Option<crate::gpu::Context>,
    pub(crate) built: Box<dyn Built>,
    /// What a recorded build's command buffer still reads (the activity
    /// LUT of a mode's build and its staging).
    pub(crate) _keep: Option<Box<dyn Any + Send + Sync>>,
}

impl Structure {
    /// The entry that built it.
    pub fn accel(&self) -> Accel {
        self.accel
    }

    /// The parameters it was built with.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// The mode of the frames it was built for (None: any, as naive).
    pub fn mode(&self) -> Option<&Mode> {
        self.mode.as_ref()
    }

    /// Its built data: what its kernel binds and reads.
    pub fn built(&self) -> &dyn Built {
        self.built.as_ref()
    }

    /// A frame of `mode` can use this structure: it was built for frames
    /// that classify alike (`Mode::same_classification`).
    pub fn check_mode(&self, mode: &Mode) -> Result<()> {
        match &self.mode {
            Some(built) if !built.same_classification(mode) => Err(Error::invalid(
                "frame mode",
                mode.name(),
                match (built, mode) {
                    (Mode::Iso(b), Mode::Iso(_)) => format!(
                        "the {} structure was built for iso values {}: build it for the frame's",
                        self.accel,
                        b.values().iter().map(|v| v.to_string()).collect::<Vec<_>>().join(",")
                    ),
                    _ => format!(
                        "the {} structure was built for {} frames: build it with the frame's mode",
                        self.accel,
                        built.name()
                    ),
                },
            )),
            _ => Ok(()),
        }
    }

    /// A frame of `volume` can use this structure: it was built over a
    /// volume of the same grid and channels (its regions index voxels, and
    /// its classification covers those channels). Another volume would
    /// march a wrong image, or read past the structure's buffers.
    pub fn check_volume(&self, volume: &crate::volume::GpuVolume) -> Result<()> {
        match self.volume {
            Some((dims, channels)) if (dims, channels) != (volume.dims, volume.channels) => Err(Error::invalid(
                "volume",
                format!(
                    "{}x{}x{} of {} channel(s)",
                    volume.dims[0], volume.dims[1], volume.dims[2], volume.channels
                ),
                format!(
                    "the {} structure was built over {}x{}x{} of {channels} channel(s): build it over the volume it renders",
                    self.accel, dims[0], dims[1], dims[2]
                ),
            )),
            _ => Ok(()),
        }
    }

    /// An error unless it can be drawn on `ctx`: it holds no buffers, or
    /// they are `ctx`'s.
    pub fn check_made_on(&self, ctx: &crate::gpu::Context) -> Result<()> {
        match &self.made_on {
            Some(made_on) => ctx.check_is(made_on, "structure"),
            None => Ok(()),
        }
    }

    /// A frame of `volume` through `tf` can use this structure: it skips
    /// what these texels (this upload, this series step) show through
    /// this transfer function. Other texels or another TF on the same grid
    /// would march a wrong image, with no error.
    pub fn check_built_for(
        &self,
        volume: &crate::volume::GpuVolume,
        tf: &crate::tf::GpuTransferFunction,
    ) -> Result<()> {
        self.check_volume(volume)?;
        let Some((content, key)) = self.built_for else {
            return Ok(());
        };
        if content != volume.content_id() {
            return Err(Error::invalid(
                "volume",
                "another upload or series step",
                format!(
                    "the {} structure was built over other texels: build it again over the volume it renders (its ranges too)",
                    self.accel
                ),
            ));
        }
        if key.is_some_and(|k| k != tf.alpha_key()) {
            return Err(Error::invalid(
                "transfer function",
                "another one",
                format!(
                    "the {} structure was built for other opacities: build it again for the transfer function it renders with",
                    self.accel
                ),
            ));
        }
        Ok(())
    }

    /// The ray direction octants it skips for ([`Built::octants`]); frames
    /// with others are exact, and slower.
    pub fn octants(&self) -> Octants {
        self.built.octants()
    }

    /// The entry whose kernel marches this structure's frames: its own, or
    /// what [`Built::marched_as`] names.
    pub fn marched_as(&self) -> Accel {
        self.built.marched_as().map_or(self.accel, |m| m.accel)
    }

    /// Why another entry's kernel marches it, when one does.
    pub fn marched_as_reason(&self) -> Option<MarchedAs> {
        self.built.marched_as()
    }

    /// The error for a frame of this structure that a device's cap on a
    /// shader's loop passes (`DeviceInfo::loop_pass_limit`) may have cut
    /// short in `groups` SIMD groups.
    pub fn cut_error(&self, info: &DeviceInfo, groups: u32) -> Error {
        let accel = self.marched_as();
        Error::LoopCap {
            structure: accel.to_string(),
            device: info.name.clone(),
            limit: info.loop_pass_limit.unwrap_or(0),
            groups,
            advice: match accel.is_naive() {
                // Naive's passes were bounded before: a march at the bound.
                true => "take a coarser step",
                false => "take a coarser step, or march naively (checked to fit this step)",
            },
        }
    }

    /// The march kernel its frames use.
    pub fn march(&self) -> March {
        self.marched_as().method().march()
    }

    /// The paper's Table 1 statistics (None when nothing was built).
    pub fn stats(&self) -> Result<Option<Stats>> {
        self.built.stats()
    }

    /// The built data as its concrete type (`auto::Chosen`, `GpuTree`, ...).
    pub fn built_as<T: Any>(&self) -> Option<&T> {
        (self.built.as_ref() as &dyn Any).downcast_ref::<T>()
    }
}
