//! The host's accesses to a buffer's mapped bytes against the device's
//! (`Buffer::host`, `host_mut`, `written_by`, `used_by`): each side refuses
//! while the other may be at it, so safe code never reads memory a
//! submission writes, nor writes memory one reads.

use super::record::Completion;
use std::sync::{Mutex, MutexGuard};

/// The host's accesses to a buffer's mapped bytes against the device's:
/// a host read while a submission that writes the buffer is recorded or
/// running, or a host write while one reads or writes it, is a data race,
/// refused both ways.
#[derive(Default)]
pub(super) struct HostAccess {
    /// `HostRead`s alive.
    pub(super) readers: usize,
    /// lacuna's submissions that write it and may not have settled.
    writers: Vec<Completion>,
    /// lacuna's submissions that only read it and may not have settled.
    users: Vec<Completion>,
}

impl HostAccess {
    /// Whether a submission that writes the buffer may still run.
    pub(super) fn written_in_flight(&mut self) -> bool {
        self.writers.retain(|w| !w.is_settled());
        !self.writers.is_empty()
    }

    /// Whether a submission that reads or writes the buffer may still run.
    pub(super) fn used_in_flight(&mut self) -> bool {
        self.users.retain(|w| !w.is_settled());
        self.written_in_flight() || !self.users.is_empty()
    }

    /// Notes a submission that writes (else reads) the buffer, once.
    pub(super) fn add(&mut self, done: Completion, writes: bool) {
        let list = match writes {
            true => &mut self.writers,
            false => &mut self.users,
        };
        list.retain(|w| !w.is_settled());
        if !list.iter().any(|w| w.same(&done)) {
            list.push(done);
        }
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
