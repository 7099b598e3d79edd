//! The kernels a context has created, kept until the context goes: a
//! builder, a renderer, auto's probes and a viewer rebuilding its structure
//! all ask for the same pipelines, and creating one is not free. On
//! lavapipe it costs 0.2 to 0.7 s a march kernel, even with Mesa's shader
//! cache warm (its NIR passes run before the cache is consulted).

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

/// What makes two kernels the same: the SPIR-V (its `'static` words, by
/// address) and the specialization, in the order given.
#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct KernelKey {
    words: (usize, usize),
    constants: Vec<(u32, u32)>,
}

impl KernelKey {
    pub fn new(words: &'static [u32], constants: &[(u32, u32)]) -> Self {
        KernelKey {
            words: (words.as_ptr() as usize, words.len()),
            constants: constants.to_vec(),
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
