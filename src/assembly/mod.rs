//! Assembly: the global residual and tangent from the cells' kernels. [`schedule`] decides
//! which cells may run at once, [`scatter`] where each cell's entries go, [`cells`] runs the
//! kernels over a block's cells.
//!
//! Parallel over cells without locks and without per-thread copies of the arrays: the cells of
//! all blocks together are cut in two by recursive coordinate bisection (one level per
//! doubling of the threads), and the two halves run at once. Of each half, only the cells that share a node
//! with the other half can add into the same entries; the left half runs its shared cells
//! first, the right half its own last, after the left's are done. So no two cells that share
//! a node ever run at once, every entry is summed in the same order whatever the scheduling,
//! and the arrays are written once, in place (copies per thread cost a zeroing and a
//! summing pass over the tangent's tens of MB per assembly, more than the cells' scatter).
//!
//! The system is reduced to the free equations; a prescribed dof's column is moved to the
//! right-hand side with its increment ("lifting"), so symmetric tangents stay symmetric.
#![allow(non_snake_case)]

mod cells;
pub mod history;
mod reference;
mod scatter;
mod schedule;
mod terms;

pub use cells::{Cells, SlabView, check_inversion};
pub use reference::References;
pub use terms::{Integrand, integrand};

use crate::dofs::{Pattern, build_pattern, build_pattern_of};
use crate::kernel::{Active, KernelError};
use crate::mesh::centroid;
use crate::model::{FacetBlock, FrictionBlock, Model, StepContext, Term};
use crate::parallel::Ranks;
use crate::parallel::{Distribution, Partition};
use cells::Arrays;
use history::{PointHistory, Slab};
use rayon::prelude::*;
use scatter::{FIRST, Shared, Slots};
use schedule::Schedule;
use std::sync::Arc;
use terms::points_per_cell;

/// A block is not split into parts of fewer cells than this (a part's scheduling costs more
/// than its cells save).
pub(crate) const MIN_PART_CELLS: usize = 256;

/// Failure found while assembling.
#[derive(Clone, Debug, PartialEq)]
pub enum AssemblyError {
    /// J ≤ 0 at a quadrature point of cell `cell` (counted in its region's block, centroid `at`
    /// in the undeformed mesh) of `region`.
    Inverted {
        region: String,
        J: f64,
        cell: usize,
        at: [f64; 3],
    },
    /// A cell of the undeformed mesh is inverted or degenerate.
    BadMesh {
        region: String,
        cell: usize,
        at: [f64; 3],
    },
    /// A regularization rotation measure is unbounded (a medium cell rotated by 90°).
    Singular { region: String },
    /// A boundary facet of `group` has collapsed to zero area (or was degenerate).
    BadFacet { group: String, facet: usize },
    /// θ ≤ 0 at a point of facet `facet` of `group`, which radiates (an absolute temperature
    /// is positive).
    ColdRadiator {
        group: String,
        facet: usize,
        theta: f64,
    },
    /// NaN or infinity in the residual or the tangent.
    NotFinite,
}

impl std::fmt::Display for AssemblyError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AssemblyError::Inverted {
                region,
                J,
                cell,
                at,
            } => {
                write!(
                    f,
                    "J = {J:.3e} ≤ 0 in cell {cell} of region \"{region}\" (centre {})",
                    point(at)
                )
            }
            AssemblyError::BadMesh { region, cell, at } => {
                write!(
                    f,
                    "cell {cell} of region \"{region}\" (centre {}) is inverted or degenerate in the undeformed mesh",
                    point(at)
                )
            }
            AssemblyError::Singular { region } => write!(
                f,
                "a cell of region \"{region}\" is rotated by 90° (regularization unbounded)"
            ),
            AssemblyError::BadFacet { group, facet } => write!(
                f,
                "facet {facet} of boundary group \"{group}\" has no area (degenerate or collapsed)"
            ),
            AssemblyError::ColdRadiator {
                group,
                facet,
                theta,
            } => write!(
                f,
                "θ = {theta:.4e} ≤ 0 on facet {facet} of boundary group \"{group}\", which \
                 radiates: radiation needs absolute temperatures (θ > 0, e.g. in kelvin, for \
                 every region's theta0, every held θ and theta_inf)"
            ),
            AssemblyError::NotFinite => write!(f, "the residual is not finite"),
        }
    }
}

/// A point as `(x, y, z)` with four significant digits.
fn point(p: &[f64; 3]) -> String {
    format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2])
}

/// Separates the fields of an error sent to the other ranks.
const SEP: char = '\u{1f}';

impl AssemblyError {
    /// The error as text, for the other ranks ([`AssemblyError::decode`] reads it back).
    fn encode(&self) -> String {
        let f = |v: &[String]| v.join(&SEP.to_string());
        match self {
            AssemblyError::Inverted {
                region,
                J,
                cell,
                at,
            } => f(&[
                "inverted".into(),
                region.clone(),
                J.to_string(),
                cell.to_string(),
                at[0].to_string(),
                at[1].to_string(),
                at[2].to_string(),
            ]),
            AssemblyError::BadMesh { region, cell, at } => f(&[
                "bad_mesh".into(),
                region.clone(),
                cell.to_string(),
                at[0].to_string(),
                at[1].to_string(),
                at[2].to_string(),
            ]),
            AssemblyError::Singular { region } => f(&["singular".into(), region.clone()]),
            AssemblyError::BadFacet { group, facet } => {
                f(&["bad_facet".into(), group.clone(), facet.to_string()])
            }
            AssemblyError::ColdRadiator {
                group,
                facet,
                theta,
            } => f(&[
                "cold_radiator".into(),
                group.clone(),
                facet.to_string(),
                theta.to_string(),
            ]),
            AssemblyError::NotFinite => "not_finite".into(),
        }
    }

    /// The error [`AssemblyError::encode`] wrote (not finite if the text is not one).
    fn decode(text: &str) -> AssemblyError {
        let v: Vec<&str> = text.split(SEP).collect();
        let num = |i: usize| {
            v.get(i)
                .and_then(|s| s.parse::<f64>().ok())
                .unwrap_or(f64::NAN)
        };
        let int = |i: usize| v.get(i).and_then(|s| s.parse::<usize>().ok()).unwrap_or(0);
        let name = || v.get(1).map_or(String::new(), |s| s.to_string());
        match v[0] {
            "inverted" => AssemblyError::Inverted {
                region: name(),
                J: num(2),
                cell: int(3),
                at: [num(4), num(5), num(6)],
            },
            "bad_mesh" => AssemblyError::BadMesh {
                region: name(),
                cell: int(2),
                at: [num(3), num(4), num(5)],
            },
            "singular" => AssemblyError::Singular { region: name() },
            "bad_facet" => AssemblyError::BadFacet {
                group: name(),
                facet: int(2),
            },
            "cold_radiator" => AssemblyError::ColdRadiator {
                group: name(),
                facet: int(2),
                theta: num(3),
            },
            _ => AssemblyError::NotFinite,
        }
    }

    /// The state is outside the admissible set (a shorter update may be fine), as opposed to a
    /// broken mesh.
    pub fn is_inadmissible(&self) -> bool {
        !matches!(self, AssemblyError::BadMesh { .. })
    }
}

/// Per-call results besides the arrays.
#[derive(Clone, Copy, Debug)]
pub struct AssemblyStats {
    pub min_J_solid: f64,
    pub min_J_medium: f64,
    pub energy: f64,
}

impl AssemblyStats {
    /// Nothing assembled yet.
    pub const EMPTY: AssemblyStats = AssemblyStats {
        min_J_solid: f64::INFINITY,
        min_J_medium: f64::INFINITY,
        energy: 0.0,
    };
}

/// Assembler state reused across calls: pattern, value and vector storage.
pub struct Assembler {
    /// Shared with the solvers' analysis that ran beside the assembler's set-up
    /// ([`Assembler::on`]), not copied.
    pub pattern: Arc<Pattern>,
    /// The terms it runs ([`Model::terms`]), and the history slab of each that has one.
    terms: Vec<Term>,
    slab_of: Vec<Option<usize>>,
    /// Per term, where its cells' tangent entries go (built once per mesh, so the scatter is
    /// a load and an add per entry, not a search).
    slots: Vec<Slots>,
    /// The order the cells run in, by global number (a term's cells follow those of the
    /// terms before it, from `first_cell[term]`).
    schedule: Schedule,
    first_cell: Vec<u32>,
    /// Entries of `values` zeroed before each tangent assembly: those whose first writer
    /// adds (see `Slots::flag_first`). Entries no cell writes stay at their initial zero.
    zero_first: Vec<u32>,
    /// Tangent values (CSC, free equations).
    pub values: Vec<f64>,
    /// Internal-minus-external force on every dof (reactions on prescribed dofs).
    pub r_full: Vec<f64>,
    /// Lifted right-hand side contribution Σ K_fd Δx_d on the free equations.
    pub lift: Vec<f64>,
    /// Ask for the cache lines each cell's tangent goes to before its kernel runs (on by
    /// default; off only to measure what it saves).
    pub prefetch: bool,
    /// History per quadrature point, one slab per term that keeps one, in term order.
    pub history: PointHistory,
    /// This rank and the ranks of the cells (`None`: one rank, every cell): a rank runs its
    /// own cells, then the ranks sum their residuals and agree on errors and statistics, so
    /// that every rank holds the whole residual; the tangent keeps this rank's cells' part.
    pub ranks: Ranks,
    distribution: Option<Distribution>,
    /// The reference configurations of the friction blocks whose medium is reconnected.
    pub reference: References,
}

/// Length of the pieces the whole-array passes below are cut into, one task each.
const PASS_CHUNK: usize = 1 << 15;

/// Whether every entry of `v` is finite, in parallel.
fn all_finite(v: &[f64]) -> bool {
    v.par_chunks(PASS_CHUNK)
        .all(|c| c.iter().fold(true, |ok, x| ok & x.is_finite()))
}

impl Assembler {
    pub fn new(model: &Model) -> Assembler {
        Self::with_ranks(model, Ranks::SERIAL, None, None)
    }

    /// [`Assembler::new`] on `pattern`, the model's whole pattern built beforehand
    /// ([`build_pattern`]), so that the solvers' analysis of it can run beside this.
    pub fn on(model: &Model, pattern: Arc<Pattern>) -> Assembler {
        Self::with_ranks(model, Ranks::SERIAL, None, Some(pattern))
    }

    /// The assembler of one rank of a distributed run: its cells are those the distribution
    /// gives it.
    pub fn distributed(model: &Model, distribution: Distribution) -> Assembler {
        Self::with_ranks(model, distribution.ranks, Some(distribution), None)
    }

    fn with_ranks(
        model: &Model,
        ranks: Ranks,
        distribution: Option<Distribution>,
        built: Option<Arc<Pattern>>,
    ) -> Assembler {
        let terms = model.terms();
        let partition = distribution.as_ref().map(|d| &d.partition);
        let mine = |bi: usize, c: usize| {
            partition.is_none_or(|p| term_rank(model, p, terms[bi], c) == ranks.rank)
        };
        // on several ranks, the entries of this rank's cells only
        let pattern = match (partition, built) {
            (None, Some(pattern)) => pattern,
            (None, None) => Arc::new(build_pattern(&model.mesh, &model.dofs, &model.cons)),
            (Some(_), _) => {
                let (nn, cells) = (model.mesh.coords.len(), cells_of(model, &terms, mine));
                Arc::new(build_pattern_of(
                    nn,
                    cells,
                    |_| true,
                    &model.dofs,
                    &model.cons,
                ))
            }
        };
        assert!(
            pattern.nnz() < FIRST as usize,
            "more than 2³¹ tangent entries"
        );
        let mut slots: Vec<Slots> = (terms.iter().enumerate())
            .map(|(bi, t)| {
                let (blk, lay) = t.block(model);
                Slots::new(model, blk, lay, &pattern, |c| mine(bi, c))
            })
            .collect();
        // one level of halves per doubling of the threads
        let depth = rayon::current_num_threads()
            .next_power_of_two()
            .trailing_zeros() as usize;
        let mesh = &model.mesh;
        let mut first_cell = vec![0u32];
        for t in &terms {
            let n = t.block(model).0.n_cells() as u32;
            first_cell.push(first_cell.last().unwrap() + n);
        }
        let nodes = |g: u32| -> &[usize] {
            let bi = first_cell.partition_point(|&f| f <= g) - 1;
            terms[bi].block(model).0.cell((g - first_cell[bi]) as usize)
        };
        let cells = (terms.iter().enumerate())
            .flat_map(|(bi, t)| {
                let first = first_cell[bi];
                (0..t.block(model).0.n_cells())
                    .filter(move |&c| mine(bi, c))
                    .map(move |c| first + c as u32)
            })
            .collect();
        let (mut mark, mut stamp) = (vec![0u32; mesh.coords.len()], 0);
        let schedule = Schedule::build(&nodes, &mesh.coords, cells, depth, &mut mark, &mut stamp);
        let mut order = Vec::new();
        schedule.order(&mut order);
        let order: Vec<(usize, usize)> = order
            .into_iter()
            .map(|g| {
                let bi = first_cell.partition_point(|&f| f <= g) - 1;
                (bi, (g - first_cell[bi]) as usize)
            })
            .collect();
        let mut zero_first = Vec::new();
        Slots::flag_first(&mut slots, &order, pattern.nnz(), &mut zero_first);
        let (history, slab_of) = initial_history(model, &terms);
        Assembler {
            terms,
            slab_of,
            history,
            zero_first,
            values: vec![0.0; pattern.nnz()],
            r_full: vec![0.0; model.dofs.n_dofs],
            lift: vec![0.0; pattern.n],
            pattern,
            slots,
            schedule,
            first_cell,
            prefetch: true,
            ranks,
            distribution,
            reference: References::new(model),
        }
    }

    /// Whether cell `c` of mesh cell block `block` is assembled here.
    pub fn owns_cell(&self, block: usize, c: usize) -> bool {
        (self.distribution.as_ref()).is_none_or(|d| d.owns_cell(block, c))
    }

    /// On several ranks, the whole rows of the equations of this rank's nodes (`None` on one
    /// rank: the pattern's): what every rank's cells add to them, for a parallel matrix's
    /// preallocation. Built from all cells, kept only for this rank's nodes.
    pub fn rows_owned(&self, model: &Model) -> Option<Pattern> {
        let d = self.distribution.as_ref()?;
        let (nn, cells) = (
            model.mesh.coords.len(),
            cells_of(model, &self.terms, |_, _| true),
        );
        let owned = |a: usize| d.owns_node(a);
        Some(build_pattern_of(nn, cells, owned, &model.dofs, &model.cons))
    }

    /// Each term that keeps a history per point, with its slab, in term order.
    pub fn slabs(&self) -> impl Iterator<Item = (Term, &Slab)> + '_ {
        (self.terms.iter().zip(&self.slab_of))
            .filter_map(|(t, s)| s.map(|s| (*t, &self.history.slabs[s])))
    }

    /// The distribution of a distributed run.
    pub fn distribution(&self) -> Option<&Distribution> {
        self.distribution.as_ref()
    }

    /// A step was accepted at the state last assembled: its history becomes the one the next
    /// step starts from.
    pub fn commit(&mut self) {
        self.history.commit();
    }

    /// Before the reconnected layers are joined again at the accepted state `x`: every
    /// reconnected cell takes its slide into its reference ([`References::absorb`]); a medium
    /// made again keeps its cells' references as they are.
    pub fn absorb_slide(&mut self, model: &Model, x: &[f64]) {
        self.absorb_where(model, x, f64::INFINITY, |fb| fb.reconnect);
    }

    /// At an accepted state `x`, before the next step: the closed layers (J below
    /// [`crate::model::remake::CLOSED`]) of a medium made again as the bodies move take their
    /// slide into their references, their slip shifted to keep each point's elastic shear
    /// ([`References::absorb`]). Between remakes a closed layer would otherwise be sheared by
    /// the whole slide since the last: its friction stress, P = F (N⊗τ + τ⊗N), then pushes
    /// along the layer by the shear times τ and the layer's ends push the bodies (the pad in
    /// a box at μ = 0.3 met 0.3133 on average, up to 0.3686), and the rotation penalty reads
    /// the shear as a rotation. A 3D medium made again without friction lets its open cells
    /// beside a body go of their shear instead ([`References::release_beside`]).
    pub fn absorb_closed_layers(&mut self, model: &Model, x: &[f64]) {
        let closed = crate::model::remake::CLOSED;
        self.absorb_where(model, x, closed, |fb| absorbing(model, fb));
        if releases_beside(model) {
            self.reference.release_beside(model, x, closed);
        }
    }

    /// The friction blocks `which` picks take the slide at `x` into the references of their
    /// cells whose J is below `closed` ([`References::absorb`]).
    fn absorb_where(
        &mut self,
        model: &Model,
        x: &[f64],
        closed: f64,
        which: impl Fn(&FrictionBlock) -> bool,
    ) {
        for (t, slab) in self.terms.iter().zip(&self.slab_of) {
            if let (Term::Friction(f), Some(i)) = (t, slab) {
                let fb = &model.friction_blocks[*f];
                if which(fb) {
                    let slab = &mut self.history.slabs[*i];
                    self.reference.absorb(model, fb, slab, x, closed);
                }
            }
        }
    }

    /// Whether a friction block's closed layers take their slide into their references
    /// ([`Assembler::absorb_closed_layers`]), so that the references are part of the state.
    pub fn absorbs(&self, model: &Model) -> bool {
        model.friction_blocks.iter().any(|fb| absorbing(model, fb)) || releases_beside(model)
    }

    /// After the reconnected layers were joined again (on this assembler's model) at the
    /// accepted state `x`: their cells' references start from it, and so does the inertia's
    /// displacement per point.
    pub fn rejoined(&mut self, model: &Model, x: &[f64]) {
        self.reference.reset(model, x);
        for (t, slab) in self.terms.iter().zip(&self.slab_of) {
            if let Some(i) = slab {
                let slab = &mut self.history.slabs[*i];
                integrand(model, *t).rejoined(model, &self.reference, x, slab);
            }
        }
    }

    /// Continue a run: the committed history of its last accepted step, per slab.
    pub fn resume(&mut self, committed: &[Vec<f64>]) {
        for (s, c) in self.history.slabs.iter_mut().zip(committed) {
            s.committed.copy_from_slice(c);
            s.trial.copy_from_slice(c);
        }
    }

    /// The committed history of every block with one, whole: on several ranks each cell's
    /// values from the rank that assembles it (every rank takes part). A checkpoint of this
    /// does not depend on how the cells were shared out, so a run can go on on other ranks.
    pub fn whole_history(&self, model: &Model) -> Vec<Vec<f64>> {
        let blocks = (self.terms.iter().zip(&self.slab_of))
            .filter(|(_, s)| s.is_some())
            .map(|(t, _)| t.mesh_block(model));
        (self.history.slabs.iter().zip(blocks))
            .map(|(slab, block)| {
                let mut whole = slab.committed.clone();
                if !self.ranks.is_serial() {
                    for (c, cell) in whole.chunks_mut(slab.width).enumerate() {
                        if !self.owns_cell(block, c) {
                            cell.fill(0.0);
                        }
                    }
                    self.ranks.sum_into(&mut whole);
                }
                whole
            })
            .collect()
    }

    /// A step was rejected: whatever its attempts wrote into the history is discarded.
    pub fn restore(&mut self) {
        self.history.restore();
    }

    /// Assemble at the state `x` (all dofs) at the end of the step `step`. With `tangent`,
    /// fills `values`; with `dx_prescribed`, also the lifting of those prescribed increments.
    pub fn assemble(
        &mut self,
        model: &Model,
        x: &[f64],
        step: &StepContext,
        tangent: bool,
        dx_prescribed: Option<&[f64]>,
    ) -> Result<AssemblyStats, AssemblyError> {
        self.assemble_part(model, x, step, tangent, dx_prescribed, Active::ALL)
    }

    /// As [`Assembler::assemble`], filling only the equations `act` names (the others' rows
    /// and residuals are left at zero).
    pub fn assemble_part(
        &mut self,
        model: &Model,
        x: &[f64],
        step: &StepContext,
        tangent: bool,
        dx_prescribed: Option<&[f64]>,
        act: Active,
    ) -> Result<AssemblyStats, AssemblyError> {
        if tangent {
            // an update that inverted a cell costs this pass, not a whole assembly
            check_inversion(model, &self.reference, x)?;
        }
        self.r_full.fill(0.0);
        if tangent {
            for &i in &self.zero_first {
                self.values[i as usize] = 0.0;
            }
        }
        self.lift.fill(0.0);
        let first_cell = &self.first_cell;
        let prefetch = tangent && self.prefetch;
        let history: Vec<SlabView> = self
            .history
            .slabs
            .iter_mut()
            .map(|s| SlabView {
                width: s.width,
                committed: &s.committed,
                trial: Shared(s.trial.as_mut_ptr()),
            })
            .collect();
        let history = &history;
        let (slots, terms, slab_of) = (&self.slots, &self.terms, &self.slab_of);
        let reference = &self.reference;
        let arrays = Arrays {
            values: Shared(self.values.as_mut_ptr()),
            r_full: Shared(self.r_full.as_mut_ptr()),
            lift: Shared(self.lift.as_mut_ptr()),
        };
        // a part's cells, sorted: runs of one model block each
        let run = |cells: &[u32]| -> Result<AssemblyStats, AssemblyError> {
            let mut stats = AssemblyStats::EMPTY;
            let mut rest = cells;
            while let Some(&g) = rest.first() {
                let bi = first_cell.partition_point(|&f| f <= g) - 1;
                let len = rest.partition_point(|&h| h < first_cell[bi + 1]);
                let (these, next) = rest.split_at(len);
                rest = next;
                let (blk, lay) = terms[bi].block(model);
                let job = Cells {
                    model,
                    blk,
                    lay,
                    first: first_cell[bi],
                    slots: &slots[bi],
                    x,
                    tangent,
                    dx_prescribed,
                    act,
                    arrays,
                    prefetch,
                    reference: reference.of(terms[bi].mesh_block(model)),
                };
                let slab = slab_of[bi].map(|i| &history[i]);
                let part = integrand(model, terms[bi]).add(job, slab, these, step)?;
                stats = combine(stats, part);
            }
            Ok(stats)
        };
        let stats = self.schedule.run(&run, &combine).and_then(|stats| {
            // the tangent's entries were checked as they were written
            if all_finite(&self.r_full) && all_finite(&self.lift) {
                Ok(stats)
            } else {
                Err(AssemblyError::NotFinite)
            }
        });
        let ranks = self.ranks;
        let mut stats = ranks.agree(stats, AssemblyError::encode, AssemblyError::decode)?;
        if !ranks.is_serial() {
            ranks.sum_into(&mut self.r_full);
            ranks.sum_into(&mut self.lift);
            stats.min_J_solid = ranks.min(stats.min_J_solid);
            stats.min_J_medium = ranks.min(stats.min_J_medium);
            stats.energy = ranks.sum(stats.energy);
        }
        let mut fe = vec![0.0; model.dofs.n_dofs];
        model.f_ext(step.lambda, &mut fe);
        for (r, f) in self.r_full.iter_mut().zip(&fe) {
            *r -= f;
        }
        Ok(stats)
    }
}

/// Whether the friction block `fb` is one of a medium made again (its cells measured from
/// their own references, not a reconnected layer's), whose closed layers take their slide
/// into their references.
fn absorbing(model: &Model, fb: &FrictionBlock) -> bool {
    !fb.reconnect && model.cell_reference[fb.block].is_some()
}

/// Whether a 3D medium made again without friction has its open cells beside a body let go
/// of their shear at each accepted step ([`References::release_beside`]).
fn releases_beside(model: &Model) -> bool {
    let made = model.cell_reference.iter().any(Option::is_some);
    model.slides_freely_in_3d() && made
}

/// Statistics of two parts together.
fn combine(a: AssemblyStats, b: AssemblyStats) -> AssemblyStats {
    AssemblyStats {
        min_J_solid: a.min_J_solid.min(b.min_J_solid),
        min_J_medium: a.min_J_medium.min(b.min_J_medium),
        energy: a.energy + b.energy,
    }
}

/// The node lists of the cells (and facets) of every term that `keep` keeps, by (term,
/// cell).
fn cells_of<'m>(
    model: &'m Model,
    terms: &'m [Term],
    keep: impl Fn(usize, usize) -> bool + Copy + 'm,
) -> impl Iterator<Item = &'m [usize]> + 'm {
    terms.iter().enumerate().flat_map(move |(bi, t)| {
        let blk = t.block(model).0;
        (0..blk.n_cells())
            .filter(move |&c| keep(bi, c))
            .map(move |c| blk.cell(c))
    })
}

/// The rank that assembles cell (or facet) `c` of `term`.
fn term_rank(model: &Model, p: &Partition, term: Term, c: usize) -> usize {
    let b = term.mesh_block(model);
    match term.on_facets() {
        true => p.facet_rank[b][c] as usize,
        false => p.cell_rank[b][c] as usize,
    }
}

/// The terms that keep a history per point, in the order of their slabs (a checkpoint's
/// `point_history`).
pub fn history_terms(model: &Model) -> Vec<Term> {
    (model.terms().into_iter())
        .filter(|&t| integrand(model, t).history_per_point(model) > 0)
        .collect()
}

/// The history at the initial state, one slab per term that keeps one (in term order), and
/// each term's slab: as each term's [`Integrand::initial_history`] makes it.
fn initial_history(model: &Model, terms: &[Term]) -> (PointHistory, Vec<Option<usize>>) {
    let x0 = model.initial_state();
    let mut slabs: Vec<Slab> = Vec::new();
    let slab_of = (terms.iter())
        .map(|&t| {
            let term = integrand(model, t);
            let per_point = term.history_per_point(model);
            if per_point == 0 {
                return None;
            }
            let blk = t.block(model).0;
            let mut slab = Slab::new(blk.n_cells(), per_point * points_per_cell(blk), 0.0);
            term.initial_history(model, &x0, &mut slab);
            slabs.push(slab);
            Some(slabs.len() - 1)
        })
        .collect();
    (PointHistory { slabs }, slab_of)
}

/// The assembly error of a facet kernel's failure.
pub(crate) fn facet_error(
    model: &Model,
    fb: &FacetBlock,
    e: KernelError,
    facet: usize,
) -> AssemblyError {
    let group = model.flux_groups[fb.group].name.clone();
    match e {
        KernelError::BadGeometry => AssemblyError::BadFacet { group, facet },
        KernelError::NotAbsolute { theta } => AssemblyError::ColdRadiator {
            group,
            facet,
            theta,
        },
        _ => AssemblyError::NotFinite,
    }
}

/// The assembly error of a kernel's failure in cell `cell` of model block `bi`.
pub(crate) fn cell_error(model: &Model, bi: usize, e: KernelError, cell: usize) -> AssemblyError {
    let region = &model.regions[model.blocks[bi].region].0;
    let at = centroid(
        &model.mesh.coords,
        model.mesh.cells[model.blocks[bi].block].cell(cell),
    );
    cell_error_in(region, e, cell, at)
}

/// The assembly error of a kernel's failure in cell `cell` (centre `at`) of `region`.
pub(crate) fn cell_error_in(
    region: &str,
    e: KernelError,
    cell: usize,
    at: [f64; 3],
) -> AssemblyError {
    let region = || region.to_string();
    match e {
        KernelError::Inverted { J } => AssemblyError::Inverted {
            region: region(),
            J,
            cell,
            at,
        },
        KernelError::BadGeometry => AssemblyError::BadMesh {
            region: region(),
            cell,
            at,
        },
        KernelError::Singular => AssemblyError::Singular { region: region() },
        // only facet laws have absolute temperatures
        KernelError::NotAbsolute { .. } => AssemblyError::NotFinite,
    }
}
