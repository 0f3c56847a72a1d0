//! The warnings of Kanada's self-organised pattern helix (paper 004): its
//! parameters outside the ranges the paper reports patterns for, and strings
//! modulated after the fact.

use crate::base::finding::{Finding, Severity};
use crate::base::toolpath::Toolpath;
use crate::generate::model::Recipe;
use crate::generate::primitive::Primitive;

/// Whether `v` lies outside [lo, hi].
fn outside(v: f64, lo: f64, hi: f64) -> bool {
    !(lo..=hi).contains(&v)
}

/// The `pattern-range` and `pattern-modulated` warnings of every
/// `pattern_helix` part; `paths` are the skirt (if any) then the parts.
pub(crate) fn findings(recipe: &Recipe, paths: &[&Toolpath], out: &mut Vec<Finding>) {
    let offset = paths.len().saturating_sub(recipe.parts.len());
    for (k, part) in recipe.parts.iter().enumerate() {
        let Some(p) = part.primitives().find_map(|p| match p {
            Primitive::PatternHelix(p) => Some(p),
            _ => None,
        }) else {
            continue;
        };
        let name = &part.name;
        let mut warn = |code: &'static str, what: String| {
            out.push(Finding {
                code,
                severity: Severity::Warning,
                message: format!("part `{name}`: {what}"),
                part: Some(name.clone()),
                string: None,
                at: None,
                strings: Vec::new(),
            })
        };
        let range = "the paper reports self-organised patterns for";
        let c = p.cross_section.unwrap_or(part.cross_section);
        let v = p.speed.unwrap_or(part.speed);
        if outside(p.layer_height, 0.1, 0.3) {
            warn("pattern-range", format!("layer_height {} mm is outside 0.1–0.3 mm, the layer heights {range} (section 2)", p.layer_height));
        }
        if outside(c, 0.02, 0.045) {
            warn("pattern-range", format!("cross_section {c} mm² is outside 0.02–0.045 mm², the cross-sections {range} (Figs. 3, 10, 12; \"much less than 0.2 mm²\")"));
        }
        if outside(v, 40.0, 150.0) {
            warn(
                "pattern-range",
                format!(
                    "speed {v} mm/s is outside 40–150 mm/s, the head speeds {range} (section 2)"
                ),
            );
        }
        if p.segments != 72 {
            warn(
                "pattern-range",
                format!(
                    "segments {} differs from the 72 strings per turn {range} (section 2)",
                    p.segments
                ),
            );
        }
        let nozzle = recipe.printer.nozzle_diameter;
        if outside(nozzle, 0.3, 0.5) {
            warn("pattern-range", format!("the nozzle of printer {} ({nozzle} mm) is outside 0.3–0.5 mm, the nozzles {range} (section 2)", recipe.printer.name));
        }
        let m = &recipe.material;
        let temps = match m.name.as_str() {
            "pla" => Some((180.0, 220.0)),
            "abs" => Some((220.0, 260.0)),
            _ => None,
        };
        match temps {
            Some((lo, hi)) if outside(m.nozzle_temp, lo, hi) => warn("pattern-range", format!("nozzle_temp {} °C is outside {lo}–{hi} °C, the {} temperatures {range} (section 2)", m.nozzle_temp, m.name)),
            Some(_) => {}
            None => warn("pattern-range", format!("material `{}`: {range} PLA and ABS only (section 2)", m.name)),
        }
        if let Some(tp) = paths.get(recipe.plate_path_of(k).unwrap_or(offset + k)) {
            modulated(tp, &mut warn);
        }
    }
}

/// Warns when the extruding strings after the first turn (the leading run of
/// strings with the first string's c and v) do not all share one c and v.
fn modulated(tp: &Toolpath, warn: &mut impl FnMut(&'static str, String)) {
    let mut strings = tp.strings.iter().enumerate().filter(|(_, s)| !s.travel);
    let Some((_, first)) = strings.next() else {
        return;
    };
    let mut rest = strings.skip_while(|(_, s)| s.c == first.c && s.v == first.v);
    let Some((k0, s0)) = rest.next() else {
        return;
    };
    let (mut count, mut first_bad) = (0usize, None);
    for (k, s) in rest {
        if s.c != s0.c || s.v != s0.v {
            count += 1;
            first_bad.get_or_insert(k);
        }
    }
    if let Some(k) = first_bad {
        warn("pattern-modulated", format!(
            "{count} strings after the first turn differ in cross-section or speed from string {k0} (c {} mm², v {} mm/s), the first at string {k}; the paper prints the pattern at constant speed and extrusion, since any change prints an artefact (section 2)",
            s0.c, s0.v
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::primitive::PatternHelix;

    #[test]
    fn modulation_after_the_first_turn_is_found() {
        let mut t = PatternHelix {
            radius: 20.0,
            layers: 150,
            layer_height: 0.2,
            segments: 72,
            cross_section: Some(0.045),
            speed: Some(60.0),
            first_layer: crate::generate::primitive::pattern::FIRST_LAYER,
            center: glam::DVec3::new(0.0, 0.0, 0.2),
        }
        .build(0.1, 40.0);
        let mut found = Vec::new();
        modulated(&t, &mut |code, m| found.push((code, m)));
        assert!(found.is_empty(), "{found:?}");
        t.strings[500].v = 61.0;
        t.strings[900].c = 0.05;
        modulated(&t, &mut |code, m| found.push((code, m)));
        assert_eq!(found.len(), 1);
        assert!(found[0].1.starts_with("2 strings"), "{}", found[0].1);
        assert!(found[0].1.contains("string 500"), "{}", found[0].1);
    }
}
