//! Probes: named scalar outputs evaluated at material points of the undeformed body, or
//! from a group's reaction (a force ratio).
#![allow(non_snake_case)]

use crate::case::{Case, CaseError, Measure};
use crate::dofs::DofMap;
use crate::element::{RefElement, local_coords};
use crate::mesh::Mesh;
use crate::output::quantity::Quantity;

/// A material point: the nodes of the cell that contains it and its shape-function weights.
#[derive(Clone, Debug)]
pub struct MaterialPoint {
    pub nodes: Vec<usize>,
    pub weights: Vec<f64>,
}

impl MaterialPoint {
    /// Interpolate a nodal quantity.
    pub fn eval(&self, f: impl Fn(usize) -> f64) -> f64 {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(&n, w)| w * f(n))
            .sum()
    }
}

/// What a probe measures.
#[derive(Clone, Debug)]
pub enum ProbeKind {
    /// Displacement component `c` at a point.
    U(usize, MaterialPoint),
    Theta(MaterialPoint),
    /// Current distance along axis `c` from `a` to `b`.
    Distance(usize, MaterialPoint, MaterialPoint),
    /// F_t/F_n of the reaction of `group` split along the unit `normal`: F_n = |R·n|; F_t in 2D
    /// R·t with t = (n_y, −n_x) (signed: positive along x for n = [0, 1]), in 3D |R − (R·n) n|.
    ForceRatio {
        group: String,
        normal: [f64; 3],
    },
}

#[derive(Clone, Debug)]
pub struct Probe {
    pub name: String,
    pub kind: ProbeKind,
}

impl Probe {
    /// What the probe measures: a length or a temperature (`None`: a ratio).
    pub fn quantity(&self) -> Option<Quantity> {
        match self.kind {
            ProbeKind::Theta(_) => Some(Quantity::Temperature),
            ProbeKind::U(..) | ProbeKind::Distance(..) => Some(Quantity::Length),
            ProbeKind::ForceRatio { .. } => None,
        }
    }

    /// Evaluate on the solution `x`, with `reaction(group, c)` the component `c` of a group's
    /// reaction there; `NaN` if the probe's field is not simulated (a force ratio with no
    /// normal force and a tangential one; 0 with neither).
    pub fn eval(
        &self,
        mesh: &Mesh,
        dofs: &DofMap,
        x: &[f64],
        reaction: &dyn Fn(&str, usize) -> f64,
    ) -> f64 {
        let d = mesh.dim;
        let u = |n: usize, c: usize| {
            if dofs.u.is_empty() || c >= d {
                0.0
            } else {
                x[dofs.u[n * d + c] as usize]
            }
        };
        match &self.kind {
            ProbeKind::U(c, p) => p.eval(|n| u(n, *c)),
            ProbeKind::Theta(p) => {
                if dofs.theta.is_empty() {
                    f64::NAN
                } else {
                    p.eval(|n| x[dofs.theta[n] as usize])
                }
            }
            ProbeKind::Distance(c, a, b) => {
                b.eval(|n| mesh.coords[n][*c] + u(n, *c))
                    - a.eval(|n| mesh.coords[n][*c] + u(n, *c))
            }
            ProbeKind::ForceRatio { group, normal } => {
                let R: [f64; 3] = std::array::from_fn(|c| reaction(group, c));
                force_ratio(R, *normal, d)
            }
        }
    }
}

/// F_t/F_n of the force `R` split along the unit normal `n` in `dim` dimensions (see
/// [`ProbeKind::ForceRatio`]).
pub fn force_ratio(R: [f64; 3], n: [f64; 3], dim: usize) -> f64 {
    let Rn: f64 = (0..3).map(|i| R[i] * n[i]).sum();
    let Ft = if dim == 2 {
        R[0] * n[1] - R[1] * n[0]
    } else {
        (0..3)
            .map(|i| (R[i] - Rn * n[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    match (Rn == 0.0, Ft == 0.0) {
        (false, _) => Ft / Rn.abs(),
        (true, true) => 0.0,
        (true, false) => f64::NAN,
    }
}

/// Find the cell containing `X` and its shape-function weights there.
pub fn locate(mesh: &Mesh, X: &[f64]) -> Option<MaterialPoint> {
    let mut p = [0.0; 3];
    p[..X.len()].copy_from_slice(X);
    let tol = 1e-9;
    for b in &mesh.cells {
        for c in 0..b.n_cells() {
            let nodes = b.cell(c);
            // bounding box first
            let inside_box = (0..mesh.dim).all(|i| {
                let lo = nodes
                    .iter()
                    .map(|&n| mesh.coords[n][i])
                    .fold(f64::INFINITY, f64::min);
                let hi = nodes
                    .iter()
                    .map(|&n| mesh.coords[n][i])
                    .fold(f64::NEG_INFINITY, f64::max);
                let pad = 1e-9 * (hi - lo).max(1e-300);
                p[i] >= lo - pad && p[i] <= hi + pad
            });
            if !inside_box {
                continue;
            }
            let w = crate::with_cell!(b.kind, |N, D, E| inverse_map::<N, D, E>(
                mesh, nodes, &p, tol
            ));
            if let Some(weights) = w {
                return Some(MaterialPoint {
                    nodes: nodes.to_vec(),
                    weights,
                });
            }
        }
    }
    None
}

/// The shape-function weights at `p` of the cell `nodes`, if the point is inside it.
fn inverse_map<const N: usize, const D: usize, E: RefElement<N, D>>(
    mesh: &Mesh,
    nodes: &[usize],
    p: &[f64; 3],
    tol: f64,
) -> Option<Vec<f64>> {
    let X: [[f64; 3]; N] = std::array::from_fn(|i| mesh.coords[nodes[i]]);
    let xi = local_coords::<N, D, E>(&X, p)?;
    E::contains(&xi, tol).then(|| E::shape(&xi).to_vec())
}

/// Build the case's probes, locating their points in the mesh.
pub fn build(case: &Case, mesh: &Mesh) -> Result<Vec<Probe>, CaseError> {
    let mut out = Vec::new();
    for p in &case.file.probe {
        let name = p.name.get_ref().clone();
        let measure = match p.measure() {
            Ok(m) => m,
            Err(msg) => return case.error(p.field.span(), msg),
        };
        let at = |pt: &[f64]| -> Result<_, CaseError> {
            match locate(mesh, pt) {
                Some(mp) => Ok(mp),
                None => case.error(
                    p.name.span(),
                    format!("probe \"{name}\": point {pt:?} is not inside the mesh"),
                ),
            }
        };
        let kind = match measure {
            Measure::U(c, pt) => ProbeKind::U(c, at(pt)?),
            Measure::Theta(pt) => ProbeKind::Theta(at(pt)?),
            Measure::Distance(axis, a, b) => ProbeKind::Distance(axis, at(a)?, at(b)?),
            Measure::ForceRatio(group, n) => {
                if n.len() != mesh.dim {
                    return case.error(
                        p.field.span(),
                        format!(
                            "probe \"{name}\": `normal` has {} components; the mesh is {}D",
                            n.len(),
                            mesh.dim
                        ),
                    );
                }
                let length = n.iter().map(|v| v * v).sum::<f64>().sqrt();
                ProbeKind::ForceRatio {
                    group: group.to_string(),
                    normal: std::array::from_fn(|i| n.get(i).map_or(0.0, |v| v / length)),
                }
            }
        };
        out.push(Probe { name, kind });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::force_ratio;

    #[test]
    fn a_force_ratio_splits_the_reaction_along_the_normal() {
        // pressed down (R_y < 0) and dragged along x: F_t/F_n signed in 2D
        let down = [0.0, 1.0, 0.0];
        assert!((force_ratio([0.3, -1.5, 0.0], down, 2) - 0.2).abs() < 1e-15);
        assert!((force_ratio([-0.3, -1.5, 0.0], down, 2) + 0.2).abs() < 1e-15);
        // a tilted normal: the reaction along it alone has no tangential part
        let s = 0.5f64.sqrt();
        assert!(force_ratio([2.0 * s, 2.0 * s, 0.0], [s, s, 0.0], 2).abs() < 1e-15);
        // 3D: the size of the tangential part
        let r = force_ratio([3.0, 4.0, -10.0], [0.0, 0.0, 1.0], 3);
        assert!((r - 0.5).abs() < 1e-15, "{r}");
        // no force at all; a tangential force with no normal one
        assert_eq!(force_ratio([0.0; 3], [0.0, 1.0, 0.0], 2), 0.0);
        assert!(force_ratio([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 2).is_nan());
    }
}
