//! `subdivide`: split long strings so later deformations bend the path smoothly.

use crate::base::error::{Error, Result};
use crate::base::toolpath::{Strands, Toolpath};

/// Splits every string longer than `max` into `ceil(L / max)` equal pieces,
/// refusing when the part would exceed `max_strings`.
pub(super) fn apply(tp: &mut Toolpath, max: f64, max_strings: u64) -> Result<()> {
    let pieces = |k: usize| -> u64 {
        let l = tp.length(k);
        if l > max {
            libm::ceil(l / max) as u64
        } else {
            1
        }
    };
    // saturating: two strings of 1e300 mm must not wrap around to a few pieces
    let total: u64 = (0..tp.len())
        .map(pieces)
        .fold(0u64, |a, b| a.saturating_add(b));
    if total > max_strings {
        return Err(Error::input(
            "",
            format!(
                "max_length {max} would make {total} strings, more than the limit of {max_strings}; expected a larger max_length"
            ),
        ));
    }
    if total == tp.len() as u64 {
        return Ok(());
    }
    let mut points = Vec::with_capacity(total as usize + 1);
    // strings all alike stay held once
    let alike = tp.strings.alike();
    let mut strings = Vec::with_capacity(if alike.is_some() { 0 } else { total as usize });
    points.push(tp.points[0]);
    // new index of the first piece of each old string (and of the end), so
    // events stay before the same string
    let mut first = Vec::with_capacity(tp.len() + 1);
    // an outline's turns u = k + s grow along the part: linear between ends
    let mut turns = tp.turns.as_ref().map(|u| {
        let mut t = Vec::with_capacity(total as usize + 1);
        t.push(u[0]);
        t
    });
    for k in 0..tp.len() {
        first.push(points.len() - 1);
        let (a, b) = tp.ends(k);
        let m = pieces(k);
        for j in 1..m {
            points.push(a.lerp(b, j as f64 / m as f64));
            if alike.is_none() {
                strings.push(tp.strings[k]);
            }
            if let (Some(t), Some(u)) = (&mut turns, &tp.turns) {
                t.push(u[k] + (u[k + 1] - u[k]) * (j as f64 / m as f64));
            }
        }
        points.push(b);
        if alike.is_none() {
            strings.push(tp.strings[k]);
        }
        if let (Some(t), Some(u)) = (&mut turns, &tp.turns) {
            t.push(u[k + 1]);
        }
    }
    tp.turns = turns;
    first.push(points.len() - 1);
    tp.points = points;
    tp.strings = match alike {
        Some(s) => Strands::same(s, total as usize),
        None => Strands::from(strings),
    };
    for ev in &mut tp.events {
        ev.0 = first[ev.0];
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn equal_pieces_no_longer_than_max() {
        let mut t = Toolpath::new(DVec3::ZERO);
        t.draw(DVec3::new(10.0, 0.0, 0.0), 0.2, 10.0);
        t.draw(DVec3::new(10.0, 0.5, 0.0), 0.3, 10.0);
        let v = t.volume();
        apply(&mut t, 3.0, 100).unwrap();
        assert_eq!(t.len(), 5);
        for k in 0..4 {
            assert!((t.length(k) - 2.5).abs() < 1e-12);
        }
        assert!((t.volume() - v).abs() < 1e-12);
        assert!(apply(&mut t, 0.001, 100).is_err());
    }

    #[test]
    fn events_stay_before_the_same_string() {
        use crate::base::toolpath::Event;
        let mut t = Toolpath::new(DVec3::ZERO);
        t.draw(DVec3::new(10.0, 0.0, 0.0), 0.2, 10.0);
        t.event(Event::Pause);
        t.draw(DVec3::new(10.0, 10.0, 0.0), 0.2, 10.0);
        t.event(Event::Dwell { ms: 5.0 });
        apply(&mut t, 3.0, 100).unwrap();
        // 4 + 4 pieces: the pause sits before piece 4 (the second string's
        // first), the dwell after the last
        assert_eq!(
            t.events,
            vec![(4, Event::Pause), (8, Event::Dwell { ms: 5.0 })]
        );
        assert_eq!(t.ends(4).0, DVec3::new(10.0, 0.0, 0.0));
    }
}
