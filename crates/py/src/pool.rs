//! Threads that live as long as a vector env and step its matches.
//!
//! A [`Pool`] owns a fixed set of items (the env's match slots), each
//! behind its own mutex, and one job to run on an item. [`Pool::run`] runs
//! the job once on every item: the calling thread and the pool's workers
//! each take the next item nobody has taken until none is left, and `run`
//! returns when all are done. The workers are started once, with the pool,
//! and wait on a condition variable between runs; dropping the pool tells
//! them to stop and joins them.
//!
//! Which thread runs which item changes nothing but speed: the job on an
//! item touches that item alone. The caller takes items from the front,
//! the workers from the back, so on a quiet machine each item mostly stays
//! on the same thread from run to run (its match stays in that core's
//! cache), and on a busy one a worker that is not scheduled in time leaves
//! its share to the caller instead of holding up the run (a thread started
//! for every run, or a fixed share per thread, waits for the slowest).
//!
//! A panic in the job ends that item's run only: it is caught where it
//! happened, in a worker or in the caller, the other items are finished,
//! and `run` returns the panic's message. The item may be half-updated.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;

/// The job every run applies to each item.
type Job<T> = Box<dyn Fn(&mut T) + Send + Sync>;

/// `threads` threads (the caller and `threads - 1` workers) running one job
/// over the same items, again and again.
pub struct Pool<T: Send + 'static> {
    shared: Arc<Shared<T>>,
    workers: Vec<JoinHandle<()>>,
}

struct Shared<T> {
    items: Vec<Mutex<T>>,
    job: Job<T>,
    round: Mutex<Round>,
    /// Signalled when a run starts and when the pool is dropped.
    start: Condvar,
    /// Signalled when a run's last item is done, and when a worker starts.
    done: Condvar,
}

/// The current run: items `front..back` are not taken yet (the caller
/// takes from the front, workers from the back); between runs the range
/// is empty and `done` is the number of items.
struct Round {
    front: usize,
    back: usize,
    done: usize,
    /// The first panic of this run.
    panic: Option<String>,
    /// Workers that have started.
    started: usize,
    shutdown: bool,
}

impl<T: Send + 'static> Pool<T> {
    /// The pool over `items`, with `threads - 1` workers (at least none, at
    /// most one fewer than the items: the caller is the other thread).
    pub fn new(
        items: Vec<T>,
        threads: usize,
        job: impl Fn(&mut T) + Send + Sync + 'static,
    ) -> std::io::Result<Pool<T>> {
        let n = items.len();
        let shared = Arc::new(Shared {
            items: items.into_iter().map(Mutex::new).collect(),
            job: Box::new(job),
            round: Mutex::new(Round {
                front: n,
                back: n,
                done: n,
                panic: None,
                started: 0,
                shutdown: false,
            }),
            start: Condvar::new(),
            done: Condvar::new(),
        });
        let workers = threads.clamp(1, n.max(1)) - 1;
        let mut pool = Pool {
            shared,
            workers: Vec::with_capacity(workers),
        };
        for k in 0..workers {
            let shared = Arc::clone(&pool.shared);
            // On an error `pool` is dropped here, which stops the workers
            // already started.
            let handle = std::thread::Builder::new()
                .name(format!("naosoccer-step-{}", k + 1))
                .spawn(move || shared.work())?;
            pool.workers.push(handle);
        }
        // Returns with every worker running (and named, which the thread
        // does first): the pool's threads are there from here on.
        let mut r = pool.shared.round();
        while r.started < workers {
            r = pool
                .shared
                .done
                .wait(r)
                .unwrap_or_else(PoisonError::into_inner);
        }
        drop(r);
        Ok(pool)
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.shared.items.len()
    }

    /// Whether the pool has no items.
    pub fn is_empty(&self) -> bool {
        self.shared.items.is_empty()
    }

    /// Worker threads (the caller of [`Pool::run`] is one more).
    pub fn workers(&self) -> usize {
        self.workers.len()
    }

    /// Item `i`, for the caller to read or change between runs.
    pub fn lock(&self, i: usize) -> MutexGuard<'_, T> {
        // A job's panic is caught inside the item's lock, so the lock is
        // never poisoned; the item's state is `run`'s caller's to judge.
        self.shared.items[i]
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
    }

    /// Runs the job once on every item, this thread taking its share;
    /// `Err` holds the message of the first panic (every other item's job
    /// still ran).
    pub fn run(&mut self) -> Result<(), String> {
        let s = &*self.shared;
        let n = s.items.len();
        {
            let mut r = s.round();
            r.front = 0;
            r.back = n;
            r.done = 0;
            r.panic = None;
        }
        if !self.workers.is_empty() {
            s.start.notify_all();
        }
        let mut r = s.take_items(s.round(), true);
        while r.done < n {
            r = s.done.wait(r).unwrap_or_else(PoisonError::into_inner);
        }
        match r.panic.take() {
            Some(message) => Err(message),
            None => Ok(()),
        }
    }
}

impl<T> Shared<T> {
    fn round(&self) -> MutexGuard<'_, Round> {
        // Nothing panics while holding it (the job runs outside it).
        self.round.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Runs the job on items not taken yet, from the front or the back,
    /// until none is left; takes and returns the round's lock.
    fn take_items<'a>(
        &'a self,
        mut r: MutexGuard<'a, Round>,
        front: bool,
    ) -> MutexGuard<'a, Round> {
        while r.front < r.back {
            let i = if front {
                r.front += 1;
                r.front - 1
            } else {
                r.back -= 1;
                r.back
            };
            drop(r);
            let outcome = {
                let mut item = self.items[i].lock().unwrap_or_else(PoisonError::into_inner);
                catch_unwind(AssertUnwindSafe(|| (self.job)(&mut item)))
            };
            r = self.round();
            r.done += 1;
            if let Err(payload) = outcome {
                r.panic.get_or_insert_with(|| panic_message(&*payload));
            }
            if r.done == self.items.len() {
                self.done.notify_one();
            }
        }
        r
    }

    /// A worker's life: take items from the back while a run has any, wait
    /// for the next run, stop when the pool is dropped.
    fn work(&self) {
        let mut r = self.round();
        r.started += 1;
        self.done.notify_all();
        loop {
            r = self.take_items(r, false);
            if r.shutdown {
                return;
            }
            r = self.start.wait(r).unwrap_or_else(PoisonError::into_inner);
        }
    }
}

impl<T: Send + 'static> Drop for Pool<T> {
    fn drop(&mut self) {
        self.shared.round().shutdown = true;
        self.shared.start.notify_all();
        for w in self.workers.drain(..) {
            // A worker catches the job's panics; it cannot end in one.
            let _ = w.join();
        }
    }
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Every run applies the job to every item exactly once, whatever the
    /// number of threads.
    #[test]
    fn each_run_does_every_item_once() {
        for threads in [1, 2, 3, 8] {
            let mut pool = Pool::new(vec![0u64; 5], threads, |x: &mut u64| *x += 1).unwrap();
            assert_eq!(pool.workers(), threads.min(5) - 1);
            for _ in 0..200 {
                pool.run().unwrap();
            }
            for i in 0..pool.len() {
                assert_eq!(*pool.lock(i), 200, "threads {threads}, item {i}");
            }
        }
    }

    /// A panic is reported by `run` as its message, the other items still
    /// run, and the pool goes on working.
    #[test]
    fn a_panic_is_returned_and_the_pool_goes_on() {
        for threads in [1, 2] {
            let mut pool = Pool::new(vec![0u32; 4], threads, |x: &mut u32| {
                *x += 1;
                if *x == 2 {
                    panic!("item at two");
                }
            })
            .unwrap();
            pool.run().unwrap();
            *pool.lock(3) = 5;
            assert_eq!(pool.run(), Err("item at two".to_owned()));
            assert_eq!(*pool.lock(3), 6, "the items that did not panic ran");
            pool.run().unwrap();
            assert_eq!(
                (0..4).map(|i| *pool.lock(i)).collect::<Vec<_>>(),
                [3, 3, 3, 7]
            );
        }
    }

    /// Dropping the pool stops and joins its workers: the job's captures,
    /// held by the workers, are released by the time `drop` returns.
    #[test]
    fn dropping_the_pool_joins_its_workers() {
        let alive = Arc::new(AtomicUsize::new(0));
        let held = Arc::clone(&alive);
        let mut pool = Pool::new(vec![(); 4], 4, move |_: &mut ()| {
            held.fetch_add(1, Ordering::Relaxed);
        })
        .unwrap();
        assert_eq!(pool.workers(), 3);
        pool.run().unwrap();
        assert_eq!(alive.load(Ordering::Relaxed), 4);
        assert_eq!(Arc::strong_count(&alive), 2);
        drop(pool);
        assert_eq!(Arc::strong_count(&alive), 1);
    }
}
