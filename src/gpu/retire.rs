//! Deferred destruction: an object dropped while one of lacuna's own
//! submissions on its context is being recorded or executed may be used by
//! it, so it is destroyed once that submission has completed, not at once.
//! (A host's command buffers are the host's to outlive: `Recording::adopt`.)

use super::Context;
use ash::vk;
use gpu_allocator::vulkan::{Allocation, Allocator};
use std::collections::BTreeSet;
use std::sync::Mutex;

/// The Vulkan objects of a dropped lacuna object.
pub(crate) enum Retired {
    Buffer(vk::Buffer, Option<Allocation>),
    BufferView(vk::BufferView),
    Image(vk::Image, vk::ImageView, Option<Allocation>),
    Sampler(vk::Sampler),
    QueryPool(vk::QueryPool),
}

/// lacuna's submissions in flight on a context and what waits for them:
/// each object for the submissions open when it was dropped (those with
/// ids up to its tag; later ones cannot name it), not for every later one.
#[derive(Default)]
pub(crate) struct Retirement {
    /// Ids of the submissions in flight.
    open: BTreeSet<u64>,
    next: u64,
    /// Each with the newest id open when it was dropped.
    pub(super) waiting: Vec<(u64, Retired)>,
}

impl Context {
    /// Destroys `objects` now, or after every submission of lacuna's now in
    /// flight on this context has completed.
    pub(crate) fn retire(&self, objects: impl IntoIterator<Item = Retired>) {
        let mut now = Vec::new();
        {
            let mut r = self.inner.retirement.lock().unwrap_or_else(|p| p.into_inner());
            if let Some(&newest) = r.open.last() {
                r.waiting.extend(objects.into_iter().map(|o| (newest, o)));
                return;
            }
            now.extend(objects);
        }
        destroy(self.device(), &self.inner.allocator, now);
    }

    /// Marks a submission in flight until the guard drops (after its wait).
    pub(super) fn open_submission(&self) -> OpenSubmission<'_> {
        let mut r = self.inner.retirement.lock().unwrap_or_else(|p| p.into_inner());
        let id = r.next;
        r.next += 1;
        r.open.insert(id);
        OpenSubmission(self, id)
    }

    /// How many dropped objects wait for submissions in flight.
    #[doc(hidden)]
    pub fn retired_waiting(&self) -> usize {
        self.inner
            .retirement
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .waiting
            .len()
    }
}

/// Destroys `objects` on `device`, freeing their memory to `allocator`.
pub(super) fn destroy(device: &ash::Device, allocator: &Mutex<Allocator>, objects: Vec<Retired>) {
    let free = |a: Option<Allocation>| {
        if let Some(a) = a {
            let _ = allocator.lock().unwrap_or_else(|p| p.into_inner()).free(a);
        }
    };
    for object in objects {
        // SAFETY: no submission of lacuna's that may use the object is in
        // flight (`Context::retire`), and the host vouched for its own
        // (`Recording::adopt`).
        unsafe {
            match object {
                Retired::Buffer(raw, allocation) => {
                    free(allocation);
                    device.destroy_buffer(raw, None);
                }
                Retired::BufferView(view) => device.destroy_buffer_view(view, None),
                Retired::Image(raw, view, allocation) => {
                    device.destroy_image_view(view, None);
                    free(allocation);
                    device.destroy_image(raw, None);
                }
                Retired::Sampler(sampler) => device.destroy_sampler(sampler, None),
                Retired::QueryPool(pool) => device.destroy_query_pool(pool, None),
            }
        }
    }
}

/// A submission of lacuna's in flight; dropping it (after the wait)
/// destroys what was retired meanwhile once every submission in flight
/// when it was dropped has closed.
pub(super) struct OpenSubmission<'a>(&'a Context, u64);

impl Drop for OpenSubmission<'_> {
    fn drop(&mut self) {
        let due = {
            let mut r = self.0.inner.retirement.lock().unwrap_or_else(|p| p.into_inner());
            r.open.remove(&self.1);
            let oldest = r.open.first().copied().unwrap_or(u64::MAX);
            let (due, wait) = std::mem::take(&mut r.waiting)
                .into_iter()
                .partition(|(tag, _)| *tag < oldest);
            r.waiting = wait;
            due.into_iter().map(|(_, o)| o).collect()
        };
        destroy(self.0.device(), &self.0.inner.allocator, due);
    }
}
