//! The kernels a context has created, kept until the context goes: a
//! builder, a renderer, auto's probes and a viewer rebuilding its structure
//! all ask for the same pipelines, and creating one is not free. On
//! lavapipe it costs 0.5 to 1 s a march kernel over a dense volume (up to
//! 3 s over bricks), even with Mesa's shader cache warm: its NIR passes run
//! before the cache is consulted.

use super::shaders::Shader;
use crate::error::Result;
use ash::vk;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

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

/// A key's kernel: empty until the thread that asked first has made it.
type Slot = Arc<Mutex<Option<KernelObjects>>>;

#[derive(Default)]
pub(crate) struct KernelCache {
    made: Mutex<HashMap<KernelKey, Slot>>,
}

impl KernelCache {
    /// `key`'s kernel, made by `make` unless it was made before. A thread
    /// asking for a key another thread is making waits for that one rather
    /// than make it again (auto's candidates often share a kernel, and
    /// their kernels are made on a thread each: `MarchKernels::prepare`).
    /// Where `make` fails, the next thread to ask tries again.
    pub fn get_or_make(&self, key: KernelKey, make: impl FnOnce() -> Result<KernelObjects>) -> Result<KernelObjects> {
        let slot = self.lock().entry(key).or_default().clone();
        // A thread that panicked while making leaves the slot empty.
        let mut slot = slot.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(made) = *slot {
            return Ok(made);
        }
        let made = make()?;
        *slot = Some(made);
        Ok(made)
    }

    /// How many kernels were made.
    pub fn len(&self) -> usize {
        // The slots are read after the map is let go: one being made holds
        // its lock for seconds, and the map's would stall every other key.
        let slots: Vec<Slot> = self.lock().values().cloned().collect();
        slots.iter().filter(|slot| lock_slot(slot).is_some()).count()
    }

    /// # Safety
    /// The device is idle as far as these kernels go, and about to be
    /// destroyed (or, adopted, handed back to its host).
    pub unsafe fn destroy_all(&mut self, device: &ash::Device) {
        let map = self.made.get_mut().unwrap_or_else(|p| p.into_inner());
        for (_, slot) in map.drain() {
            if let Some(objects) = lock_slot(&slot).take() {
                objects.destroy(device);
            }
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<KernelKey, Slot>> {
        // A panic elsewhere never leaves the map half-written: it is only
        // read or inserted into whole.
        self.made.lock().unwrap_or_else(|p| p.into_inner())
    }
}

fn lock_slot(slot: &Slot) -> std::sync::MutexGuard<'_, Option<KernelObjects>> {
    slot.lock().unwrap_or_else(|p| p.into_inner())
}

#[cfg(test)]
mod tests {
    use super::{KernelCache, KernelKey, KernelObjects};
    use crate::error::Error;
    use crate::gpu::shaders;
    use ash::vk;
    use std::sync::atomic::{AtomicUsize, Ordering};

    #[test]
    fn keys_name_the_shader_and_its_constants_in_any_order() {
        let copy = &shaders::PRIMS_COPY;
        let key = |c: &[(u32, u32)]| KernelKey::new(copy, c);
        assert!(key(&[(1, 2), (0, 3)]) == key(&[(0, 3), (1, 2)]));
        assert!(key(&[(0, 3)]) != key(&[(0, 4)]));
        assert!(KernelKey::new(&shaders::PRIMS_COMPACT, &[]) != key(&[]));
    }

    /// Null handles stand in for a kernel: nothing here touches a device.
    fn objects() -> KernelObjects {
        KernelObjects {
            module: vk::ShaderModule::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            layout: vk::PipelineLayout::null(),
            pipeline: vk::Pipeline::null(),
        }
    }

    #[test]
    fn threads_asking_for_one_key_at_once_make_it_once() {
        let cache = KernelCache::default();
        let makes = AtomicUsize::new(0);
        let key = || KernelKey::new(&shaders::PRIMS_COPY, &[(0, 1)]);
        std::thread::scope(|scope| {
            for _ in 0..4 {
                scope.spawn(|| {
                    cache
                        .get_or_make(key(), || {
                            makes.fetch_add(1, Ordering::SeqCst);
                            // Long enough that the other threads ask while it is made.
                            std::thread::sleep(std::time::Duration::from_millis(100));
                            Ok(objects())
                        })
                        .unwrap()
                });
            }
        });
        assert_eq!(makes.load(Ordering::SeqCst), 1);
        assert_eq!(cache.len(), 1);
        // Another key is made on its own.
        cache
            .get_or_make(KernelKey::new(&shaders::PRIMS_COPY, &[(0, 2)]), || {
                makes.fetch_add(1, Ordering::SeqCst);
                Ok(objects())
            })
            .unwrap();
        assert_eq!(makes.load(Ordering::SeqCst), 2);
    }

    #[test]
    fn a_kernel_that_failed_is_tried_again() {
        let cache = KernelCache::default();
        let key = || KernelKey::new(&shaders::PRIMS_COPY, &[]);
        let failed = cache.get_or_make(key(), || Err(Error::Interface("no pipeline".into())));
        assert!(failed.is_err());
        assert_eq!(cache.len(), 0);
        assert!(cache.get_or_make(key(), || Ok(objects())).is_ok());
        assert_eq!(cache.len(), 1);
    }
}
