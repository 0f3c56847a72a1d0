//! Parts of several primitives and groups of parts deformed as one
//! (draw3dp's `Trace` and "a combination of parts can be deformed", Kanada,
//! paper 000 §3.3–3.4; issue 15).
//!
//! A part's primitives are built in order and concatenated: where one ends
//! away from where the next starts, a travel string joins them. A group's
//! steps run after its children's own steps (inner groups first) on the
//! strings of all its leaf parts as one set, in print order: the parts are
//! joined into one toolpath, the step is applied, and the toolpath is cut
//! back into the parts. Position expressions see `i` counting the points of
//! all the parts in print order and `n` their total; string expressions see
//! the strings of all the parts with one joining travel between consecutive
//! parts (which no step changes and which is dropped again). A step that
//! uses none of `i`, `n`, `t` gives exactly what it gives applied to each
//! part alone.

use crate::base::error::{Error, Result};
use crate::base::toolpath::{Strand, Toolpath};
use crate::generate::model::{make_part_within, Group, Part, Recipe};
use crate::generate::step::Step;

/// Most strings all parts of a recipe may have together, before and after
/// their steps: the recipe's `max_strings` (50 million unless it says).
pub(crate) fn total_limit(recipe: &Recipe) -> u64 {
    recipe.max_strings
}

/// Makes every part with its own steps, then runs the group steps.
#[cfg(any(test, feature = "testing"))]
pub fn make_parts(recipe: &Recipe) -> Result<Vec<Toolpath>> {
    make_parts_in(recipe, None)
}

/// [`make_parts`], each part's own toolpath taken from `kept` when the
/// build before made it from the same inputs (`p3dp watch`).
pub(crate) fn make_parts_in(recipe: &Recipe, kept: Option<&Parts>) -> Result<Vec<Toolpath>> {
    let limit = total_limit(recipe);
    let mut parts = Vec::with_capacity(recipe.parts.len());
    let mut total = 0u64;
    for k in 0..recipe.parts.len() {
        // each part's steps get what the limits leave after the parts before it
        let budget = recipe.max_strings.min(limit.saturating_sub(total));
        let make = || make_part_within(recipe, k, budget);
        let tp = match kept {
            Some(kept) => kept.part(&recipe.parts[k], budget, make)?,
            None => make()?,
        };
        total = total.saturating_add(tp.len() as u64);
        if total > limit {
            return Err(over_total(&recipe.parts[k].place, total, limit));
        }
        parts.push(tp);
    }
    for g in &recipe.groups {
        apply(g, &mut parts[g.first..g.end], recipe.max_strings)?;
    }
    // stands, then brims, last: under and round each part's first contact
    // as printed, undeformed (a brim goes round its part's stand); their
    // strings count against the limit like the part's own
    let tip_radius = 0.5 * recipe.printer.head.tip_diameter;
    let mut extra = false;
    let mut all: u64 = parts.iter().map(total_of).sum();
    for (tp, part) in parts.iter_mut().zip(&recipe.parts) {
        if let Some(s) = &part.stand {
            let before = total_of(tp);
            *tp = s
                .under(tp, tip_radius, limit.saturating_sub(all))
                .map_err(|e| e.under(&part.place))?;
            all = all.saturating_add(total_of(tp) - before);
            extra = true;
        }
        if let Some(b) = &part.brim {
            b.put_round(tp);
            extra = true;
        }
    }
    if extra || recipe.groups.iter().any(|g| has_subdivide(&g.steps)) {
        let total: u64 = parts.iter().map(total_of).sum();
        if total > limit {
            return Err(over_total("parts", total, limit));
        }
    }
    Ok(parts)
}

fn total_of(tp: &Toolpath) -> u64 {
    tp.len() as u64
}

fn has_subdivide(steps: &[Step]) -> bool {
    steps.iter().any(|s| matches!(s, Step::Subdivide(_)))
}

fn over_total(place: &str, total: u64, limit: u64) -> Error {
    Error::input(
        place,
        format!("the parts together have {total} strings here, more than the limit of {limit} for a whole recipe; expected fewer parts or strings"),
    )
}

/// The speed marking the travel strings that join parts in a group.
///
/// No step changes a travel string's c or v, and every real speed is finite,
/// so a NaN speed marks exactly the joins (and the pieces `subdivide` cuts
/// them into).
const JOIN: f64 = f64::NAN;

fn is_join(s: &Strand) -> bool {
    s.travel && s.v.is_nan()
}

/// Runs a group's steps on `parts` as one string set.
fn apply(g: &Group, parts: &mut [Toolpath], max_strings: u64) -> Result<()> {
    let names: Vec<String> = parts.iter().map(|t| t.name.clone()).collect();
    // the previews' turtle markers stay with their parts (not moved by steps)
    let markers: Vec<_> = parts.iter().map(|t| t.markers.clone()).collect();
    let mut all = join(parts);
    for (j, step) in g.steps.iter().enumerate() {
        step.apply(&mut all, max_strings)
            .map_err(|e| e.under(&format!("{}.steps[{j}].{}", g.place, step.key())))?;
        if matches!(step, Step::Subdivide(_)) {
            // one string again between two parts, for the steps after it
            all = join(&split(all));
        }
    }
    for ((tp, (part, name)), markers) in parts
        .iter_mut()
        .zip(split(all).into_iter().zip(names))
        .zip(markers)
    {
        *tp = Toolpath {
            name,
            markers,
            ..part
        };
    }
    Ok(())
}

/// The parts as one toolpath: every point of every part, in order, with a
/// marked travel string from each part's end to the next part's start.
fn join(parts: &[Toolpath]) -> Toolpath {
    let n: usize = parts.iter().map(|t| t.len() + 1).sum();
    let mut all = Toolpath::with_capacity(parts[0].points[0], n);
    all.points.clear();
    for (k, t) in parts.iter().enumerate() {
        if k > 0 {
            all.strings.push(Strand {
                c: 0.0,
                v: JOIN,
                travel: true,
                hair: false,
            });
        }
        let base = all.strings.len();
        all.events
            .extend(t.events.iter().map(|(i, e)| (base + i, e.clone())));
        all.points.extend_from_slice(&t.points);
        all.strings.extend_from(&t.strings);
    }
    // an outline's `s` travels with its points (0 on parts without one)
    if parts.iter().any(|t| t.turns.is_some()) {
        let mut u = Vec::with_capacity(all.points.len());
        for t in parts {
            match &t.turns {
                Some(v) => u.extend_from_slice(v),
                None => u.resize(u.len() + t.points.len(), 0.0),
            }
        }
        all.turns = Some(u);
    }
    all
}

/// Cuts a joined toolpath back into its parts at each run of join strings
/// (the points `subdivide` added inside a join are dropped).
fn split(all: Toolpath) -> Vec<Toolpath> {
    let mut parts = Vec::new();
    let mut events = all.events.iter().peekable();
    let (mut first, mut k) = (0, 0);
    let n = all.strings.len();
    loop {
        // the part runs from string `first` to the next join (or the end)
        while k < n && !is_join(&all.strings[k]) {
            k += 1;
        }
        let mut tp = Toolpath {
            name: String::new(),
            points: all.points[first..=k].to_vec(),
            strings: all.strings.range(first, k),
            events: Vec::new(),
            markers: Vec::new(),
            turns: all.turns.as_ref().map(|u| u[first..=k].to_vec()),
        };
        while let Some(&(i, e)) = events.peek() {
            if *i > k {
                break;
            }
            tp.events.push((i - first, e.clone()));
            events.next();
        }
        parts.push(tp);
        if k == n {
            return parts;
        }
        while k < n && is_join(&all.strings[k]) {
            k += 1;
        }
        first = k;
    }
}

/// The parts one build made, kept for the next by a long-running command
/// (`p3dp watch`, in its loading context): each part's own toolpath (its
/// primitives and steps, before groups, stands and brims) under the
/// fingerprint of everything that made it, so that a part whose inputs are
/// unchanged is taken back instead of made again. What a part reads is in
/// its resolved form (its expressions with the params they read, the pixels
/// of its images, its turtle's path), so the fingerprint is SHA-256 of that
/// form as `Debug` writes it (every field, floats in their shortest exact
/// form) and of the strings its steps may make.
#[derive(Debug, Default)]
pub(crate) struct Parts(std::sync::Mutex<Kept>);

/// The inside of [`Parts`].
#[derive(Debug, Default)]
struct Kept {
    /// The build before's parts.
    last: Vec<([u8; 32], Toolpath)>,
    /// This build's, as they are made.
    next: Vec<([u8; 32], Toolpath)>,
    /// This build's parts taken back.
    reused: usize,
}

/// What a build did with the parts kept ([`Parts::finish`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct PartsMade {
    /// Parts made anew.
    pub(crate) made: usize,
    /// All the parts of the build.
    pub(crate) parts: usize,
}

impl Parts {
    fn lock(&self) -> std::sync::MutexGuard<'_, Kept> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// The toolpath of `part` under `budget`: the build before's when it
    /// was made from the same, else `make`'s.
    fn part(
        &self,
        part: &Part,
        budget: u64,
        make: impl FnOnce() -> Result<Toolpath>,
    ) -> Result<Toolpath> {
        let key = fingerprint(part, budget);
        let found = (self.lock().last.iter())
            .find(|(k, _)| *k == key)
            .map(|(_, tp)| tp.clone());
        let reused = found.is_some();
        let tp = match found {
            Some(tp) => tp,
            None => make()?,
        };
        let mut kept = self.lock();
        kept.reused += usize::from(reused);
        kept.next.push((key, tp.clone()));
        Ok(tp)
    }

    /// Ends a build: the parts it made are those kept for the next (a
    /// build that `failed` part way keeps the ones before too); how many it
    /// made anew, of how many it took.
    pub(crate) fn finish(&self, failed: bool) -> PartsMade {
        let mut kept = self.lock();
        let next = std::mem::take(&mut kept.next);
        let made = PartsMade {
            made: next.len() - kept.reused,
            parts: next.len(),
        };
        let old = std::mem::replace(&mut kept.last, next);
        if failed {
            // at most twice the parts of a whole build, however many fail
            let most = 2 * old.len().max(kept.last.len());
            for (k, tp) in old {
                if kept.last.len() < most && !kept.last.iter().any(|(n, _)| *n == k) {
                    kept.last.push((k, tp));
                }
            }
        }
        kept.reused = 0;
        made
    }
}

/// SHA-256 of `part`'s resolved form as `Debug` writes it and of `budget`.
fn fingerprint(part: &Part, budget: u64) -> [u8; 32] {
    use sha2::Digest;
    use std::fmt::Write;
    struct Hashing(sha2::Sha256);
    impl Write for Hashing {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            self.0.update(s.as_bytes());
            Ok(())
        }
    }
    let mut h = Hashing(sha2::Sha256::new());
    let _ = write!(h, "{budget} {part:?}");
    h.0.finalize().into()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::base::toolpath::Event;
    use glam::DVec3;

    fn line(x0: f64, n: usize) -> Toolpath {
        let mut t = Toolpath::new(DVec3::new(x0, 0.0, 0.0));
        for k in 1..=n {
            t.draw(DVec3::new(x0 + k as f64, 0.0, 0.0), 0.2, 10.0);
        }
        t
    }

    #[test]
    fn join_then_split_gives_the_parts_back() {
        let mut a = line(0.0, 3);
        a.event(Event::Pause);
        let mut b = line(10.0, 2);
        b.events.push((0, Event::Dwell { ms: 5.0 }));
        let c = Toolpath::new(DVec3::new(20.0, 0.0, 0.0));
        let parts = vec![a, b, c];
        let all = join(&parts);
        assert_eq!(all.points.len(), 4 + 3 + 1);
        assert_eq!(all.len(), 3 + 1 + 2 + 1);
        assert_eq!(split(all), parts);
    }

    #[test]
    fn subdivided_joins_are_dropped() {
        let parts = vec![line(0.0, 2), line(30.0, 1)];
        let mut all = join(&parts);
        crate::generate::step::Step::Subdivide(1.0)
            .apply(&mut all, 1000)
            .unwrap();
        let back = split(all);
        assert_eq!(back.len(), 2);
        assert_eq!(back[0].points, parts[0].points);
        assert_eq!(back[1].points, parts[1].points);
    }
}
