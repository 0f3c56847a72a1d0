//! Numbers as written ([`Num`]: a literal or an expression string over the
//! params) evaluated, with the key path named in every error.
//!
//! Key paths come from the field names: `at!``(raw.height)` is the field
//! and its key `height` (its own name, which is the key serde reads it by),
//! `key!``(raw.infill)` the key alone; a [`Scope`] holds the path above
//! (`solid.infill`) and joins them. Only keys that are no field's name
//! (a serde `rename`, an enum's variant, a list index) are written out.

use glam::DVec3;

use crate::base::error::{Error, Result};
use crate::base::expr::{self, Expr, Params};
use crate::recipe::schema::{Num, Num3};

/// A value as written and its key: what `at!` makes of a field.
#[derive(Debug)]
pub(crate) struct At<'v, T> {
    /// The value.
    pub(crate) value: &'v T,
    /// Its key in the map that holds it.
    pub(crate) key: &'static str,
}

impl<T> Clone for At<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for At<'_, T> {}

impl<'v, T> At<'v, T> {
    /// `value` at `key`, for a key that is no field's name.
    pub(crate) fn new(value: &'v T, key: &'static str) -> At<'v, T> {
        At { value, key }
    }
}

impl<'v, T> At<'v, Option<T>> {
    /// The value, when given, at the same key.
    pub(crate) fn some(self) -> Option<At<'v, T>> {
        self.value.as_ref().map(|value| At {
            value,
            key: self.key,
        })
    }
}

/// `at!(raw.field)`: the field and its key, the field's own name
/// (`stringify!`): an [`At`]. `at!(field)` is the same for a binding that a
/// pattern named after its field (`RawStep::Subdivide { max_length }`).
macro_rules! at {
    ($raw:ident . $field:ident) => {
        $crate::recipe::eval::At {
            value: &$raw.$field,
            key: stringify!($field),
        }
    };
    ($field:ident) => {
        $crate::recipe::eval::At {
            value: $field,
            key: stringify!($field),
        }
    };
}

/// `key!(raw.field)`: the key of a field, its own name (the compiler checks
/// that the field exists); `key!(Type, field)` the same from the type.
macro_rules! key {
    ($raw:ident . $field:ident) => {{
        let _ = &$raw.$field;
        stringify!($field)
    }};
    ($ty:ty, $field:ident) => {{
        let _ = |raw: &$ty| {
            let _ = &raw.$field;
        };
        stringify!($field)
    }};
}

pub(crate) use {at, key};

/// `key` under the key path `prefix`: `prefix.key`, or `prefix[k]` for an
/// index (as [`Error::under`] joins them).
pub(crate) fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else if key.is_empty() {
        prefix.to_string()
    } else if key.starts_with('[') {
        format!("{prefix}{key}")
    } else {
        format!("{prefix}.{key}")
    }
}

/// Evaluates a recipe's numbers against its params; every error names the
/// key path: the scope's own path joined with the value's key.
#[derive(Clone, Debug)]
pub(crate) struct Scope<'a> {
    /// The params (and template or loop values) expressions may use.
    pub(crate) params: &'a Params,
    /// The key path the keys it is given are under; empty at the top.
    path: String,
}

impl<'a> Scope<'a> {
    /// A scope over `params`, at the top.
    pub(crate) fn new(params: &'a Params) -> Scope<'a> {
        Scope {
            params,
            path: String::new(),
        }
    }

    /// The same params under `key` (`helix`, `features[1]`).
    pub(crate) fn under(&self, key: &str) -> Scope<'a> {
        Scope {
            params: self.params,
            path: join(&self.path, key),
        }
    }

    /// The key path of `key` in this scope.
    pub(crate) fn place(&self, key: &str) -> String {
        join(&self.path, key)
    }

    /// This scope's own key path.
    pub(crate) fn here(&self) -> &str {
        &self.path
    }

    /// An input error at `key`.
    pub(crate) fn error(&self, key: &str, message: impl Into<String>) -> Error {
        Error::input(self.place(key), message)
    }

    /// A number: a literal, or an expression over the params.
    pub(crate) fn num(&self, at: At<Num>) -> Result<f64> {
        eval(at.value, self.params, &self.place(at.key))
    }

    /// A number for which `ok` holds, else an error saying it `expected`.
    pub(crate) fn checked(
        &self,
        at: At<Num>,
        ok: impl Fn(f64) -> bool,
        expected: &str,
    ) -> Result<f64> {
        let v = self.num(at)?;
        if ok(v) {
            Ok(v)
        } else {
            Err(self.error(at.key, format!("{v} is not allowed; expected {expected}")))
        }
    }

    /// A number checked as [`Scope::checked`] does, or `default` when absent.
    pub(crate) fn checked_or(
        &self,
        at: At<Option<Num>>,
        default: f64,
        ok: impl Fn(f64) -> bool,
        expected: &str,
    ) -> Result<f64> {
        match at.some() {
            Some(n) => self.checked(n, ok, expected),
            None => Ok(default),
        }
    }

    /// A number > 0.
    pub(crate) fn positive(&self, at: At<Num>) -> Result<f64> {
        self.checked(at, |v| v > 0.0, "a number > 0")
    }

    /// A number > 0, or `default` when absent.
    pub(crate) fn positive_or(&self, at: At<Option<Num>>, default: f64) -> Result<f64> {
        self.checked_or(at, default, |v| v > 0.0, "a number > 0")
    }

    /// A number ≥ 0.
    pub(crate) fn non_negative(&self, at: At<Num>) -> Result<f64> {
        self.checked(at, |v| v >= 0.0, "a number ≥ 0")
    }

    /// A whole number from `min` to 10,000,000.
    pub(crate) fn whole(&self, at: At<Num>, min: u32) -> Result<u32> {
        self.whole_max(at, min, 10_000_000)
    }

    /// A whole number from `min` to `max`.
    pub(crate) fn whole_max(&self, at: At<Num>, min: u32, max: u32) -> Result<u32> {
        let ok = |v: f64| v.fract() == 0.0 && v >= min as f64 && v <= max as f64;
        let expected = format!("a whole number from {min} to {max}");
        Ok(self.checked(at, ok, &expected)? as u32)
    }

    /// `segments:` (a whole number ≥ 3), 72 when absent.
    pub(crate) fn segments(&self, at: At<Option<Num>>) -> Result<u32> {
        match at.some() {
            Some(n) => self.whole(n, 3),
            None => Ok(72),
        }
    }

    /// Three numbers, a point or vector; errors name `KEY[i]`.
    pub(crate) fn point(&self, at: At<Num3>) -> Result<DVec3> {
        let s = self.under(at.key);
        let n = at.value;
        Ok(DVec3::new(
            s.num(At::new(&n[0], "[0]"))?,
            s.num(At::new(&n[1], "[1]"))?,
            s.num(At::new(&n[2], "[2]"))?,
        ))
    }

    /// A point, or `default` when absent.
    pub(crate) fn point_or(&self, at: At<Option<Num3>>, default: DVec3) -> Result<DVec3> {
        match at.some() {
            Some(n) => self.point(n),
            None => Ok(default),
        }
    }

    /// `center:`, the origin when absent.
    pub(crate) fn center(&self, at: At<Option<Num3>>) -> Result<DVec3> {
        self.point_or(at, DVec3::ZERO)
    }

    /// An expression compiled over the params, with only the `allowed` variables.
    pub(crate) fn expr(&self, at: At<Num>, allowed: &[usize]) -> Result<Expr> {
        Expr::compile(&at.value.src(), self.params, allowed).map_err(|e| e.at(self.place(at.key)))
    }
}

/// A number written at `place` (a key that is no field's, such as a
/// param's name): a literal, or an expression over `params`.
pub(crate) fn eval(n: &Num, params: &Params, place: &str) -> Result<f64> {
    match n {
        Num::Value(v) => finite(*v, place),
        Num::Expr(s) => expr::eval_const(s, params).map_err(|e| e.at(place)),
    }
}

/// `v` when it is a finite number; otherwise an error naming `place`.
pub(crate) fn finite(v: f64, place: &str) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::input(
            place,
            format!("{v} is not allowed; expected a finite number"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_the_field_names_under_the_scope_path() {
        struct Raw {
            height: Num,
            center: Option<Num3>,
        }
        let raw = Raw {
            height: Num::Value(-1.0),
            center: Some([Num::Value(0.0), Num::Value(1.0), Num::Expr("q".into())]),
        };
        let params = Params::new();
        let s = Scope::new(&params).under("helix");
        let e = s.positive(at!(raw.height)).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("helix.height"));
        assert_eq!(e.message, "-1 is not allowed; expected a number > 0");
        let e = s.center(at!(raw.center)).unwrap_err();
        assert_eq!(e.place.as_deref(), Some("helix.center[2]"));
        assert_eq!(key!(raw.center), "center");
        assert_eq!(join("a", "[1]"), "a[1]");
        assert_eq!(join("", "b"), "b");
        assert_eq!(Scope::new(&params).place("x"), "x");
    }
}
