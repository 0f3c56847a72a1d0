//! Lindenmayer systems as turtle programs (Prusinkiewicz and Lindenmayer,
//! *The Algorithmic Beauty of Plants*, ch. 1).
//!
//! An L-system rewrites every symbol of a word at once by its rule (symbols
//! without a rule stay), `iterations` times, starting from the axiom; each
//! symbol of the final word then runs its commands (symbols without commands
//! do nothing, as `X` and `Y` of the Hilbert curve). The word grows
//! exponentially, so it is never built: the interpreter walks the derivation
//! tree depth first, a symbol at depth d < iterations standing for its
//! rule's symbols at depth d + 1. Memory is one stack frame per iteration,
//! and the interpreter's budget of strings and steps bounds the time.

use std::sync::Arc;

use super::program::{Cmd, Compiler, RawLsystem, Val};
use crate::base::error::{Error, Result};

/// Most iterations an L-system may ask for (a word of one symbol doubling
/// every iteration is already 2^40 symbols long there).
pub const MAX_ITERATIONS: u32 = 40;

/// A compiled L-system: symbols numbered in order of first appearance.
#[derive(Clone, Debug)]
pub struct Lsystem {
    /// The symbols, by number.
    pub symbols: Vec<char>,
    /// The axiom, as symbol numbers.
    pub axiom: Vec<u16>,
    /// Each symbol's replacement, if it has a rule.
    pub rules: Vec<Option<Vec<u16>>>,
    /// Each symbol's commands (empty: it draws nothing).
    pub commands: Vec<Vec<Cmd>>,
    /// How many times the rules apply, evaluated when the command runs.
    pub iterations: Val,
}

fn one_symbol(key: &str, place: &str) -> Result<char> {
    let mut cs = key.chars();
    match (cs.next(), cs.next()) {
        (Some(c), None) => Ok(c),
        _ => Err(Error::input(
            place,
            format!("`{key}` is not one symbol; expected a single character such as F or +"),
        )),
    }
}

impl Lsystem {
    /// Compiles `raw` written at `place`, its commands seeing `scope`.
    pub fn compile(
        raw: &RawLsystem,
        c: &Compiler,
        scope: &Arc<Vec<String>>,
        place: &str,
    ) -> Result<Lsystem> {
        let mut symbols: Vec<char> = Vec::new();
        let number = |ch: char, symbols: &mut Vec<char>| -> Result<u16> {
            if let Some(k) = symbols.iter().position(|&s| s == ch) {
                return Ok(k as u16);
            }
            if symbols.len() >= u16::MAX as usize {
                return Err(Error::input(place, "too many different symbols"));
            }
            symbols.push(ch);
            Ok(symbols.len() as u16 - 1)
        };
        if raw.axiom.is_empty() {
            return Err(Error::input(
                format!("{place}.axiom"),
                "expected a non-empty word",
            ));
        }
        let mut axiom = Vec::new();
        for ch in raw.axiom.chars() {
            axiom.push(number(ch, &mut symbols)?);
        }
        let mut rules_at = Vec::new();
        for (key, rhs) in &raw.rules {
            let p = format!("{place}.rules.{key}");
            let s = number(one_symbol(key, &p)?, &mut symbols)?;
            let mut word = Vec::new();
            for ch in rhs.chars() {
                word.push(number(ch, &mut symbols)?);
            }
            rules_at.push((s, word));
        }
        let mut commands_at = Vec::new();
        for (key, cmds) in &raw.commands {
            let p = format!("{place}.commands.{key}");
            let s = number(one_symbol(key, &p)?, &mut symbols)?;
            commands_at.push((s, c.block(cmds, &p, scope)?));
        }
        let n = symbols.len();
        let mut rules = vec![None; n];
        for (s, w) in rules_at {
            rules[s as usize] = Some(w);
        }
        let mut commands = vec![Vec::new(); n];
        for (s, cmds) in commands_at {
            commands[s as usize] = cmds;
        }
        Ok(Lsystem {
            symbols,
            axiom,
            rules,
            commands,
            iterations: c.val(&raw.iterations, scope, &format!("{place}.iterations"))?,
        })
    }

    /// The word after `n` iterations, if it has at most `max` symbols (for tests
    /// and reports; the interpreter never builds it).
    pub fn word(&self, n: u32, max: usize) -> Option<String> {
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
