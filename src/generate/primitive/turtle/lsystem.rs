//! Lindenmayer systems as turtle programs (Prusinkiewicz and Lindenmayer,
//! *The Algorithmic Beauty of Plants*, ch. 1).
//!
//! An L-system rewrites every symbol of a word at once by its rule (symbols
//! without a rule stay), `iterations` times, starting from the axiom; each
//! symbol of the final word then runs its commands (symbols without commands
//! do nothing, as `X` and `Y` of the Hilbert curve). The word grows
//! exponentially, so it is never built: the interpreter walks the derivation
//! tree depth first, a symbol at depth d < iterations standing for its
//! rule's symbols at depth d + 1. Memory is one task on the interpreter's
//! stack per iteration, and the interpreter's budget of strings and steps
//! bounds the time.

use super::program::{Cmd, Val};

/// Most iterations an L-system may ask for (a word of one symbol doubling
/// every iteration is already 2^40 symbols long there).
pub(crate) const MAX_ITERATIONS: u32 = 40;

/// A compiled L-system: symbols numbered in order of first appearance.
#[derive(Clone, Debug)]
pub(crate) struct Lsystem {
    #[cfg_attr(not(test), allow(dead_code))]
    /// The symbols, by number.
    pub(crate) symbols: Vec<char>,
    /// The axiom, as symbol numbers.
    pub(crate) axiom: Vec<u16>,
    /// Each symbol's replacement, if it has a rule.
    pub(crate) rules: Vec<Option<Vec<u16>>>,
    /// Each symbol's commands (empty: it draws nothing).
    pub(crate) commands: Vec<Vec<Cmd>>,
    /// How many times the rules apply, evaluated when the command runs.
    pub(crate) iterations: Val,
}

impl Lsystem {
    #[cfg(test)]
    /// The word after `n` iterations, if it has at most `max` symbols (for tests
    /// and reports; the interpreter never builds it).
    pub(crate) fn word(&self, n: u32, max: usize) -> Option<String> {
        let mut w = self.axiom.clone();
        for _ in 0..n {
            let mut next = Vec::new();
            for &s in &w {
                match &self.rules[s as usize] {
                    Some(r) => next.extend_from_slice(r),
                    None => next.push(s),
                }
                if next.len() > max {
                    return None;
                }
            }
            w = next;
        }
        Some(w.iter().map(|&s| self.symbols[s as usize]).collect())
    }
}
