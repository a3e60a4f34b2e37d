//! Loads over (pseudo-)time: the load factor and the groups' own amplitudes, and the nodal
//! weights that turn distributed loads into nodal ones.
#![allow(non_snake_case)]

use crate::element::{RefElement, facet_measure};
use crate::mesh::{CellKind, Mesh};

/// Loads over pseudo-time t ∈ [0, T]: the load factor λ(t) and the amplitudes of groups with
/// their own `path`, each piecewise linear between the values given at t = 0, 1, …, T.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadPath {
    /// λ at t = 0, 1, …, T (default `[0, 1]`: t = λ).
    pub lambda: Vec<f64>,
    /// Amplitudes of groups with their own path, at the same times.
    pub own: Vec<Vec<f64>>,
}

impl Default for LoadPath {
    fn default() -> Self {
        LoadPath {
            lambda: vec![0.0, 1.0],
            own: Vec::new(),
        }
    }
}

impl LoadPath {
    /// Amplitude index of values held at full value from the start.
    pub const HELD: usize = 0;
    /// Amplitude index of values scaled by λ.
    pub const RAMPED: usize = 1;

    /// The end of pseudo-time, T.
    pub fn end(&self) -> f64 {
        (self.lambda.len() - 1) as f64
    }

    fn interp(v: &[f64], t: f64) -> f64 {
        let t = t.clamp(0.0, (v.len() - 1) as f64);
        if t.fract() == 0.0 {
            return v[t as usize]; // a vertex: exactly its value
        }
        let i = t.floor() as usize;
        let s = t - i as f64;
        v[i] + s * (v[i + 1] - v[i])
    }

    /// The load factor λ(t).
    pub fn lambda(&self, t: f64) -> f64 {
        Self::interp(&self.lambda, t)
    }

    /// All amplitudes at t: [1, λ(t), own paths…], indexed by `Prescribed::amp`.
    pub fn amplitudes(&self, t: f64) -> Vec<f64> {
        let mut a = vec![1.0, self.lambda(t)];
        a.extend(self.own.iter().map(|v| Self::interp(v, t)));
        a
    }
}

/// ∫ N_I dΩ over one element (facet or cell) in the reference configuration.
pub fn facet_weights(kind: CellKind, nodes: &[usize], mesh: &Mesh) -> Vec<f64> {
    fn integrate<const N: usize, const D: usize, E: RefElement<N, D>>(
        nodes: &[usize],
        mesh: &Mesh,
    ) -> Vec<f64> {
        let X: [[f64; 3]; N] = std::array::from_fn(|i| mesh.coords[nodes[i]]);
        let mut w = vec![0.0; N];
        for (xi, wq) in E::quadrature() {
            let m = facet_measure::<N, D>(&E::grad(xi), &X);
            let n = E::shape(xi);
            for i in 0..N {
                w[i] += n[i] * m * wq;
            }
        }
        w
    }
    crate::with_element!(kind, |N, D, E| integrate::<N, D, E>(nodes, mesh))
}
