//! The integration tests: one binary, one module per subject.
//!
//! One binary links the crate and its dependencies once, where a file per
//! subject under `tests/` linked them once a file. `cargo test --test it
//! NAME` runs the tests whose path holds NAME (`mutate::`, `watch::`).
//!
//! The modules here use the crate's public face; those under `internals`
//! reach past it (see `internals/mod.rs`). Fixtures stay where they were:
//! `tests/fixtures`, `tests/bad`, `tests/checks`, `tests/snapshots`,
//! `tests/browser`.

mod common;

mod authoring;
mod bad_inputs;
mod batch;
mod bounds;
mod bowl;
mod ca;
mod checks;
mod cli;
mod docs_examples;
mod error_snapshots;
mod explain;
mod extruder_turtle;
mod fullcontrol;
mod gallery;
mod gallery_docs;
mod hostile;
mod hosts;
mod inputs;
mod io_errors;
mod layers;
mod machines;
mod macros;
mod mesh;
mod new_user;
mod olympic;
mod planner;
mod plate;
mod presets;
mod preview;
mod procedural;
mod schema;
mod send;
mod solid;
mod sphere;
mod stream;
mod svg;
mod threads;
mod thumbnails;
mod turtle;
mod watch;
