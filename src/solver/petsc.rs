//! The linear systems of a run on PETSc (the `petsc` feature): one parallel matrix whose rows
//! are cut into one contiguous range per rank, each rank's range the equations of its nodes
//! (see `mesh::partition`). Each rank adds the entries of its own cells, PETSc sends those of
//! other ranks' rows where they belong, and its KSP solves; the solution is then copied to
//! every rank, so that each holds the whole state and takes the same Newton decisions.
//!
//! PETSc's options (`[solver.petsc] options`, the `PETSC_OPTIONS` environment) choose the
//! solver; without them, tmc's defaults: MUMPS, Cholesky for a symmetric system and LU
//! otherwise.

use super::linear::{Factorization, LinearError};
use crate::case::PetscMethod;
use crate::dofs::{Pattern, Structure};
use crate::parallel::Ranks;
use crate::parallel::ffi::PetscInt;
use crate::parallel::petsc::{
    IndexSet, Krylov, Matrix, NearKernel, PetscError, ToAll, Vector, default_option, unused_options,
};

/// A PETSc system that failed.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// A PETSc call failed, or PETSc did not use options it was given: the run cannot go on.
    #[error("{0}")]
    Failed(String),
    /// PETSc's solver did not converge on this matrix: a smaller load step may.
    #[error("{0}")]
    Diverged(String),
}

impl From<PetscError> for EngineError {
    fn from(e: PetscError) -> EngineError {
        EngineError::Failed(e.to_string())
    }
}

impl From<EngineError> for LinearError {
    fn from(e: EngineError) -> LinearError {
        match e {
            EngineError::Failed(m) => LinearError::Engine(m),
            EngineError::Diverged(m) => LinearError::Diverged(m),
        }
    }
}

impl Factorization for PetscSystem {
    fn factor(&mut self, values: &[f64]) -> Result<(), LinearError> {
        Ok(PetscSystem::factor(self, values)?)
    }

    fn solve(&mut self, b: &mut [f64]) -> Result<usize, LinearError> {
        Ok(PetscSystem::solve(self, b)?)
    }

    /// PETSc's solver and preconditioner, as `ksp_type/pc_type`.
    fn describe(&self) -> Option<String> {
        Some(self.ksp.describe())
    }

    fn engine(&self) -> &'static str {
        "petsc"
    }
}

/// Who owns each node, and the whole rows of this rank's equations (`None`: one rank; the
/// pattern of the system is then whole).
pub struct Ownership<'a> {
    pub ranks: Ranks,
    pub node_rank: Option<&'a [u32]>,
    pub rows: Option<&'a Pattern>,
}

/// What a multigrid needs to know of the model, beyond the matrix.
pub struct Hints<'a> {
    /// The rigid motions of all equations (see `model::rigid`): the near-kernel of the
    /// solids' mechanical rows.
    pub rigid: &'a [Vec<f64>],
    /// Per mesh node: whether a medium cell has it (`Model::nodes_of`). Those rows form
    /// a block of their own, solved directly: where the medium closes, its stiffness across
    /// the gap grows without bound and smoothers and aggregates of a multigrid fail there.
    pub medium: &'a [bool],
}

/// One linear system on PETSc: the equations `eqs` of the system whose entries this rank adds
/// have the pattern `p` (on several ranks, those of its own cells only).
pub struct PetscSystem {
    /// PETSc's row of each of `eqs`.
    row: Vec<PetscInt>,
    /// For each of this rank's rows, its place in `eqs`.
    local: Vec<usize>,
    /// The entries this rank adds, column by column: (PETSc column, end of its entries in
    /// `slots` and `rows`).
    columns: Vec<(PetscInt, usize)>,
    /// Per entry, its place in the pattern's values and its PETSc row.
    slots: Vec<u32>,
    rows: Vec<PetscInt>,
    mat: Matrix,
    ksp: Krylov,
    b: Vector,
    x: Vector,
    to_all: ToAll,
    solves: usize,
    /// The solver is a direct one (PETSc's "preonly"): its iteration is not a Krylov one.
    direct: bool,
    /// Keep the preconditioner across matrices while it works (the multigrid method): the
    /// iterations of the solve after its last build, and of the last solve.
    reuse: Option<Reuse>,
}

/// A preconditioner kept for later matrices: rebuilt when a solve with it takes more than
/// twice the iterations of the first solve after its build (and at least 10 more), or fails.
#[derive(Clone, Copy, Debug, Default)]
struct Reuse {
    fresh: Option<usize>,
    last: usize,
}

impl Reuse {
    fn keep(&self) -> bool {
        self.fresh.is_some_and(|f| self.last <= (2 * f).max(f + 10))
    }
}

// SAFETY: PETSc's objects are plain heap objects that may be used from any one thread at a
// time; a `PetscSystem` is only ever used through `&mut`, and runs (see `driver::run`) keep
// its calls on the thread that started MPI (no idle-thread runner around PETSc solves).
unsafe impl Send for PetscSystem {}

impl PetscSystem {
    /// The system of equations `eqs`; `hints` say what a multigrid needs to know of the
    /// model (which rows go to which block, and the near-kernel of the solids' mechanics).
    pub fn new(
        p: &Pattern,
        s: &Structure,
        eqs: &[usize],
        own: &Ownership,
        symmetric: bool,
        hints: &Hints,
        method: PetscMethod,
    ) -> Result<PetscSystem, EngineError> {
        let RowLayout {
            row,
            local,
            diag,
            off,
            columns,
            slots,
            rows,
        } = RowLayout::new(p, s, eqs, own);
        let mut mat = Matrix::aij(eqs.len(), local.len(), &diag, &off, symmetric)?;
        // the rows of the medium's nodes (every field), the solids' mechanical rows with their
        // rigid motions, the solids' thermal rows
        let (medium, solid): (Vec<usize>, Vec<usize>) = local
            .iter()
            .partition(|&&k| hints.medium[s.node[eqs[k]] as usize]);
        let (mech, heat): (Vec<usize>, Vec<usize>) =
            solid.iter().partition(|&&k| !s.thermal[eqs[k]]);
        // collective decisions: some rank may hold no rows of a split
        let anywhere =
            |rows: &[usize]| own.ranks.max(if rows.is_empty() { 0.0 } else { 1.0 }) > 0.0;
        let near_kernel = if !anywhere(&mech) {
            None
        } else {
            let modes = orthonormal(
                &own.ranks,
                hints
                    .rigid
                    .iter()
                    .map(|m| mech.iter().map(|&k| m[eqs[k]]).collect())
                    .collect(),
            );
            Some(NearKernel::new(mech.len(), &modes)?)
        };
        let present: Vec<(&str, &Vec<usize>)> =
            [("up", &mech), ("theta", &heat), ("medium", &medium)]
                .into_iter()
                .filter(|(_, rows)| anywhere(rows))
                .collect();
        let mut splits = Vec::new();
        if present.len() > 1 {
            for (name, ks) in &present {
                let rows: Vec<PetscInt> = ks.iter().map(|&k| row[k]).collect();
                let is = IndexSet::new(&rows)?;
                if let Some(k) = near_kernel.as_ref().filter(|_| *name == "up") {
                    is.set_near_kernel(k)?;
                }
                splits.push((*name, is));
            }
        } else if let Some(k) = &near_kernel {
            mat.set_near_kernel(k)?;
        }
        let named: Vec<(&str, &IndexSet)> = splits.iter().map(|(n, is)| (*n, is)).collect();
        let (ksp_type, pc_type, package) = match method {
            PetscMethod::Direct if symmetric => ("preonly", "cholesky", Some("mumps")),
            PetscMethod::Direct => ("preonly", "lu", Some("mumps")),
            PetscMethod::Multigrid => {
                let names: Vec<&str> = present.iter().map(|(n, _)| *n).collect();
                multigrid_defaults(&names)?
            }
        };
        // the field split, the matrix and the index set keep their own references to the
        // index sets and the near-kernel: ours go at the end of this function
        let ksp = Krylov::new(&mat, ksp_type, pc_type, package, 1e-10, &named)?;
        let direct = ksp.describe().starts_with("preonly/");
        let b = mat.vector()?;
        let x = mat.vector()?;
        let to_all = ToAll::new(&x)?;
        Ok(PetscSystem {
            row,
            local,
            columns,
            slots,
            rows,
            mat,
            ksp,
            b,
            x,
            to_all,
            solves: 0,
            direct,
            // a kept factorisation under "preonly" would solve with an old matrix
            reuse: (method == PetscMethod::Multigrid && !direct).then(Reuse::default),
        })
    }

    /// The matrix of this rank's entries `values` (of its pattern), summed over the ranks
    /// (collective).
    pub fn factor(&mut self, values: &[f64]) -> Result<(), EngineError> {
        self.mat.zero()?;
        let mut vals = Vec::new();
        let mut start = 0;
        for &(col, end) in &self.columns {
            vals.clear();
            vals.extend(self.slots[start..end].iter().map(|&k| values[k as usize]));
            self.mat.add_column(&self.rows[start..end], col, &vals)?;
            start = end;
        }
        self.mat.assemble()?;
        Ok(())
    }

    /// Solve with the last matrix: `b` (every rank's the same) becomes the solution on every
    /// rank. Returns the Krylov iterations (0 for a direct solve).
    pub fn solve(&mut self, b: &mut [f64]) -> Result<usize, EngineError> {
        let (local, n) = (&self.local, self.local.len());
        self.b.with_local(
            |a| {
                for (v, &k) in a.iter_mut().zip(local) {
                    *v = b[k];
                }
            },
            n,
        );
        let keep = self.reuse.is_some_and(|r| r.keep());
        self.ksp.reuse_preconditioner(keep)?;
        let mut report = self.ksp.solve(&self.b, &mut self.x)?;
        let (mut built, mut wasted) = (!keep, 0);
        if keep && report.reason < 0 {
            // the kept preconditioner no longer serves: build it for this matrix
            wasted = report.iterations;
            self.ksp.reuse_preconditioner(false)?;
            report = self.ksp.solve(&self.b, &mut self.x)?;
            built = true;
        }
        if let Some(r) = &mut self.reuse {
            if built {
                r.fresh = Some(report.iterations);
            }
            r.last = report.iterations;
        }
        if report.reason < 0 {
            return Err(EngineError::Diverged(format!(
                "PETSc's {} did not converge ({}, KSPConvergedReason {}) after {} iterations",
                self.ksp.describe(),
                crate::parallel::petsc::reason_name(report.reason),
                report.reason,
                report.iterations
            )));
        }
        let row = &self.row;
        self.to_all.gather(&self.x, row.len(), |all| {
            for (v, &r) in b.iter_mut().zip(row) {
                *v = all[r as usize];
            }
        })?;
        self.solves += 1;
        if self.solves == 1 {
            let left = unused_options();
            if !left.is_empty() {
                return Err(EngineError::Failed(format!(
                    "PETSc did not use the option(s) {} with its {} solver: misspelt, or for \
                     another solver or preconditioner",
                    left.join(", "),
                    self.ksp.describe()
                )));
            }
        }
        Ok(if self.direct {
            0
        } else {
            wasted + report.iterations
        })
    }
}

/// Where a system's equations go on PETSc: rows in rank order (each rank's in equation
/// order), this rank's rows with their entries in and out of its diagonal block (for the
/// matrix's preallocation), and the entries this rank adds, column by column.
struct RowLayout {
    row: Vec<PetscInt>,
    local: Vec<usize>,
    diag: Vec<PetscInt>,
    off: Vec<PetscInt>,
    columns: Vec<(PetscInt, usize)>,
    slots: Vec<u32>,
    rows: Vec<PetscInt>,
}

impl RowLayout {
    fn new(p: &Pattern, s: &Structure, eqs: &[usize], own: &Ownership) -> RowLayout {
        let me = own.ranks.rank as u32;
        let mut place = vec![usize::MAX; p.n];
        for (k, &e) in eqs.iter().enumerate() {
            place[e] = k;
        }
        let owner = |e: usize| own.node_rank.map_or(0, |r| r[s.node[e] as usize]);
        // rows in rank order, each rank's in equation order
        let mut order: Vec<usize> = (0..eqs.len()).collect();
        order.sort_by_key(|&k| (owner(eqs[k]), k));
        let mut row = vec![0 as PetscInt; eqs.len()];
        for (r, &k) in order.iter().enumerate() {
            row[k] = r as PetscInt;
        }
        let local: Vec<usize> = order
            .iter()
            .copied()
            .filter(|&k| owner(eqs[k]) == me)
            .collect();
        let first = local.first().map_or(0, |&k| row[k]);
        let mine = |r: PetscInt| r >= first && r < first + local.len() as PetscInt;
        // the pattern is structurally symmetric: row e's columns are column e's rows; on
        // several ranks `p` has this rank's cells' entries only, `own.rows` the whole rows
        let whole = own.rows.unwrap_or(p);
        let (mut diag, mut off) = (Vec::new(), Vec::new());
        for &k in &local {
            let (d, o) = within(whole, &place, eqs[k]).fold((0, 0), |(d, o), (_, i)| {
                if mine(row[i]) { (d + 1, o) } else { (d, o + 1) }
            });
            diag.push(d);
            off.push(o);
        }
        // sized exactly: these two span every entry this rank adds, for the whole run
        let entries = eqs.iter().map(|&e| within(p, &place, e).count()).sum();
        let (mut columns, mut slots, mut rows) = (
            Vec::new(),
            Vec::with_capacity(entries),
            Vec::with_capacity(entries),
        );
        for (k, &e) in eqs.iter().enumerate() {
            let start = slots.len();
            for (j, i) in within(p, &place, e) {
                slots.push(j as u32);
                rows.push(row[i]);
            }
            // a column without entries here (another rank's cells') is not added
            if slots.len() > start {
                columns.push((row[k], slots.len()));
            }
        }
        RowLayout {
            row,
            local,
            diag,
            off,
            columns,
            slots,
            rows,
        }
    }
}

/// The entries of column `e` of `q` in the rows of the system's equations: (entry, the row's
/// place among the equations), `place` giving that of each equation (`usize::MAX`: not one).
fn within<'a>(
    q: &'a Pattern,
    place: &'a [usize],
    e: usize,
) -> impl Iterator<Item = (usize, usize)> + 'a {
    (q.col_ptr[e]..q.col_ptr[e + 1]).filter_map(move |j| {
        let i = place[q.row_idx[j]];
        (i != usize::MAX).then_some((j, i))
    })
}

/// `vectors` (this rank's entries of each) made orthonormal over all ranks by modified
/// Gram–Schmidt (collective); vectors that vanish in the span of the earlier ones are dropped.
fn orthonormal(ranks: &Ranks, vectors: Vec<Vec<f64>>) -> Vec<Vec<f64>> {
    let dot = |a: &[f64], b: &[f64]| ranks.sum(a.iter().zip(b).map(|(x, y)| x * y).sum());
    let mut out: Vec<Vec<f64>> = Vec::new();
    for mut v in vectors {
        let before = dot(&v, &v).sqrt();
        for q in &out {
            let c = dot(&v, q);
            v.iter_mut().zip(q).for_each(|(x, y)| *x -= c * y);
        }
        let norm = dot(&v, &v).sqrt();
        if norm > 1e-10 * before && norm > 0.0 {
            v.iter_mut().for_each(|x| *x /= norm);
            out.push(v);
        }
    }
    out
}

/// tmc's multigrid for a system whose rows fall in the blocks `blocks` names ("up": the
/// solids' mechanics, "theta": the solids' temperatures, "medium": every row of the medium's
/// nodes). Several: GMRES around a multiplicative field split, one V-cycle of smoothed
/// aggregation on the solids' mechanics (GAMG, the rigid motions as near-kernel, weak
/// couplings under 1 % dropped so that aggregates do not straddle bodies), one BoomerAMG
/// V-cycle on their temperatures, and a direct solve (MUMPS) of the medium's rows. One: GMRES
/// with that GAMG for the solids' mechanics, CG with BoomerAMG for their heat, MUMPS for a
/// system of the medium alone. Options the user gives win. Returns the (ksp, pc, factor
/// package) types.
fn multigrid_defaults(
    blocks: &[&str],
) -> Result<(&'static str, &'static str, Option<&'static str>), EngineError> {
    default_option("ksp_gmres_restart", "100")?;
    let gamg = |prefix: &str| -> Result<(), PetscError> {
        default_option(&format!("{prefix}pc_gamg_threshold"), "0.01")?;
        default_option(&format!("{prefix}pc_gamg_reuse_interpolation"), "true")
    };
    Ok(if blocks.len() > 1 {
        for name in blocks {
            default_option(&format!("fieldsplit_{name}_ksp_type"), "preonly")?;
            let pc = format!("fieldsplit_{name}_pc_type");
            match *name {
                "up" => {
                    default_option(&pc, "gamg")?;
                    gamg("fieldsplit_up_")?;
                }
                "theta" => default_option(&pc, "hypre")?,
                _ => {
                    default_option(&pc, "lu")?;
                    default_option(
                        &format!("fieldsplit_{name}_pc_factor_mat_solver_type"),
                        "mumps",
                    )?;
                }
            }
        }
        ("gmres", "fieldsplit", None)
    } else {
        match blocks.first() {
            Some(&"up") => {
                gamg("")?;
                ("gmres", "gamg", None)
            }
            Some(&"theta") => ("cg", "hypre", None),
            _ => ("preonly", "lu", Some("mumps")),
        }
    })
}
