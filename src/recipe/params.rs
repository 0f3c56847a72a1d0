//! A recipe's params: evaluated in order, each over the ones before it, with
//! the command line's `--set NAME=VALUE` in place of a param's own value.

use indexmap::IndexMap;

use crate::base::error::{Error, Result};
use crate::base::expr::{self, Params};
use crate::recipe::eval::{finite, join, key};
use crate::recipe::schema::{Num, RawRecipe};

pub(crate) fn is_identifier(s: &str) -> bool {
    let mut cs = s.chars();
    matches!(cs.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && cs.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Evaluates params in order, each over the ones before it; `sets` replaces
/// a param's expression (`--set NAME=VALUE`).
pub(crate) fn eval_params(
    raw: &IndexMap<String, Num>,
    sets: &[(String, String)],
) -> Result<Params> {
    let mut params = Params::new();
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
        let v = match sets.iter().rev().find(|(n, _)| n == name) {
            Some((_, s)) => {
                expr::eval_const(s, &params).map_err(|e| e.at(format!("--set {name}={s}")))?
            }
            None => match value {
                Num::Value(v) => finite(*v, &place)?,
                Num::Expr(s) => expr::eval_const(s, &params).map_err(|e| e.at(&place))?,
            },
        };
        params.insert(name.clone(), v);
    }
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
    Ok(params)
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
