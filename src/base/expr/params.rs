//! The params an expression sees: named numbers in order, and beside them
//! the lists and choices (strings) a recipe may declare.

use std::ops::{Deref, DerefMut};
use std::sync::Arc;

use indexmap::IndexMap;

/// Named params of a recipe, in the order they were defined: the numbers
/// (a map, through `Deref`), the list params (read as `name[k]` and
/// `len(name)`), the strings of the choice params (a choice param's number
/// is the number of its string, which a quoted string in an expression
/// stands for: `part_type == 'wing_nut'`), and how a param that is not a
/// plain number is shown (`wing_nut`, `true`, `[1, 2]`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Params {
    values: IndexMap<String, f64>,
    lists: IndexMap<String, Arc<Vec<f64>>>,
    symbols: Arc<IndexMap<String, f64>>,
    kinds: IndexMap<String, Kind>,
}

/// What a param that is not a plain number is.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Kind {
    /// One of the strings of a choice param.
    Choice(String),
    /// `true` or `false` (1 or 0 in expressions).
    Bool(bool),
    /// A list of numbers.
    List,
}

impl Deref for Params {
    type Target = IndexMap<String, f64>;
    fn deref(&self) -> &IndexMap<String, f64> {
        &self.values
    }
}

impl DerefMut for Params {
    fn deref_mut(&mut self) -> &mut IndexMap<String, f64> {
        &mut self.values
    }
}

impl Params {
    /// No params.
    pub(crate) fn new() -> Params {
        Params::default()
    }

    /// Declares the strings of every choice param: each gets the number of
    /// its first place in `strings` (the same string, the same number).
    pub(crate) fn set_symbols<'a>(&mut self, strings: impl IntoIterator<Item = &'a str>) {
        let mut m = IndexMap::new();
        for s in strings {
            let k = m.len() as f64;
            m.entry(s.to_string()).or_insert(k);
        }
        self.symbols = Arc::new(m);
    }

    /// The number a quoted string stands for, if it is a declared choice.
    pub(crate) fn symbol(&self, s: &str) -> Option<f64> {
        self.symbols.get(s).copied()
    }

    /// The declared choice strings, in order.
    pub(crate) fn symbols(&self) -> impl Iterator<Item = &str> {
        self.symbols.keys().map(String::as_str)
    }

    /// Adds a list param.
    pub(crate) fn insert_list(&mut self, name: &str, values: Vec<f64>) {
        self.kinds.insert(name.to_string(), Kind::List);
        self.lists.insert(name.to_string(), Arc::new(values));
    }

    /// The values of list param `name`.
    pub(crate) fn list(&self, name: &str) -> Option<&[f64]> {
        self.lists.get(name).map(|v| v.as_slice())
    }

    /// The names of the list params.
    pub(crate) fn list_names(&self) -> impl Iterator<Item = &str> {
        self.lists.keys().map(String::as_str)
    }

    /// Whether `name` is a param of any kind (a number or a list).
    pub(crate) fn has(&self, name: &str) -> bool {
        self.values.contains_key(name) || self.lists.contains_key(name)
    }

    /// Marks number param `name` as a choice or a boolean.
    pub(crate) fn set_kind(&mut self, name: &str, kind: Kind) {
        self.kinds.insert(name.to_string(), kind);
    }

    /// What param `name` is when it is not a plain number.
    pub(crate) fn kind(&self, name: &str) -> Option<&Kind> {
        self.kinds.get(name)
    }

    /// Param `name` as a person reads it, when it is not a plain number: a
    /// choice's string, `true` or `false`, a list `[a, b]`.
    pub(crate) fn text(&self, name: &str) -> Option<String> {
        Some(match self.kinds.get(name)? {
            Kind::Choice(s) => s.clone(),
            Kind::Bool(b) => b.to_string(),
            Kind::List => show_list(self.list(name)?),
        })
    }

    /// Param `name` as a person reads it: [`Params::text`], or the number
    /// written short.
    pub(crate) fn show(&self, name: &str) -> Option<String> {
        self.text(name)
            .or_else(|| self.values.get(name).map(|&v| short(v)))
    }

    /// Every param as JSON, in order: numbers, then lists; a choice as its
    /// string, a boolean as `true`/`false`.
    pub(crate) fn to_json(&self) -> IndexMap<String, serde_json::Value> {
        let mut m = IndexMap::new();
        for (k, &v) in &self.values {
            let j = match self.kinds.get(k) {
                Some(Kind::Choice(s)) => serde_json::Value::from(s.as_str()),
                Some(Kind::Bool(b)) => serde_json::Value::from(*b),
                _ => serde_json::Value::from(v),
            };
            m.insert(k.clone(), j);
        }
        for (k, l) in &self.lists {
            m.insert(k.clone(), serde_json::Value::from(l.as_slice().to_vec()));
        }
        m
    }
}

/// A number as short as it can be written: `3`, `1.5`, `0.1` (rounded to
/// nine decimals, so 0.30000000000000004 is 0.3).
pub(crate) fn short(v: f64) -> String {
    let r = libm::round(v * 1e9) / 1e9;
    let s = format!("{r}");
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

fn show_list(values: &[f64]) -> String {
    let v: Vec<String> = values.iter().map(|&x| short(x)).collect();
    format!("[{}]", v.join(", "))
}
