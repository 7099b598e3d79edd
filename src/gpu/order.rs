//! The device order of lacuna's own submissions: one at a time from its
//! submit to its wait, first come first served, so a thread that submits
//! back to back cannot keep another's recorded submission waiting (and
//! what the waiting one's recording pinned from being destroyed).

use std::sync::{Condvar, Mutex, MutexGuard};

/// A ticket lock: tickets are served in the order they were taken.
#[derive(Default)]
pub(super) struct Order {
    /// The next ticket to take, and the ticket being served.
    tickets: Mutex<(u64, u64)>,
    turn: Condvar,
}

/// The device order, held until dropped.
pub(super) struct Turn<'a>(&'a Order);

impl Order {
    fn tickets(&self) -> MutexGuard<'_, (u64, u64)> {
        self.tickets.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Waits for this thread's turn.
    pub(super) fn take(&self) -> Turn<'_> {
        let mut t = self.tickets();
        let mine = t.0;
        t.0 += 1;
        while t.1 != mine {
            t = self.turn.wait(t).unwrap_or_else(|p| p.into_inner());
        }
        Turn(self)
    }
}

impl Drop for Turn<'_> {
    fn drop(&mut self) {
        self.0.tickets().1 += 1;
        self.0.turn.notify_all();
    }
}
