//! Degrees of freedom: which fields live on which nodes, their global numbering, the
//! Dirichlet constraints that remove some of them from the system, a cell's local view of
//! them ([`local`]) and the sparsity pattern they couple in ([`pattern`]).

pub mod local;
pub mod pattern;

pub use local::{CellState, Layout, gather, rebase};
pub use pattern::{
    Ordering, Pattern, Structure, build_pattern, build_pattern_of, equation_structure,
};

use crate::mesh::Mesh;

/// Marker for "no dof here".
pub const NONE: u32 = u32::MAX;

/// Fields that can carry unknowns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Field {
    U,
    Theta,
    P,
}

impl Field {
    pub const ALL: [Field; 3] = [Field::U, Field::Theta, Field::P];
    pub fn name(self) -> &'static str {
        match self {
            Field::U => "u",
            Field::Theta => "theta",
            Field::P => "p",
        }
    }
}

/// Global dof numbering, node-major (all unknowns of a node are adjacent).
#[derive(Clone, Debug)]
pub struct DofMap {
    pub dim: usize,
    pub n_nodes: usize,
    pub n_dofs: usize,
    /// `u[node * dim + c]`, empty when mechanics is off.
    pub u: Vec<u32>,
    /// `theta[node]`, empty when conduction is off.
    pub theta: Vec<u32>,
    /// Regularization components per node (1 in 2D, 3 in 3D; 0 when off).
    pub np: usize,
    /// `p[node * np + c]`, `NONE` on nodes outside the medium.
    pub p: Vec<u32>,
    /// Field of each dof.
    pub field: Vec<Field>,
}

impl DofMap {
    /// Number the unknowns: u on every node if `mechanics`, θ on every node if `thermal`, and
    /// `np` regularization components on the nodes flagged in `p_nodes`.
    pub fn new(mesh: &Mesh, mechanics: bool, thermal: bool, np: usize, p_nodes: &[bool]) -> DofMap {
        let (dim, n) = (mesh.dim, mesh.coords.len());
        let mut next = 0u32;
        let mut u = if mechanics {
            vec![NONE; n * dim]
        } else {
            Vec::new()
        };
        let mut theta = if thermal { vec![NONE; n] } else { Vec::new() };
        let mut p = if np > 0 {
            vec![NONE; n * np]
        } else {
            Vec::new()
        };
        let mut field = Vec::new();
        for node in 0..n {
            if mechanics {
                for c in 0..dim {
                    u[node * dim + c] = next;
                    field.push(Field::U);
                    next += 1;
                }
            }
            if thermal {
                theta[node] = next;
                field.push(Field::Theta);
                next += 1;
            }
            if np > 0 && p_nodes[node] {
                for c in 0..np {
                    p[node * np + c] = next;
                    field.push(Field::P);
                    next += 1;
                }
            }
        }
        DofMap {
            dim,
            n_nodes: n,
            n_dofs: next as usize,
            u,
            theta,
            np,
            p,
            field,
        }
    }

    pub fn has(&self, f: Field) -> bool {
        match f {
            Field::U => !self.u.is_empty(),
            Field::Theta => !self.theta.is_empty(),
            Field::P => self.np > 0,
        }
    }

    pub fn count(&self, f: Field) -> usize {
        self.field.iter().filter(|&&g| g == f).count()
    }

    /// The mesh node of every dof.
    pub fn node_of_dof(&self) -> Vec<u32> {
        let mut out = vec![0u32; self.n_dofs];
        let mut buf = Vec::new();
        for n in 0..self.n_nodes {
            self.node_dofs(n, &mut buf);
            for &d in &buf {
                out[d as usize] = n as u32;
            }
        }
        out
    }

    /// All dofs of a node, in numbering order.
    pub fn node_dofs(&self, node: usize, out: &mut Vec<u32>) {
        out.clear();
        if !self.u.is_empty() {
            out.extend_from_slice(&self.u[node * self.dim..(node + 1) * self.dim]);
        }
        if !self.theta.is_empty() {
            out.push(self.theta[node]);
        }
        if self.np > 0 {
            out.extend(
                self.p[node * self.np..(node + 1) * self.np]
                    .iter()
                    .filter(|&&d| d != NONE),
            );
        }
    }
}

/// A prescribed value of one dof: `start + a (value − start)`, with `a` the value of its
/// amplitude (see [`crate::model::LoadPath`]): 1 for values held from the start, the load
/// factor λ for ramped ones, or the group's own path. `start` is the dof's initial state: 0 for
/// displacements, θ0 for temperatures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prescribed {
    pub value: f64,
    pub start: f64,
    /// Index into the amplitudes of [`crate::model::LoadPath::amplitudes`].
    pub amp: usize,
    /// Index of the boundary-condition group that prescribes it (for reactions).
    pub bc: usize,
}

impl Prescribed {
    /// The value at amplitudes `amps` (from `LoadPath::amplitudes`).
    pub fn at(&self, amps: &[f64]) -> f64 {
        self.start + amps[self.amp] * (self.value - self.start)
    }
}

/// Constraints: prescribed dofs and the numbering of the remaining (free) equations.
#[derive(Clone, Debug)]
pub struct Constraints {
    /// Per dof: `Some` if prescribed.
    pub prescribed: Vec<Option<Prescribed>>,
    /// Per dof: equation number, or `NONE` for prescribed dofs.
    pub eq: Vec<u32>,
    pub n_eq: usize,
}

impl Constraints {
    pub fn new(prescribed: Vec<Option<Prescribed>>) -> Constraints {
        let mut eq = vec![NONE; prescribed.len()];
        let mut n = 0u32;
        for (e, p) in eq.iter_mut().zip(&prescribed) {
            if p.is_none() {
                *e = n;
                n += 1;
            }
        }
        Constraints {
            prescribed,
            eq,
            n_eq: n as usize,
        }
    }
}
