//! A recipe's params: evaluated in order, each over the ones before it, with
//! the command line's `--set NAME=VALUE` in place of a param's own value.

use indexmap::IndexMap;

use crate::base::error::{Error, Result};
use crate::base::expr::{self, Kind, Params};
use crate::recipe::eval::{finite, join, key};
use crate::recipe::schema::{Num, RawChoice, RawEach, RawLoop, RawParam, RawRecipe};

pub(crate) fn is_identifier(s: &str) -> bool {
    let mut cs = s.chars();
    matches!(cs.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && cs.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Evaluates params in order, each over the ones before it; `sets` replaces
/// a param's value (`--set NAME=VALUE`: a number or expression, `true` or
/// `false`, a list `[a, b]`, or one of a choice param's strings).
pub(crate) fn eval_params(
    raw: &IndexMap<String, RawParam>,
    sets: &[(String, String)],
) -> Result<Params> {
    let mut params = Params::new();
    // every choice's strings first: a quoted string may stand in any expression
    let mut strings = Vec::new();
    for (name, value) in raw {
        if let RawParam::Choice(c) = value {
            check_choices(c, &join(key!(RawRecipe, params), name))?;
            strings.extend(c.choices.iter().map(String::as_str));
        }
    }
    params.set_symbols(strings);
    for (name, value) in raw {
        let place = join(key!(RawRecipe, params), name);
        if !is_identifier(name) {
            return Err(Error::input(
                place,
                "a param name must be letters, digits and `_`, not starting with a digit",
            ));
        }
        if expr::is_reserved(name) {
            return Err(Error::input(
                place,
                format!("`{name}` is a name expressions already use; choose another param name"),
            ));
        }
        let set = sets
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .map(|(_, s)| (s.as_str(), format!("--set {name}={s}")));
        match value {
            RawParam::Num(n) => {
                let v = match &set {
                    Some((s, at)) => expr::eval_const(s, &params).map_err(|e| e.at(at))?,
                    None => number(n, &params, &place)?,
                };
                params.insert(name.clone(), v);
            }
            RawParam::Bool(b) => {
                let b = match &set {
                    Some((s, at)) => parse_bool(s, at)?,
                    None => *b,
                };
                params.insert(name.clone(), if b { 1.0 } else { 0.0 });
                params.set_kind(name, Kind::Bool(b));
            }
            RawParam::List(items) => {
                let values = match &set {
                    Some((s, at)) => split_list(s, at)?
                        .iter()
                        .map(|t| expr::eval_const(t, &params).map_err(|e| e.at(at)))
                        .collect::<Result<Vec<f64>>>()?,
                    None => items
                        .iter()
                        .enumerate()
                        .map(|(k, n)| number(n, &params, &format!("{place}[{k}]")))
                        .collect::<Result<Vec<f64>>>()?,
                };
                params.insert_list(name, values);
            }
            RawParam::Each(e) => {
                let values = match &set {
                    Some((s, at)) => split_list(s, at)?
                        .iter()
                        .map(|t| expr::eval_const(t, &params).map_err(|e| e.at(at)))
                        .collect::<Result<Vec<f64>>>()?,
                    None => each(e, &params, &place)?,
                };
                params.insert_list(name, values);
            }
            RawParam::Choice(c) => {
                let s = choice(c, name, &set)?;
                let v = params.symbol(&s).expect("the choices were declared");
                params.insert(name.clone(), v);
                params.set_kind(name, Kind::Choice(s));
            }
        }
    }
    unknown_sets(raw, sets)?;
    Ok(params)
}

/// Most values of a list made by a loop.
pub(crate) const MAX_EACH: usize = 100_000;

/// The values of a list made by a loop (`{for: {k: RANGE}, value: EXPR}`,
/// written at `place`): EXPR over `params` and `k`, for each value of `k`.
pub(crate) fn each(e: &RawEach, params: &Params, place: &str) -> Result<Vec<f64>> {
    let at = join(place, "for");
    let mut names = e.each.iter();
    let (Some((var, l)), None) = (names.next(), names.next()) else {
        return Err(Error::input(
            at,
            "expected one name and its values, e.g. {k: \"0..3\"}",
        ));
    };
    if !is_identifier(var) || expr::is_reserved(var) {
        return Err(Error::input(
            join(&at, var),
            format!("`{var}` cannot name a loop variable; expected letters, digits and `_`, not a name expressions already use"),
        ));
    }
    let ks = match l {
        RawLoop::Range(s) => range(s, params, &join(&at, var), MAX_EACH, "values in a list")?,
        RawLoop::List(v) => v
            .iter()
            .enumerate()
            .map(|(k, n)| number(n, params, &format!("{}[{k}]", join(&at, var))))
            .collect::<Result<Vec<f64>>>()?,
    };
    let mut inner = params.clone();
    let value = join(place, "value");
    ks.iter()
        .map(|&k| {
            inner.insert(var.clone(), k);
            number(&e.value, &inner, &value)
        })
        .collect()
}

/// The values of `"a..b"` or `"a..b:step"`: a, a + step, … up to b
/// included (within 1e-9 of a step, so 0..1:0.1 ends at 1); none when the
/// step never reaches b (`1..0`).
///
/// At most `max` values (`what` names the limit in the error).
pub(crate) fn range(
    s: &str,
    params: &Params,
    place: &str,
    max: usize,
    what: &str,
) -> Result<Vec<f64>> {
    let not_range = || {
        Error::input(place, format!("`{s}` is not a range; expected \"a..b\" or \"a..b:step\" (b included), or a list [v1, v2, …]"))
    };
    let (a, rest) = s.split_once("..").ok_or_else(not_range)?;
    let (b, step) = match rest.split_once(':') {
        Some((b, st)) => (b, Some(st)),
        None => (rest, None),
    };
    if a.trim().is_empty() || b.trim().is_empty() {
        return Err(not_range());
    }
    let a = expr::eval_const(a, params).map_err(|e| e.at(place))?;
    let b = expr::eval_const(b, params).map_err(|e| e.at(place))?;
    let step = match step {
        Some(st) => expr::eval_const(st, params).map_err(|e| e.at(place))?,
        None => 1.0,
    };
    if step == 0.0 {
        return Err(Error::input(
            place,
            format!("the step of `{s}` is 0; expected a step that moves from a to b"),
        ));
    }
    let span = (b - a) / step;
    if span < -1e-9 {
        // from a the step never reaches b: no values (`1..n` with n = 0
        // makes no copy, as a part switched off)
        return Ok(Vec::new());
    }
    let n = libm::floor(span + 1e-9 * span.abs().max(1.0)) + 1.0;
    if !n.is_finite() || n > max as f64 {
        return Err(Error::input(place, format!(
            "`{s}` has {} values, more than the limit of {max} {what}; expected a shorter range or a larger step",
            if n.is_finite() { format!("{n}") } else { "endless".into() }
        )));
    }
    Ok((0..n as usize).map(|k| a + k as f64 * step).collect())
}

/// The string a choice param is: `set` (its `--set` text and place), which
/// must be one of its choices, or its default.
fn choice(c: &RawChoice, name: &str, set: &Option<(&str, String)>) -> Result<String> {
    let Some((s, at)) = set else {
        return Ok(c.default.clone());
    };
    let s = s.trim_matches(|c| c == '\'' || c == '"');
    if !c.choices.iter().any(|x| x == s) {
        return Err(Error::input(
            at,
            format!(
                "`{s}` is not a choice of `{name}`; expected one of {}",
                c.choices.join(", ")
            ),
        ));
    }
    Ok(s.to_string())
}

/// Refuses a `--set` of a name that is none of the recipe's params.
fn unknown_sets(raw: &IndexMap<String, RawParam>, sets: &[(String, String)]) -> Result<()> {
    for (name, s) in sets {
        if !raw.contains_key(name) {
            let known: Vec<&str> = raw.keys().map(String::as_str).collect();
            return Err(Error::input(
                format!("--set {name}={s}"),
                if known.is_empty() {
                    format!("unknown param `{name}`; this recipe has no params")
                } else {
                    format!(
                        "unknown param `{name}`; the recipe's params are {}",
                        known.join(", ")
                    )
                },
            ));
        }
    }
    Ok(())
}

/// A number or expression as written at `place`, over `params`.
fn number(n: &Num, params: &Params, place: &str) -> Result<f64> {
    match n {
        Num::Value(v) => finite(*v, place),
        Num::Expr(s) => expr::eval_const(s, params).map_err(|e| e.at(place)),
    }
}

/// A choice param's strings: at least one, each once, names (letters,
/// digits and `_`), the default among them.
pub(crate) fn check_choices(c: &RawChoice, place: &str) -> Result<()> {
    let choices = join(place, key!(RawChoice, choices));
    if c.choices.is_empty() {
        return Err(Error::input(choices, "expected at least one choice"));
    }
    for (k, s) in c.choices.iter().enumerate() {
        if !is_identifier(s) {
            return Err(Error::input(
                format!("{choices}[{k}]"),
                format!("`{s}` is not allowed; a choice is letters, digits and `_`, not starting with a digit"),
            ));
        }
        if c.choices[..k].contains(s) {
            return Err(Error::input(
                format!("{choices}[{k}]"),
                format!("`{s}` is given twice; expected each choice once"),
            ));
        }
    }
    if !c.choices.contains(&c.default) {
        return Err(Error::input(
            join(place, key!(RawChoice, default)),
            format!(
                "`{}` is not one of the choices; expected one of {}",
                c.default,
                c.choices.join(", ")
            ),
        ));
    }
    Ok(())
}

fn parse_bool(s: &str, place: &str) -> Result<bool> {
    match s {
        "true" => Ok(true),
        "false" => Ok(false),
        _ => Err(Error::input(
            place,
            format!("`{s}` is not allowed for a true/false param; expected true or false"),
        )),
    }
}

/// The items of `[a, b, …]` (commas inside parentheses stay with their item).
fn split_list(s: &str, place: &str) -> Result<Vec<String>> {
    let inner = s
        .trim()
        .strip_prefix('[')
        .and_then(|t| t.strip_suffix(']'))
        .ok_or_else(|| {
            Error::input(
                place,
                "a list param takes a list: expected [a, b, …], e.g. --set fractions=[0, 0.5, 1]",
            )
        })?;
    if inner.trim().is_empty() {
        return Ok(Vec::new());
    }
    let (mut items, mut depth, mut start) = (Vec::new(), 0i32, 0);
    for (k, c) in inner.char_indices() {
        match c {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' if depth == 0 => {
                items.push(inner[start..k].trim().to_string());
                start = k + 1;
            }
            _ => {}
        }
    }
    items.push(inner[start..].trim().to_string());
    if items.iter().any(String::is_empty) {
        return Err(Error::input(place, "an empty item; expected [a, b, …]"));
    }
    Ok(items)
}

/// A number as short as it can be written: `3`, `1.5`, `0.1`.
pub(crate) fn format_value(v: f64) -> String {
    let r = libm::round(v * 1e9) / 1e9; // 0.30000000000000004 → 0.3
    let s = format!("{r}");
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// Most values one `--sweep` may take.
pub(crate) const MAX_SWEEP_VALUES: u64 = 10_000;

/// Parses `NAME=v1,v2,…`, `NAME=a..b:step` (b included when reached) or
/// `NAME=a..b` (step 1, as `for:`).
pub(crate) fn parse_sweep(s: &str) -> Result<(String, Vec<String>)> {
    let place = format!("--sweep {s}");
    let (name, spec) = s
        .split_once('=')
        .filter(|(n, v)| !n.trim().is_empty() && !v.trim().is_empty())
        .ok_or_else(|| {
            Error::input(
                &place,
                "expected NAME=v1,v2,… or NAME=a..b:step, e.g. --sweep cycles=3,4,5",
            )
        })?;
    let spec = spec.trim();
    // a..b steps by 1, as a part's `for: "a..b"` does
    let range = spec.contains("..").then(|| match spec.split_once(':') {
        Some((range, step)) => (range.split_once(".."), step),
        None => (spec.split_once(".."), "1"),
    });
    let values = if let Some((range, step)) = range {
        let (a, b) = range.ok_or_else(|| {
            Error::input(
                &place,
                "a range is written a..b:step, e.g. --sweep pitch=0.3..0.5:0.1",
            )
        })?;
        let num = |t: &str, what: &str| -> Result<f64> {
            t.trim().parse::<f64>().map_err(|_| {
                Error::input(
                    &place,
                    format!("the {what} `{t}` is not a number; expected a..b:step"),
                )
            })
        };
        let (a, b, step) = (num(a, "start")?, num(b, "end")?, num(step, "step")?);
        if step.is_nan() || step <= 0.0 || b < a || !a.is_finite() || !b.is_finite() {
            return Err(Error::input(&place, "expected start ≤ end and a step > 0")
                .with_help("a sweep is NAME=v1,v2,… (a list), NAME=a..b:step or NAME=a..b (a range from a up to b, step 1)"));
        }
        // as a float first: a tiny step makes more values than u64 holds
        let steps = libm::floor((b - a) / step + 1e-9);
        if steps.is_nan() || steps >= MAX_SWEEP_VALUES as f64 {
            return Err(Error::input(
                &place,
                format!(
                    "{} values; expected at most {MAX_SWEEP_VALUES}",
                    format_value(steps + 1.0)
                ),
            ));
        }
        let values: Vec<String> = (0..steps as u64 + 1)
            .map(|k| format_value(a + step * k as f64))
            .collect();
        if let Some(w) = values.windows(2).find(|w| w[0] == w[1]) {
            return Err(Error::input(
                &place,
                format!(
                    "the step {step} is too small to tell the values apart ({} twice); expected a larger step",
                    w[0]
                ),
            ));
        }
        values
    } else {
        let vals: Vec<String> = spec.split(',').map(|v| v.trim().to_string()).collect();
        if vals.iter().any(String::is_empty) {
            return Err(Error::input(&place, "an empty value; expected v1,v2,…"));
        }
        vals
    };
    Ok((name.trim().to_string(), values))
}

/// Parses a `NAME=VALUE` of `--set`.
pub(crate) fn parse_set(s: &str) -> Result<(String, String)> {
    match s.split_once('=') {
        Some((n, v)) if !n.trim().is_empty() && !v.trim().is_empty() => {
            Ok((n.trim().to_string(), v.trim().to_string()))
        }
        _ => Err(Error::input(
            format!("--set {s}"),
            "expected NAME=VALUE, e.g. --set radius=30",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recipe::yaml::parse_yaml;

    fn eval(yaml: &str, sets: &[(&str, &str)]) -> Result<Params> {
        let raw: IndexMap<String, RawParam> = parse_yaml(yaml, "t").unwrap();
        let sets: Vec<(String, String)> = sets
            .iter()
            .map(|(n, v)| (n.to_string(), v.to_string()))
            .collect();
        eval_params(&raw, &sets)
    }

    const PARAMS: &str = "part_type: {choices: [wing_nut, wing_bolt, threaded_tube], default: wing_bolt}\nangry: false\nfr: [0, 0.5, 1]\nm: \"len(fr) + if(part_type == 'wing_bolt', 10, 20) + angry\"\n";

    #[test]
    fn choices_booleans_and_lists() {
        let p = eval(PARAMS, &[]).unwrap();
        assert_eq!(p["m"], 13.0);
        assert_eq!(p.show("part_type").as_deref(), Some("wing_bolt"));
        assert_eq!(p.show("angry").as_deref(), Some("false"));
        assert_eq!(p.show("fr").as_deref(), Some("[0, 0.5, 1]"));
        let p = eval(
            PARAMS,
            &[
                ("part_type", "wing_nut"),
                ("angry", "true"),
                ("fr", "[1, max(2, 3)]"),
            ],
        )
        .unwrap();
        assert_eq!(p["m"], 2.0 + 20.0 + 1.0);
        assert_eq!(p.list("fr"), Some(&[1.0, 3.0][..]));
    }

    #[test]
    fn a_list_made_by_a_loop_and_its_sums() {
        let yaml = "a: [10, 20, 30]\nsq: {for: {k: \"0..3\"}, value: \"k^2\"}\nrun: {for: {k: \"0..3\"}, value: \"sum(a, 0, k - 1)\"}\nback: {for: {k: [2, 0]}, value: \"a[k]\"}\ntot: \"sum(sq) + sum(a, 1, 2) + sum(a, 2, 1)\"\n";
        let p = eval(yaml, &[]).unwrap();
        assert_eq!(p.list("sq"), Some(&[0.0, 1.0, 4.0, 9.0][..]));
        // the partial sums: the points a walk of steps a reaches
        assert_eq!(p.list("run"), Some(&[0.0, 10.0, 30.0, 60.0][..]));
        assert_eq!(p.list("back"), Some(&[30.0, 10.0][..]));
        assert_eq!(p["tot"], 14.0 + 50.0);
        // the loop's name is the loop's alone
        assert!(!p.contains_key("k"));
        // --set gives it as any list
        let p = eval(yaml, &[("sq", "[1, 2]")]).unwrap();
        assert_eq!(p["tot"], 3.0 + 50.0);
    }

    #[test]
    fn a_bad_loop_list_or_sum_is_named() {
        let e = eval("l: {for: {k: \"0..2\"}, value: \"q\"}\n", &[]).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("params.l.value"), "{e}");
        let e = eval("l: {for: {k: \"0..2\", j: [1]}, value: 1}\n", &[]).unwrap_err();
        assert!(e.message.contains("one name"), "{e}");
        let e = parse_yaml::<IndexMap<String, RawParam>>(
            "l: {for: {k: \"0..2\"}, value: 1, default: 2}\n",
            "t",
        )
        .unwrap_err();
        assert!(e.message.contains("a list made by a loop"), "{e}");
        let e = eval("l: [1, 2]\ntot: \"sum(l, 0, 2)\"\n", &[]).unwrap_err();
        assert!(e.message.contains("indices 0 to 1"), "{e}");
        let e = eval("l: 3\ntot: \"sum(l)\"\n", &[]).unwrap_err();
        assert!(e.message.contains("the name of a list param"), "{e}");
    }

    #[test]
    fn wrong_values_name_what_is_allowed() {
        let e = eval(PARAMS, &[("part_type", "wing")]).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("--set part_type=wing"));
        assert!(
            e.message
                .contains("expected one of wing_nut, wing_bolt, threaded_tube"),
            "{e}"
        );
        let e = eval(PARAMS, &[("angry", "yes")]).unwrap_err();
        assert!(e.message.contains("expected true or false"), "{e}");
        let e = eval(PARAMS, &[("fr", "3")]).unwrap_err();
        assert!(e.message.contains("expected [a, b, …]"), "{e}");
        let e = eval("k: {choices: [a, b], default: c}\n", &[]).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("params.k.default"));
        let e = eval("k: {choices: [a, 'b c'], default: a}\n", &[]).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("params.k.choices[1]"));
        let e = parse_yaml::<IndexMap<String, RawParam>>(
            "k: {choices: [a], default: a, other: 1}\n",
            "t",
        )
        .unwrap_err();
        assert_eq!(e.place.as_deref(), Some("k.other"));
    }
}
