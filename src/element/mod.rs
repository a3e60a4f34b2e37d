//! Reference elements: shape functions, their reference gradients and quadrature rules.
//!
//! Each element type is a zero-sized struct implementing [`RefElement<N, D>`] with `N` nodes in
//! `D` reference dimensions, so kernels are monomorphic per element type. Node order is tmc's
//! own, which for the linear elements equals gmsh's and VTK's.
//!
//! Quadrature rules are the standard Gauss rules that basix (FEniCSx) also uses, so a
//! validation run can integrate with the very same points and weights.

mod quadratic;
pub use quadratic::{Hex20, Hex27, Line3, Quad8, Quad9, Tet10, Tri6};

/// Evaluate `$body` with `$n` (nodes), `$d` (reference dimension) and `$e` (the element type)
/// bound for a cell kind of dimension 2 or 3, so a generic kernel is called monomorphically
/// per element block. Facet kinds are a logic error here.
#[macro_export]
macro_rules! with_cell {
    ($kind:expr, |$n:ident, $d:ident, $e:ident| $body:expr) => {{
        use $crate::element as el;
        use $crate::mesh::CellKind as K;
        match $kind {
            K::Tri3 => $crate::with_cell!(@ 3, 2, el::Tri3, $n, $d, $e, $body),
            K::Quad4 => $crate::with_cell!(@ 4, 2, el::Quad4, $n, $d, $e, $body),
            K::Tet4 => $crate::with_cell!(@ 4, 3, el::Tet4, $n, $d, $e, $body),
            K::Hex8 => $crate::with_cell!(@ 8, 3, el::Hex8, $n, $d, $e, $body),
            K::Tri6 => $crate::with_cell!(@ 6, 2, el::Tri6, $n, $d, $e, $body),
            K::Quad8 => $crate::with_cell!(@ 8, 2, el::Quad8, $n, $d, $e, $body),
            K::Quad9 => $crate::with_cell!(@ 9, 2, el::Quad9, $n, $d, $e, $body),
            K::Tet10 => $crate::with_cell!(@ 10, 3, el::Tet10, $n, $d, $e, $body),
            K::Hex20 => $crate::with_cell!(@ 20, 3, el::Hex20, $n, $d, $e, $body),
            K::Hex27 => $crate::with_cell!(@ 27, 3, el::Hex27, $n, $d, $e, $body),
            K::Point1 | K::Line2 | K::Line3 => unreachable!("facets are not cells"),
        }
    }};
    (@ $nv:literal, $dv:literal, $ty:ty, $n:ident, $d:ident, $e:ident, $body:expr) => {{
        const $n: usize = $nv;
        const $d: usize = $dv;
        type $e = $ty;
        $body
    }};
}

/// As [`with_cell!`], for any kind including boundary facets (points, lines, and the 2D kinds
/// as faces of 3D cells).
#[macro_export]
macro_rules! with_element {
    ($kind:expr, |$n:ident, $d:ident, $e:ident| $body:expr) => {{
        use $crate::element as el;
        use $crate::mesh::CellKind as K;
        match $kind {
            K::Point1 => $crate::with_cell!(@ 1, 0, el::Point1, $n, $d, $e, $body),
            K::Line2 => $crate::with_cell!(@ 2, 1, el::Line2, $n, $d, $e, $body),
            K::Line3 => $crate::with_cell!(@ 3, 1, el::Line3, $n, $d, $e, $body),
            k => $crate::with_cell!(k, |$n, $d, $e| $body),
        }
    }};
}

/// A reference element with `N` nodes in `D` reference dimensions.
pub trait RefElement<const N: usize, const D: usize>: Sync + Send + 'static {
    /// Shape function values N_I(ξ).
    fn shape(xi: &[f64; D]) -> [f64; N];
    /// Reference gradients ∂N_I/∂ξ_j.
    fn grad(xi: &[f64; D]) -> [[f64; D]; N];
    /// Reference second derivatives ∂²N_I/∂ξ_j∂ξ_k.
    fn hessian(xi: &[f64; D]) -> [[[f64; D]; D]; N];
    /// Quadrature points and weights on the reference element.
    fn quadrature() -> &'static [([f64; D], f64)];
    /// Reference coordinates of the nodes.
    fn nodes() -> [[f64; D]; N];
    /// Simplex (unit triangle/tetrahedron) or cube ([−1, 1]^D) reference domain.
    const SIMPLEX: bool;
    /// Whether ξ lies in the reference domain, up to `tol`.
    fn contains(xi: &[f64; D], tol: f64) -> bool {
        if Self::SIMPLEX {
            xi.iter().all(|&v| v >= -tol) && xi.iter().sum::<f64>() <= 1.0 + tol
        } else {
            xi.iter().all(|&v| v.abs() <= 1.0 + tol)
        }
    }
}

/// The element's centre in reference coordinates: the mean of its nodes'.
pub fn centre<const N: usize, const D: usize, E: RefElement<N, D>>() -> [f64; D] {
    let mut xi = [0.0; D];
    for r in &E::nodes() {
        for d in 0..D {
            xi[d] += r[d] / N as f64;
        }
    }
    xi
}

/// The reference coordinates ξ of the point `p` in the cell with nodes at `X`: the
/// isoparametric map inverted by Newton from the element's centre. `None` where the map is
/// singular; a ξ outside the reference domain (see [`RefElement::contains`]) where the point
/// is outside the cell.
#[allow(non_snake_case)]
pub fn local_coords<const N: usize, const D: usize, E: RefElement<N, D>>(
    X: &[[f64; 3]; N],
    p: &[f64; 3],
) -> Option<[f64; D]> {
    let mut xi = centre::<N, D, E>();
    for _ in 0..30 {
        let n = E::shape(&xi);
        let g = E::grad(&xi);
        let mut res = [0.0; D];
        let mut jac = [[0.0; D]; D];
        for I in 0..N {
            for i in 0..D {
                res[i] += n[I] * X[I][i];
                for j in 0..D {
                    jac[i][j] += X[I][i] * g[I][j];
                }
            }
        }
        for i in 0..D {
            res[i] -= p[i];
        }
        let (_, inv) = invert_small(&jac)?;
        let mut step = 0.0f64;
        for i in 0..D {
            let dxi: f64 = (0..D).map(|j| inv[i][j] * res[j]).sum();
            xi[i] -= dxi;
            step = step.max(dxi.abs());
        }
        if step < 1e-14 {
            break;
        }
    }
    Some(xi)
}

/// 2-node line on [−1, 1] (boundary facet of T1/Q1).
pub struct Line2;
/// 3-node triangle on the unit simplex (T1).
pub struct Tri3;
/// 4-node quadrilateral on [−1, 1]² (Q1).
pub struct Quad4;
/// 4-node tetrahedron on the unit simplex (tet4).
pub struct Tet4;
/// 8-node hexahedron on [−1, 1]³ (H1).
pub struct Hex8;

const G2: f64 = 0.577_350_269_189_625_8; // 1/√3

static LINE_GAUSS2: [([f64; 1], f64); 2] = [([-G2], 1.0), ([G2], 1.0)];

impl RefElement<2, 1> for Line2 {
    const SIMPLEX: bool = false;
    fn shape(xi: &[f64; 1]) -> [f64; 2] {
        [0.5 * (1.0 - xi[0]), 0.5 * (1.0 + xi[0])]
    }
    fn grad(_xi: &[f64; 1]) -> [[f64; 1]; 2] {
        [[-0.5], [0.5]]
    }
    fn hessian(_xi: &[f64; 1]) -> [[[f64; 1]; 1]; 2] {
        [[[0.0]]; 2]
    }
    fn quadrature() -> &'static [([f64; 1], f64)] {
        &LINE_GAUSS2
    }
    fn nodes() -> [[f64; 1]; 2] {
        [[-1.0], [1.0]]
    }
}

/// One-point rule: exact for T1, whose gradients are constant (basix degree 1).
static TRI_CENTROID: [([f64; 2], f64); 1] = [([1.0 / 3.0, 1.0 / 3.0], 0.5)];

impl RefElement<3, 2> for Tri3 {
    const SIMPLEX: bool = true;
    fn shape(xi: &[f64; 2]) -> [f64; 3] {
        [1.0 - xi[0] - xi[1], xi[0], xi[1]]
    }
    fn grad(_xi: &[f64; 2]) -> [[f64; 2]; 3] {
        [[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]
    }
    fn hessian(_xi: &[f64; 2]) -> [[[f64; 2]; 2]; 3] {
        [[[0.0; 2]; 2]; 3]
    }
    fn quadrature() -> &'static [([f64; 2], f64)] {
        &TRI_CENTROID
    }
    fn nodes() -> [[f64; 2]; 3] {
        [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]
    }
}

static QUAD_GAUSS2: [([f64; 2], f64); 4] = [
    ([-G2, -G2], 1.0),
    ([G2, -G2], 1.0),
    ([-G2, G2], 1.0),
    ([G2, G2], 1.0),
];

const QUAD_NODES: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

impl RefElement<4, 2> for Quad4 {
    const SIMPLEX: bool = false;
    fn shape(xi: &[f64; 2]) -> [f64; 4] {
        QUAD_NODES.map(|a| 0.25 * (1.0 + a[0] * xi[0]) * (1.0 + a[1] * xi[1]))
    }
    fn grad(xi: &[f64; 2]) -> [[f64; 2]; 4] {
        QUAD_NODES.map(|a| {
            [
                0.25 * a[0] * (1.0 + a[1] * xi[1]),
                0.25 * a[1] * (1.0 + a[0] * xi[0]),
            ]
        })
    }
    fn hessian(_xi: &[f64; 2]) -> [[[f64; 2]; 2]; 4] {
        QUAD_NODES.map(|a| [[0.0, 0.25 * a[0] * a[1]], [0.25 * a[0] * a[1], 0.0]])
    }
    fn quadrature() -> &'static [([f64; 2], f64)] {
        &QUAD_GAUSS2
    }
    fn nodes() -> [[f64; 2]; 4] {
        QUAD_NODES
    }
}

static TET_CENTROID: [([f64; 3], f64); 1] = [([0.25, 0.25, 0.25], 1.0 / 6.0)];

impl RefElement<4, 3> for Tet4 {
    const SIMPLEX: bool = true;
    fn shape(xi: &[f64; 3]) -> [f64; 4] {
        [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]]
    }
    fn grad(_xi: &[f64; 3]) -> [[f64; 3]; 4] {
        [
            [-1.0, -1.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
    }
    fn hessian(_xi: &[f64; 3]) -> [[[f64; 3]; 3]; 4] {
        [[[0.0; 3]; 3]; 4]
    }
    fn quadrature() -> &'static [([f64; 3], f64)] {
        &TET_CENTROID
    }
    fn nodes() -> [[f64; 3]; 4] {
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
    }
}

const HEX_NODES: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

static HEX_GAUSS2: [([f64; 3], f64); 8] = [
    ([-G2, -G2, -G2], 1.0),
    ([G2, -G2, -G2], 1.0),
    ([-G2, G2, -G2], 1.0),
    ([G2, G2, -G2], 1.0),
    ([-G2, -G2, G2], 1.0),
    ([G2, -G2, G2], 1.0),
    ([-G2, G2, G2], 1.0),
    ([G2, G2, G2], 1.0),
];

impl RefElement<8, 3> for Hex8 {
    const SIMPLEX: bool = false;
    fn shape(xi: &[f64; 3]) -> [f64; 8] {
        HEX_NODES
            .map(|a| 0.125 * (1.0 + a[0] * xi[0]) * (1.0 + a[1] * xi[1]) * (1.0 + a[2] * xi[2]))
    }
    fn grad(xi: &[f64; 3]) -> [[f64; 3]; 8] {
        HEX_NODES.map(|a| {
            let (s, t, u) = (1.0 + a[0] * xi[0], 1.0 + a[1] * xi[1], 1.0 + a[2] * xi[2]);
            [
                0.125 * a[0] * t * u,
                0.125 * a[1] * s * u,
                0.125 * a[2] * s * t,
            ]
        })
    }
    fn hessian(xi: &[f64; 3]) -> [[[f64; 3]; 3]; 8] {
        HEX_NODES.map(|a| {
            let f = [1.0 + a[0] * xi[0], 1.0 + a[1] * xi[1], 1.0 + a[2] * xi[2]];
            let mut h = [[0.0; 3]; 3];
            for i in 0..3 {
                for j in 0..3 {
                    if i != j {
                        h[i][j] = 0.125 * a[i] * a[j] * f[3 - i - j];
                    }
                }
            }
            h
        })
    }
    fn quadrature() -> &'static [([f64; 3], f64)] {
        &HEX_GAUSS2
    }
    fn nodes() -> [[f64; 3]; 8] {
        HEX_NODES
    }
}

/// Geometry of an element at one reference point: physical shape gradients and |det ∂X/∂ξ|.
///
/// `X` are the element's nodal coordinates (only the first `D` components are used). Returns
/// `None` when the reference map is singular or inverted (det ≤ 0), which for an undeformed
/// mesh means the mesh itself is broken.
#[allow(non_snake_case)]
#[inline(always)]
pub fn physical_gradients<const N: usize, const D: usize>(
    dN_dxi: &[[f64; D]; N],
    X: &[[f64; 3]; N],
) -> Option<([[f64; D]; N], f64)> {
    let (det, inv) = invert_small(&reference_jacobian(dN_dxi, X))?;
    if det <= 0.0 {
        return None;
    }
    // ∂N/∂X_k = Σ_j ∂N/∂ξ_j (J⁻¹)_jk
    let mut out = [[0.0; D]; N];
    for (o, g) in out.iter_mut().zip(dN_dxi) {
        for k in 0..D {
            o[k] = (0..D).map(|j| g[j] * inv[j][k]).sum();
        }
    }
    Some((out, det))
}

/// The reference map's Jacobian ∂X_i/∂ξ_j at a point with reference gradients `dN_dxi`, of
/// the nodal coordinates `X` (their first `D` components).
#[allow(non_snake_case)]
#[inline(always)]
fn reference_jacobian<const N: usize, const D: usize>(
    dN_dxi: &[[f64; D]; N],
    X: &[[f64; 3]; N],
) -> [[f64; D]; D] {
    let mut jac = [[0.0; D]; D];
    for (g, x) in dN_dxi.iter().zip(X) {
        for i in 0..D {
            for j in 0..D {
                jac[i][j] += x[i] * g[j];
            }
        }
    }
    jac
}

/// The corner of a cell where its shape `x` is the most inverted relative to its reference
/// shape `X`: (corner, det ∂x/∂ξ / det ∂X/∂ξ there), over those of its first `corners` nodes
/// that `looked_at` keeps (∞ if none). The ratio is ≤ 0 at a corner where the cell is
/// inverted. Only a linear simplex has one Jacobian; any other cell's varies over it and can
/// change sign at a corner while it stays positive at every quadrature point.
#[allow(non_snake_case)]
pub fn worst_corner<const N: usize, const D: usize, E: RefElement<N, D>>(
    X: &[[f64; 3]; N],
    x: &[[f64; 3]; N],
    corners: usize,
    looked_at: impl Fn(usize) -> bool,
) -> (usize, f64) {
    let det = |jac: [[f64; D]; D]| invert_small(&jac).map_or(0.0, |(d, _)| d);
    let nodes = E::nodes();
    (0..corners.min(N))
        .filter(|&c| looked_at(c))
        .map(|c| {
            let g = E::grad(&nodes[c]);
            let reference = det(reference_jacobian(&g, X));
            (c, det(reference_jacobian(&g, x)) / reference)
        })
        .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
}

/// Determinant and inverse of a 1×1, 2×2 or 3×3 matrix; `None` if singular.
pub fn invert_small<const D: usize>(a: &[[f64; D]; D]) -> Option<(f64, [[f64; D]; D])> {
    let mut inv = [[0.0; D]; D];
    let det = match D {
        1 => {
            let d = a[0][0];
            if d == 0.0 {
                return None;
            }
            inv[0][0] = 1.0 / d;
            d
        }
        2 => {
            let d = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            if d == 0.0 {
                return None;
            }
            inv[0][0] = a[1][1] / d;
            inv[0][1] = -a[0][1] / d;
            inv[1][0] = -a[1][0] / d;
            inv[1][1] = a[0][0] / d;
            d
        }
        3 => {
            let c00 = a[1][1] * a[2][2] - a[1][2] * a[2][1];
            let c01 = a[1][2] * a[2][0] - a[1][0] * a[2][2];
            let c02 = a[1][0] * a[2][1] - a[1][1] * a[2][0];
            let d = a[0][0] * c00 + a[0][1] * c01 + a[0][2] * c02;
            if d == 0.0 {
                return None;
            }
            inv[0][0] = c00 / d;
            inv[0][1] = (a[0][2] * a[2][1] - a[0][1] * a[2][2]) / d;
            inv[0][2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / d;
            inv[1][0] = c01 / d;
            inv[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / d;
            inv[1][2] = (a[0][2] * a[1][0] - a[0][0] * a[1][2]) / d;
            inv[2][0] = c02 / d;
            inv[2][1] = (a[0][1] * a[2][0] - a[0][0] * a[2][1]) / d;
            inv[2][2] = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / d;
            d
        }
        _ => return None,
    };
    Some((det, inv))
}

/// Measure element of a facet or cell: |∂X/∂ξ| for a line, |∂X/∂ξ1 × ∂X/∂ξ2| for a surface
/// (in 2D or 3D) and |det ∂X/∂ξ| for a volume.
#[allow(non_snake_case)]
pub fn facet_measure<const N: usize, const D: usize>(
    dN_dxi: &[[f64; D]; N],
    X: &[[f64; 3]; N],
) -> f64 {
    let mut t = [[0.0; 3]; D];
    for (g, x) in dN_dxi.iter().zip(X) {
        for j in 0..D {
            for i in 0..3 {
                t[j][i] += x[i] * g[j];
            }
        }
    }
    match D {
        0 => 1.0,
        1 => (t[0][0] * t[0][0] + t[0][1] * t[0][1] + t[0][2] * t[0][2]).sqrt(),
        2 => {
            let (a, b) = (t[0], t[1]);
            let c = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt()
        }
        _ => {
            let (a, b, c) = (t[0], t[1], t[2]);
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                .abs()
        }
    }
}

/// 1-node point "element" for point groups.
pub struct Point1;

static POINT_RULE: [([f64; 0], f64); 1] = [([], 1.0)];

impl RefElement<1, 0> for Point1 {
    const SIMPLEX: bool = false;
    fn shape(_xi: &[f64; 0]) -> [f64; 1] {
        [1.0]
    }
    fn grad(_xi: &[f64; 0]) -> [[f64; 0]; 1] {
        [[]]
    }
    fn hessian(_xi: &[f64; 0]) -> [[[f64; 0]; 0]; 1] {
        [[]]
    }
    fn quadrature() -> &'static [([f64; 0], f64)] {
        &POINT_RULE
    }
    fn nodes() -> [[f64; 0]; 1] {
        [[]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_element<const N: usize, const D: usize, E: RefElement<N, D>>() {
        let nodes = E::nodes();
        // Kronecker property at the nodes
        for (a, xa) in nodes.iter().enumerate() {
            let n = E::shape(xa);
            for (b, v) in n.iter().enumerate() {
                let expect = if a == b { 1.0 } else { 0.0 };
                assert!((v - expect).abs() < 1e-14, "N_{b}(node {a}) = {v}");
            }
        }
        // partition of unity, linear reproduction and gradient vs finite differences
        let pts: Vec<[f64; D]> = E::quadrature().iter().map(|q| q.0).collect();
        for xi in pts {
            let n = E::shape(&xi);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for d in 0..D {
                let lin: f64 = n.iter().zip(&nodes).map(|(n, x)| n * x[d]).sum();
                assert!((lin - xi[d]).abs() < 1e-14);
            }
            let g = E::grad(&xi);
            for d in 0..D {
                let h = 1e-6;
                let (mut p, mut m) = (xi, xi);
                p[d] += h;
                m[d] -= h;
                let (np, nm) = (E::shape(&p), E::shape(&m));
                for i in 0..N {
                    let fd = (np[i] - nm[i]) / (2.0 * h);
                    assert!(
                        (fd - g[i][d]).abs() < 1e-8,
                        "dN{i}/dxi{d}: {fd} vs {}",
                        g[i][d]
                    );
                }
            }
            for d in 0..D {
                let s: f64 = g.iter().map(|gi| gi[d]).sum();
                assert!(s.abs() < 1e-14);
            }
            // second derivatives against finite differences of the gradients
            let hs = E::hessian(&xi);
            for d in 0..D {
                let h = 1e-6;
                let (mut p, mut m) = (xi, xi);
                p[d] += h;
                m[d] -= h;
                let (gp, gm) = (E::grad(&p), E::grad(&m));
                for i in 0..N {
                    for e in 0..D {
                        let fd = (gp[i][e] - gm[i][e]) / (2.0 * h);
                        assert!(
                            (fd - hs[i][e][d]).abs() < 1e-7,
                            "d2N{i}/dxi{e}dxi{d}: {fd} vs {}",
                            hs[i][e][d]
                        );
                        assert_eq!(hs[i][e][d], hs[i][d][e], "symmetric");
                    }
                }
            }
        }
    }

    /// Quadratic elements reproduce every complete quadratic polynomial exactly, with its
    /// gradient and Hessian, and their rules integrate quadratics (and the volume) exactly.
    fn check_quadratic<const N: usize, const D: usize, E: RefElement<N, D>>(volume: f64) {
        check_element::<N, D, E>();
        let nodes = E::nodes();
        // f = 1 + Σ c_d ξ_d + Σ_{d≤e} q_de ξ_d ξ_e
        let c = [0.7, -1.3, 0.4];
        let q = [[2.0, -0.6, 0.9], [0.0, 1.1, -1.7], [0.0, 0.0, 0.5]];
        let f = |x: &[f64; D]| {
            let mut v = 1.0;
            for d in 0..D {
                v += c[d] * x[d];
                for e in d..D {
                    v += q[d][e] * x[d] * x[e];
                }
            }
            v
        };
        let hess_f = |d: usize, e: usize| {
            if d == e {
                2.0 * q[d][d]
            } else {
                q[d.min(e)][d.max(e)]
            }
        };
        let fv: Vec<f64> = nodes.iter().map(f).collect();
        for xi in [[0.13; D], std::array::from_fn(|d| 0.05 + 0.1 * d as f64)] {
            let n = E::shape(&xi);
            let v: f64 = n.iter().zip(&fv).map(|(a, b)| a * b).sum();
            assert!((v - f(&xi)).abs() < 1e-13, "value {v} vs {}", f(&xi));
            let hs = E::hessian(&xi);
            for d in 0..D {
                for e in 0..D {
                    let h: f64 = (0..N).map(|i| hs[i][d][e] * fv[i]).sum();
                    assert!((h - hess_f(d, e)).abs() < 1e-12, "hessian {d}{e}: {h}");
                }
            }
        }
        let rule = E::quadrature();
        assert!((rule.iter().map(|r| r.1).sum::<f64>() - volume).abs() < 1e-14);
        // ∫ f = Σ_I f_I ∫ N_I, exact for the rule's degree ≥ 2
        let exact: f64 = rule.iter().map(|(x, w)| w * f(x)).sum();
        let by_shape: f64 = rule
            .iter()
            .map(|(x, w)| w * E::shape(x).iter().zip(&fv).map(|(a, b)| a * b).sum::<f64>())
            .sum();
        assert!((exact - by_shape).abs() < 1e-13);
    }

    #[test]
    fn quadratic_elements_reproduce_quadratic_fields() {
        check_quadratic::<3, 1, Line3>(2.0);
        check_quadratic::<6, 2, Tri6>(0.5);
        check_quadratic::<8, 2, Quad8>(4.0);
        check_quadratic::<9, 2, Quad9>(4.0);
        check_quadratic::<10, 3, Tet10>(1.0 / 6.0);
        check_quadratic::<20, 3, Hex20>(8.0);
        check_quadratic::<27, 3, Hex27>(8.0);
    }

    #[test]
    fn linear_elements_are_consistent() {
        check_element::<2, 1, Line2>();
        check_element::<3, 2, Tri3>();
        check_element::<4, 2, Quad4>();
        check_element::<4, 3, Tet4>();
        check_element::<8, 3, Hex8>();
    }

    #[test]
    fn quadrature_integrates_reference_volume() {
        let s = |r: &[([f64; 2], f64)]| r.iter().map(|q| q.1).sum::<f64>();
        assert!((s(Tri3::quadrature()) - 0.5).abs() < 1e-15);
        assert!((s(Quad4::quadrature()) - 4.0).abs() < 1e-15);
        let s3 = |r: &[([f64; 3], f64)]| r.iter().map(|q| q.1).sum::<f64>();
        assert!((s3(Tet4::quadrature()) - 1.0 / 6.0).abs() < 1e-15);
        assert!((s3(Hex8::quadrature()) - 8.0).abs() < 1e-15);
    }

    #[test]
    fn physical_gradients_reproduce_linear_field_on_distorted_quad() {
        let x = [
            [0.0, 0.0, 0.0],
            [2.0, 0.3, 0.0],
            [2.4, 1.9, 0.0],
            [-0.2, 1.1, 0.0],
        ];
        let f = |p: &[f64; 3]| 3.0 * p[0] - 2.0 * p[1] + 1.0;
        for (xi, _) in Quad4::quadrature() {
            let (g, det) = physical_gradients::<4, 2>(&Quad4::grad(xi), &x).unwrap();
            assert!(det > 0.0);
            let grad: [f64; 2] = [0, 1].map(|k| (0..4).map(|i| g[i][k] * f(&x[i])).sum());
            assert!((grad[0] - 3.0).abs() < 1e-12 && (grad[1] + 2.0).abs() < 1e-12);
        }
    }

    #[test]
    #[allow(non_snake_case)]
    fn a_flattened_quad_inverted_at_a_corner_keeps_every_quadrature_point_positive() {
        // a cell of a closed medium layer, 0.0625 wide and 0.25 thick, flattened to a few
        // thousandths with its top-left node (a solid's corner) pushed just below its bottom
        // edge's line: inverted at that corner only
        let X = [
            [3.0, 0.0, 0.0],
            [3.0625, 0.0, 0.0],
            [3.0625, 0.25, 0.0],
            [3.0, 0.25, 0.0],
        ];
        let x = [
            [3.0, 0.0, 0.0],
            [3.0625, 0.0, 0.0],
            [3.0554, 0.0042, 0.0],
            [3.0084, -2e-4, 0.0],
        ];
        for (xi, _) in Quad4::quadrature() {
            let g = Quad4::grad(xi);
            let (_, reference) = physical_gradients(&g, &X).unwrap();
            let (_, deformed) = physical_gradients(&g, &x).expect("J > 0 at every point");
            assert!(deformed / reference > 0.0);
        }
        let (corner, ratio) = worst_corner::<4, 2, Quad4>(&X, &x, 4, |_| true);
        assert_eq!(corner, 3);
        assert!(ratio < 0.0, "{ratio}");
        // the edge from the bottom-left corner up to it dips below the bottom: inverted at
        // both of its ends, not at the right-hand corners
        assert!(worst_corner::<4, 2, Quad4>(&X, &x, 4, |c| c == 0).1 < 0.0);
        let (_, others) = worst_corner::<4, 2, Quad4>(&X, &x, 4, |c| c == 1 || c == 2);
        assert!(others > 0.0, "{others}");
        // undeformed, and moved rigidly: 1 at every corner
        let moved = X.map(|p| [p[0] + 0.3, p[1] - 0.1, 0.0]);
        assert!((worst_corner::<4, 2, Quad4>(&X, &moved, 4, |_| true).1 - 1.0).abs() < 1e-12);
        // a linear triangle's is its one J, the same at every corner
        let (T, t) = ([X[0], X[1], X[3]], [x[0], x[1], [3.03, 0.001, 0.0]]);
        let (_, j) = physical_gradients(&Tri3::grad(&[0.0, 0.0]), &t).unwrap();
        let (_, j0) = physical_gradients(&Tri3::grad(&[0.0, 0.0]), &T).unwrap();
        assert!((worst_corner::<3, 2, Tri3>(&T, &t, 3, |_| true).1 - j / j0).abs() < 1e-12);
    }
}
