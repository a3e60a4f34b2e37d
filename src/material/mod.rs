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

/// The finite-difference checks every stress law passes, at both [`sample_F`] and θ = 70:
/// P = ∂Ψ/∂F, ∂P/∂F against differences of P (with major symmetry, the law being
/// hyperelastic) and ∂P/∂θ.
#[cfg(test)]
pub(crate) fn check_stress_law(
    stress: impl Fn(&nalgebra::Matrix3<f64>, f64) -> Option<StressResponse>,
) {
    let at = |F: &nalgebra::Matrix3<f64>, theta: f64| stress(F, theta).unwrap();
    for plane in [false, true] {
        let F = sample_F(plane);
        let r = at(&F, 70.0);
        let h = 1e-6;
        for (k, l) in (0..9).map(|n| (n / 3, n % 3)) {
            let (mut p, mut m) = (F, F);
            p[(k, l)] += h;
            m[(k, l)] -= h;
            let (rp, rm) = (at(&p, 70.0), at(&m, 70.0));
            let fd = (rp.psi - rm.psi) / (2.0 * h);
            assert!(
                (fd - r.P[(k, l)]).abs() < 1e-7 * (1.0 + fd.abs()),
                "P{k}{l}: {fd} vs {}",
                r.P[(k, l)]
            );
            let dP = (rp.P - rm.P) / (2.0 * h);
            for (i, j) in (0..9).map(|n| (n / 3, n % 3)) {
                let a = r.dP_dF[(3 * i + j, 3 * k + l)];
                assert!(
                    (dP[(i, j)] - a).abs() < 1e-6 * (1.0 + a.abs()),
                    "A{i}{j}{k}{l}: {} vs {a}",
                    dP[(i, j)]
                );
            }
        }
        assert!((r.dP_dF - r.dP_dF.transpose()).norm() < 1e-12);
        let h = 1e-4;
        let dP = (at(&F, 70.0 + h).P - at(&F, 70.0 - h).P) / (2.0 * h);
        assert!((dP - r.dP_dtheta).norm() < 1e-9);
    }
}
