//! Every integration test, in one binary (one link instead of one per file). Each module is
//! one concern; `common` holds what they share. Run one module with
//! `cargo test --release --test it friction::`, one test by its name.
//!
//! Tests run in parallel threads of this one process, so nothing a test writes may be shared
//! with another: [`common::scratch`] gives each test folders of its own.

mod common;

mod analytical;
mod bad_input;
mod cli;
mod distributed;
mod docs;
mod effects;
mod fenicsx;
mod first_hour;
mod friction;
mod inertia;
mod medium;
mod patch_and_tangent;
mod robustness;
mod sliding;
mod stability;
mod transient;
