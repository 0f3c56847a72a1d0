//! A uniform grid hashed over space, of line segments (the deposited strings).
//!
//! Space is cut into cubes of side `cell`; a segment is listed under every
//! cube its pieces (at most `cell` long) touch. Cubes are not stored: each is
//! hashed to one of a power-of-two number of buckets (about two per segment),
//! so memory follows the number of strings, not the size of the print, and a
//! bucket may hold segments of several cubes (the caller measures distances,
//! so such strangers only cost time). Buckets are laid out flat (offsets into
//! one array), each listing segment ids in ascending order: the strings
//! printed before string `g` are the front of the bucket up to `g`.

use glam::DVec3;

/// Segments in a hashed uniform grid.
#[derive(Clone, Debug)]
pub(crate) struct SegGrid {
    cell: f64,
    inv: f64,
    mask: u64,
    /// Bucket b holds `items[ends[b - 1]..ends[b]]` (from 0 for b = 0).
    ends: Vec<u32>,
    items: Vec<u32>,
}

/// `libm::floor(v) as i64`, without the call: truncate, then step down
/// when that rounded up (a negative fraction). The same for every f64: NaN
/// is 0, and values past i64's range saturate as the cast does.
#[inline]
pub(crate) fn floor_i64(v: f64) -> i64 {
    let t = v as i64;
    if (t as f64) > v {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `libm::ceil(v) as i64`, without the call (see [`floor_i64`]).
#[inline]
pub(crate) fn ceil_i64(v: f64) -> i64 {
    let t = v as i64;
    if (t as f64) < v {
        t.saturating_add(1)
    } else {
        t
    }
}

/// Integer cube coordinates of `p` for cubes of side 1 / `inv`.
#[inline]
pub(crate) fn cube(p: DVec3, inv: f64) -> [i64; 3] {
    // clamped so that far-away points stay in range
    let f = |v: f64| floor_i64((v * inv).clamp(-1e15, 1e15));
    [f(p.x), f(p.y), f(p.z)]
}

/// The bucket of cube `c` among `mask + 1` buckets.
#[inline]
fn hash(c: [i64; 3], mask: u64) -> usize {
    let h = (c[0] as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (c[1] as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (c[2] as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    ((h ^ (h >> 29)) & mask) as usize
}

impl SegGrid {
    /// Lists `n` segments, `seg(i)` giving segment i's ends, in cubes of side
    /// `cell` (> 0). A segment is cut into pieces at most `cell / 2` long and
    /// listed in the cube of each piece's middle, so a segment lies within
    /// [`SegGrid::slack`] of a cube it is listed in.
    pub(crate) fn build(n: usize, cell: f64, seg: impl Fn(usize) -> (DVec3, DVec3)) -> SegGrid {
        // at most 2^30 buckets: a key keeps its top bit for a mark (below)
        let buckets = n.next_power_of_two().clamp(1024, 1 << 30);
        let mut g = SegGrid {
            cell,
            inv: 1.0 / cell,
            mask: buckets as u64 - 1,
            ends: vec![0; buckets],
            items: Vec::new(),
        };
        // first pass counts (keeping each segment's buckets, worked out
        // once: the top bit marks a segment's first), second fills: ids go
        // in ascending order
        const FIRST: u32 = 1 << 31;
        let mut ends = std::mem::take(&mut g.ends);
        let mut keys: Vec<u32> = Vec::with_capacity(n + n / 2);
        for i in 0..n {
            let (a, b) = seg(i);
            let mut flag = FIRST;
            g.each_bucket(a, b, |k| {
                ends[k] += 1;
                keys.push(k as u32 | flag);
                flag = 0;
            });
        }
        let mut acc = 0u32;
        for e in ends.iter_mut() {
            let c = *e;
            *e = acc; // the bucket's start, for now
            acc += c;
        }
        let mut items = vec![0; acc as usize];
        let mut i = u32::MAX; // the segment of the key, counted from its first
        for &key in &keys {
            i = i.wrapping_add(key >> 31);
            let k = (key & !FIRST) as usize;
            items[ends[k] as usize] = i;
            ends[k] += 1; // ends up as the bucket's end
        }
        g.ends = ends;
        g.items = items;
        g
    }

    /// How far a listed segment may lie outside its cube, mm.
    pub(crate) fn slack(&self) -> f64 {
        self.cell / 4.0
    }

    /// Calls `f` with the bucket of each piece of segment a–b (repeats skipped).
    #[inline]
    fn each_bucket(&self, a: DVec3, b: DVec3, mut f: impl FnMut(usize)) {
        let len = a.distance(b);
        let pieces = (len * 2.0 * self.inv).clamp(0.0, 1e6) as usize + 1;
        let mut last = usize::MAX;
        for j in 0..pieces {
            let m = a.lerp(b, (j as f64 + 0.5) / pieces as f64);
            let k = hash(cube(m, self.inv), self.mask);
            if k != last {
                f(k);
                last = k;
            }
        }
    }

    /// Ids listed in cube `c`'s bucket (ascending; may include other cubes').
    #[inline]
    pub(crate) fn bucket(&self, c: [i64; 3]) -> &[u32] {
        let b = hash(c, self.mask);
        let start = if b == 0 { 0 } else { self.ends[b - 1] };
        &self.items[start as usize..self.ends[b] as usize]
    }

    /// The cube of `p`, and the ranges of cubes within `r` (plus the slack) of it.
    #[inline]
    pub(crate) fn around(&self, p: DVec3, r: f64) -> ([i64; 3], [i64; 3], [i64; 3]) {
        let r = r + self.slack();
        (
            cube(p, self.inv),
            cube(p - DVec3::splat(r), self.inv),
            cube(p + DVec3::splat(r), self.inv),
        )
    }

    /// Calls `f` on the ids listed near `p` (within `r`) below `g`, newest
    /// first, `p`'s own cube first, until it says stop; whether it did.
    #[inline]
    pub(crate) fn search(&self, p: DVec3, r: f64, g: u32, mut f: impl FnMut(u32) -> bool) -> bool {
        let (own, lo, hi) = self.around(p, r);
        let mut visit = |c: [i64; 3]| {
            let bucket = self.bucket(c);
            let end = bucket.partition_point(|&j| j < g);
            bucket[..end].iter().rev().any(|&j| f(j))
        };
        if visit(own) {
            return true;
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    if [x, y, z] != own && visit([x, y, z]) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// A hasher for small keys of integers (grid cells, bit patterns): each
/// 64-bit word is folded in by a rotate, xor and multiply by an odd constant
/// (Fx's), far cheaper than std's SipHash for the millions of look-ups the
/// checks make. Not proof against chosen keys; fine for cells of a grid.
/// Nothing iterates these maps, so their order never reaches an output.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct CellHasher(u64);

impl std::hash::Hasher for CellHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut w = [0u8; 8];
            w[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(w));
        }
    }
    #[inline]
    fn write_u64(&mut self, n: u64) {
        self.0 = (self.0.rotate_left(5) ^ n).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    #[inline]
    fn write_i64(&mut self, n: i64) {
        self.write_u64(n as u64);
    }
    #[inline]
    fn write_usize(&mut self, n: usize) {
        self.write_u64(n as u64);
    }
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

/// A `HashMap` keyed by grid cells, hashed by [`CellHasher`].
pub(crate) type CellMap<K, V> =
    std::collections::HashMap<K, V, std::hash::BuildHasherDefault<CellHasher>>;

/// A `HashSet` of grid cells, hashed by [`CellHasher`].
pub(crate) type CellSet<K> =
    std::collections::HashSet<K, std::hash::BuildHasherDefault<CellHasher>>;

/// Segments added one at a time, listed as [`SegGrid`] lists them (pieces
/// at most `cell / 2` long, in the cube of each piece's middle), for a scan
/// that only ever searches what it has kept so far.
#[derive(Clone, Debug)]
pub(crate) struct GrowGrid {
    inv: f64,
    cell: f64,
    cubes: CellMap<[i64; 3], Vec<u32>>,
}

impl GrowGrid {
    /// An empty grid of cubes of side `cell` (> 0).
    pub(crate) fn new(cell: f64) -> GrowGrid {
        GrowGrid {
            inv: 1.0 / cell,
            cell,
            cubes: CellMap::default(),
        }
    }

    /// Lists segment `id` from `a` to `b`.
    pub(crate) fn insert(&mut self, id: u32, a: DVec3, b: DVec3) {
        let pieces = (a.distance(b) * 2.0 * self.inv).clamp(0.0, 1e6) as usize + 1;
        let mut last = None;
        for j in 0..pieces {
            let c = cube(a.lerp(b, (j as f64 + 0.5) / pieces as f64), self.inv);
            if last != Some(c) {
                let ids = self.cubes.entry(c).or_default();
                if ids.last() != Some(&id) {
                    ids.push(id);
                }
                last = Some(c);
            }
        }
    }

    /// Calls `f` on the ids listed within `r` of `p`, oldest first cube by
    /// cube, until it says stop; whether it did.
    pub(crate) fn search(&self, p: DVec3, r: f64, mut f: impl FnMut(u32) -> bool) -> bool {
        let r = r + self.cell / 4.0;
        let (lo, hi) = (
            cube(p - DVec3::splat(r), self.inv),
            cube(p + DVec3::splat(r), self.inv),
        );
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    if let Some(ids) = self.cubes.get(&[x, y, z]) {
                        if ids.iter().any(|&j| f(j)) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

/// Closest point of segment a–b to `p`: the parameter u in [0, 1].
#[inline]
pub(crate) fn closest(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let d = b - a;
    let l2 = d.length_squared();
    if l2 <= 0.0 {
        return 0.0;
    }
    ((p - a).dot(d) / l2).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_and_ceil_are_libms() {
        let mut rng = crate::base::rng::SplitMix64::new(7);
        let mut vals = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.5,
            -2.5,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            9.2e18,
            9.3e18,
            -9.3e18,
            (1u64 << 63) as f64,
            -((1u64 << 63) as f64),
            4503599627370495.5,
            -4503599627370495.5,
        ];
        // any bits, and values of a few mm on the 0.025 mm grid
        vals.extend((0..100_000).map(|_| f64::from_bits(rng.next_u64())));
        vals.extend((0..100_000).map(|_| (rng.uniform() - 0.5) * 1e4 / 0.025 - 0.5));
        for v in vals {
            assert_eq!(floor_i64(v), libm::floor(v) as i64, "floor {v:e}");
            assert_eq!(ceil_i64(v), libm::ceil(v) as i64, "ceil {v:e}");
        }
    }

    #[test]
    fn segments_are_found_near_any_of_their_points() {
        let segs = [
            (DVec3::ZERO, DVec3::new(10.0, 0.0, 0.0)),
            (DVec3::new(0.0, 5.0, 0.0), DVec3::new(0.0, 5.0, 3.0)),
            (DVec3::new(-50.0, -50.0, 7.0), DVec3::new(-49.5, -50.0, 7.0)),
        ];
        let g = SegGrid::build(segs.len(), 1.0, |i| segs[i]);
        let found = |p: DVec3| -> Vec<u32> {
            let mut ids = Vec::new();
            g.search(p, 0.5, 3, |j| {
                ids.push(j);
                false
            });
            ids
        };
        assert!(found(DVec3::new(7.3, 0.2, 0.1)).contains(&0));
        assert!(found(DVec3::new(0.1, 5.0, 2.9)).contains(&1));
        assert!(found(DVec3::new(-49.7, -50.2, 7.0)).contains(&2));
        // only ids below the limit, newest first
        let mut seen = Vec::new();
        g.search(DVec3::new(0.1, 0.1, 0.0), 20.0, 1, |j| {
            seen.push(j);
            false
        });
        assert!(seen.iter().all(|&j| j < 1) && seen.contains(&0));
        // buckets list ids in ascending order
        for b in 0..g.ends.len() {
            let start = if b == 0 { 0 } else { g.ends[b - 1] };
            let s = &g.items[start as usize..g.ends[b] as usize];
            assert!(s.windows(2).all(|w| w[0] <= w[1]));
        }
        // the own cube comes first
        let (own, lo, hi) = g.around(DVec3::new(3.5, 0.5, 0.5), 0.3);
        assert_eq!((own, lo, hi), ([3, 0, 0], [2, -1, -1], [4, 1, 1]));
    }

    #[test]
    fn floor_of_negative_coordinates() {
        assert_eq!(cube(DVec3::new(-0.5, 0.0, 2.0), 1.0), [-1, 0, 2]);
        assert_eq!(cube(DVec3::new(-1.0, -2.5, 0.999), 1.0), [-1, -3, 0]);
    }

    #[test]
    fn closest_point_parameter() {
        let (a, b) = (DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0));
        assert_eq!(closest(DVec3::new(1.0, 1.0, 0.0), a, b), 0.5);
        assert_eq!(closest(DVec3::new(-1.0, 1.0, 0.0), a, b), 0.0);
        assert_eq!(closest(DVec3::new(5.0, 0.0, 0.0), a, b), 1.0);
        assert_eq!(closest(DVec3::ONE, a, a), 0.0);
    }

    #[test]
    fn far_points_do_not_overflow() {
        let c = cube(DVec3::new(1e300, -1e300, 0.0), 2.0);
        assert_eq!(c, [1_000_000_000_000_000, -1_000_000_000_000_000, 0]);
    }

    #[test]
    fn a_growing_grid_finds_what_a_built_one_finds() {
        // random segments added one by one: the ids found near a point
        // within r (by distance to the segment) are those a full scan finds
        let mut rng = crate::base::rng::SplitMix64::new(5);
        let mut r = |lo: f64, hi: f64| lo + (hi - lo) * rng.uniform();
        let segs: Vec<(DVec3, DVec3)> = (0..300)
            .map(|_| {
                let a = DVec3::new(r(-10.0, 10.0), r(-10.0, 10.0), r(0.0, 3.0));
                let b = a + DVec3::new(r(-4.0, 4.0), r(-4.0, 4.0), r(-0.5, 0.5));
                (a, b)
            })
            .collect();
        let mut g = GrowGrid::new(1.0);
        for (i, &(a, b)) in segs.iter().enumerate() {
            g.insert(i as u32, a, b);
            let p = DVec3::new(r(-10.0, 10.0), r(-10.0, 10.0), r(0.0, 3.0));
            let near = |&(a, b): &(DVec3, DVec3)| p.distance(a.lerp(b, closest(p, a, b))) <= 0.7;
            let want: Vec<u32> = (0..=i as u32)
                .filter(|&j| near(&segs[j as usize]))
                .collect();
            let mut got = Vec::new();
            g.search(p, 0.7, |j| {
                if near(&segs[j as usize]) && !got.contains(&j) {
                    got.push(j);
                }
                false
            });
            got.sort();
            assert_eq!(got, want, "after {i}");
        }
    }
}
