//! Quadratic reference elements: line3, tri6, quad8 (serendipity), quad9, tet10, hex20
//! (serendipity, H2S) and hex27 (H2). Node order is gmsh's (the reference coordinates below are
//! those `gmsh.model.mesh.getElementProperties` reports for gmsh 4.8), so cells read from a
//! `.msh` need no permutation; output maps them to VTK's order.
//!
//! Quadrature: 3-point Gauss per direction on lines, quads and hexes, the degree-2 rule on
//! triangles (3 points) and the degree-4 rule on tetrahedra (14 points): basix's rules of
//! degree 4 (interval, quadrilateral, hexahedron, tetrahedron) and 2 (triangle). Each is exact
//! for ∇N det(∂X/∂ξ) of a curved (isoparametric) cell, so patch tests pass on curved meshes.

use super::RefElement;

/// 3-node line on [−1, 1]: ends, then middle.
pub struct Line3;
/// 6-node triangle on the unit simplex: corners, then edges (0,1), (1,2), (2,0).
pub struct Tri6;
/// 8-node serendipity quadrilateral on [−1, 1]².
pub struct Quad8;
/// 9-node Lagrange quadrilateral on [−1, 1]².
pub struct Quad9;
/// 10-node tetrahedron: corners, then edges (0,1), (1,2), (2,0), (0,3), (2,3), (1,3).
pub struct Tet10;
/// 20-node serendipity hexahedron (H2S) on [−1, 1]³.
pub struct Hex20;
/// 27-node Lagrange hexahedron (H2) on [−1, 1]³.
pub struct Hex27;

const QUAD_NODES9: [[f64; 2]; 9] = [
    [-1.0, -1.0],
    [1.0, -1.0],
    [1.0, 1.0],
    [-1.0, 1.0],
    [0.0, -1.0],
    [1.0, 0.0],
    [0.0, 1.0],
    [-1.0, 0.0],
    [0.0, 0.0],
];

const HEX_NODES27: [[f64; 3]; 27] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [0.0, -1.0, -1.0],
    [-1.0, 0.0, -1.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, -1.0],
    [1.0, -1.0, 0.0],
    [0.0, 1.0, -1.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [0.0, 0.0, -1.0],
    [0.0, -1.0, 0.0],
    [-1.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, 0.0],
];

/// Corner pairs of the edge nodes of tri6 and tet10, in gmsh's order.
const TRI_EDGES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];
const TET_EDGES: [(usize, usize); 6] = [(0, 1), (1, 2), (2, 0), (0, 3), (2, 3), (1, 3)];

/// Shape function values, gradients and Hessians at one point.
type Values<const N: usize, const D: usize> = ([f64; N], [[f64; D]; N], [[[f64; D]; D]; N]);

/// 1D quadratic Lagrange function of the node at `c` ∈ {−1, 0, 1}: (value, d/dx, d²/dx²).
fn lagrange(c: f64, x: f64) -> (f64, f64, f64) {
    if c < -0.5 {
        (0.5 * x * (x - 1.0), x - 0.5, 1.0)
    } else if c > 0.5 {
        (0.5 * x * (x + 1.0), x + 0.5, 1.0)
    } else {
        (1.0 - x * x, -2.0 * x, -2.0)
    }
}

/// Tensor-product Lagrange functions (value, gradient, Hessian) at nodes `nodes`.
fn tensor<const N: usize, const D: usize>(nodes: &[[f64; D]; N], xi: &[f64; D]) -> Values<N, D> {
    let mut v = [0.0; N];
    let mut g = [[0.0; D]; N];
    let mut h = [[[0.0; D]; D]; N];
    for (I, a) in nodes.iter().enumerate() {
        let l: [(f64, f64, f64); D] = std::array::from_fn(|d| lagrange(a[d], xi[d]));
        v[I] = l.iter().map(|t| t.0).product();
        for i in 0..D {
            for j in i..D {
                let mut p = 1.0;
                for (d, t) in l.iter().enumerate() {
                    p *= match (d == i, d == j) {
                        (true, true) => t.2,
                        (true, false) | (false, true) => t.1,
                        _ => t.0,
                    };
                }
                h[I][i][j] = p;
                h[I][j][i] = p;
            }
            g[I][i] = l
                .iter()
                .enumerate()
                .map(|(d, t)| if d == i { t.1 } else { t.0 })
                .product();
        }
    }
    (v, g, h)
}

/// Quadratic simplex functions from barycentric coordinates λ_0 = 1 − Σξ, λ_k = ξ_k:
/// corners λ(2λ − 1), edges 4 λ_a λ_b. Returns (value, gradient, Hessian).
fn simplex<const N: usize, const D: usize>(
    edges: &[(usize, usize)],
    xi: &[f64; D],
) -> Values<N, D> {
    let mut lam = [0.0; 4];
    let mut dlam = [[0.0; D]; 4]; // ∂λ_a/∂ξ
    lam[0] = 1.0 - xi.iter().sum::<f64>();
    for d in 0..D {
        lam[d + 1] = xi[d];
        dlam[0][d] = -1.0;
        dlam[d + 1][d] = 1.0;
    }
    let mut v = [0.0; N];
    let mut g = [[0.0; D]; N];
    let mut h = [[[0.0; D]; D]; N];
    for a in 0..=D {
        v[a] = lam[a] * (2.0 * lam[a] - 1.0);
        for i in 0..D {
            g[a][i] = (4.0 * lam[a] - 1.0) * dlam[a][i];
            for j in 0..D {
                h[a][i][j] = 4.0 * dlam[a][i] * dlam[a][j];
            }
        }
    }
    for (k, &(a, b)) in edges.iter().enumerate() {
        let I = D + 1 + k;
        v[I] = 4.0 * lam[a] * lam[b];
        for i in 0..D {
            g[I][i] = 4.0 * (dlam[a][i] * lam[b] + lam[a] * dlam[b][i]);
            for j in 0..D {
                h[I][i][j] = 4.0 * (dlam[a][i] * dlam[b][j] + dlam[a][j] * dlam[b][i]);
            }
        }
    }
    (v, g, h)
}

/// Serendipity functions of quad8 / hex20 (corner nodes first, then mid-edge nodes with one
/// zero coordinate), with gradient and Hessian.
fn serendipity<const N: usize, const D: usize>(
    nodes: &[[f64; D]; N],
    xi: &[f64; D],
) -> Values<N, D> {
    let mut v = [0.0; N];
    let mut g = [[0.0; D]; N];
    let mut h = [[[0.0; D]; D]; N];
    let scale = 0.5f64.powi(D as i32);
    for (I, a) in nodes.iter().enumerate() {
        if a.iter().all(|c| c.abs() > 0.5) {
            // corner: scale Π(1 + a_d ξ_d) (Σ a_d ξ_d − (D − 1))
            let f: [f64; D] = std::array::from_fn(|d| 1.0 + a[d] * xi[d]);
            let s: f64 = (0..D).map(|d| a[d] * xi[d]).sum::<f64>() - (D as f64 - 1.0);
            let prod = |skip: &[usize]| -> f64 {
                (0..D).filter(|d| !skip.contains(d)).map(|d| f[d]).product()
            };
            v[I] = scale * prod(&[]) * s;
            for i in 0..D {
                g[I][i] = scale * a[i] * (prod(&[i]) * s + prod(&[]));
                for j in 0..D {
                    h[I][i][j] = if i == j {
                        scale * 2.0 * a[i] * a[i] * prod(&[i])
                    } else {
                        scale * a[i] * a[j] * (prod(&[i, j]) * s + prod(&[i]) + prod(&[j]))
                    };
                }
            }
        } else {
            // mid-edge: the zero coordinate m carries (1 − ξ_m²); scale·2 Π_{d≠m}(1 + a_d ξ_d)
            let m = (0..D)
                .find(|&d| a[d].abs() < 0.5)
                .expect("one zero coordinate");
            let f: [f64; D] = std::array::from_fn(|d| {
                if d == m {
                    1.0 - xi[d] * xi[d]
                } else {
                    1.0 + a[d] * xi[d]
                }
            });
            let df: [f64; D] = std::array::from_fn(|d| if d == m { -2.0 * xi[d] } else { a[d] });
            let d2f: [f64; D] = std::array::from_fn(|d| if d == m { -2.0 } else { 0.0 });
            let c = 2.0 * scale;
            v[I] = c * f.iter().product::<f64>();
            for i in 0..D {
                g[I][i] = c
                    * (0..D)
                        .map(|d| if d == i { df[d] } else { f[d] })
                        .product::<f64>();
                for j in 0..D {
                    h[I][i][j] = c
                        * (0..D)
                            .map(|d| match (d == i, d == j) {
                                (true, true) => d2f[d],
                                (true, false) | (false, true) => df[d],
                                _ => f[d],
                            })
                            .product::<f64>();
                }
            }
        }
    }
    // mirror the upper triangle: the products above are not evaluated in a symmetric order
    for hI in h.iter_mut() {
        for i in 0..D {
            for j in 0..i {
                hI[i][j] = hI[j][i];
            }
        }
    }
    (v, g, h)
}

const G3: f64 = 0.774_596_669_241_483_4; // √(3/5)
const W3: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
const X3: [f64; 3] = [-G3, 0.0, G3];

static LINE_GAUSS3: [([f64; 1], f64); 3] =
    [([-G3], 5.0 / 9.0), ([0.0], 8.0 / 9.0), ([G3], 5.0 / 9.0)];

static QUAD_GAUSS3: std::sync::LazyLock<Vec<([f64; 2], f64)>> = std::sync::LazyLock::new(|| {
    let mut q = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            q.push(([X3[i], X3[j]], W3[i] * W3[j]));
        }
    }
    q
});

static HEX_GAUSS3: std::sync::LazyLock<Vec<([f64; 3], f64)>> = std::sync::LazyLock::new(|| {
    let mut q = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                q.push(([X3[i], X3[j], X3[k]], W3[i] * W3[j] * W3[k]));
            }
        }
    }
    q
});

static TRI_DEG2: [([f64; 2], f64); 3] = [
    ([1.0 / 6.0, 1.0 / 6.0], 1.0 / 6.0),
    ([1.0 / 6.0, 2.0 / 3.0], 1.0 / 6.0),
    ([2.0 / 3.0, 1.0 / 6.0], 1.0 / 6.0),
];

// basix's degree-4 tetrahedron rule (14 points, positive weights). Degree 2 would do for
// straight-sided tet10, but on curved ones ∇N det(∂X/∂ξ) is cubic: the patch test caught it.
const TA: f64 = 0.100_526_765_225_204_5;
const TB: f64 = 0.698_419_704_324_386_6;
const TC: f64 = 0.314_372_873_493_192_2;
const TD: f64 = 0.056_881_379_520_423_4;
const W1: f64 = 0.003_174_603_174_603_17;
const W2: f64 = 0.014_764_970_790_496_78;
const W3T: f64 = 0.022_139_791_114_265_12;
static TET_DEG4: [([f64; 3], f64); 14] = [
    ([0.0, 0.5, 0.5], W1),
    ([0.5, 0.0, 0.5], W1),
    ([0.5, 0.5, 0.0], W1),
    ([0.5, 0.0, 0.0], W1),
    ([0.0, 0.5, 0.0], W1),
    ([0.0, 0.0, 0.5], W1),
    ([TB, TA, TA], W2),
    ([TA, TA, TA], W2),
    ([TA, TA, TB], W2),
    ([TA, TB, TA], W2),
    ([TD, TC, TC], W3T),
    ([TC, TC, TC], W3T),
    ([TC, TC, TD], W3T),
    ([TC, TD, TC], W3T),
];

/// A quadratic element whose values, gradients and Hessians all come from one evaluation
/// `$eval(nodes, ξ)` (`tensor`, `serendipity`) or `simplex(edges, ξ)`.
macro_rules! quadratic_element {
    ($ty:ty, $n:literal, $d:literal, simplex: $simplex:literal, $eval:expr, $rule:expr, $nodes:expr) => {
        impl RefElement<$n, $d> for $ty {
            const SIMPLEX: bool = $simplex;
            fn shape(xi: &[f64; $d]) -> [f64; $n] {
                $eval(xi).0
            }
            fn grad(xi: &[f64; $d]) -> [[f64; $d]; $n] {
                $eval(xi).1
            }
            fn hessian(xi: &[f64; $d]) -> [[[f64; $d]; $d]; $n] {
                $eval(xi).2
            }
            fn quadrature() -> &'static [([f64; $d], f64)] {
                &$rule
            }
            fn nodes() -> [[f64; $d]; $n] {
                $nodes
            }
        }
    };
}

const LINE_NODES3: [[f64; 1]; 3] = [[-1.0], [1.0], [0.0]];

/// tet10 nodes: corners, then the midpoints of `TET_EDGES`.
fn tet10_nodes() -> [[f64; 3]; 10] {
    let c = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    std::array::from_fn(|i| {
        if i < 4 {
            c[i]
        } else {
            let (a, b) = TET_EDGES[i - 4];
            std::array::from_fn(|d| 0.5 * (c[a][d] + c[b][d]))
        }
    })
}

quadratic_element!(Line3, 3, 1, simplex: false, |xi| tensor(&LINE_NODES3, xi), LINE_GAUSS3, LINE_NODES3);
quadratic_element!(
    Tri6,
    6,
    2,
    simplex: true,
    |xi| simplex(&TRI_EDGES, xi),
    TRI_DEG2,
    [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.5, 0.0], [0.5, 0.5], [0.0, 0.5]]
);
quadratic_element!(
    Quad8,
    8,
    2,
    simplex: false,
    |xi| serendipity(&Self::nodes(), xi),
    QUAD_GAUSS3,
    std::array::from_fn(|i| QUAD_NODES9[i])
);
quadratic_element!(Quad9, 9, 2, simplex: false, |xi| tensor(&QUAD_NODES9, xi), QUAD_GAUSS3, QUAD_NODES9);
quadratic_element!(Tet10, 10, 3, simplex: true, |xi| simplex(&TET_EDGES, xi), TET_DEG4, tet10_nodes());
quadratic_element!(
    Hex20,
    20,
    3,
    simplex: false,
    |xi| serendipity(&Self::nodes(), xi),
    HEX_GAUSS3,
    std::array::from_fn(|i| HEX_NODES27[i])
);
quadratic_element!(Hex27, 27, 3, simplex: false, |xi| tensor(&HEX_NODES27, xi), HEX_GAUSS3, HEX_NODES27);
