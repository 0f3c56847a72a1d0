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
