//! The GPU batch tracer: `TraceKernels` holds the pipelines of
//! `glsl/octree/trace.comp` (one per traversal, chosen by a specialization
//! constant), created once per context; a `GpuTracer` uploads one octree,
//! its references and primitives, and traces rays in batches, each batch
//! timed with GPU timestamps.

use super::build::Octree;
use super::prims::{Ray, TraceResult, TraceScene};
use super::traverse::Traversal;
use crate::error::Result;
use crate::gpu::record::{self, Access};
use crate::gpu::shaders::{self, octree_trace};
use crate::gpu::{vk, Binding, Buffer, Context, Kernel, MemoryLocation, Timer};

/// Rays per dispatch (32 MiB of rays and of results at most).
const BATCH: usize = 1 << 20;

/// The trace pipelines, once per context.
pub struct TraceKernels {
    ctx: Context,
    kernels: Vec<(Traversal, Kernel)>,
}

impl TraceKernels {
    pub fn new(ctx: &Context) -> Result<Self> {
        let kernels = Traversal::ALL
            .into_iter()
            .map(|t| {
                // SAFETY: the constants are the ones this kernel is written for (its own table).
                unsafe { Kernel::with_constants::<octree_trace::Push>(ctx, &shaders::OCTREE_TRACE, &[t.id()]) }
                    .map(|k| (t, k))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(TraceKernels {
            ctx: ctx.clone(),
            kernels,
        })
    }

    fn kernel(&self, kind: Traversal) -> &Kernel {
        // `new` creates one kernel for every `Traversal`.
        #[allow(clippy::expect_used)]
        &self
            .kernels
            .iter()
            .find(|(t, _)| *t == kind)
            .expect("a kernel per traversal")
            .1
    }
}

/// An SPD scene's octree and rays on the device, traced by each traversal's
/// kernel.
pub struct GpuTracer<'k> {
    kernels: &'k TraceKernels,
    nodes: Buffer,
    refs: Buffer,
    prims: Buffer,
    verts: Buffer,
    rays: Buffer,
    results: Buffer,
    timer: Timer,
}

fn storage(ctx: &Context, name: &str, bytes: &[u8]) -> Result<Buffer> {
    // Empty arrays still need a binding.
    let data: &[u8] = if bytes.is_empty() { &[0u8; 16] } else { bytes };
    Buffer::with_data(ctx, name, data, vk::BufferUsageFlags::STORAGE_BUFFER)
}

impl<'k> GpuTracer<'k> {
    /// Uploads `tree` over `scene` for tracing with `kernels`.
    pub fn new(kernels: &'k TraceKernels, tree: &Octree, scene: &TraceScene) -> Result<Self> {
        let ctx = &kernels.ctx;
        let info = ctx.info();
        for (what, bytes) in [
            ("octree nodes", std::mem::size_of_val(tree.nodes.as_slice())),
            ("octree references", std::mem::size_of_val(tree.refs.as_slice())),
            ("primitives", std::mem::size_of_val(scene.prims.as_slice())),
        ] {
            info.check(
                what,
                "maxStorageBufferRange",
                bytes as u64,
                info.max_storage_buffer_range,
            )?;
        }
        let io = |name: &str| {
            Buffer::new(
                ctx,
                name,
                (BATCH * 32) as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::CpuToGpu,
            )
        };
        let results = Buffer::new(
            ctx,
            "trace results",
            (BATCH * 32) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryLocation::GpuToCpu,
        )?;
        Ok(GpuTracer {
            kernels,
            nodes: storage(ctx, "octree nodes", bytemuck::cast_slice(&tree.nodes))?,
            refs: storage(ctx, "octree references", bytemuck::cast_slice(&tree.refs))?,
            prims: storage(ctx, "primitives", bytemuck::cast_slice(&scene.prims))?,
            verts: storage(ctx, "polygon vertices", bytemuck::cast_slice(&scene.verts))?,
            rays: io("trace rays")?,
            results,
            timer: Timer::new(ctx, 1)?,
        })
    }

    /// Traces `rays`; returns the results and the GPU time in milliseconds.
    pub fn trace(&mut self, kind: Traversal, rays: &[Ray], any_hit: bool) -> Result<(Vec<TraceResult>, f64)> {
        let mut out = Vec::with_capacity(rays.len());
        let mut ms = 0.0;
        let kernels: &'k TraceKernels = self.kernels;
        let (ctx, kernel) = (&kernels.ctx, kernels.kernel(kind));
        for batch in rays.chunks(BATCH) {
            // Host-visible, coherent: the submission makes these writes visible.
            let ray_bytes: &[u8] = bytemuck::cast_slice(batch);
            self.rays.host_mut()?[..ray_bytes.len()].copy_from_slice(ray_bytes);
            let groups = record::groups_linear(ctx.info(), "trace rays", batch.len() as u64, kernel.local_size()[0])?;
            let push = octree_trace::Push {
                count: batch.len() as u32,
                any_hit: u32::from(any_hit),
                groups_x: groups[0],
            };
            let timer = &mut self.timer;
            let bindings = octree_trace::Bindings {
                nodes: Binding::Storage(&self.nodes),
                refs: Binding::Storage(&self.refs),
                prims: Binding::Storage(&self.prims),
                verts: Binding::Storage(&self.verts),
                rays: Binding::Storage(&self.rays),
                results: Binding::Storage(&self.results),
            }
            .list();
            ctx.submit_and_wait(|cmd| {
                timer.reset(cmd);
                let pass = timer.begin(cmd, "trace")?;
                // SAFETY: every binding is a live object of this context borrowed for
                // the call, or the host's (`Recording::adopt`, `HostImage::new`).
                unsafe { kernel.dispatch(cmd, &bindings, bytemuck::bytes_of(&push), groups) }?;
                timer.end(cmd, pass);
                cmd.barrier(Access::COMPUTE_WRITE, Access::HOST_READ);
                Ok(())
            })?;
            ms += self.timer.results()?.total();
            let bytes = &self.results.host()?[..batch.len() * 32];
            out.extend_from_slice(bytemuck::cast_slice(bytes));
        }
        Ok((out, ms))
    }
}
