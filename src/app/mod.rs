//! Layer 7, the application: the commands, the plan of each build, batches
//! and sweeps, the watch server, errors as the terminal shows them.

pub mod batch;
pub mod cli;
pub mod command;
pub mod diagnostic;
pub mod http;
pub mod pipeline;
pub mod prepare;
pub mod watch;
