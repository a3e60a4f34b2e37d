//! Loads over (pseudo-)time: the load factor and the groups' own amplitudes, and the nodal
//! weights that turn distributed loads into nodal ones.
#![allow(non_snake_case)]

use crate::element::{RefElement, facet_measure};
use crate::mesh::{CellKind, Mesh};

/// Loads over time t ∈ [0, T]: the load factor λ(t) and the amplitudes of groups with their
/// own `path`, each piecewise linear between its values at the vertices `times`. Pseudo-time
/// (no `[time]`) has vertices t = 0, 1, …, T; physical time those of `[time] lambda`.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadPath {
    /// Vertex times, increasing from 0.
    pub times: Vec<f64>,
    /// λ at the vertices (default `[0, 1]` at t = 0, 1: t = λ).
    pub lambda: Vec<f64>,
    /// Amplitudes of groups with their own path, at the same vertices.
    pub own: Vec<Vec<f64>>,
}

impl Default for LoadPath {
    fn default() -> Self {
        LoadPath::pseudo(vec![0.0, 1.0])
    }
}

impl LoadPath {
    /// Amplitude index of values held at full value from the start.
    pub const HELD: usize = 0;
    /// Amplitude index of values scaled by λ.
    pub const RAMPED: usize = 1;

    /// λ given at pseudo-times 0, 1, …, T.
    pub fn pseudo(lambda: Vec<f64>) -> LoadPath {
        LoadPath {
            times: (0..lambda.len()).map(|i| i as f64).collect(),
            lambda,
            own: Vec::new(),
        }
    }

    /// The end of time, T.
    pub fn end(&self) -> f64 {
        *self.times.last().expect("a path has vertices")
    }

    fn interp(&self, v: &[f64], t: f64) -> f64 {
        let t = t.clamp(0.0, self.end());
        // the first vertex at or after t
        let i = self.times.partition_point(|&s| s < t);
        if self.times[i] == t {
            return v[i]; // a vertex: exactly its value
        }
        let (t0, t1) = (self.times[i - 1], self.times[i]);
        let s = (t - t0) / (t1 - t0);
        v[i - 1] + s * (v[i] - v[i - 1])
    }

    /// The load factor λ(t).
    pub fn lambda(&self, t: f64) -> f64 {
        self.interp(&self.lambda, t)
    }

    /// Whether λ equals the pseudo-time along the whole path (the default `[0, 1]`, or
    /// `[0, 1, 2, …]`): then λ alone says where a run stands.
    pub fn lambda_is_time(&self) -> bool {
        self.times == self.lambda
    }

    /// The step from the accepted time `from` to `to` (`from == to`: the state at `from`
    /// itself, over no time).
    pub fn step(&self, from: f64, to: f64) -> StepContext {
        StepContext {
            t: to,
            dt: to - from,
            lambda: self.lambda(to),
        }
    }

    /// All amplitudes at t: [1, λ(t), own paths…], indexed by `Prescribed::amp`.
    pub fn amplitudes(&self, t: f64) -> Vec<f64> {
        let mut a = vec![1.0, self.lambda(t)];
        a.extend(self.own.iter().map(|v| self.interp(v, t)));
        a
    }
}

/// Where a step goes, as every term of the assembly sees it: the time `t` it ends at, its
/// length `dt` from the last accepted state, and the load factor λ(t). Made once per step by
/// whoever steps ([`LoadPath::step`]) and passed down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepContext {
    pub t: f64,
    pub dt: f64,
    pub lambda: f64,
}

impl StepContext {
    /// 1/Δt, or 0 over a step of no length (the accepted state itself: nothing stored or
    /// dissipated over it).
    pub fn inv_dt(&self) -> f64 {
        if self.dt > 0.0 { 1.0 / self.dt } else { 0.0 }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_interpolate_between_their_vertices() {
        let p = LoadPath::pseudo(vec![0.0, 1.0, 0.2]);
        assert_eq!(p.end(), 2.0);
        assert_eq!(p.lambda(1.0), 1.0);
        assert!((p.lambda(1.5) - 0.6).abs() < 1e-15);
        assert_eq!(p.lambda(7.0), 0.2);
        let t = LoadPath {
            times: vec![0.0, 0.1, 2.5],
            lambda: vec![0.0, 1.0, 1.0],
            own: vec![vec![0.0, 0.5, -1.0]],
        };
        assert!((t.lambda(0.05) - 0.5).abs() < 1e-15);
        assert_eq!(t.lambda(1.0), 1.0);
        let a = t.amplitudes(1.3);
        assert_eq!(a[..2], [1.0, 1.0]);
        assert!((a[2] - (0.5 - 1.5 * 0.5)).abs() < 1e-15);
    }
}
