//! tmc: finite-strain thermo-mechanical contact with the third-medium method.
//!
//! Layers in pipeline order, each a folder that owns one concept and imports only from the
//! layers before it:
//!
//! [`mesh`] (gmsh → .msh → mesh) → [`element`] (reference elements) → [`dofs`] (numbering,
//! constraints, local layout, sparsity) → [`material`] (pure laws) → [`kernel`] (local residual
//! and tangent) → [`case`] and [`model`] (the discrete problem) → [`assembly`] → [`post`]
//! (what an accepted state holds: heat, works, slips) → [`solver`] (linear, Newton, stepping) →
//! [`output`] (VTU, history, probes) → [`driver`] (`tmc solve`) → [`study`] and [`plot`]. Under
//! them all, [`files`]: writing a file under a temporary name, [`console`]: lines on the
//! terminal that a closed pipe silences, [`threads`]: how many threads tmc computes with,
//! [`memory`]: freed memory kept for a run that builds its structures again, and [`dynamic`]:
//! gmsh and PETSc opened when a run first needs them.
//! See docs/ARCHITECTURE.md.

#![allow(non_snake_case)]
// maths names: F, P, J, X, dP_dF
// index loops mirror the tensor formulas (Σ_J P_iJ ∂N_I/∂X_J); `!(x > 0.0)` rejects NaN on purpose
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod assembly;
pub mod case;
pub mod console;
pub mod dofs;
pub mod driver;
pub mod dynamic;
pub mod element;
pub mod files;
pub mod kernel;
pub mod material;
pub mod memory;
pub mod mesh;
pub mod model;
pub mod output;
pub mod parallel;
pub mod plot;
pub mod post;
pub mod signals;
pub mod solver;
pub mod study;
pub mod threads;
