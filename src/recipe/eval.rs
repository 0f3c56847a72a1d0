//! Numbers as written ([`Num`]: a literal or an expression string over the
//! params) evaluated, with the key path named in every error.

use glam::DVec3;

use crate::base::error::{Error, Result};
use crate::base::expr::{self, Expr, Params};
use crate::recipe::schema::{Num, Num3};

/// Evaluates one number with the place named (a primitive's view of a [`Scope`]).
pub type NumFn<'a> = &'a dyn Fn(&Num, &str) -> Result<f64>;

/// Evaluates a recipe's numbers against its params; every error names the
/// key path given as `place`.
#[derive(Clone, Copy, Debug)]
pub struct Scope<'a> {
    /// The params (and template or loop values) expressions may use.
    pub params: &'a Params,
}

impl<'a> Scope<'a> {
    /// A scope over `params`.
    pub fn new(params: &'a Params) -> Scope<'a> {
        Scope { params }
    }

    /// A number: a literal, or an expression over the params.
    pub fn num(&self, n: &Num, place: &str) -> Result<f64> {
        match n {
            Num::Value(v) => finite(*v, place),
            Num::Expr(s) => expr::eval_const(s, self.params).map_err(|e| e.at(place)),
        }
    }

    /// A number > 0.
    pub fn positive(&self, n: &Num, place: &str) -> Result<f64> {
        let v = self.num(n, place)?;
        if v > 0.0 {
            Ok(v)
        } else {
            Err(Error::input(
                place,
                format!("{v} is not allowed; expected a number > 0"),
            ))
        }
    }

    /// `n` as [`Scope::positive`] reads it, or `default` when absent.
    pub fn positive_or(&self, n: &Option<Num>, place: &str, default: f64) -> Result<f64> {
        match n {
            Some(n) => self.positive(n, place),
            None => Ok(default),
        }
    }

    /// A number ≥ 0.
    pub fn non_negative(&self, n: &Num, place: &str) -> Result<f64> {
        let v = self.num(n, place)?;
        if v >= 0.0 {
            Ok(v)
        } else {
            Err(Error::input(
                place,
                format!("{v} is not allowed; expected a number ≥ 0"),
            ))
        }
    }

    /// A whole number from `min` to 10,000,000.
    pub fn whole(&self, n: &Num, place: &str, min: u32) -> Result<u32> {
        let v = self.num(n, place)?;
        if v.fract() != 0.0 || v < min as f64 || v > 1e7 {
            return Err(Error::input(
                place,
                format!("{v} is not allowed; expected a whole number from {min} to 10000000"),
            ));
        }
        Ok(v as u32)
    }

    /// A whole number from `min` to `max`.
    pub fn whole_max(&self, n: &Num, place: &str, min: u32, max: u32) -> Result<u32> {
        let v = self.num(n, place)?;
        if v.fract() != 0.0 || v < min as f64 || v > max as f64 {
            return Err(Error::input(
                place,
                format!("{v} is not allowed; expected a whole number from {min} to {max}"),
            ));
        }
        Ok(v as u32)
    }

    /// `segments:` (a whole number ≥ 3), 72 when absent.
    pub fn segments(&self, n: &Option<Num>, place: &str) -> Result<u32> {
        match n {
            Some(n) => self.whole(n, &format!("{place}.segments"), 3),
            None => Ok(72),
        }
    }

    /// Three numbers, a point or vector.
    pub fn point(&self, n: &Num3, place: &str) -> Result<DVec3> {
        Ok(DVec3::new(
            self.num(&n[0], &format!("{place}[0]"))?,
            self.num(&n[1], &format!("{place}[1]"))?,
            self.num(&n[2], &format!("{place}[2]"))?,
        ))
    }

    /// `center:`, the origin when absent.
    pub fn center(&self, n: &Option<Num3>, place: &str) -> Result<DVec3> {
        match n {
            Some(n) => self.point(n, &format!("{place}.center")),
            None => Ok(DVec3::ZERO),
        }
    }

    /// An expression compiled over the params, with only the `allowed` variables.
    pub fn expr(&self, n: &Num, allowed: &[usize], place: &str) -> Result<Expr> {
        Expr::compile(&n.src(), self.params, allowed).map_err(|e| e.at(place))
    }
}

/// `v` when it is a finite number; otherwise an error naming `place`.
pub fn finite(v: f64, place: &str) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::input(
            place,
            format!("{v} is not allowed; expected a finite number"),
        ))
    }
}
