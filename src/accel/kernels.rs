//! The march kernels, specialized and created on first use, shared by
//! everything that marches frames: `render::Renderer` and auto's counting
//! and trial frames (`probe.rs`). A kernel is a structure's shader (or one
//! of its output variants, `march/NAME@rgba8`: build.rs) with the
//! structure's constants (ids 0, 1, ...), the frame's and volume's
//! (`FrameDesc::kernel_constants`) and the probe's (counting, tile stride).

use super::method::March;
use crate::desc::KernelConstants;
use crate::error::{Error, Result};
use crate::gpu::{shaders, Context, Kernel};
use std::sync::Arc;

/// `constant_id` of `MARCH_COUNT` (glsl/common/lattice.glsl): 1 writes the
/// loop iterations each pixel's SIMD group ran instead of its colour.
pub const COUNT_CONSTANT_ID: u32 = 22;
/// `constant_id` of `MARCH_TILE_STRIDE` (glsl/common/march.glsl): workgroup
/// (x, y) marches tile (x, y) times this.
pub const TILE_STRIDE_CONSTANT_ID: u32 = 23;
/// `constant_id` of `MARCH_LOOP_CHECK` (glsl/common/march.glsl): 1 on a
/// device that caps a shader's loop passes (`DeviceInfo::loop_pass_limit`).
pub const LOOP_CHECK_CONSTANT_ID: u32 = 24;

/// How a probe frame departs from a plain one: counting instead of colour,
/// and every `tile_stride`-th 8x8 tile along each axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ProbeConstants {
    pub count: bool,
    pub tile_stride: u32,
}

impl ProbeConstants {
    /// A plain frame: colour, every tile.
    pub const PLAIN: ProbeConstants = ProbeConstants {
        count: false,
        tile_stride: 1,
    };
}

/// The march kernels of one context, created on first use (the context
/// keeps each one it made: `gpu/kernel_cache.rs`).
pub struct MarchKernels {
    ctx: Context,
}

impl MarchKernels {
    pub fn new(ctx: &Context) -> Self {
        MarchKernels { ctx: ctx.clone() }
    }

    /// `march`'s kernel (its output `variant`, or the frame buffer's) for
    /// frames with `frame` constants and `probe`'s.
    pub(crate) fn get(
        &self,
        march: March,
        variant: Option<&str>,
        frame: KernelConstants,
        probe: ProbeConstants,
    ) -> Result<Arc<Kernel>> {
        let march = with_variant(march, variant)?;
        Ok(Arc::new(self.create(march, frame, probe)?))
    }

    /// Creates the kernels of `wanted` the context has not made yet, in
    /// parallel (one thread each; creating a pipeline compiles it, on
    /// lavapipe in 0.5 to 3 s a march kernel): what a probe will dispatch.
    /// Candidates that differ only in cell size share a kernel; its threads
    /// wait for the one that makes it (`gpu/kernel_cache.rs`).
    pub(crate) fn prepare(&self, wanted: &[(March, KernelConstants, ProbeConstants)]) -> Result<()> {
        std::thread::scope(|scope| {
            let jobs: Vec<_> = wanted
                .iter()
                .map(|&(march, frame, probe)| scope.spawn(move || self.get(march, None, frame, probe).map(|_| ())))
                .collect();
            jobs.into_iter().try_for_each(|j| {
                j.join()
                    .unwrap_or_else(|_| Err(Error::Interface("creating a march kernel panicked".into())))
            })
        })
    }

    /// The workgroup size `get` would give the kernel, read from its SPIR-V
    /// without creating it (every output variant shares it).
    pub(crate) fn local_size(&self, march: March, frame: KernelConstants) -> [u32; 3] {
        march
            .shader
            .local_size_for(&self.constants(march, frame, ProbeConstants::PLAIN))
    }

    fn constants(&self, march: March, frame: KernelConstants, probe: ProbeConstants) -> Vec<(u32, u32)> {
        let mut constants: Vec<(u32, u32)> = (0..).zip(march.constants.iter().copied()).collect();
        constants.extend(frame);
        constants.push((COUNT_CONSTANT_ID, probe.count as u32));
        constants.push((TILE_STRIDE_CONSTANT_ID, probe.tile_stride));
        constants.push((LOOP_CHECK_CONSTANT_ID, self.ctx.info().loop_pass_limit.is_some() as u32));
        constants
    }

    fn create(&self, march: March, frame: KernelConstants, probe: ProbeConstants) -> Result<Kernel> {
        let constants = self.constants(march, frame, probe);
        let shader = march.shader;
        // SAFETY: the structure's constants are its `Method`'s (an unsafe
        // trait: `march` names them for this shader), the frame's come from
        // a checked `FrameDesc`, the rest are the march shaders' own.
        unsafe { Kernel::specialized(&self.ctx, &shader, shader.push_size as usize, &constants) }
    }
}

/// `march` with its shader replaced by its output `variant` (`NAME@rgba8`).
fn with_variant(mut march: March, variant: Option<&str>) -> Result<March> {
    if let Some(v) = variant {
        let name = format!("{}@{v}", march.shader.name);
        march.shader = *shaders::ALL
            .iter()
            .find(|s| s.name == name)
            .ok_or_else(|| Error::Interface(format!("kernel {name}: no such shader variant")))?;
    }
    Ok(march)
}
