//! The z-buffer of loops, updated feature by feature (paper 003: "this
//! z-buffer is modified each time a feature is added to a part").
//!
//! Layer j's slab is a function of the settings and of the list of
//! (section at z_j = (j − ½)·h, op) over all features, where a feature's
//! section is `None` outside z0 ≤ z_j < z1. Adding or removing a union or a
//! subtract therefore changes only the layers whose middle plane it holds:
//! outside its range it is a `None` union (r ∨ false = r) or a `None`
//! subtract (r ∧ ¬false = r). An intersect is different: outside its range it
//! holds no point and empties the result (r ∧ false), so it reaches every
//! layer, and every layer is recomputed when one is added or removed.
//!
//! A layer no union holds is empty without any boolean (only a union makes
//! a point inside). Consecutive recomputed layers held by the same features
//! share one slab, computed once. Every slab is computed by the same
//! function on the same input as a full build, so the buffer equals a full
//! build after any sequence of updates (`tests/solid.rs` checks it on
//! random ones).

use super::*;

/// The z-buffer of a solid: its features (each with an id) and one slab per layer.
#[derive(Clone, Debug)]
pub(crate) struct ZBuffer {
    settings: Settings,
    features: Vec<Feature>,
    ids: Vec<u64>,
    next_id: u64,
    /// Slab of layer j + 1 (`None`: nothing at that height).
    layers: Vec<Option<Arc<Slab>>>,
}

/// What one update did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Update {
    /// The layers (1 for the first) whose slab was recomputed, ascending.
    pub(crate) layers: Vec<u64>,
    /// Booleans computed for them (recomputed layers held by the same
    /// features share one).
    pub(crate) sections: u64,
    /// Ids of the features added, in order.
    pub(crate) added: Vec<u64>,
}

impl Update {
    /// How many layers were recomputed.
    pub(crate) fn recomputed(&self) -> u64 {
        self.layers.len() as u64
    }
}

impl ZBuffer {
    /// An empty buffer (no features, no layers).
    pub(crate) fn new(settings: Settings) -> ZBuffer {
        ZBuffer {
            settings,
            features: Vec::new(),
            ids: Vec::new(),
            next_id: 0,
            layers: Vec::new(),
        }
    }

    /// A buffer built from `features` at once.
    pub(crate) fn build(settings: Settings, features: Vec<Feature>) -> Result<ZBuffer> {
        let mut zb = ZBuffer::new(settings);
        zb.splice(0, 0, features)?;
        Ok(zb)
    }

    /// The settings its slabs are made with.
    pub(crate) fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The features in order.
    pub(crate) fn features(&self) -> &[Feature] {
        &self.features
    }

    /// Number of layers (up to the highest union's top).
    pub(crate) fn layer_count(&self) -> u64 {
        self.layers.len() as u64
    }

    /// Each layer's slab, bottom up (`None`: nothing at that height).
    pub(crate) fn layer_slabs(&self) -> impl Iterator<Item = Option<&Arc<Slab>>> + '_ {
        self.layers.iter().map(Option::as_ref)
    }

    /// Adds a feature after the others; only the layers it reaches are recomputed.
    #[cfg(test)]
    pub(crate) fn add_feature(&mut self, f: Feature) -> Result<Update> {
        let n = self.features.len();
        self.splice(n, 0, vec![f])
    }

    /// Removes the feature with id `id`; only the layers it reached are recomputed.
    #[cfg(test)]
    pub(crate) fn remove_feature(&mut self, id: u64) -> Result<Update> {
        let Some(k) = self.ids.iter().position(|&i| i == id) else {
            return Err(Error::input(
                "solid.features",
                format!("no feature has id {id}; expected one of {:?}", self.ids),
            ));
        };
        self.splice(k, 1, Vec::new())
    }

    /// Replaces the features `at .. at + remove` by `insert` and recomputes
    /// the layers any of them reaches (see the module comment). On an error
    /// (too many layers or lines) the buffer is left as it was.
    pub(crate) fn splice(
        &mut self,
        at: usize,
        remove: usize,
        insert: Vec<Feature>,
    ) -> Result<Update> {
        let end = at.saturating_add(remove);
        if end > self.features.len() {
            return Err(Error::input(
                "solid.features",
                format!(
                    "features {at}..{end} are not there; expected at most {}",
                    self.features.len()
                ),
            ));
        }
        let mut features = self.features.clone();
        let changed: Vec<Feature> = features
            .splice(at..end, insert.iter().copied())
            .chain(insert.iter().copied())
            .collect();
        let layers = check(&self.settings, &features)?;
        let mut dirty = reached(&changed, self.settings.layer_height, layers);
        let ids: Vec<u64> = (0..insert.len() as u64).map(|k| self.next_id + k).collect();
        self.next_id += insert.len() as u64;
        self.ids.splice(at..end, ids.iter().copied());
        self.features = features;
        let old = self.layers.len();
        self.layers.resize(layers as usize, None);
        self.mark_new_layers(old, &mut dirty);
        let mut update = Update {
            added: ids,
            ..Update::default()
        };
        self.recompute(&dirty, &mut update);
        Ok(update)
    }

    /// Marks dirty each layer above the `old` top that a union holds though
    /// no changed feature reaches it (no union held it before; a guard
    /// against rounding).
    fn mark_new_layers(&self, old: usize, dirty: &mut [bool]) {
        let h = self.settings.layer_height;
        for j in old + 1..=self.layers.len() {
            let z = mid(j as u64, h);
            if !dirty[j - 1]
                && self
                    .features
                    .iter()
                    .any(|f| f.op == Op::Union && f.section(z).is_some())
            {
                dirty[j - 1] = true;
            }
        }
    }

    /// Recomputes the slab of each `dirty` layer, bottom up, recording them
    /// in `update`; consecutive dirty layers held by the same features share
    /// the first one's slab, and a layer no union holds is empty without a
    /// boolean.
    fn recompute(&mut self, dirty: &[bool], update: &mut Update) {
        let h = self.settings.layer_height;
        let mut last: Option<(Vec<bool>, Option<Arc<Slab>>)> = None;
        for j in 1..=self.layers.len() as u64 {
            if !dirty[j as usize - 1] {
                last = None;
                continue;
            }
            update.layers.push(j);
            let z = mid(j, h);
            let held: Vec<bool> = self
                .features
                .iter()
                .map(|f| f.section(z).is_some())
                .collect();
            let slab = match &last {
                Some((sig, slab)) if *sig == held => slab.clone(),
                _ => {
                    let any_union = self
                        .features
                        .iter()
                        .zip(&held)
                        .any(|(f, &h)| h && f.op == Op::Union);
                    let slab = if any_union {
                        update.sections += 1;
                        self.settings.make_slab(&self.features, z).map(Arc::new)
                    } else {
                        None
                    };
                    last = Some((held, slab.clone()));
                    slab
                }
            };
            self.layers[j as usize - 1] = slab;
        }
    }
}

/// The middle plane of layer `j` (1 for the first) of height `h`: (j − ½)·h.
fn mid(j: u64, h: f64) -> f64 {
    (j as f64 - 0.5) * h
}

/// Per layer (index j − 1 for layer j of `layers`): whether one of the
/// `changed` features reaches it, i.e. holds its middle plane, or is an
/// intersect (which reaches every layer).
fn reached(changed: &[Feature], h: f64, layers: u64) -> Vec<bool> {
    let mut dirty = vec![false; layers as usize];
    for f in changed {
        if f.op == Op::Intersect {
            dirty.iter_mut().for_each(|d| *d = true);
            break;
        }
        let (z0, z1) = f.z_range();
        // j with z0 ≤ (j − ½)·h < z1, found by the same test as the
        // sections' after a guess widened by one on each side
        let lo = (libm::floor(z0 / h + 0.5) - 1.0).max(1.0);
        let hi = (libm::ceil(z1 / h + 0.5) + 1.0).min(layers as f64);
        if lo.is_nan() || hi.is_nan() || lo > hi {
            continue;
        }
        for j in lo as u64..=hi as u64 {
            if z0 <= mid(j, h) && mid(j, h) < z1 {
                dirty[j as usize - 1] = true;
            }
        }
    }
    dirty
}

/// The number of layers of `features` (those whose middle lies below the
/// highest union's top), refused when there would be too many layers, too
/// many infill lines or too many chords of a circle.
fn check(st: &Settings, features: &[Feature]) -> Result<u64> {
    let layer_height = st.layer_height;
    // nothing but a union adds material: the top is the highest union's
    let top = features
        .iter()
        .filter(|f| f.op == Op::Union)
        .map(|f| f.z_range().1)
        .fold(f64::NEG_INFINITY, f64::max);
    // layers whose middle (j − ½)·h lies below the top
    let layers = (libm::ceil(top / layer_height + 0.5) - 1.0).max(0.0);
    if layers > MAX_LAYERS as f64 {
        return Err(Error::input(
            "solid.layer_height",
            format!(
                "{layer_height} would make {layers} layers up to z = {top}; expected at most {MAX_LAYERS}"
            ),
        ));
    }
    if features.is_empty() {
        return Ok(0);
    }
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for f in features {
        let [a, b] = f.footprint();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    let diag = (hi - lo).length();
    if diag / st.infill.spacing > MAX_LINES {
        return Err(Error::input(
            "solid.infill.spacing",
            format!(
                "{} would need more than {MAX_LINES} infill lines across the part ({diag:.1} mm); expected a larger spacing",
                st.infill.spacing
            ),
        ));
    }
    if piece::chords(diag, std::f64::consts::TAU, st.chord_tolerance) as f64 > MAX_LINES {
        return Err(Error::input(
            "solid.chord_tolerance",
            format!(
                "{} would cut a circle into more than {MAX_LINES} strings; expected a larger tolerance",
                st.chord_tolerance
            ),
        ));
    }
    Ok(layers as u64)
}

/// What a build did with one solid's z-buffer when a cache was lent to it ([`Reusing`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Reuse {
    /// Layers of the solid.
    pub(crate) layers: u64,
    /// Layers whose slab was recomputed (all of them when nothing was kept).
    pub(crate) recomputed: u64,
}

/// The z-buffers a long-running command keeps between builds (`p3dp
/// watch`), in the order a build resolves its solids; lent to each build as
/// [`Reusing`].
#[derive(Clone, Debug, Default)]
pub(crate) struct Cache {
    buffers: Vec<ZBuffer>,
    /// What the last build it was lent to did with each solid, in order.
    pub(crate) last: Vec<Reuse>,
}

/// A [`Cache`] lent to one build: the k-th solid it resolves starts from
/// the cache's k-th z-buffer when the settings are the same, and only the
/// features that differ (those between the longest common head and tail of
/// the two feature lists) are removed and added (see [`ZBuffer::splice`]).
#[derive(Debug, Default)]
pub(crate) struct Reusing(std::sync::Mutex<Lent>);

/// The buffers of the cache, those of the build so far, and what it did.
#[derive(Debug, Default)]
struct Lent {
    old: Vec<ZBuffer>,
    new: Vec<ZBuffer>,
    last: Vec<Reuse>,
}

impl Reusing {
    /// Lends `cache` to a build.
    pub(crate) fn new(cache: Cache) -> Reusing {
        Reusing(std::sync::Mutex::new(Lent {
            old: cache.buffers,
            ..Lent::default()
        }))
    }

    /// The cache to keep once the build has ended.
    pub(crate) fn finish(self) -> Cache {
        let Lent {
            mut old,
            mut new,
            last,
        } = self.0.into_inner().unwrap_or_else(|e| e.into_inner());
        // a build that stopped early keeps the rest for the next one
        if old.len() > new.len() {
            new.extend(old.drain(new.len()..));
        }
        Cache { buffers: new, last }
    }

    fn lent(&self) -> std::sync::MutexGuard<'_, Lent> {
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The z-buffer of `features`: from the lent cache when there is one
/// (noting what was recomputed), else built whole.
pub(super) fn cached(
    settings: Settings,
    features: Vec<Feature>,
    reuse: Option<&Reusing>,
) -> Result<ZBuffer> {
    let Some(reuse) = reuse else {
        return ZBuffer::build(settings, features);
    };
    let old = {
        let lent = reuse.lent();
        let k = lent.new.len();
        lent.old
            .get(k)
            .filter(|zb| zb.settings == settings)
            .cloned()
    };
    let (zb, recomputed) = match old {
        Some(mut zb) => {
            let (a, b) = (zb.features(), &features[..]);
            let head = a.iter().zip(b).take_while(|(x, y)| x == y).count();
            let rest = a.len().min(b.len()) - head;
            let tail = a
                .iter()
                .rev()
                .zip(b.iter().rev())
                .take(rest)
                .take_while(|(x, y)| x == y)
                .count();
            let (remove, insert) = (a.len() - head - tail, b[head..b.len() - tail].to_vec());
            let up = zb.splice(head, remove, insert)?;
            (zb, up.recomputed())
        }
        None => {
            let zb = ZBuffer::build(settings, features)?;
            let n = zb.layer_count();
            (zb, n)
        }
    };
    let mut lent = reuse.lent();
    lent.new.push(zb.clone());
    lent.last.push(Reuse {
        layers: zb.layer_count(),
        recomputed,
    });
    Ok(zb)
}
