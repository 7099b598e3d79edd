//! MPI and IceT through `icet_shim.c` (feature `mpi`): the process's rank
//! in `MPI_COMM_WORLD`, agreement on failure, and IceT's ordered blend of
//! the ranks' frames.

use crate::error::{Error, Result};
use crate::volume::RangeAcross;
use std::os::raw::{c_double, c_float, c_int};

extern "C" {
    fn lacuna_mpi_init(rank: *mut c_int, size: *mut c_int) -> c_int;
    fn lacuna_mpi_finalize();
    fn lacuna_mpi_min(v: c_int) -> c_int;
    fn lacuna_mpi_barrier();
    fn lacuna_mpi_abort(code: c_int);
    fn lacuna_mpi_stream_round(lo: c_double, hi: c_double, failed: c_int, done: c_int, out: *mut c_double);
    fn lacuna_mpi_pick(
        n: c_int,
        value: *const c_float,
        largest: c_int,
        rgba: *const c_float,
        out: *mut c_float,
        ms: *mut c_double,
    ) -> c_int;
    fn lacuna_mpi_gather(values: *const c_double, n: c_int, out: *mut c_double);
    fn lacuna_icet_composite(
        width: c_int,
        height: c_int,
        rgba: *const c_float,
        order: *const c_int,
        out: *mut c_float,
        ms: *mut c_double,
    ) -> c_int;
}

/// This process in `MPI_COMM_WORLD`; MPI is finalized when it drops. One
/// per process: MPI initializes once.
pub struct World {
    pub rank: u32,
    pub size: u32,
}

impl World {
    pub fn init() -> Result<World> {
        let (mut rank, mut size) = (0, 0);
        // SAFETY: two valid out-pointers; the shim calls MPI_Init only once.
        if unsafe { lacuna_mpi_init(&mut rank, &mut size) } == 0 {
            return Err(Error::invalid("MPI", "MPI_Init", "failed"));
        }
        Ok(World {
            rank: rank as u32,
            size: size as u32,
        })
    }

    /// The rank that reports a failure, on every rank (a collective: every
    /// rank calls it, so none waits on one that failed): the lowest rank
    /// that failed on its own (`Failed::Own`), else the lowest that failed
    /// because another did (`Failed::Elsewhere`); None where none failed.
    pub fn first_failed(&self, outcome: Failed) -> Option<u32> {
        let n = self.size as c_int;
        let mine = match outcome {
            Failed::Own => self.rank as c_int,
            Failed::Elsewhere => n + self.rank as c_int,
            Failed::No => 2 * n,
        };
        // SAFETY: a collective over plain ints.
        let first = unsafe { lacuna_mpi_min(mine) };
        (first < 2 * n).then_some((first % n) as u32)
    }

    /// How the ranks streaming their own layers agree on the volume's range
    /// (`StreamTo::across`): the least and greatest of every rank's, where
    /// every rank has one; `Error::Elsewhere` where another rank's stream
    /// failed or ended (this rank's own failure is its own to report). Each
    /// call is one round of a collective that `end_streams` ends, so a rank
    /// that fails before, between or after its agreements never leaves the
    /// others waiting in one.
    pub fn range_across(&self) -> RangeAcross {
        std::sync::Arc::new(|mine: Option<(f64, f64)>| {
            let (lo, hi) = mine.unwrap_or((f64::INFINITY, f64::NEG_INFINITY));
            let round = stream_round(lo, hi, mine.is_none(), false);
            match round {
                Round {
                    failed: false,
                    any_done: false,
                    ..
                } => Ok((round.lo, round.hi)),
                _ => Err(Error::Elsewhere("streaming the volume".into())),
            }
        })
    }

    /// Ends this rank's part in the streaming agreement (`range_across`),
    /// whatever its load did: rounds until every rank has ended its part.
    /// A rank still streaming meets these rounds as a failure elsewhere,
    /// stops, and ends its part too. Every rank calls it once, after its
    /// load.
    pub fn end_streams(&self, failed: bool) {
        while !stream_round(f64::INFINITY, f64::NEG_INFINITY, failed, true).all_done {}
    }

    /// Waits for every rank.
    pub fn barrier(&self) {
        // SAFETY: a collective without arguments.
        unsafe { lacuna_mpi_barrier() };
    }

    /// Every rank's `values` (the same count on each), in rank order, on
    /// rank 0; empty elsewhere.
    pub fn gather(&self, values: &[f64]) -> Vec<f64> {
        let mut out = vec![
            0.0;
            if self.rank == 0 {
                values.len() * self.size as usize
            } else {
                1
            }
        ];
        // SAFETY: out holds n * size values on rank 0, the only one that writes it.
        unsafe { lacuna_mpi_gather(values.as_ptr(), values.len() as c_int, out.as_mut_ptr()) };
        if self.rank == 0 {
            out
        } else {
            Vec::new()
        }
    }

    /// Composites every rank's premultiplied `pixels` (`width` x `height`,
    /// one layout on every rank) with IceT's ordered blend, `order` front
    /// to back. Rank 0 gets the frame's pixels and the compositing's
    /// milliseconds; the others `None`. Every rank must call it.
    pub fn composite(
        &self,
        (width, height): (u32, u32),
        pixels: &[[f32; 4]],
        order: &[u32],
    ) -> Result<(Option<Vec<[f32; 4]>>, f64)> {
        if pixels.len() != width as usize * height as usize || order.len() != self.size as usize {
            return Err(Error::invalid(
                "composite",
                format!("{} pixels, {} ranks ordered", pixels.len(), order.len()),
                format!("expected {width}x{height} pixels and {} ranks", self.size),
            ));
        }
        let order: Vec<c_int> = order.iter().map(|&r| r as c_int).collect();
        let mut out = vec![[0.0f32; 4]; if self.rank == 0 { pixels.len() } else { 1 }];
        let mut ms = 0.0;
        // SAFETY: pixels and out hold width * height RGBA floats (out on rank
        // 0, the only one the shim writes); order holds one entry per rank.
        let error = unsafe {
            lacuna_icet_composite(
                width as c_int,
                height as c_int,
                pixels.as_ptr().cast(),
                order.as_ptr(),
                out.as_mut_ptr().cast(),
                &mut ms,
            )
        };
        if error != 0 {
            return Err(Error::invalid(
                "IceT",
                "icetCompositeImage",
                format!("failed with error {error:#x}"),
            ));
        }
        Ok(((self.rank == 0).then_some(out), ms))
    }

    /// Keeps, per pixel, the colour of the rank whose ray value (`values`,
    /// `FrameDesc::writes_ray_values`) is the largest (`largest`: MIP) or
    /// the smallest (MinIP; an iso frame's surface depth), as `super::pick`
    /// does on one machine: the one process's frame bit for bit. Rank 0 gets the frame's
    /// pixels and the milliseconds; the others `None`. Every rank must call
    /// it.
    pub fn pick(
        &self,
        (width, height): (u32, u32),
        pixels: &[[f32; 4]],
        values: &[f32],
        largest: bool,
    ) -> Result<(Option<Vec<[f32; 4]>>, f64)> {
        let n = width as usize * height as usize;
        if pixels.len() != n || values.len() != n {
            return Err(Error::invalid(
                "composite",
                format!("{} pixels and {} values", pixels.len(), values.len()),
                format!("expected {width}x{height} of each"),
            ));
        }
        let mut out = vec![[0.0f32; 4]; if self.rank == 0 { n } else { 1 }];
        let mut ms = 0.0;
        // SAFETY: pixels, values and out hold n pixels (out on rank 0, the
        // only one MPI_Reduce writes); every rank passes the same n.
        let status = unsafe {
            lacuna_mpi_pick(
                n as c_int,
                values.as_ptr(),
                largest as c_int,
                pixels.as_ptr().cast(),
                out.as_mut_ptr().cast(),
                &mut ms,
            )
        };
        if status != 0 {
            return Err(Error::invalid(
                "composite",
                format!("{width}x{height} ray values"),
                "could not allocate the reduction's buffers on every rank",
            ));
        }
        Ok(((self.rank == 0).then_some(out), ms))
    }
}

/// How a rank's part ended (`World::first_failed`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Failed {
    No,
    /// Its own error.
    Own,
    /// Because another rank failed (`Error::Elsewhere`).
    Elsewhere,
}

/// One round of the streaming agreement, as every rank sees it.
struct Round {
    lo: f64,
    hi: f64,
    failed: bool,
    any_done: bool,
    all_done: bool,
}

fn stream_round(lo: f64, hi: f64, failed: bool, done: bool) -> Round {
    let mut out = [0.0; 5];
    // SAFETY: a collective over plain doubles (MPI is initialized while a
    // World lives); out holds five.
    unsafe { lacuna_mpi_stream_round(lo, hi, failed as c_int, done as c_int, out.as_mut_ptr()) };
    Round {
        lo: out[0],
        hi: out[1],
        failed: out[2] != 0.0,
        any_done: out[3] != 0.0,
        all_done: out[4] != 0.0,
    }
}

impl Drop for World {
    fn drop(&mut self) {
        // A panic unwinding past the ranks' agreement would leave the others
        // waiting in a collective, and MPI_Finalize waiting for them: abort
        // the job instead.
        if std::thread::panicking() {
            // SAFETY: ends the process and every rank.
            unsafe { lacuna_mpi_abort(70) };
        }
        // SAFETY: once per process, after every collective.
        unsafe { lacuna_mpi_finalize() };
    }
}
