//! Probes: named scalar outputs evaluated at material points of the undeformed body.

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
}

#[derive(Clone, Debug)]
pub struct Probe {
    pub name: String,
    pub kind: ProbeKind,
}

impl Probe {
    /// What the probe measures: a length or a temperature.
    pub fn quantity(&self) -> Quantity {
        match self.kind {
            ProbeKind::Theta(_) => Quantity::Temperature,
            ProbeKind::U(..) | ProbeKind::Distance(..) => Quantity::Length,
        }
    }

    /// Evaluate on the solution `x`; `NaN` if the probe's field is not simulated.
    pub fn eval(&self, mesh: &Mesh, dofs: &DofMap, x: &[f64]) -> f64 {
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
        }
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
        };
        out.push(Probe { name, kind });
    }
    Ok(out)
}
