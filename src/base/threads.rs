//! The thread budget of one build: how many threads its pools (step chunks,
//! the support check, the planner) may use together. `-j` sets it; nothing
//! below the command line asks the machine for more.
//!
//! Chunks run on rayon's pool of parked workers ([`warm`] starts it with the
//! command's `-j`): on a 2-core machine a newly spawned thread often waited
//! for the core of the thread that spawned it, 1.3 ms at the median and up
//! to a scheduler slice (3 ms), while a parked worker wakes in microseconds.
//! Which thread runs a chunk never changes what it computes.

/// Starts the pool of `n` worker threads the chunks run on (once per
/// process: later calls, and calls after the pool has started, change
/// nothing). Without it the pool starts at its first use, one worker per
/// core.
pub fn warm(n: usize) {
    let built = rayon::ThreadPoolBuilder::new()
        .num_threads(n.max(1))
        .thread_name(|k| format!("p3dp-worker-{k}"))
        .build_global();
    if built.is_ok() {
        // every worker to run once, soon, not waited for: a new thread may
        // sit on this one's core until it blocks, while a worker that has
        // run and sleeps is woken on an idle core (waiting for them here
        // took 3-4 ms when the other core was halted)
        rayon::spawn_broadcast(|_| ());
    }
}

/// How many threads one build may use; at least 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Threads(usize);

impl Threads {
    /// One thread: everything runs inline on the caller's.
    pub const ONE: Threads = Threads(1);

    /// A budget of `n` threads (0 is taken as 1).
    pub fn new(n: usize) -> Threads {
        Threads(n.max(1))
    }

    /// One thread per core the machine offers (1 when that is unknown).
    pub fn available() -> Threads {
        Threads::new(std::thread::available_parallelism().map_or(1, |n| n.get()))
    }

    /// The number of threads, ≥ 1.
    pub fn get(self) -> usize {
        self.0
    }

    /// Whether a second thread may run beside the caller's.
    pub fn parallel(self) -> bool {
        self.0 >= 2
    }
}

impl Threads {
    /// Calls `f(start, chunk)` on consecutive chunks of `items` (chunk j
    /// starts at item `start`) on up to this many threads (the pool's and
    /// the caller's), or on the caller's alone below `min` items. For work
    /// whose every item is computed the same way wherever the split falls.
    pub fn chunks<T: Send>(self, items: &mut [T], min: usize, f: impl Fn(usize, &mut [T]) + Sync) {
        let n = items.len();
        let threads = if n < min { 1 } else { self.get() };
        if threads <= 1 {
            return f(0, items);
        }
        let size = n.div_ceil(threads);
        // a panic in a chunk is raised here once all have ended
        rayon::in_place_scope(|s| {
            let f = &f;
            let mut rest = items;
            let mut start = 0;
            while rest.len() > size {
                let (chunk, tail) = rest.split_at_mut(size);
                s.spawn(move |_| f(start, chunk));
                start += size;
                rest = tail;
            }
            f(start, rest); // the last chunk on the caller's thread
        });
    }
}

impl Threads {
    /// A vector of `len` items, item k = `f(k)`, made in chunks on up to this
    /// many threads (on the caller's alone below `min` items). Each chunk
    /// writes its items straight into the vector's memory, so its first
    /// touch (the page faults of a big vector) is shared out too.
    pub fn fill_vec<T: Send>(
        self,
        len: usize,
        min: usize,
        f: impl Fn(usize) -> T + Sync,
    ) -> Vec<T> {
        let f = &f;
        self.fill_vec_with(len, min, |start| {
            let mut k = start;
            move || {
                k += 1;
                f(k - 1)
            }
        })
    }

    /// [`Threads::fill_vec`] where a chunk's items come from one generator:
    /// `make(start)` gives the items from index `start` on, one per call
    /// (for items that follow from the one before more cheaply).
    pub fn fill_vec_with<T: Send, G: FnMut() -> T>(
        self,
        len: usize,
        min: usize,
        make: impl Fn(usize) -> G + Sync,
    ) -> Vec<T> {
        let mut v: Vec<T> = Vec::with_capacity(len);
        self.chunks(&mut v.spare_capacity_mut()[..len], min, |start, chunk| {
            crate::base::mem::fault_in(chunk);
            let mut next = make(start);
            for slot in chunk.iter_mut() {
                slot.write(next());
            }
        });
        // SAFETY: `chunks` called the closure on chunks covering items
        // 0..len exactly once each (a panic in one propagates out of
        // `chunks` once all have ended, and this line is not reached), and the closure wrote every
        // slot of its chunk: all `len` items are initialised.
        unsafe { v.set_len(len) };
        v
    }
}

/// A pool worker kept busy until [`Awake::release`] (or drop, or a few
/// milliseconds at most), so that its core is still awake when work comes:
/// in a virtual machine an idle core is halted, and the system then wakes a
/// worker for new work on the busy core of the thread that posts it, where
/// it waited up to a scheduler slice (3 ms). The worker yields between
/// checks, so it never takes a core another thread wants.
#[derive(Debug)]
pub struct Awake(std::sync::Arc<std::sync::atomic::AtomicBool>);

impl Awake {
    /// The longest a worker is kept.
    const MAX: std::time::Duration = std::time::Duration::from_millis(5);

    /// Keeps a worker of the pool busy, when the budget has a second thread.
    pub fn keep(threads: Threads) -> Option<Awake> {
        if !threads.parallel() {
            return None;
        }
        let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let flag = done.clone();
        rayon::spawn(move || {
            let until = std::time::Instant::now() + Awake::MAX;
            while !flag.load(std::sync::atomic::Ordering::Acquire)
                && std::time::Instant::now() < until
            {
                std::thread::yield_now();
            }
        });
        Some(Awake(done))
    }

    /// Lets the worker go (to the work just posted).
    pub fn release(&self) {
        self.0.store(true, std::sync::atomic::Ordering::Release);
    }
}

impl Drop for Awake {
    fn drop(&mut self) {
        self.release();
    }
}

impl Default for Threads {
    /// [`Threads::available`].
    fn default() -> Threads {
        Threads::available()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn at_least_one() {
        assert_eq!(Threads::new(0).get(), 1);
        assert_eq!(Threads::new(3).get(), 3);
        assert!(!Threads::ONE.parallel());
        assert!(Threads::new(2).parallel());
        assert!(Threads::available().get() >= 1);
    }

    #[test]
    fn a_worker_kept_awake_is_let_go() {
        assert!(Awake::keep(Threads::ONE).is_none());
        // kept, then released: the pool's workers all take work again
        // (a broadcast waits for every one of them)
        let a = Awake::keep(Threads::new(2)).expect("two threads keep one");
        a.release();
        assert_eq!(
            rayon::broadcast(|c| c.index()).len(),
            rayon::current_num_threads()
        );
        // dropped unreleased: the same
        drop(Awake::keep(Threads::new(2)));
        assert_eq!(
            rayon::broadcast(|c| c.index()).len(),
            rayon::current_num_threads()
        );
    }

    #[test]
    fn chunks_cover_every_item_once_at_its_index() {
        for t in [1, 2, 3, 4] {
            for n in [0, 1, 7, 100, 1001] {
                let mut v = vec![0usize; n];
                Threads::new(t).chunks(&mut v, 10, |start, chunk| {
                    for (j, x) in chunk.iter_mut().enumerate() {
                        *x += start + j + 1;
                    }
                });
                let want: Vec<usize> = (1..=n).collect();
                assert_eq!(v, want, "{t} threads, {n} items");
            }
        }
    }

    #[test]
    fn filled_vectors_hold_f_of_every_index() {
        for t in [1, 2, 3, 4] {
            for n in [0, 1, 9, 1000] {
                let v = Threads::new(t).fill_vec(n, 4, |k| (k * k) as u64);
                assert_eq!(v, (0..n).map(|k| (k * k) as u64).collect::<Vec<_>>());
                let s = Threads::new(t).fill_vec(n, 4, |k| k.to_string());
                assert!(s.len() == n && s.iter().enumerate().all(|(k, x)| *x == k.to_string()));
            }
        }
    }
}
