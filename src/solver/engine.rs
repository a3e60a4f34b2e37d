//! The linear engines behind one trait. A run's plan says which systems its strategy solves
//! ([`System`]: the equations of a part and the symmetry of its tangent); the engine sets up a
//! solver for each: [`Faer`] on this process (LDLᵀ, LU with static pivots, GMRES with the
//! block-triangular preconditioner), or `Petsc` over the ranks of an MPI run.

use super::linear::{LinearError, LinearKind, LinearSolver};
use super::newton::Part;
use crate::dofs::{Pattern, Structure};

/// One system a strategy solves.
#[derive(Clone, Debug)]
pub struct System {
    pub part: Part,
    /// Its equations (increasing).
    pub eqs: Vec<usize>,
    /// Whether its tangent is symmetric.
    pub symmetric: bool,
    /// Whether its mechanics rows are (not with friction, whose limit moves with the normal
    /// traction).
    pub symmetric_mechanics: bool,
}

/// What solves a run's linear systems.
pub trait Engine {
    /// A solver for `system`, its symbolic analysis done, on the pattern of the whole system.
    fn solver(
        &self,
        system: &System,
        pattern: &Pattern,
        structure: &Structure,
    ) -> Result<LinearSolver, LinearError>;

    /// One solver per system, in order.
    fn solvers(
        &self,
        systems: &[System],
        pattern: &Pattern,
        structure: &Structure,
    ) -> Result<Vec<(Part, LinearSolver)>, LinearError> {
        systems
            .iter()
            .map(|s| Ok((s.part, self.solver(s, pattern, structure)?)))
            .collect()
    }
}

/// faer's sparse solvers on this process. `whole`: the method for a monolithic system (the
/// parts of a one-way split take LDLᵀ, or LU where their tangent is unsymmetric).
pub struct Faer {
    pub whole: LinearKind,
}

impl Engine for Faer {
    fn solver(
        &self,
        system: &System,
        pattern: &Pattern,
        structure: &Structure,
    ) -> Result<LinearSolver, LinearError> {
        match system.part {
            Part::All if self.whole == LinearKind::BlockGmres => {
                LinearSolver::block_gmres(pattern, structure, !system.symmetric_mechanics)
            }
            Part::All => LinearSolver::new(self.whole, pattern, structure),
            _ if system.symmetric => LinearSolver::block_ldlt(pattern, structure, &system.eqs),
            _ => LinearSolver::block_lu(pattern, structure, &system.eqs),
        }
    }
}

/// PETSc's KSP over the ranks, each holding the rows of the nodes it owns.
#[cfg(feature = "petsc")]
pub struct Petsc<'a> {
    pub own: super::petsc::Ownership<'a>,
    pub hints: super::petsc::Hints<'a>,
    pub method: crate::case::PetscMethod,
}

#[cfg(feature = "petsc")]
impl Engine for Petsc<'_> {
    fn solver(
        &self,
        system: &System,
        pattern: &Pattern,
        structure: &Structure,
    ) -> Result<LinearSolver, LinearError> {
        LinearSolver::petsc(
            pattern,
            structure,
            &system.eqs,
            &self.own,
            system.symmetric,
            &self.hints,
            self.method,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two nodes, each with one mechanics and one temperature unknown, all coupled.
    fn two_nodes() -> (Pattern, Structure) {
        let n = 4;
        let pattern = Pattern {
            n,
            col_ptr: (0..=n).map(|j| j * n).collect(),
            row_idx: (0..n * n).map(|k| k % n).collect(),
        };
        let structure = Structure {
            node: vec![0, 0, 1, 1],
            thermal: vec![false, true, false, true],
        };
        (pattern, structure)
    }

    #[test]
    fn faer_sets_up_the_solver_each_system_asks_for() {
        let (p, s) = two_nodes();
        let system = |part, eqs: &[usize], symmetric, symmetric_mechanics| System {
            part,
            eqs: eqs.to_vec(),
            symmetric,
            symmetric_mechanics,
        };
        let one_way = |friction: bool| {
            vec![
                system(Part::Mechanics, &[0, 2], !friction, !friction),
                system(Part::Heat, &[1, 3], true, !friction),
            ]
        };
        let kinds = |engine: &Faer, systems: &[System]| -> Vec<LinearKind> {
            let solvers = engine.solvers(systems, &p, &s).unwrap();
            solvers.iter().map(|(_, l)| l.kind).collect()
        };
        let ldlt = Faer {
            whole: LinearKind::Ldlt,
        };
        // a one-way split: LDLᵀ for its symmetric parts, LU for friction's mechanics
        assert_eq!(kinds(&ldlt, &one_way(false)), [LinearKind::Ldlt; 2]);
        assert_eq!(
            kinds(&ldlt, &one_way(true)),
            [LinearKind::Lu, LinearKind::Ldlt]
        );
        // the whole system: the method asked for
        let all = [system(Part::All, &[0, 1, 2, 3], false, false)];
        for whole in [LinearKind::Lu, LinearKind::BlockGmres, LinearKind::Ldlt] {
            assert_eq!(kinds(&Faer { whole }, &all), [whole]);
        }
    }
}
