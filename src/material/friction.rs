//! Coulomb friction in a slip plane of the third medium.
//!
//! Everything is measured in the reference configuration, so it stays well conditioned where
//! the medium has closed to J ≈ 1e-3. With N the plane's unit normal, P = I − N⊗N and
//! C = FᵀF, the plane's shear per reference thickness is γ = P C N: a layer of reference
//! thickness H whose faces slide δ apart has γ = δ/H however far it has closed (not δ over the
//! closed thickness, which is 10³ times larger), and a rotation leaves γ unchanged.
//!
//! Slip g_p lies in the plane, one per point, committed at accepted steps; the elastic shear is
//! γ_e = γ − g_p and the shear traction per reference area τ = G_f(J) γ_e, with G_f rising as
//! the medium closes ([`shear_modulus`]). Its virtual work τ · δγ gives the second
//! Piola–Kirchhoff stress S_f = N⊗τ + τ⊗N and P_f = F S_f, whose traction on the plane,
//! P_f N = F τ, is tangential to it in the current configuration (F τ · F⁻ᵀN = τ · N = 0).
//! Coulomb's condition bounds that traction: |F τ| ≤ μ p_n, with p_n = −n · (P_m N) the
//! compressive normal traction per reference area that the medium's own stress P_m carries
//! across the plane (n = F⁻ᵀN / |F⁻ᵀN|, the plane's current normal), so tangential over
//! normal traction is μ however the plane stretches; an open medium (p_n ≤ 0) resists no slip.
//! The return is closed form: at fixed F, τ is linear in g_p and p_n does not depend on it, so
//! the trial shear τ* = G_f (γ − gₙ) is scaled back along itself, τ = τ* μ p_n / |F τ*|. G_f(J) is a
//! coefficient, not differentiated as part of an energy, so the shear puts no pressure on the
//! plane; the tangent is unsymmetric, as Coulomb friction's always is. With a slip viscosity
//! η_s the slip of a step pays a rate term as well, |F τ| = μ p_n + (η_s/Δt) |Δg_p|, and the
//! return stays along τ*. With the limit lagged, μ p_n takes a given normal traction (the
//! last accepted step's) and stays put within the step. The slip of a step dissipates
//! τ · Δg_p per reference volume (the frictional heat).
#![allow(non_snake_case)]

use super::Tensor4;
use nalgebra::{Matrix3, SMatrix, Vector3};

/// A trial shear this little (relative) beyond the Coulomb limit still sticks.
const YIELD_TOLERANCE: f64 = 1e-9;

/// Derivatives of a vector with respect to F: (I, 3k + L).
type VectorByF = SMatrix<f64, 3, 9>;

/// A slip plane with its Coulomb coefficient.
#[derive(Clone, Copy, Debug)]
pub struct Friction {
    /// μ_f ≥ 0.
    pub mu: f64,
    /// The plane's unit normal N in the reference configuration.
    pub normal: Vector3<f64>,
    /// η_s/Δt: the slip's viscosity over the step, so that slipping takes
    /// |F τ| = μ p_n + (η_s/Δt) |Δg| (0: rate-independent Coulomb).
    pub rate: f64,
    /// The normal traction the limit takes, when it is the last accepted step's (the limit
    /// then does not move within the step: Tresca's); `None`: the current one.
    pub lagged: Option<f64>,
    /// The plane carries its traction alone, P = F τ ⊗ N, as an interface does, instead of
    /// P = F (N⊗τ + τ⊗N) ([`plane_stress`]).
    pub traction_only: bool,
}

/// The medium's own first Piola–Kirchhoff stress at the point and its derivatives: the normal
/// traction across the plane comes from it.
pub struct MediumStress<'a> {
    pub P: &'a Matrix3<f64>,
    pub dP_dF: &'a Tensor4,
    /// ∂P/∂θ (thermal expansion moves the normal traction, and so the Coulomb limit).
    pub dP_dtheta: &'a Matrix3<f64>,
}

/// The friction term at one point after the return to the Coulomb cone.
#[derive(Clone, Debug)]
pub struct FrictionResponse {
    /// First Piola–Kirchhoff stress F (N⊗τ + τ⊗N).
    pub P: Matrix3<f64>,
    /// Its derivative in F (9×9, (3i + J, 3k + L)), unsymmetric.
    pub dP_dF: Tensor4,
    /// Its derivative in θ (through the Coulomb limit while slipping).
    pub dP_dtheta: Matrix3<f64>,
    /// Shear traction per reference area, in the plane.
    pub tau: Vector3<f64>,
    /// The slip after the step (to commit if the step is accepted).
    pub slip: Vector3<f64>,
    /// Compressive normal traction per reference area across the plane.
    pub p_n: f64,
    /// On the Coulomb cone (the slip moved).
    pub slipping: bool,
    /// τ · (slip − previous slip) per reference volume: the heat the step's slip makes.
    pub dissipated: f64,
    /// ∂(dissipated)/∂F at (k, L), and ∂(dissipated)/∂θ.
    pub ddissipated_dF: Matrix3<f64>,
    pub ddissipated_dtheta: f64,
}

/// The friction modulus G_f and dG_f/dJ: c_f K_m (1 − ln J) / J² where the medium is
/// compressed (J ≤ 1), the medium's own stiffness against closing (K_m its bulk modulus) times
/// c_f, so stick stiffens as the contact does; c_f K_m / J³ where it is stretched, which meets
/// it at J = 1 with the same value and slope and stays positive. (The first form alone turns
/// negative beyond J = e: a stretched cell that the plane still pressed then pushed its nodes
/// away, and an open medium's corner ran away with the energy it made.)
pub fn shear_modulus(c_f: f64, K_m: f64, J: f64) -> (f64, f64) {
    if J > 1.0 {
        let J3 = J * J * J;
        return (c_f * K_m / J3, -3.0 * c_f * K_m / (J3 * J));
    }
    let l = J.ln();
    (
        c_f * K_m * (1.0 - l) / (J * J),
        -c_f * K_m * (3.0 - 2.0 * l) / (J * J * J),
    )
}

/// P = I − N⊗N: the projection onto the slip plane of unit normal `N`.
pub fn along_plane(N: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::identity() - N * N.transpose()
}

/// S = N⊗τ + τ⊗N: the second Piola stress of a shear τ on the slip plane of unit normal `N`
/// (the virtual work τ · δγ), or of its derivative in a scalar where τ is that derivative.
pub fn plane_pair(N: &Vector3<f64>, tau: &Vector3<f64>) -> Matrix3<f64> {
    N * tau.transpose() + tau * N.transpose()
}

/// The slip plane's second Piola stress for a shear τ on the plane of unit normal `N` (or its
/// derivative in a scalar where τ is that derivative): N⊗τ + τ⊗N ([`plane_pair`]), or with
/// `traction_only` τ⊗N, whose P = F τ ⊗ N carries the traction F τ across the plane and
/// nothing across any other. The first is the work conjugate of γ; on a layer sheared by s
/// since its reference it also carries F N τ across planes normal to τ, whose part along the
/// layer, s τ, pushes the bodies at the layer's ends (δ τ per end for a slide δ, whatever the
/// layer's thickness). The second drops it: its couple, τ times the layer's current
/// thickness, vanishes as the layer closes. A medium made again takes the second.
pub fn plane_stress(N: &Vector3<f64>, tau: &Vector3<f64>, traction_only: bool) -> Matrix3<f64> {
    match traction_only {
        true => tau * N.transpose(),
        false => plane_pair(N, tau),
    }
}

/// The plane's shear per reference thickness at `F`, γ = P C N (C = FᵀF), for the slip
/// plane of unit normal `N`.
pub fn plane_shear(F: &Matrix3<f64>, N: &Vector3<f64>) -> Vector3<f64> {
    along_plane(N) * (F.transpose() * F) * N
}

impl Friction {
    /// The friction stress at `F`, from the previous accepted `slip`, with the friction modulus
    /// `modulus` = (G_f, dG_f/dJ) at this J and the medium's own stress, in `D` dimensions: in
    /// 2D (plane strain) the derivatives are those in F's in-plane entries, the only ones a
    /// variation of the plane's displacements moves (the others are left zero). `None` when F
    /// is singular.
    pub fn respond<const D: usize>(
        &self,
        F: &Matrix3<f64>,
        slip: &Vector3<f64>,
        modulus: (f64, f64),
        medium: &MediumStress,
    ) -> Option<FrictionResponse> {
        let N = self.normal;
        let (G, dG) = modulus;
        let Pn = along_plane(&N);
        let Finv = F.try_inverse()?;
        let J = F.determinant();
        let gamma = plane_shear(F, &N);
        let elastic = gamma - slip;
        let trial = elastic * G;
        // dγ_I/dF_kL = P_IL (F N)_k + (F P)_kI N_L; dJ/dF = J F⁻ᵀ
        let (FN, FP) = (F * N, F * Pn);
        let mut dgamma = VectorByF::zeros();
        let mut dtrial = VectorByF::zeros();
        for (I, k, L) in in_plane::<D>() {
            dgamma[(I, 3 * k + L)] = Pn[(I, L)] * FN[k] + FP[(k, I)] * N[L];
            dtrial[(I, 3 * k + L)] =
                dG * J * Finv[(L, k)] * elastic[I] + G * dgamma[(I, 3 * k + L)];
        }
        // the normal traction and its derivative: n = m/|m|, m = F⁻ᵀN, dm_a/dF_kL = −m_k F⁻¹_La
        let m = Finv.transpose() * N;
        let n = m / m.norm();
        let t = medium.P * N;
        let p_n = -n.dot(&t);
        let limit = self.mu * self.lagged.unwrap_or(p_n).max(0.0);
        // the trial's traction on the plane, F τ*, and its size
        let a = F * trial;
        let size = a.norm();
        // on the cone to round-off (γ − gₙ cancels digits where the layer is closed) is stick
        let slipping = size > limit * (1.0 + YIELD_TOLERANCE);
        // while slipping: τ and its derivatives in F and θ, and the slip that leaves exactly τ
        // as elastic shear
        let (tau, dtau, dtau_dtheta, new_slip) = if !slipping {
            (trial, dtrial, Vector3::zeros(), *slip)
        } else {
            // τ = s τ*, Δg = (1 − s) τ*/G: s |F τ*| = μ p_n + b (1 − s), b = (η_s/Δt) |γ − gₙ|
            let b = self.rate * elastic.norm();
            let denominator = size + b;
            let scale = (limit + b) / denominator;
            let tau = trial * scale;
            // d|a| = a · (dF τ* + F dτ*) / |a|
            let Fdtrial = F * dtrial;
            let mut dtau = dtrial * scale;
            for (k, L) in columns::<D>() {
                let c = 3 * k + L;
                let dsize = (a[k] * trial[L] + a.dot(&Fdtrial.column(c))) / size;
                for I in 0..D {
                    dtau[(I, c)] -= tau[I] * dsize / denominator;
                }
                if b > 0.0 {
                    // db = (η_s/Δt) (γ − gₙ) · dγ / |γ − gₙ|
                    let db: f64 = (0..D).map(|I| elastic[I] * dgamma[(I, c)]).sum::<f64>()
                        * self.rate
                        / elastic.norm();
                    for I in 0..D {
                        dtau[(I, c)] += trial[I] * db * (1.0 - scale) / denominator;
                    }
                }
            }
            // ∂τ/∂(μ p_n): the limit moves with the normal traction (unless it is lagged)
            let e = trial / denominator;
            let dtau_dtheta = if p_n > 0.0 && self.lagged.is_none() {
                self.limit_moves::<D>(&mut dtau, &e, &m, &Finv, medium)
            } else {
                Vector3::zeros()
            };
            (tau, dtau, dtau_dtheta, gamma - tau / G)
        };
        let step = new_slip - slip;
        let (ddissipated_dF, ddissipated_dtheta) = if slipping {
            let slip_rate = SlipDerivatives {
                dgamma: &dgamma,
                dtau: &dtau,
                dtau_dtheta: &dtau_dtheta,
            };
            slip_rate.dissipation::<D>(&tau, &step, (G, dG * J), &Finv)
        } else {
            (Matrix3::zeros(), 0.0)
        };
        let S = plane_stress(&N, &tau, self.traction_only);
        // A_iJkL = δ_ik S_LJ + (F N)_i dτ_J/dF_kL + (F dτ/dF)_i,kL N_J (the second term not
        // where the plane carries its traction alone)
        let pair = if self.traction_only { 0.0 } else { 1.0 };
        let Fdtau = F * dtau;
        let mut A = Tensor4::zeros();
        for (i, Jc, k, L) in
            in_plane::<D>().flat_map(|(i, k, L)| (0..D).map(move |Jc| (i, Jc, k, L)))
        {
            let d = if i == k { S[(L, Jc)] } else { 0.0 };
            A[(3 * i + Jc, 3 * k + L)] =
                d + pair * FN[i] * dtau[(Jc, 3 * k + L)] + Fdtau[(i, 3 * k + L)] * N[Jc];
        }
        let S_theta = plane_stress(&N, &dtau_dtheta, self.traction_only);
        Some(FrictionResponse {
            P: F * S,
            dP_dF: A,
            dP_dtheta: F * S_theta,
            tau,
            slip: new_slip,
            p_n,
            slipping,
            dissipated: tau.dot(&step),
            ddissipated_dF,
            ddissipated_dtheta,
        })
    }
}

impl Friction {
    /// A slipping point's τ = μ p_n e moves with the normal traction p_n = −n · P N, n = m/|m|,
    /// m = F⁻ᵀ N: its derivative in F is added to `dtau`, its derivative in θ returned.
    fn limit_moves<const D: usize>(
        &self,
        dtau: &mut VectorByF,
        e: &Vector3<f64>,
        m: &Vector3<f64>,
        Finv: &Matrix3<f64>,
        medium: &MediumStress,
    ) -> Vector3<f64> {
        let N = self.normal;
        let n = m / m.norm();
        let t = medium.P * N;
        let project = (Matrix3::identity() - n * n.transpose()) / m.norm();
        for (k, L) in columns::<D>() {
            let dm = -Finv.row(L).transpose() * m[k];
            let dn = project * dm;
            let mut dt = Vector3::zeros();
            for i in 0..D {
                dt[i] = (0..D)
                    .map(|A| medium.dP_dF[(3 * i + A, 3 * k + L)] * N[A])
                    .sum();
            }
            let dp = -dn.dot(&t) - n.dot(&dt);
            for I in 0..D {
                dtau[(I, 3 * k + L)] += self.mu * dp * e[I];
            }
        }
        e * (-self.mu * n.dot(&(medium.dP_dtheta * N)))
    }
}

/// The entries (k, L) of F that a variation in `D` dimensions moves.
fn columns<const D: usize>() -> impl Iterator<Item = (usize, usize)> {
    (0..D * D).map(|c| (c / D, c % D))
}

/// A vector's components I with the entries (k, L) of F: its derivatives in `D` dimensions.
fn in_plane<const D: usize>() -> impl Iterator<Item = (usize, usize, usize)> {
    (0..D).flat_map(|I| columns::<D>().map(move |(k, L)| (I, k, L)))
}

/// The derivatives of a slipping point's shear γ and traction τ in F (3 × 9, column 3k + L
/// for F_kL) and of τ in θ.
struct SlipDerivatives<'a> {
    dgamma: &'a VectorByF,
    dtau: &'a VectorByF,
    dtau_dtheta: &'a Vector3<f64>,
}

impl SlipDerivatives<'_> {
    /// The derivatives in F and θ of the heat made, D = τ · (g − gₙ) with g = γ − τ/G in slip:
    /// dD = dτ · Δg + τ · (dγ − dτ/G + τ dG/G²), with dG/dF = G'(J) J F⁻ᵀ (`modulus`: G and
    /// G'(J) J).
    fn dissipation<const D: usize>(
        &self,
        tau: &Vector3<f64>,
        step: &Vector3<f64>,
        modulus: (f64, f64),
        Finv: &Matrix3<f64>,
    ) -> (Matrix3<f64>, f64) {
        let (G, dG_J) = modulus;
        let mut dF = Matrix3::zeros();
        for (k, L) in columns::<D>() {
            let c = 3 * k + L;
            let dGc = dG_J * Finv[(L, k)];
            let mut d = 0.0;
            for I in 0..D {
                let dslip = self.dgamma[(I, c)] - self.dtau[(I, c)] / G + tau[I] * dGc / (G * G);
                d += self.dtau[(I, c)] * step[I] + tau[I] * dslip;
            }
            dF[(k, L)] = d;
        }
        let dtheta = self.dtau_dtheta.dot(step) - tau.dot(self.dtau_dtheta) / G;
        (dF, dtheta)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::ThermoElastic;
    use crate::material::sample_F;

    /// A third medium (γ = 1e-3 of K = 20, μ = 10).
    const MEDIUM: ThermoElastic = ThermoElastic {
        K: 0.02,
        mu: 0.01,
        alpha: 0.05,
        theta0: 0.0,
    };
    /// The temperature the checks run at: the medium expands a little.
    const THETA: f64 = 0.4;
    const C_F: f64 = 1.0;

    fn plane(dim: usize) -> Friction {
        let normal = if dim == 2 {
            Vector3::new(0.6, 0.8, 0.0)
        } else {
            Vector3::new(0.48, 0.6, 0.64)
        };
        Friction {
            mu: 0.3,
            normal,
            rate: 0.0,
            lagged: None,
            traction_only: false,
        }
    }

    /// The whole chain at F and θ: medium stress, modulus at J(F), friction.
    fn respond_at(
        law: &Friction,
        F: &Matrix3<f64>,
        theta: f64,
        slip: &Vector3<f64>,
    ) -> FrictionResponse {
        let m = MEDIUM.stress(F, theta).unwrap();
        let modulus = shear_modulus(C_F, MEDIUM.K, m.J);
        let medium = MediumStress {
            P: &m.P,
            dP_dF: &m.dP_dF,
            dP_dtheta: &m.dP_dtheta,
        };
        if law.normal[2] == 0.0 {
            law.respond::<2>(F, slip, modulus, &medium).unwrap()
        } else {
            law.respond::<3>(F, slip, modulus, &medium).unwrap()
        }
    }

    fn respond(law: &Friction, F: &Matrix3<f64>, slip: &Vector3<f64>) -> FrictionResponse {
        respond_at(law, F, THETA, slip)
    }

    /// The unit direction the layers of [`layer`] slide along: in the plane normal to N, and in
    /// the xy plane.
    fn along(N: Vector3<f64>) -> Vector3<f64> {
        Vector3::new(-N[1], N[0], 0.0).normalize()
    }

    /// A layer normal to N closed to thickness `closed` (of 1), slid `slide` along T, then
    /// turned by `turn` about z, and a small general `noise`.
    fn layer(N: Vector3<f64>, closed: f64, slide: f64, turn: f64, noise: f64) -> Matrix3<f64> {
        let T = along(N);
        let d = T * slide - N * (1.0 - closed);
        let (s, c) = turn.sin_cos();
        let R = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let G = sample_F(N[2] == 0.0) - Matrix3::identity();
        R * (Matrix3::identity() + d * N.transpose() + G * noise)
    }

    /// A stretch by λ of the plane normal to N along the direction its layers slide in, to be
    /// applied first: `layer(..) * stretched(N, λ)` maps T to λ T's image.
    fn stretched(N: Vector3<f64>, lambda: f64) -> Matrix3<f64> {
        let T = along(N);
        Matrix3::identity() + T * T.transpose() * (lambda - 1.0)
    }

    #[test]
    fn the_tangent_is_the_derivative_of_the_stress_in_stick_and_in_slip() {
        // rate-independent, viscous, with the limit's p_n lagged (a value near the layer's
        // own, 0.9), and carrying the plane's traction alone
        for (dim, rate, lagged, traction_only) in [
            (2, 0.0, None, false),
            (3, 0.0, None, false),
            (2, 5.0, None, false),
            (3, 5.0, None, false),
            (2, 0.0, Some(0.9), false),
            (3, 5.0, Some(0.9), false),
            (2, 0.0, None, true),
            (3, 0.0, None, true),
            (3, 5.0, Some(0.9), true),
        ] {
            let law = Friction {
                rate,
                lagged,
                traction_only,
                ..plane(dim)
            };
            // a plane shortened along the slide, as under a leading corner
            let F = layer(law.normal, 0.05, 0.05, 0.3, 0.01) * stretched(law.normal, 0.85);
            // from no slip, the trial leaves the cone; from half the elastic shear of the
            // return, it stays inside
            let on_cone = respond(&law, &F, &Vector3::zeros());
            let G = shear_modulus(C_F, MEDIUM.K, F.determinant()).0;
            let inside = on_cone.slip + on_cone.tau / G * 0.5;
            for (previous, slips) in [(Vector3::zeros(), true), (inside, false)] {
                let r = respond(&law, &F, &previous);
                assert_eq!(r.slipping, slips, "{dim}D");
                assert!(r.p_n > 0.0, "the layer is pressed");
                let h = 1e-7;
                let scale = r.dP_dF.amax();
                let heat_scale = r.ddissipated_dF.amax().max(1e-300);
                // in 2D, F's in-plane entries (the others a plane's displacements never move)
                for c in (0..9).filter(|c| dim == 3 || (c / 3 < 2 && c % 3 < 2)) {
                    let (mut p, mut m) = (F, F);
                    p[(c / 3, c % 3)] += h;
                    m[(c / 3, c % 3)] -= h;
                    let (rp, rm) = (respond(&law, &p, &previous), respond(&law, &m, &previous));
                    let dP = (rp.P - rm.P) / (2.0 * h);
                    for a in 0..9 {
                        let exact = r.dP_dF[(a, c)];
                        assert!(
                            (dP[(a / 3, a % 3)] - exact).abs() < 1e-6 * scale,
                            "{dim}D slipping {slips}: A[{a},{c}] = {exact}, FD {}",
                            dP[(a / 3, a % 3)]
                        );
                    }
                    let dD = (rp.dissipated - rm.dissipated) / (2.0 * h);
                    let exact = r.ddissipated_dF[(c / 3, c % 3)];
                    assert!(
                        (dD - exact).abs() < 1e-6 * heat_scale,
                        "{dim}D slipping {slips}: dD/dF[{c}] = {exact}, FD {dD}"
                    );
                }
                // in θ: through the Coulomb limit while slipping, not at all in stick
                let (rp, rm) = (
                    respond_at(&law, &F, THETA + h, &previous),
                    respond_at(&law, &F, THETA - h, &previous),
                );
                let dP = (rp.P - rm.P) / (2.0 * h);
                assert!(
                    (dP - r.dP_dtheta).amax() < 1e-6 * r.P.amax(),
                    "{dim}D slipping {slips}: dP/dθ {} FD {dP}",
                    r.dP_dtheta
                );
                let dD = (rp.dissipated - rm.dissipated) / (2.0 * h);
                assert!(
                    (dD - r.ddissipated_dtheta).abs() < 1e-6 * r.dissipated.abs().max(1e-12),
                    "{dim}D slipping {slips}: dD/dθ {} FD {dD}",
                    r.ddissipated_dtheta
                );
                assert_eq!(
                    r.dP_dtheta.amax() > 0.0,
                    slips && lagged.is_none(),
                    "θ moves the limit only in slip, and not a lagged one"
                );
                assert_eq!(r.dissipated > 0.0, slips);
            }
        }
    }

    /// A layer sheared by a slide of 0.4 across its closed thickness 0.05, slipping: both
    /// stresses carry the same traction across the plane; the symmetric one also carries s τ
    /// along the layer across planes normal to the slide (what pushes at the layer's ends),
    /// the traction alone nothing.
    #[test]
    fn a_sheared_layer_pushes_along_itself_unless_its_plane_carries_its_traction_alone() {
        for dim in [2, 3] {
            let pair = plane(dim);
            let alone = Friction {
                traction_only: true,
                ..pair
            };
            let N = pair.normal;
            let T = along(N);
            let s = 0.4;
            let F = layer(N, 0.05, s, 0.0, 0.0);
            let (a, b) = (
                respond(&pair, &F, &Vector3::zeros()),
                respond(&alone, &F, &Vector3::zeros()),
            );
            assert!(a.slipping && b.slipping);
            assert!((a.P * N - b.P * N).amax() < 1e-14 * (a.P * N).amax());
            let tau = a.tau.norm();
            let across = |r: &FrictionResponse| T.dot(&(r.P * T));
            assert!(
                (across(&a) - s * tau).abs() < 1e-9 * tau,
                "{dim}D: {} against s τ = {}",
                across(&a),
                s * tau
            );
            assert!(across(&b).abs() < 1e-15, "{dim}D: {}", across(&b));
        }
    }

    #[test]
    fn the_friction_modulus_is_positive_smooth_and_its_slope_exact() {
        // positive however far the medium is squeezed or stretched (the compressed form alone
        // turns negative beyond J = e), with value and slope continuous at J = 1 where its two
        // forms meet, and dG/dJ the central difference of G on either side
        let (c_f, K) = (2.0, 0.3);
        for J in [
            1e-4,
            1e-2,
            0.5,
            0.999,
            1.001,
            2.0,
            std::f64::consts::E,
            10.0,
            1e3,
        ] {
            let (G, dG) = shear_modulus(c_f, K, J);
            assert!(G > 0.0, "G_f({J}) = {G}");
            let h = 1e-6 * J;
            let fd = (shear_modulus(c_f, K, J + h).0 - shear_modulus(c_f, K, J - h).0) / (2.0 * h);
            assert!((dG - fd).abs() <= 1e-6 * dG.abs(), "J = {J}: {dG} vs {fd}");
        }
        let (below, above) = (
            shear_modulus(c_f, K, 1.0),
            shear_modulus(c_f, K, 1.0 + 1e-12),
        );
        assert!((below.0 - c_f * K).abs() < 1e-12 && (above.0 - c_f * K).abs() < 1e-11);
        assert!((below.1 - above.1).abs() < 1e-9, "{below:?} {above:?}");
    }

    #[test]
    fn with_a_constant_modulus_stick_is_the_gradient_of_its_energy() {
        // ½ G |P C N − g|²: P_f = ∂Ψ/∂F
        let law = Friction {
            mu: 1e6,
            ..plane(3)
        };
        let F = sample_F(false);
        let g = Vector3::new(0.01, -0.02, 0.0);
        let g = g - law.normal * law.normal.dot(&g);
        let G = 3.0;
        let energy = |F: &Matrix3<f64>| {
            let N = law.normal;
            let e = plane_shear(F, &N) - g;
            0.5 * G * e.norm_squared()
        };
        // a medium under a pressure of 1 (P = −J F⁻ᵀ): with μ this large, far inside the cone
        let P = -F.try_inverse().unwrap().transpose() * F.determinant();
        let A = Tensor4::zeros();
        let medium = MediumStress {
            P: &P,
            dP_dF: &A,
            dP_dtheta: &Matrix3::zeros(),
        };
        let r = law.respond::<3>(&F, &g, (G, 0.0), &medium).unwrap();
        assert!(!r.slipping);
        let h = 1e-6;
        for c in 0..9 {
            let (mut p, mut m) = (F, F);
            p[(c / 3, c % 3)] += h;
            m[(c / 3, c % 3)] -= h;
            let d = (energy(&p) - energy(&m)) / (2.0 * h);
            assert!((d - r.P[(c / 3, c % 3)]).abs() < 1e-8, "P[{c}]");
        }
        // and then the tangent is symmetric
        assert!((r.dP_dF - r.dP_dF.transpose()).amax() < 1e-12);
    }

    #[test]
    fn a_closed_layer_measures_its_slide_per_reference_thickness() {
        // however far it has closed and however it is turned; a plane stretched by λ along the
        // slide counts the stretch as well, λ times the slide (docs/THEORY.md, "The block
        // with one cell across": the measure of the slide between the points that face each
        // other, 0.3 / λ here, was measured and not adopted)
        for dim in [2, 3] {
            let law = plane(dim);
            for closed in [0.5, 1e-2, 1e-3] {
                for turn in [0.0, 0.7] {
                    for stretch in [1.0, 0.8, 1.25] {
                        let F = layer(law.normal, closed, 0.3, turn, 0.0)
                            * stretched(law.normal, stretch);
                        // with no previous slip and a cone of zero width, all shear turns into
                        // slip
                        let free = Friction { mu: 0.0, ..law };
                        let r = respond(&free, &F, &Vector3::zeros());
                        let T = along(law.normal);
                        assert!(
                            (r.slip - T * (0.3 * stretch)).norm() < 1e-12,
                            "{dim}D closed to {closed}, stretched {stretch}: {}",
                            r.slip
                        );
                        assert!(r.tau.norm() == 0.0 && r.P.norm() == 0.0);
                    }
                }
            }
        }
    }

    #[test]
    fn slip_returns_to_the_cone_and_dissipates() {
        for dim in [2, 3] {
            let law = plane(dim);
            let F = layer(law.normal, 1e-2, 0.3, 0.4, 1e-3);
            let r = respond(&law, &F, &Vector3::zeros());
            assert!(r.slipping && r.p_n > 0.0);
            // on the cone (the traction F τ is μ p_n), in the plane, and tangential to the
            // plane in the current configuration
            assert!(((F * r.tau).norm() - law.mu * r.p_n).abs() < 1e-12 * r.p_n);
            let n = F.try_inverse().unwrap().transpose() * law.normal;
            assert!((F * r.tau).dot(&n).abs() < 1e-12 * r.tau.norm() * n.norm());
            assert!(r.tau.dot(&law.normal).abs() < 1e-12 * r.tau.norm());
            // from the returned slip, the same state sticks
            let again = respond(&law, &F, &r.slip);
            assert!(!again.slipping && again.dissipated == 0.0);
            assert!((again.tau - r.tau).norm() < 1e-9 * r.tau.norm());
            // heat: the slip is along τ, τ · Δg = |τ| |Δg| > 0
            let expected = r.tau.norm() * r.slip.norm();
            assert!((r.dissipated - expected).abs() < 1e-12 * expected);
            // an open medium resists no slip
            let open = layer(law.normal, 1.3, 0.3, 0.0, 0.0);
            let r = respond(&law, &open, &Vector3::zeros());
            assert!(r.p_n < 0.0 && r.tau.norm() == 0.0);
        }
    }

    #[test]
    fn a_viscous_slip_carries_its_rate_beyond_the_cone() {
        for dim in [2, 3] {
            let plain = plane(dim);
            let F = layer(plain.normal, 1e-2, 0.3, 0.4, 1e-3);
            let coulomb = respond(&plain, &F, &Vector3::zeros());
            // η_s/Δt such that the overstress is about a third of the limit
            let rate = 0.5 * plain.mu * coulomb.p_n / coulomb.slip.norm();
            let law = Friction { rate, ..plain };
            let r = respond(&law, &F, &Vector3::zeros());
            assert!(r.slipping && (r.p_n - coulomb.p_n).abs() < 1e-12 * r.p_n);
            // |F τ| = μ p_n + (η_s/Δt) |Δg|, with the slip along the inviscid one, but shorter
            let over = (F * r.tau).norm() - law.mu * r.p_n;
            assert!(over > 0.2 * law.mu * r.p_n, "{dim}D: {over}");
            assert!((over - rate * r.slip.norm()).abs() < 1e-12 * over, "{dim}D");
            assert!(r.slip.norm() < coulomb.slip.norm());
            assert!(r.slip.normalize().dot(&coulomb.slip.normalize()) > 1.0 - 1e-12);
        }
    }
}
