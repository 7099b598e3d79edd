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
    readers: usize,
    /// lacuna's submissions that write it and may not have settled.
    writers: Vec<Completion>,
    /// lacuna's submissions that only read it and may not have settled.
    users: Vec<Completion>,
}

impl HostAccess {
    /// Counts a host read (true), unless a submission that writes the
    /// buffer may still run.
    pub(super) fn start_read(&mut self) -> bool {
        if unsettled(&mut self.writers) {
            return false;
        }
        self.readers += 1;
        true
    }

    /// Whether the host may write (through `&mut`, so no `HostRead` is
    /// alive, and one forgotten no longer counts): no submission that
    /// reads or writes the buffer may still run.
    pub(super) fn start_write(&mut self) -> bool {
        self.readers = 0;
        !unsettled(&mut self.writers) && !unsettled(&mut self.users)
    }

    /// Notes a submission that writes (else reads) the buffer, once (a
    /// host's, `None`, is the host's to wait for); a write is refused
    /// (false) while a `HostRead` is alive.
    pub(super) fn note(&mut self, done: Option<Completion>, writes: bool) -> bool {
        if writes && self.readers > 0 {
            return false;
        }
        let list = match writes {
            true => &mut self.writers,
            false => &mut self.users,
        };
        if let Some(done) = done {
            unsettled(list);
            if !list.iter().any(|w| w.same(&done)) {
                list.push(done);
            }
        }
        true
    }
}

/// Drops the settled submissions from `list`: whether any is left.
fn unsettled(list: &mut Vec<Completion>) -> bool {
    list.retain(|w| !w.is_settled());
    !list.is_empty()
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
