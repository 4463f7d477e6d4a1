//! Two persistent worker threads for the concurrent benches (`benches/hashgrid.rs`,
//! `examples/speed.rs`), as a renderer's thread pool has them.
//!
//! The workers are spawned once (`std::thread::scope`) and park on a [`Barrier`] between
//! runs, so no thread is spawned or joined inside a timed run. Each run is prepared the same
//! way for 1 and 2 working threads:
//!
//! 1. `reset` on the calling thread (e.g. emptying the table), untimed;
//! 2. the calling thread wakes both workers (barrier);
//! 3. *eviction*, untimed: each of the two workers streams through its own
//!    [`EVICT_BYTES`] buffer, so neither core's private L2 still holds the table: whatever
//!    the run touches comes from the shared L3 or memory, whichever worker touches it;
//! 4. the two workers meet (a short spin on an atomic counter, as a pool's awake workers
//!    hand over work), so both are running when the timed part begins;
//! 5. the timed run: worker `w < threads` calls `work(w, threads)`; the other one goes back
//!    to the barrier.
//!
//! The time of a run is measured by the workers themselves: from the earliest start of a
//! working worker to the latest end (`Instant`s taken around `work`). Waking a parked thread
//! (tens of µs on a VM whose idle vCPU must be woken by an interrupt) is therefore not timed,
//! for 1 and 2 threads alike; a second worker that starts late still is.

#![allow(dead_code)]

use std::hint::black_box;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Barrier, Mutex};
use std::time::{Duration, Instant};

/// Bytes each worker streams through before a run: twice a core's 1 MiB L2 on the machine
/// the numbers were taken on, enough to push the table out of it.
pub const EVICT_BYTES: usize = 2 << 20;

const STOP: usize = 0;
/// `RUN + threads`.
const RUN: usize = 1;

/// The handle the caller drives the workers with (see [`with_workers`]).
pub struct Workers<'a> {
    start: &'a Barrier,
    done: &'a Barrier,
    cmd: &'a AtomicUsize,
    spans: &'a [Mutex<Option<(Instant, Instant)>>; 2],
}

impl Workers<'_> {
    fn step(&self, cmd: usize) {
        self.cmd.store(cmd, Ordering::Release);
        self.start.wait();
        self.done.wait();
    }

    /// One run with `threads` (1 or 2) working workers after the untimed `reset` and
    /// eviction; returns its duration (first start to last end of the working workers).
    pub fn run(&self, threads: usize, reset: impl FnOnce()) -> Duration {
        assert!((1..=2).contains(&threads));
        reset();
        for s in self.spans {
            *s.lock().unwrap() = None;
        }
        self.step(RUN + threads);
        let spans: Vec<(Instant, Instant)> = self
            .spans
            .iter()
            .filter_map(|s| *s.lock().unwrap())
            .collect();
        let first = spans.iter().map(|s| s.0).min().unwrap();
        let last = spans.iter().map(|s| s.1).max().unwrap();
        last - first
    }
}

/// Runs `body` with two parked workers that execute `work(worker, threads)` on each
/// [`Workers::run`]; the workers end when `body` returns.
pub fn with_workers<R>(
    work: impl Fn(usize, usize) + Sync,
    body: impl FnOnce(&Workers<'_>) -> R,
) -> R {
    let start = Barrier::new(3);
    let done = Barrier::new(3);
    let cmd = AtomicUsize::new(STOP);
    let spans = [Mutex::new(None), Mutex::new(None)];
    let arrived = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for w in 0..2 {
            let (start, done, cmd, spans, work, arrived) =
                (&start, &done, &cmd, &spans, &work, &arrived);
            s.spawn(move || {
                let mut buffer = vec![0_u8; EVICT_BYTES];
                let mut round = 0;
                loop {
                    start.wait();
                    let c = cmd.load(Ordering::Acquire);
                    if c == STOP {
                        break;
                    }
                    for b in buffer.iter_mut().step_by(64) {
                        *b = b.wrapping_add(1);
                    }
                    black_box(&mut buffer);
                    // Meet the other worker: each adds 1 per run, so after run `round` the
                    // counter reaches 2 · (round + 1).
                    round += 1;
                    arrived.fetch_add(1, Ordering::AcqRel);
                    let mut spins = 0_u32;
                    while arrived.load(Ordering::Acquire) < 2 * round {
                        spins += 1;
                        if spins < 1 << 16 {
                            std::hint::spin_loop();
                        } else {
                            std::thread::yield_now();
                        }
                    }
                    let threads = c - RUN;
                    if w < threads {
                        let t0 = Instant::now();
                        work(w, threads);
                        *spans[w].lock().unwrap() = Some((t0, Instant::now()));
                    }
                    done.wait();
                }
            });
        }
        let workers = Workers {
            start: &start,
            done: &done,
            cmd: &cmd,
            spans: &spans,
        };
        let r = body(&workers);
        cmd.store(STOP, Ordering::Release);
        start.wait();
        r
    })
}

/// The `w`-th of `threads` contiguous shares of `items`.
pub fn share<T>(items: &[T], w: usize, threads: usize) -> &[T] {
    let chunk = items.len().div_ceil(threads);
    let lo = (w * chunk).min(items.len());
    &items[lo..(lo + chunk).min(items.len())]
}
