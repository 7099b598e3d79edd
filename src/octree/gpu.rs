//! The GPU batch tracer: `TraceKernels` holds the pipelines of
//! `glsl/octree/trace.comp` (one per traversal, chosen by a specialization
//! constant), created once per context; a `GpuTracer` uploads one octree,
//! its references and primitives, and traces rays in batches, each batch
//! timed with GPU timestamps.

use super::build::{Octree, MAX_DEPTH_LIMIT};
use super::prims::{Ray, TraceResult, TraceScene, POLYGON};
use super::traverse::Traversal;
use crate::error::{Error, Result};
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
        check_for_gpu(tree, scene)?;
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

/// An error unless every index the traversal kernels follow stays in its
/// array: the octree and scene have public fields, and the kernels read
/// them unchecked (no robust buffer access). Children come after their
/// parent (so the tree has no cycle) and no deeper than the kernels'
/// stacks; each node's stored depth and parent are its own.
fn check_for_gpu(tree: &Octree, scene: &TraceScene) -> Result<()> {
    let bad = |what: String| Err(Error::invalid("octree", what, "is not an octree the builder makes"));
    let (nodes, refs) = (&tree.nodes, &tree.refs);
    if nodes.is_empty() || nodes[0].depth() != 0 || nodes[0].parent() != 0 {
        return bad("its root".into());
    }
    for (i, n) in nodes.iter().enumerate() {
        let (first, count) = (n.first() as u64, n.count() as u64);
        if n.is_leaf() {
            if first + count > refs.len() as u64 {
                return bad(format!("leaf {i}'s references"));
            }
            continue;
        }
        if first <= i as u64 || first + 8 > nodes.len() as u64 || n.depth() >= MAX_DEPTH_LIMIT {
            return bad(format!("node {i}'s children"));
        }
        for c in &nodes[first as usize..first as usize + 8] {
            if c.parent() as usize != i || c.depth() != n.depth() + 1 {
                return bad(format!("node {i}'s children"));
            }
        }
    }
    if let Some(r) = refs.iter().find(|&&r| r as usize >= scene.prims.len()) {
        return bad(format!("reference to primitive {r}"));
    }
    for (i, p) in scene.prims.iter().enumerate() {
        let [kind, first, count, drop] = p.info;
        let polygon_fits = first as u64 + count as u64 <= scene.verts.len() as u64 && drop < 3;
        if kind > POLYGON || (kind == POLYGON && !polygon_fits) {
            return Err(Error::invalid(
                "primitive",
                i.to_string(),
                "a sphere, cone, or polygon of the scene's vertices",
            ));
        }
    }
    Ok(())
}
