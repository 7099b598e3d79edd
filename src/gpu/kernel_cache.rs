//! The kernels a context has created, kept until the context goes: a
//! builder, a renderer, auto's probes and a viewer rebuilding its structure
//! all ask for the same pipelines, and creating one is not free. On
//! lavapipe it costs 0.2 to 0.7 s a march kernel, even with Mesa's shader
//! cache warm (its NIR passes run before the cache is consulted).

use super::shaders::Shader;
use ash::vk;
use std::collections::HashMap;
use std::sync::Mutex;

/// A kernel's Vulkan objects, owned by the cache.
#[derive(Clone, Copy)]
pub(crate) struct KernelObjects {
    pub module: vk::ShaderModule,
    pub set_layout: vk::DescriptorSetLayout,
    pub layout: vk::PipelineLayout,
    pub pipeline: vk::Pipeline,
}

impl KernelObjects {
    /// # Safety
    /// No command buffer using them may be pending; `device` made them.
    pub unsafe fn destroy(&self, device: &ash::Device) {
        device.destroy_pipeline(self.pipeline, None);
        device.destroy_pipeline_layout(self.layout, None);
        device.destroy_descriptor_set_layout(self.set_layout, None);
        device.destroy_shader_module(self.module, None);
    }
}

/// What makes two kernels the same: the shader (its `'static` SPIR-V words
/// and binding table, by address) and the specialization, by constant id.
#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct KernelKey {
    words: (usize, usize),
    bindings: usize,
    constants: Vec<(u32, u32)>,
}

impl KernelKey {
    pub fn new(shader: &Shader, constants: &[(u32, u32)]) -> Self {
        let mut constants = constants.to_vec();
        constants.sort_unstable();
        KernelKey {
            words: (shader.words.as_ptr() as usize, shader.words.len()),
            bindings: shader.bindings.as_ptr() as usize,
            constants,
        }
    }
}

#[derive(Default)]
pub(crate) struct KernelCache {
    made: Mutex<HashMap<KernelKey, KernelObjects>>,
}

impl KernelCache {
    pub fn get(&self, key: &KernelKey) -> Option<KernelObjects> {
        self.lock().get(key).copied()
    }

    /// Keeps `made` for `key`, or, where another thread kept one first,
    /// destroys `made` and returns that one.
    pub fn keep(&self, device: &ash::Device, key: KernelKey, made: KernelObjects) -> KernelObjects {
        let mut map = self.lock();
        if let Some(first) = map.get(&key) {
            // SAFETY: `made` was just created and never recorded.
            unsafe { made.destroy(device) };
            return *first;
        }
        map.insert(key, made);
        made
    }

    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// # Safety
    /// The device is idle as far as these kernels go, and about to be
    /// destroyed (or, adopted, handed back to its host).
    pub unsafe fn destroy_all(&mut self, device: &ash::Device) {
        let map = self.made.get_mut().unwrap_or_else(|p| p.into_inner());
        for (_, objects) in map.drain() {
            objects.destroy(device);
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<KernelKey, KernelObjects>> {
        // A panic elsewhere never leaves the map half-written: it is only
        // read or inserted into whole.
        self.made.lock().unwrap_or_else(|p| p.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::KernelKey;
    use crate::gpu::shaders;

    #[test]
    fn keys_name_the_shader_and_its_constants_in_any_order() {
        let copy = &shaders::PRIMS_COPY;
        let key = |c: &[(u32, u32)]| KernelKey::new(copy, c);
        assert!(key(&[(1, 2), (0, 3)]) == key(&[(0, 3), (1, 2)]));
        assert!(key(&[(0, 3)]) != key(&[(0, 4)]));
        assert!(KernelKey::new(&shaders::PRIMS_COMPACT, &[]) != key(&[]));
    }
}
