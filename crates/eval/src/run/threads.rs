//! The threads that step a batch of matches: the same for an evaluation's
//! [`super::Batch`], the learning crate's vectorised environment and the
//! Python package's vector env.
//!
//! A [`Stepper`] of one thread runs every item on the caller's thread, in
//! order. With more, the caller and a rayon pool of workers, started once
//! and kept for the stepper's life, share the items, each taking the next
//! one nobody has taken ([`Stepper::for_each`]). Each item is one match (or
//! one match's share of the outputs) and touches nothing else, so which
//! thread steps which match changes no result: the thread count changes
//! speed only.

use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::thread::JoinHandle;

/// Threads stepping the items of a batch, tick after tick. Dropping it
/// stops its workers and waits for them to end.
pub struct Stepper {
    /// The workers beside the caller (`None`: one thread, the caller's).
    pool: Option<rayon::ThreadPool>,
    /// The workers' threads, joined when the stepper is dropped.
    workers: Vec<JoinHandle<()>>,
    threads: usize,
}

impl Stepper {
    /// `threads` threads (at least one), the caller's included: beyond it,
    /// a pool of `threads - 1` named workers (`naosoccer-step-1`, ...)
    /// started now.
    pub fn new(threads: usize) -> std::io::Result<Stepper> {
        let threads = threads.max(1);
        let (pool, workers) = if threads == 1 {
            (None, Vec::new())
        } else {
            let (pool, workers) = joined_pool(threads - 1)?;
            (Some(pool), workers)
        };
        Ok(Stepper {
            pool,
            workers,
            threads,
        })
    }

    /// The threads stepping items, the caller's included.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Runs `step` on every item; returns when all are done. A panic in
    /// `step` reaches the caller once every other item's step has ended.
    pub fn for_each<T: Send>(&self, items: &mut [T], step: impl Fn(&mut T) + Sync) {
        match &self.pool {
            None => items.iter_mut().for_each(step),
            Some(pool) => self.share(pool, items.iter_mut(), step, || {}),
        }
    }

    /// `step` of every work item (each typically a match and its share of
    /// the batch's output buffers), its results in the items' order.
    pub fn map<W: Send, R: Send>(&self, work: Vec<W>, step: impl Fn(W) -> R + Sync) -> Vec<R> {
        self.map_beside(work, step, || {})
    }

    /// [`Stepper::map`], the caller's thread running `beside` first while
    /// the workers start on the items (the caller's own work that the
    /// items do not wait for), then taking its share of them.
    pub fn map_beside<W: Send, R: Send>(
        &self,
        work: Vec<W>,
        step: impl Fn(W) -> R + Sync,
        beside: impl FnOnce(),
    ) -> Vec<R> {
        match &self.pool {
            None => {
                beside();
                work.into_iter().map(step).collect()
            }
            Some(pool) => {
                let mut out: Vec<Option<R>> = work.iter().map(|_| None).collect();
                let items = work.into_iter().zip(out.iter_mut());
                self.share(pool, items, |(w, r)| *r = Some(step(w)), beside);
                out.into_iter()
                    .map(|r| r.expect("every item was stepped"))
                    .collect()
            }
        }
    }

    /// The caller and the workers each take the next item nobody has
    /// taken, the caller from the front, the workers from the back, until
    /// none is left: on a quiet machine an item mostly stays on the same
    /// thread from tick to tick, and on a busy one a worker the machine
    /// does not run in time leaves its share to the others instead of
    /// holding up the tick.
    fn share<I>(
        &self,
        pool: &rayon::ThreadPool,
        items: I,
        step: impl Fn(I::Item) + Sync,
        beside: impl FnOnce(),
    ) where
        I: DoubleEndedIterator + Send,
    {
        let items = Mutex::new(items);
        let take = |front: bool| loop {
            let next = {
                let mut items = items.lock().unwrap_or_else(PoisonError::into_inner);
                if front {
                    items.next()
                } else {
                    items.next_back()
                }
            };
            match next {
                Some(item) => step(item),
                None => break,
            }
        };
        pool.in_place_scope(|s| {
            for _ in 1..self.threads {
                s.spawn(|_| take(false));
            }
            beside();
            take(true);
        });
    }
}

/// A rayon pool of `n` named workers, returned once every one of them is
/// running, and the workers' threads. rayon's own threads end some time
/// after the pool is dropped; these can be joined, so that a closed Python
/// env has none left.
fn joined_pool(n: usize) -> std::io::Result<(rayon::ThreadPool, Vec<JoinHandle<()>>)> {
    let mut workers = Vec::new();
    // Workers that have started (and are named: a thread names itself
    // before it runs its closure).
    let started = Arc::new((Mutex::new(0usize), Condvar::new()));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("naosoccer-step-{}", i + 1))
        .spawn_handler(|worker| {
            let mut b = std::thread::Builder::new();
            if let Some(name) = worker.name() {
                b = b.name(name.to_owned());
            }
            if let Some(size) = worker.stack_size() {
                b = b.stack_size(size);
            }
            let started = Arc::clone(&started);
            workers.push(b.spawn(move || {
                *started.0.lock().unwrap_or_else(PoisonError::into_inner) += 1;
                started.1.notify_all();
                worker.run()
            })?);
            Ok(())
        })
        .build()
        // The pool stops the workers it started when it fails.
        .map_err(std::io::Error::other)?;
    let (count, cv) = &*started;
    let mut running = count.lock().unwrap_or_else(PoisonError::into_inner);
    while *running < workers.len() {
        running = cv.wait(running).unwrap_or_else(PoisonError::into_inner);
    }
    drop(running);
    Ok((pool, workers))
}

impl Drop for Stepper {
    fn drop(&mut self) {
        drop(self.pool.take());
        for w in self.workers.drain(..) {
            // A worker's panics are caught by rayon; it ends when told to.
            let _ = w.join();
        }
    }
}

impl std::fmt::Debug for Stepper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stepper")
            .field("threads", &self.threads)
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::panic::AssertUnwindSafe;

    /// Every item is stepped once a run, whatever the threads; `map`
    /// keeps the items' order.
    #[test]
    fn every_item_once_in_order() {
        for threads in [1, 2, 3, 8] {
            let stepper = Stepper::new(threads).unwrap();
            assert_eq!(stepper.threads(), threads);
            let mut items = vec![0u64; 5];
            for _ in 0..100 {
                stepper.for_each(&mut items, |x| *x += 1);
            }
            assert_eq!(items, [100; 5], "threads {threads}");
            let squares = stepper.map((0..7u64).collect(), |x| x * x);
            assert_eq!(squares, [0, 1, 4, 9, 16, 25, 36], "threads {threads}");
        }
    }

    /// `map_beside` runs its caller's work once, on the caller's thread,
    /// and steps every item as `map` does.
    #[test]
    fn the_callers_work_beside_the_items() {
        for threads in [1, 2, 3] {
            let stepper = Stepper::new(threads).unwrap();
            let caller = std::thread::current().id();
            let mut ran = Vec::new();
            let squares = stepper.map_beside(
                (0..9u64).collect(),
                |x| x * x,
                || ran.push(std::thread::current().id()),
            );
            assert_eq!(
                squares,
                [0, 1, 4, 9, 16, 25, 36, 49, 64],
                "threads {threads}"
            );
            assert_eq!(ran, [caller], "threads {threads}");
        }
    }

    /// Dropping the stepper ends its workers: none is left after `drop`.
    #[test]
    fn dropping_the_stepper_ends_its_workers() {
        let alive = std::sync::Arc::new(());
        let stepper = Stepper::new(3).unwrap();
        let mut items = vec![0u8; 6];
        let held = std::sync::Arc::clone(&alive);
        // Every worker keeps a clone of `alive` in a thread-local until it
        // ends.
        thread_local!(static HOLD: std::cell::RefCell<Option<std::sync::Arc<()>>> = const { std::cell::RefCell::new(None) });
        stepper.for_each(&mut items, |x| {
            *x += 1;
            HOLD.with(|h| *h.borrow_mut() = Some(std::sync::Arc::clone(&held)));
        });
        HOLD.with(|h| *h.borrow_mut() = None);
        drop(held);
        drop(stepper);
        assert_eq!(
            std::sync::Arc::strong_count(&alive),
            1,
            "every worker ended"
        );
    }

    /// A panic in a step reaches the caller, and the stepper works on.
    #[test]
    fn a_panic_reaches_the_caller() {
        for threads in [1, 2] {
            let stepper = Stepper::new(threads).unwrap();
            let mut items = vec![0u32; 4];
            let r = std::panic::catch_unwind(AssertUnwindSafe(|| {
                stepper.for_each(&mut items, |x| {
                    if *x == 0 {
                        panic!("item at zero")
                    }
                })
            }));
            assert!(r.is_err(), "threads {threads}");
            stepper.for_each(&mut items, |x| *x = 7);
            assert_eq!(items, [7; 4]);
        }
    }
}
