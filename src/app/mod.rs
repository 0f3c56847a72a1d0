//! Layer 7, the application: the commands, the plan of each build, batches
//! and sweeps, the watch server, errors as the terminal shows them.

pub(crate) mod batch;
pub(crate) mod cli;
pub(crate) mod command;
pub(crate) mod diagnostic;
pub(crate) mod http;
pub mod pipeline;
pub(crate) mod prepare;
pub(crate) mod watch;

#[cfg(test)]
pub(crate) mod testing;

#[cfg(feature = "testing")]
pub mod fuzzing;
