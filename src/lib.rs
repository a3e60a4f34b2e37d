//! tmc: finite-strain thermo-mechanical contact with the third-medium method.
//!
//! Layers in pipeline order: [`mesh`] (gmsh → .msh → mesh) → [`dofs`] → [`element`] and
//! [`material`] → [`kernel`] → [`assembly`] → [`linsolve`] → [`newton`] → [`stepping`] →
//! [`output`]. [`case`] reads the case file, [`model`] builds the discrete problem from it,
//! [`solve`] drives a run, [`study`] runs a scene over variants, [`plot`] draws charts.

#![allow(non_snake_case)]
// maths names: F, P, J, X, dP_dF
// index loops mirror the tensor formulas (Σ_J P_iJ ∂N_I/∂X_J); `!(x > 0.0)` rejects NaN on purpose
#![allow(clippy::needless_range_loop, clippy::neg_cmp_op_on_partial_ord)]

pub mod assembly;
pub mod case;
pub mod dofs;
pub mod element;
pub mod kernel;
pub mod linsolve;
pub mod material;
pub mod mesh;
pub mod model;
pub mod newton;
pub mod output;
pub mod plot;
pub mod post;
pub mod probe;
pub mod solve;
pub mod stepping;
pub mod study;
