//! The host's reads of a buffer's mapped bytes against the device's writes
//! (`Buffer::host`, `Buffer::written_by`): each side refuses while the
//! other may be at it, so safe code never reads memory a submission writes.

use super::record::Completion;
use std::sync::{Mutex, MutexGuard};

/// The host's reads of a buffer's mapped bytes against the device's
/// writes: a host read while a submission that writes the buffer is
/// recorded or running is a data race, refused both ways.
#[derive(Default)]
pub(super) struct HostAccess {
    /// `HostRead`s alive.
    pub(super) readers: usize,
    /// lacuna's submissions that write it and may not have settled.
    pub(super) writers: Vec<Completion>,
}

impl HostAccess {
    /// Whether a submission that writes the buffer may still run.
    pub(super) fn written_in_flight(&mut self) -> bool {
        self.writers.retain(|w| !w.is_settled());
        !self.writers.is_empty()
    }
}

/// A buffer's mapped bytes, read on the host: while it lives, recording a
/// device write into the buffer is an error (`Buffer::host`).
pub struct HostRead<'a> {
    bytes: &'a [u8],
    access: &'a Mutex<HostAccess>,
}

impl<'a> HostRead<'a> {
    /// A read `access` already counts (checked and counted under one lock).
    pub(super) fn counted(bytes: &'a [u8], access: &'a Mutex<HostAccess>) -> Self {
        HostRead { bytes, access }
    }
}

impl std::ops::Deref for HostRead<'_> {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        self.bytes
    }
}

impl Drop for HostRead<'_> {
    fn drop(&mut self) {
        lock(self.access).readers -= 1;
    }
}

pub(super) fn lock(access: &Mutex<HostAccess>) -> MutexGuard<'_, HostAccess> {
    access.lock().unwrap_or_else(|p| p.into_inner())
}
