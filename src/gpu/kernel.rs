//! Compute kernels from embedded SPIR-V: one descriptor set bound with push
//! descriptors (`VK_KHR_push_descriptor`), so recording needs no descriptor
//! pools and a recorded command buffer holds no lacuna-owned descriptor state.
//! Resources are bound by the shader's binding names (`shaders::NAME::Bindings`
//! lists them), never by position.

use super::binding::{Binding, Bound};
use super::kernel_cache::{KernelKey, KernelObjects};
use super::record::Recording;
use super::shaders::{Shader, Slot};
use super::Context;
use crate::error::{Error, Result, VkContext};
use ash::vk;

/// A compute pipeline with its layout. Its Vulkan objects belong to the
/// context, which creates each (SPIR-V, specialization) once and destroys
/// them when it goes (`kernel_cache.rs`): dropping a kernel frees nothing,
/// and a second kernel of the same specialization costs no compile.
pub struct Kernel {
    ctx: Context,
    name: &'static str,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    bindings: &'static [Slot],
    push_size: u32,
    local_size: [u32; 3],
}

impl Kernel {
    /// The kernel of `shader`, whose push-constant block is `P` (`()` for
    /// none). Descriptor bindings, push size and workgroup size come from the
    /// shader's reflected interface; a `P` of another size than the shader's
    /// block is an error naming the kernel.
    pub fn new<P: bytemuck::Pod>(ctx: &Context, shader: &Shader) -> Result<Self> {
        // SAFETY: no constants: the shader's own defaults.
        unsafe { Self::create(ctx, shader, std::mem::size_of::<P>(), &[]) }
    }

    /// As `new`, with u32 specialization constants for `constant_id` 0, 1, ...
    /// (`local_size_x_id = 0` makes constant 0 the workgroup width).
    ///
    /// # Safety
    /// As `specialized`.
    pub unsafe fn with_constants<P: bytemuck::Pod>(ctx: &Context, shader: &Shader, constants: &[u32]) -> Result<Self> {
        // SAFETY: the caller's contract.
        unsafe { Self::create(ctx, shader, std::mem::size_of::<P>(), constants) }
    }

    /// As `with_constants`, with the Rust side's push block size in bytes.
    ///
    /// # Safety
    /// As `specialized`.
    pub unsafe fn create(ctx: &Context, shader: &Shader, push_size: usize, constants: &[u32]) -> Result<Self> {
        let entries: Vec<(u32, u32)> = (0..).zip(constants.iter().copied()).collect();
        // SAFETY: the caller's contract.
        unsafe { Self::specialized(ctx, shader, push_size, &entries) }
    }

    /// As `create`, with (`constant_id`, value) pairs: ids the shader does
    /// not declare are ignored, as Vulkan specifies. A workgroup size of 0 or
    /// past the device's limits is an error.
    ///
    /// # Safety
    /// Each constant is a value the shader was written to take at its id
    /// (an array size it can hold, a variant it declares): the driver
    /// compiles whatever the constants make of it.
    pub unsafe fn specialized(
        ctx: &Context,
        shader: &Shader,
        push_size: usize,
        constants: &[(u32, u32)],
    ) -> Result<Self> {
        let name = shader.name;
        if push_size != shader.push_size as usize {
            return Err(Error::Interface(format!(
                "kernel {name}: the Rust push-constant block is {push_size} bytes, the shader's is {} bytes",
                shader.push_size
            )));
        }
        let info = ctx.info();
        info.check(
            format!("push constants of kernel {name}"),
            "maxPushConstantsSize",
            push_size as u64,
            info.max_push_constants_size as u64,
        )?;
        let local_size = shader.local_size_for(constants);
        for (a, &n) in local_size.iter().enumerate() {
            let what = format!("workgroup of kernel {name} ({local_size:?})");
            info.check(
                what,
                "maxComputeWorkGroupSize",
                n as u64,
                info.max_compute_work_group_size[a] as u64,
            )?;
            if n == 0 {
                return Err(Error::invalid(
                    "workgroup size",
                    format!("{local_size:?}"),
                    format!("kernel {name}: every axis needs an invocation"),
                ));
            }
        }
        let threads: u64 = local_size.iter().map(|&n| n as u64).product();
        info.check(
            format!("workgroup of kernel {name} ({local_size:?})"),
            "maxComputeWorkGroupInvocations",
            threads,
            info.max_compute_work_group_invocations as u64,
        )?;
        let key = KernelKey::new(shader, constants);
        let objects = ctx.inner.kernels.get_or_make(key, || make(ctx, shader, constants))?;
        Ok(Kernel {
            ctx: ctx.clone(),
            name,
            layout: objects.layout,
            pipeline: objects.pipeline,
            bindings: shader.bindings,
            push_size: shader.push_size,
            local_size,
        })
    }

    /// Threads per workgroup, after specialization.
    pub fn local_size(&self) -> [u32; 3] {
        self.local_size
    }

    /// Workgroups covering `threads` invocations (checked against
    /// `maxComputeWorkGroupCount`).
    pub fn groups(&self, what: &str, threads: [u32; 3]) -> Result<[u32; 3]> {
        super::record::groups_for(self.ctx.info(), what, threads, self.local_size)
    }

    /// The shader's name (`glsl/` path without the extension).
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// The shader's bindings: (name, descriptor type), in binding order.
    pub fn slots(&self) -> &'static [Slot] {
        self.bindings
    }

    /// Binds the pipeline, pushes `bindings` (each to the binding of its
    /// name) and `push` constants, and dispatches `groups` workgroups.
    /// Records only; no barriers. A binding missing, given twice, unknown
    /// to the shader or of another type, or a push block of another size, is
    /// an error naming the kernel and the binding, and nothing is recorded.
    ///
    /// A command buffer or a bound `Buffer` of another context is an error.
    ///
    /// # Safety
    /// - Every raw handle in `bindings` (`Binding`'s `StorageRange`,
    ///   `Sampled`, `SampledIn`, `StorageImage` and `TexelBuffer`) is a live
    ///   object of this kernel's device, of the type the binding names (an
    ///   image view in the layout it states, a sampled view with a
    ///   compatible sampler, a storage image of the format the shader
    ///   declares), and stays so until the dispatch has executed.
    /// - Every buffer has the usage its binding needs, and given `push` and
    ///   `groups` the kernel reads and writes within what is bound (lacuna
    ///   enables no robust buffer access).
    /// - Memory bound through a raw handle is not read or written on the
    ///   host until the dispatch has executed: where it is a lacuna
    ///   `Buffer`'s or `TexelBuffer`'s, lacuna does not see the access, so
    ///   bind those as `Storage`, `Uniform` or `Texels`, or make no
    ///   `host`/`host_mut` call on them until then.
    pub unsafe fn dispatch(&self, cmd: Recording<'_>, bindings: &[Bound], push: &[u8], groups: [u32; 3]) -> Result<()> {
        // SAFETY: the caller's contract is `dispatch_base`'s.
        unsafe { self.dispatch_base(cmd, bindings, push, [0; 3], groups) }
    }

    /// As `dispatch`, for the workgroups from `base` on (`vkCmdDispatchBase`:
    /// `gl_WorkGroupID` and `gl_GlobalInvocationID` include `base`).
    ///
    /// # Safety
    /// As `dispatch`.
    pub unsafe fn dispatch_base(
        &self,
        cmd: Recording<'_>,
        bindings: &[Bound],
        push: &[u8],
        base: [u32; 3],
        groups: [u32; 3],
    ) -> Result<()> {
        self.ctx.check_is(cmd.context(), "command buffer")?;
        let ordered = self.in_slot_order(bindings)?;
        for (name, b) in bindings {
            let info = self.ctx.info();
            if let Binding::Texels(t) = b {
                self.ctx.check_is(t.buffer().context(), "bound texel buffer")?;
                t.buffer().used_by(cmd)?;
                continue;
            }
            let (buf, usage, range, limit) = match b {
                Binding::Storage(buf) => (
                    buf,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    info.max_storage_buffer_range,
                    "maxStorageBufferRange",
                ),
                Binding::Uniform(buf) => (
                    buf,
                    vk::BufferUsageFlags::UNIFORM_BUFFER,
                    info.max_uniform_buffer_range,
                    "maxUniformBufferRange",
                ),
                _ => continue,
            };
            self.ctx.check_is(buf.context(), "bound buffer")?;
            // Bound whole: all of it must be in range.
            info.check(
                format!("kernel {}: binding {name}", self.name),
                limit,
                buf.size(),
                range,
            )?;
            if !buf.usage().contains(usage) {
                return Err(Error::Interface(format!(
                    "kernel {}: binding {name} needs a buffer of {usage:?} usage",
                    self.name
                )));
            }
            // The host must not read what the kernel may write, nor write
            // what it reads, until the submission settles.
            let writes = self.bindings.iter().any(|s| s.name == *name && s.writes);
            match writes {
                true => buf.written_by(cmd)?,
                false => buf.used_by(cmd)?,
            }
        }
        let bindings = ordered;
        if push.len() != self.push_size as usize {
            return Err(Error::Interface(format!(
                "kernel {}: {} push bytes given, the shader's block is {}",
                self.name,
                push.len(),
                self.push_size
            )));
        }
        let device = self.ctx.device();
        let buffer_infos: Vec<[vk::DescriptorBufferInfo; 1]> = bindings
            .iter()
            .map(|b| match *b {
                Binding::Storage(buf) | Binding::Uniform(buf) => [buf.descriptor()],
                Binding::StorageRange(buffer, offset, range) => [vk::DescriptorBufferInfo { buffer, offset, range }],
                Binding::Sampled(..)
                | Binding::SampledIn(..)
                | Binding::StorageImage(_)
                | Binding::Texels(_)
                | Binding::TexelBuffer(_) => [vk::DescriptorBufferInfo::default()],
            })
            .collect();
        let image_infos: Vec<[vk::DescriptorImageInfo; 1]> = bindings
            .iter()
            .map(|b| match *b {
                Binding::Sampled(view, sampler) => [vk::DescriptorImageInfo {
                    sampler,
                    image_view: view,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }],
                Binding::SampledIn(view, sampler, image_layout) => [vk::DescriptorImageInfo {
                    sampler,
                    image_view: view,
                    image_layout,
                }],
                Binding::StorageImage(view) => [vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: view,
                    image_layout: vk::ImageLayout::GENERAL,
                }],
                _ => [vk::DescriptorImageInfo::default()],
            })
            .collect();
        let texel_views: Vec<[vk::BufferView; 1]> = bindings
            .iter()
            .map(|b| match *b {
                Binding::Texels(t) => [t.view()],
                Binding::TexelBuffer(view) => [view],
                _ => [vk::BufferView::null()],
            })
            .collect();
        let writes: Vec<_> = bindings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let ty = b.descriptor_type();
                let w = vk::WriteDescriptorSet::default()
                    .dst_binding(i as u32)
                    .descriptor_type(ty);
                match b {
                    Binding::Sampled(..) | Binding::SampledIn(..) | Binding::StorageImage(_) => {
                        w.image_info(&image_infos[i])
                    }
                    Binding::Texels(_) | Binding::TexelBuffer(_) => w.texel_buffer_view(&texel_views[i]),
                    _ => w.buffer_info(&buffer_infos[i]),
                }
            })
            .collect();
        unsafe {
            device.cmd_bind_pipeline(cmd.raw(), vk::PipelineBindPoint::COMPUTE, self.pipeline);
            self.ctx.inner.push_descriptor.cmd_push_descriptor_set(
                cmd.raw(),
                vk::PipelineBindPoint::COMPUTE,
                self.layout,
                0,
                &writes,
            );
            if !push.is_empty() {
                device.cmd_push_constants(cmd.raw(), self.layout, vk::ShaderStageFlags::COMPUTE, 0, push);
            }
            if base == [0; 3] {
                device.cmd_dispatch(cmd.raw(), groups[0], groups[1], groups[2]);
            } else {
                device.cmd_dispatch_base(cmd.raw(), base[0], base[1], base[2], groups[0], groups[1], groups[2]);
            }
        }
        Ok(())
    }
}

impl Kernel {
    /// `bindings` in the shader's binding order, checked by name and type.
    fn in_slot_order<'a>(&self, bindings: &[Bound<'a>]) -> Result<Vec<Binding<'a>>> {
        let fail = |why: String| Err(Error::Interface(format!("kernel {}: {why}", self.name)));
        for (i, (name, _)) in bindings.iter().enumerate() {
            if !self.bindings.iter().any(|s| s.name == *name) {
                let known: Vec<&str> = self.bindings.iter().map(|s| s.name).collect();
                return fail(format!("no binding named {name} (the shader has {})", known.join(", ")));
            }
            if bindings[..i].iter().any(|(n, _)| n == name) {
                return fail(format!("binding {name} given twice"));
            }
        }
        let mut ordered = Vec::with_capacity(self.bindings.len());
        for slot in self.bindings {
            let Some((_, b)) = bindings.iter().find(|(n, _)| *n == slot.name) else {
                return fail(format!("binding {} not given", slot.name));
            };
            if b.descriptor_type() != slot.ty {
                return fail(format!(
                    "binding {} is a {:?}, the shader declares a {:?}",
                    slot.name,
                    b.descriptor_type(),
                    slot.ty
                ));
            }
            ordered.push(*b);
        }
        Ok(ordered)
    }
}

/// Whether kernels are created from SPIR-V pruned of the code their
/// specialization constants rule out (`gpu/prune`): yes, unless
/// `LACUNA_SPIRV_PRUNE=0` hands drivers every module whole (to compare the
/// two, or to work around a driver that mishandles a pruned one).
fn prune_spirv() -> bool {
    static PRUNE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *PRUNE.get_or_init(|| std::env::var("LACUNA_SPIRV_PRUNE").map_or(true, |v| v != "0"))
}

/// Creates `shader`'s module, layouts and pipeline specialized with
/// `constants`; on failure destroys what it made.
fn make(ctx: &Context, shader: &Shader, constants: &[(u32, u32)]) -> Result<KernelObjects> {
    let name = shader.name;
    let device = ctx.device();
    let mut objects = KernelObjects {
        module: vk::ShaderModule::null(),
        set_layout: vk::DescriptorSetLayout::null(),
        layout: vk::PipelineLayout::null(),
        pipeline: vk::Pipeline::null(),
    };
    let made = (|| {
        let words = match prune_spirv() {
            true => std::borrow::Cow::Owned(super::prune::prune(shader.words, constants)),
            false => std::borrow::Cow::Borrowed(shader.words),
        };
        objects.module =
            unsafe { device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) }
                .vk("vkCreateShaderModule")?;
        ctx.name_object(objects.module, name);
        let slots: Vec<_> = shader
            .bindings
            .iter()
            .enumerate()
            .map(|(i, slot)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(i as u32)
                    .descriptor_type(slot.ty)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let set_info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&slots);
        objects.set_layout =
            unsafe { device.create_descriptor_set_layout(&set_info, None) }.vk("vkCreateDescriptorSetLayout")?;
        let ranges = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::COMPUTE,
            offset: 0,
            size: shader.push_size,
        }];
        let set_layouts = [objects.set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if shader.push_size > 0 {
            layout_info = layout_info.push_constant_ranges(&ranges);
        }
        objects.layout = unsafe { device.create_pipeline_layout(&layout_info, None) }.vk("vkCreatePipelineLayout")?;
        let entries: Vec<vk::SpecializationMapEntry> = (0..)
            .zip(constants)
            .map(|(i, &(id, _))| vk::SpecializationMapEntry {
                constant_id: id,
                offset: i * 4,
                size: 4,
            })
            .collect();
        let values: Vec<u32> = constants.iter().map(|&(_, v)| v).collect();
        let spec = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(bytemuck::cast_slice(&values));
        let mut stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(objects.module)
            .name(c"main");
        if !constants.is_empty() {
            stage = stage.specialization_info(&spec);
        }
        // DISPATCH_BASE: large frames are dispatched in bands of rows.
        let create = [vk::ComputePipelineCreateInfo::default()
            .flags(vk::PipelineCreateFlags::DISPATCH_BASE)
            .stage(stage)
            .layout(objects.layout)];
        objects.pipeline = unsafe { device.create_compute_pipelines(vk::PipelineCache::null(), &create, None) }
            .map_err(|(_, r)| r)
            .vk("vkCreateComputePipelines")?[0];
        ctx.name_object(objects.pipeline, name);
        ctx.name_object(objects.layout, name);
        Ok(())
    })();
    match made {
        Ok(()) => Ok(objects),
        Err(e) => {
            // SAFETY: nothing recorded them; null handles are ignored.
            unsafe { objects.destroy(device) };
            Err(e)
        }
    }
}
