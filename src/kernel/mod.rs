//! Element kernels: from a cell's reference data and local unknowns, the local residual and
//! tangent. Only the assembler touches global arrays.
//!
//! - [`bulk`]: the one-cell kernel of the bulk (solid or medium), the reference every other
//!   kernel is checked against, with its finite-difference tests;
//! - [`lanes`]: the same for four cells at once, one per SIMD lane;
//! - [`regularization`]: the medium's regularization terms, with p fields (eq. 20) or direct
//!   (eq. 18);
//! - [`capacity`]: heat storage of transient conduction (backward Euler);
//! - [`inertia`]: ρ ü of the displacements (backward Euler);
//! - [`facet`]: integrals over boundary facets (convection);
//! - [`fields`]: cell averages for output (σ, q, J, k).
//!
//! Local dof order is field-blocked: u (node-major, `D` components), then θ, then p
//! ([`crate::dofs::Layout`]).
#![allow(non_snake_case)]

pub mod bulk;
pub mod capacity;
pub mod facet;
pub mod fields;
pub mod friction;
pub mod inertia;
pub mod lanes;
mod point;
pub mod regularization;

pub use bulk::{bulk, inversion};
pub use fields::{CellFields, cell_fields, nodal_forces};

use crate::material::{Conductivity, Regularization, SolidLaw};

/// Material of a cell block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellMaterial {
    pub law: SolidLaw,
    pub cond: Conductivity,
    pub medium: bool,
    /// Regularization of a linear medium cell (eq. 20); used when the layout carries p.
    pub reg: Option<Regularization>,
    /// Weight c = γ α_r of the direct regularization of a quadratic medium cell (eq. 18).
    pub reg_direct: Option<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KernelError {
    /// The undeformed cell has a non-positive Jacobian (broken mesh).
    BadGeometry,
    /// J ≤ 0 (or not finite) at a quadrature point.
    Inverted { J: f64 },
    /// A rotation measure of the regularization is unbounded (F_aa + F_bb = 0).
    Singular,
    /// θ ≤ 0 where a law needs an absolute temperature (radiation).
    NotAbsolute { theta: f64 },
}

/// What a kernel call reports besides r and K.
#[derive(Clone, Copy, Debug)]
pub struct CellSummary {
    pub min_J: f64,
    /// Stored mechanical energy ∫ Ψ dV.
    pub energy: f64,
}

/// Which equations a kernel call fills: a one-way coupled solve needs only the mechanical rows
/// while it iterates on mechanics, and only the thermal rows (with their θ columns) after.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Active {
    pub mechanics: bool,
    pub heat: bool,
}

impl Active {
    pub const ALL: Active = Active {
        mechanics: true,
        heat: true,
    };
}

/// A node-by-node matrix: `[I][K]` couples node I's equation with node K's unknown.
pub(super) type NodeBlock<const N: usize> = [[f64; N]; N];
/// ∂r_u/∂u by component pair: `[i][k]`, blocks i ≤ k only (K_uu is symmetric).
pub(super) type UuBlocks<const N: usize> = [[NodeBlock<N>; 3]; 3];

/// The regularization's own tangent blocks: ∂r_u(a)/∂p(c) (K_pu is its transpose) and
/// ∂r_p(c)/∂p(c).
pub(super) struct PBlocks<const N: usize> {
    pub(super) up: [[NodeBlock<N>; 3]; 3],
    pub(super) pp: [NodeBlock<N>; 3],
}

/// Zero a kernel's local residual (`nd`) and, when asked for, its tangent (`nd × nd`): every
/// kernel overwrites what it is given.
#[inline(always)]
fn zero_local(nd: usize, r: &mut [f64], k: Option<&mut [f64]>) {
    r[..nd].fill(0.0);
    if let Some(k) = k {
        k[..nd * nd].fill(0.0);
    }
}

/// Whether this CPU has AVX2 and FMA, the features the fast kernels are compiled for (the
/// check is cached by the standard library).
pub(super) fn avx2_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// a b + c, fused into one rounding where the instruction set has it.
pub(super) trait MulAdd {
    fn mul_add(a: f64, b: f64, c: f64) -> f64;
}

/// One instruction (only where the caller is compiled with FMA: elsewhere a library call).
pub(super) struct Fused;
/// A multiply and an add.
pub(super) struct Separate;

impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
}

impl MulAdd for Separate {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a * b + c
    }
}
