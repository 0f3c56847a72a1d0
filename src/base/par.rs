//! Data parallelism for the domain code: a few functions that split work over
//! the thread pool the application installed (`app::pipeline` runs every
//! command inside one pool of `-j` threads), or run it inline when called
//! outside one, or below a size where splitting does not pay.
//!
//! Every function here gives the same result whatever the number of threads:
//! each item is computed from its index alone (or by a generator started at
//! the chunk's first index), never from how the work was split.

/// How many threads the work of the current pool may be split over.
pub(crate) fn width() -> usize {
    rayon::current_num_threads().max(1)
}

/// Calls `f(start, chunk)` on consecutive chunks of `items` (the chunk
/// starting at item `start`), as many chunks as the pool has threads, or
/// one chunk below `min` items.
pub(crate) fn chunks<T: Send>(items: &mut [T], min: usize, f: impl Fn(usize, &mut [T]) + Sync) {
    let n = items.len();
    let threads = if n < min { 1 } else { width() };
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

/// [`chunks`] for work that can fail: each chunk stops at its own first
/// error, and the error returned is that of the earliest failing chunk, so
/// results and error are those of one thread whatever the split.
pub(crate) fn try_chunks<T: Send, E: Send + Sync>(
    items: &mut [T],
    min: usize,
    f: impl Fn(usize, &mut [T]) -> Result<(), E> + Sync,
) -> Result<(), E> {
    let n = items.len();
    let threads = if n < min { 1 } else { width() };
    if threads <= 1 {
        return f(0, items);
    }
    // the same split as `chunks`: chunk j starts at j × size
    let size = n.div_ceil(threads);
    let results: Vec<std::sync::OnceLock<Result<(), E>>> =
        (0..n.div_ceil(size)).map(|_| Default::default()).collect();
    chunks(items, 0, |start, chunk| {
        let _ = results[start / size].set(f(start, chunk));
    });
    results
        .into_iter()
        .try_for_each(|r| r.into_inner().expect("every chunk ran"))
}

/// A vector of `len` items, item k = `f(k)`, made in chunks (see
/// [`chunks`]); each chunk writes its items straight into the vector's
/// memory, so the first touch of a big vector's pages is shared out too.
pub(crate) fn fill_vec<T: Send>(len: usize, min: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let f = &f;
    fill_vec_with(len, min, |start| {
        let mut k = start;
        move || {
            k += 1;
            f(k - 1)
        }
    })
}

/// [`fill_vec`] where a chunk's items come from one generator: `make(start)`
/// gives the items from index `start` on, one per call (for items that
/// follow from the one before more cheaply).
pub(crate) fn fill_vec_with<T: Send, G: FnMut() -> T>(
    len: usize,
    min: usize,
    make: impl Fn(usize) -> G + Sync,
) -> Vec<T> {
    let mut v: Vec<T> = Vec::with_capacity(len);
    chunks(&mut v.spare_capacity_mut()[..len], min, |start, chunk| {
        crate::base::mem::fault_in(chunk);
        let mut next = make(start);
        for slot in chunk.iter_mut() {
            slot.write(next());
        }
    });
    // SAFETY: `chunks` called the closure on chunks covering items 0..len
    // exactly once each (a panic in one propagates out of `chunks` once all
    // have ended, and this line is not reached), and the closure wrote every
    // slot of its chunk: all `len` items are initialised.
    unsafe { v.set_len(len) };
    v
}

/// `f` of every item, in order, the items split over the pool.
pub(crate) fn map<T: Sync, U: Send>(items: &[T], f: impl Fn(&T) -> U + Sync + Send) -> Vec<U> {
    use rayon::prelude::*;
    if items.len() < 2 || width() == 1 {
        return items.iter().map(f).collect();
    }
    items.par_iter().map(f).collect()
}

/// Calls `f` on every item, each taken by whichever thread of the pool is
/// free (for items of uneven cost); `f` sees its item alone, so the result
/// is the same whatever the threads.
pub(crate) fn each<T: Send>(items: &mut [T], f: impl Fn(&mut T) + Sync + Send) {
    use rayon::prelude::*;
    if items.len() < 2 || width() == 1 {
        return items.iter_mut().for_each(f);
    }
    items.par_iter_mut().with_max_len(1).for_each(f);
}

/// Sorts `items` by `key` (unstable; the key computed at each comparison,
/// so it should be cheap), over the pool when it has a second thread;
/// keys must be distinct for the result to be the same whatever the threads.
pub(crate) fn sort_unstable_by_key<T: Send, K: Ord>(items: &mut [T], key: impl Fn(&T) -> K + Sync) {
    use rayon::slice::ParallelSliceMut;
    if width() > 1 {
        items.par_sort_unstable_by_key(key);
    } else {
        items.sort_unstable_by_key(key);
    }
}

/// `a()` and `b()`, side by side when the pool has a second thread.
#[allow(dead_code)] // the previews' two halves will use it
pub(crate) fn join<A: Send, B: Send>(
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    if width() == 1 {
        return (a(), b());
    }
    rayon::join(a, b)
}

/// Runs `f` in a pool of `n` threads of its own: for the tests of code that
/// splits its work, which must give the same result on any number.
#[cfg(test)]
pub(crate) fn on_threads<R: Send>(n: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .expect("a pool for a test")
        .install(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(n: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    }

    #[test]
    fn chunks_cover_every_item_once_at_its_index() {
        for t in [1, 2, 3, 4] {
            for n in [0, 1, 7, 100, 1001] {
                let mut v = vec![0usize; n];
                pool(t).install(|| {
                    chunks(&mut v, 10, |start, chunk| {
                        for (j, x) in chunk.iter_mut().enumerate() {
                            *x += start + j + 1;
                        }
                    })
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
                let (v, s) = pool(t).install(|| {
                    (
                        fill_vec(n, 4, |k| (k * k) as u64),
                        fill_vec(n, 4, |k| k.to_string()),
                    )
                });
                assert_eq!(v, (0..n).map(|k| (k * k) as u64).collect::<Vec<_>>());
                assert!(s.len() == n && s.iter().enumerate().all(|(k, x)| *x == k.to_string()));
            }
        }
    }

    #[test]
    fn map_keeps_the_order_each_sees_every_item_and_join_gives_both() {
        let items: Vec<u32> = (0..500).collect();
        for t in [1, 3] {
            let (m, (a, b)) = pool(t).install(|| (map(&items, |x| x * 2), join(|| 1, || "b")));
            assert_eq!(m, items.iter().map(|x| x * 2).collect::<Vec<_>>());
            let mut e = items.clone();
            pool(t).install(|| each(&mut e, |x| *x += 1));
            assert_eq!(e, items.iter().map(|x| x + 1).collect::<Vec<_>>());
            assert_eq!((a, b), (1, "b"));
        }
    }
}
