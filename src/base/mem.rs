//! Big vectors faulted in ahead: the first touch of fresh memory costs a
//! page fault per 4 KiB page; asking the system to fill a big range at once
//! (`MADV_POPULATE_WRITE`, Linux 5.14) makes the same pages with one call
//! (docs/performance.md has the figures). Only advice: the contents, and so
//! every output, are the same with or without it. Huge pages
//! (`MADV_HUGEPAGE`) are not asked for: their cost depends on how the host
//! backs free memory.

/// Bytes from which a range is faulted in ahead.
const AHEAD_MIN: usize = 1 << 20;

/// A vector with room for `n` items, its memory faulted in ahead when it is
/// big: for a vector about to be filled.
pub(crate) fn with_capacity<T>(n: usize) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    fault_in(v.spare_capacity_mut());
    v
}

/// Faults in the pages of `items` ahead when they span at least
/// [`AHEAD_MIN`] bytes (memory about to be written).
pub(crate) fn fault_in<T>(items: &mut [T]) {
    populate(items.as_mut_ptr() as usize, std::mem::size_of_val(items));
}

/// Asks the system to make the whole pages inside `len` bytes at `addr`
/// (memory of this process's own allocation) writable at once.
#[cfg(target_os = "linux")]
fn populate(addr: usize, len: usize) {
    const PAGE: usize = 4096;
    /// `MADV_POPULATE_WRITE` (Linux 5.14; older kernels refuse it: EINVAL).
    const POPULATE_WRITE: libc::c_int = 23;
    if len < AHEAD_MIN {
        return;
    }
    let start = addr.next_multiple_of(PAGE);
    let end = (addr + len) / PAGE * PAGE;
    if end > start {
        // SAFETY: the range lies inside memory this process owns (the
        // slice's); MADV_POPULATE_WRITE faults its pages in as a write
        // would, changing no contents; a failure leaves them to fault later
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, POPULATE_WRITE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
fn populate(_addr: usize, _len: usize) {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_big_vector_holds_what_is_written() {
        let n = 3 * (AHEAD_MIN / 8) + 5;
        let mut v: Vec<u64> = with_capacity(n);
        assert!(v.capacity() >= n);
        v.extend((0..n as u64).map(|k| k * 7));
        assert!(v.iter().enumerate().all(|(k, &x)| x == 7 * k as u64));
        let small: Vec<u8> = with_capacity(10);
        assert!(small.capacity() >= 10);
    }

    #[test]
    fn faulting_in_keeps_the_contents() {
        let mut v: Vec<u32> = (0..(AHEAD_MIN as u32)).collect();
        fault_in(&mut v[3..]);
        assert!(v.iter().enumerate().all(|(k, &x)| x == k as u32));
    }
}
