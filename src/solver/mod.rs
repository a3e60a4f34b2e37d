//! Solving the discrete problem: the linear engines behind one trait ([`engine`]), sparse
//! linear solvers ([`linear`]), Newton–Raphson for one
//! load step ([`newton`]), the step controller ([`stepping`]) and what idle threads do during
//! linear solves ([`idle`]).

pub mod engine;
pub mod idle;
pub mod linear;
pub mod newton;
#[cfg(feature = "petsc")]
pub mod petsc;
pub mod stepping;
