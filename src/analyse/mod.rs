//! Layer 4, analysis: what the strings mean for a real machine, before any
//! byte is written: the printability and safety checks, the print-time
//! planner, the stats report.

pub mod check;
pub mod frame;
pub mod plan;
pub mod planner;
pub mod stats;
