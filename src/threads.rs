//! The thread budget of one build: how many threads its pools (step chunks,
//! the support check, the planner) may use together. `-j` sets it; nothing
//! below the command line asks the machine for more.

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
    /// starts at item `start`) on up to this many scoped threads, or on the
    /// caller's alone below `min` items. For work whose every item is
    /// computed the same way wherever the split falls.
    pub fn chunks<T: Send>(self, items: &mut [T], min: usize, f: impl Fn(usize, &mut [T]) + Sync) {
        let n = items.len();
        let threads = if n < min { 1 } else { self.get() };
        if threads <= 1 {
            return f(0, items);
        }
        let size = n.div_ceil(threads);
        std::thread::scope(|s| {
            let f = &f;
            let mut rest = items;
            let mut start = 0;
            while rest.len() > size {
                let (chunk, tail) = rest.split_at_mut(size);
                s.spawn(move || f(start, chunk));
                start += size;
                rest = tail;
            }
            f(start, rest); // the last chunk on the caller's thread
        });
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
}
