//! Pure material laws: functions of a point's kinematics returning stresses, fluxes and their
//! exact derivatives. They know nothing of meshes or dofs. One file per law family:
//! [`thermo_elastic`] (the solid's and the medium's stress), [`mooney_rivlin`] (a solid's,
//! chosen in [`solid`]'s list), [`conduction`] (the pulled-back
//! Fourier law), [`regularization`] (the medium's rotation measures and their penalty),
//! [`convection`] and [`radiation`] (heat lost through a boundary, chosen in [`boundary`]'s
//! list), [`friction`] (Coulomb slip in the medium).
//!
//! Tensors are 3×3 even in 2D (plane strain: F33 = 1, 3D invariants). Fourth-order tangents
//! are stored as 9×9 matrices with the index pair (i, J) ↦ 3 i + J.
#![allow(non_snake_case)]

pub mod boundary;
pub mod conduction;
pub mod convection;
pub mod friction;
pub mod mooney_rivlin;
pub mod radiation;
pub mod real;
pub mod regularization;
pub mod solid;
pub mod thermo_elastic;

pub use boundary::BoundaryFlux;
pub use conduction::{Conductivity, HeatResponse, fourier};
pub use convection::Convection;
pub use mooney_rivlin::MooneyRivlin;
pub use radiation::Radiation;
pub use real::Real;
pub use regularization::{
    ROTATION_PLANES, Regularization, RotationMeasure, rotation_measure, rotation_measure_d3,
};
pub use solid::{SolidLaw, Stress};
pub use thermo_elastic::{Coefficients, Scalars, StressResponse, ThermoElastic};

use nalgebra::SMatrix;

/// 9×9 storage of a fourth-order tensor A_iJkL at (3i+J, 3k+L).
pub type Tensor4 = SMatrix<f64, 9, 9>;
/// 3×9 storage of a third-order tensor B_I,kL at (I, 3k+L).
pub type Tensor3 = SMatrix<f64, 3, 9>;

/// Deformation gradients the laws' finite-difference checks are run at: a general 3D one and
/// a plane-strain one (F33 = 1).
#[cfg(test)]
pub(crate) fn sample_F(plane: bool) -> nalgebra::Matrix3<f64> {
    use nalgebra::Matrix3;
    if plane {
        Matrix3::new(1.2, 0.3, 0.0, -0.15, 0.8, 0.0, 0.0, 0.0, 1.0)
    } else {
        Matrix3::new(1.1, 0.2, -0.1, 0.05, 0.9, 0.15, -0.2, 0.1, 1.3)
    }
}
