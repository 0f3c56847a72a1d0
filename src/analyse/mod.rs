//! Layer 4, analysis: what the strings mean for a real machine, before any
//! byte is written: the printability and safety checks, the print-time
//! planner, the stats report.

pub(crate) mod check;
pub(crate) mod frame;
pub(crate) mod plan;
pub(crate) mod planner;
pub(crate) mod stats;

#[cfg(test)]
mod tests;
