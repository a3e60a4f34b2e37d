//! The discrete problem built from a case and its mesh: active physics ([`physics`]),
//! materials per cell block, dof numbering, constraints and external loads ([`loads`]), put
//! together by [`build`]. Nothing here changes during a solve.

pub mod build;
pub mod held;
pub mod loads;
pub mod physics;
pub mod rejoin;
pub mod remake;
pub mod rigid;
pub mod validate;

pub use build::build;
pub use loads::{LoadPath, StepContext, facet_weights};
pub use physics::{Physics, decide_physics};

pub use crate::case::RegionKind;
use crate::dofs::{Constraints, DofMap, Field, Layout};
use crate::kernel::CellMaterial;
use crate::kernel::friction::FrictionMaterial;
use crate::material::BoundaryFlux;
use crate::mesh::{Block, Mesh};
use nalgebra::Vector3;

/// One cell block of the mesh with its material and local layout.
#[derive(Clone, Debug)]
pub struct BlockInfo {
    /// Index into `mesh.cells`.
    pub block: usize,
    /// Index into the case's regions.
    pub region: usize,
    pub mat: CellMaterial,
    pub layout: Layout,
}

/// A Dirichlet group, for reactions.
#[derive(Clone, Debug)]
pub struct BcGroup {
    pub name: String,
    /// Components prescribed here ("ux", "theta", ...).
    pub fields: Vec<&'static str>,
}

/// A block of boundary facets that carries a facet law (convection or radiation), with its
/// local layout.
#[derive(Clone, Debug)]
pub struct FacetBlock {
    /// Index into `mesh.facets`.
    pub block: usize,
    /// Index into `Model::flux_groups`.
    pub group: usize,
    pub law: BoundaryFlux,
    pub layout: Layout,
}

/// The cells of a region that stores heat, for the capacity term ρc (θ − θₙ)/Δt, with the
/// θ-only local layout of that term.
#[derive(Clone, Debug)]
pub struct CapacityBlock {
    /// Index into `mesh.cells`.
    pub block: usize,
    /// Index into the case's regions.
    pub region: usize,
    /// Heat capacity per reference volume.
    pub rho_c: f64,
    /// The region's θ0: stored heat is counted from it.
    pub theta_ref: f64,
    pub layout: Layout,
}

/// The cells of a region with a mass density, for the inertia term ρ ü, with the u-only
/// local layout of that term.
#[derive(Clone, Debug)]
pub struct InertiaBlock {
    /// Index into `mesh.cells`.
    pub block: usize,
    /// Index into the case's regions.
    pub region: usize,
    /// Mass per reference volume.
    pub rho: f64,
    pub layout: Layout,
}

/// The cells of a medium region with friction, for the slip term and its heat, with the
/// region's layout without p (the friction term does not touch the regularization).
#[derive(Clone, Debug)]
pub struct FrictionBlock {
    /// Index into `mesh.cells`.
    pub block: usize,
    /// Index into the case's regions.
    pub region: usize,
    pub mat: FrictionMaterial,
    /// The slip plane's unit normal in each cell.
    pub normals: SlipNormals,
    /// Whether the layer's cells are joined again as its faces slide (`reconnect`), each cell
    /// measured from a reference of its own ([`crate::assembly::References`]).
    pub reconnect: bool,
    /// Fraction of the dissipated work that becomes heat (0 where no heat is made).
    pub heat_fraction: f64,
    pub layout: Layout,
}

/// The slip planes' unit normals (reference configuration) of a friction block: the region's
/// given one for all its cells, or one per cell from the nearest solid surface (`"auto"`).
#[derive(Clone, Debug)]
pub enum SlipNormals {
    Given(Vector3<f64>),
    PerCell(Vec<Vector3<f64>>),
}

impl SlipNormals {
    /// The normal of the block's cell `c`.
    pub fn of(&self, c: usize) -> &Vector3<f64> {
        match self {
            SlipNormals::Given(n) => n,
            SlipNormals::PerCell(n) => &n[c],
        }
    }
}

/// A boundary group with a flux condition (traction, heat flux, convection): its force and
/// heat on the body are reported with the Dirichlet groups' reactions.
#[derive(Clone, Debug)]
pub struct FluxGroup {
    pub name: String,
    /// Prescribed loads on free dofs: (dof, component "x", "y", "z" or "heat", value at full
    /// load, whether it is scaled by λ).
    pub loads: Vec<(usize, &'static str, f64, bool)>,
    /// Whether facet blocks of this group convect or radiate (their heat is assembled, not
    /// prescribed).
    pub convects: bool,
}

/// One term of the discrete problem: an integrand over the cells (or facets) of one mesh
/// block, by its index into the model's list of that kind. The assembler runs
/// [`Model::terms`] in order, each through its integrand (`assembly/terms/`), which owns its
/// kernel and its history per point; the terms with history own one slab of per-point values
/// each, in that order too.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Term {
    /// A region's cells: mechanics, conduction, the medium's regularization
    /// (`blocks`).
    Bulk(usize),
    /// A boundary heat flux on a facet block (`facet_blocks`).
    Flux(usize),
    /// Heat stored, ρc (θ − θₙ)/Δt, with θₙ per point as history (`capacity_blocks`).
    Capacity(usize),
    /// Coulomb friction in a medium's slip planes, with the slip per point as history
    /// (`friction_blocks`).
    Friction(usize),
    /// Inertia, ρ ü by backward Euler, with the displacement and velocity per point as history
    /// (`inertia_blocks`).
    Inertia(usize),
}

impl Term {
    /// The mesh block (cells, or facets for [`Term::Flux`]) the term integrates over, and
    /// the term's local layout of unknowns.
    pub fn block<'m>(&self, model: &'m Model) -> (&'m Block, Layout) {
        let (m, i) = (&model.mesh, self.mesh_block(model));
        match *self {
            Term::Bulk(b) => (&m.cells[i], model.blocks[b].layout),
            Term::Flux(f) => (&m.facets[i], model.facet_blocks[f].layout),
            Term::Capacity(c) => (&m.cells[i], model.capacity_blocks[c].layout),
            Term::Friction(f) => (&m.cells[i], model.friction_blocks[f].layout),
            Term::Inertia(b) => (&m.cells[i], model.inertia_blocks[b].layout),
        }
    }

    /// Index of the term's block in `mesh.cells` (`mesh.facets` for [`Term::Flux`]).
    pub fn mesh_block(&self, model: &Model) -> usize {
        match *self {
            Term::Bulk(b) => model.blocks[b].block,
            Term::Flux(f) => model.facet_blocks[f].block,
            Term::Capacity(c) => model.capacity_blocks[c].block,
            Term::Friction(f) => model.friction_blocks[f].block,
            Term::Inertia(b) => model.inertia_blocks[b].block,
        }
    }

    /// Whether the term integrates over facets (`mesh.facets`) rather than cells.
    pub fn on_facets(&self) -> bool {
        matches!(self, Term::Flux(_))
    }
}

/// The discrete problem.
#[derive(Debug)]
pub struct Model {
    pub mesh: Mesh,
    pub physics: Physics,
    pub dofs: DofMap,
    pub cons: Constraints,
    /// The regions' cell blocks ([`Term::Bulk`]).
    pub blocks: Vec<BlockInfo>,
    /// Boundary facets with a facet law ([`Term::Flux`]).
    pub facet_blocks: Vec<FacetBlock>,
    /// Groups with flux conditions, for reporting.
    pub flux_groups: Vec<FluxGroup>,
    /// Cells that store heat (transient scenes only; [`Term::Capacity`]).
    pub capacity_blocks: Vec<CapacityBlock>,
    /// Medium cells with friction ([`Term::Friction`]).
    pub friction_blocks: Vec<FrictionBlock>,
    /// Cells with a mass density ([`Term::Inertia`]).
    pub inertia_blocks: Vec<InertiaBlock>,
    /// Region names and kinds, in case order.
    pub regions: Vec<(String, RegionKind)>,
    /// The load factor and the groups' own amplitudes over pseudo-time.
    pub path: LoadPath,
    /// External loads on all dofs: f_ext = λ f_ramp + f_full.
    pub f_ramp: Vec<f64>,
    pub f_full: Vec<f64>,
    /// Dirichlet groups, indexed by `Prescribed::bc`.
    pub bc_groups: Vec<BcGroup>,
    /// Largest undeformed extent d (eq. 21).
    pub d: f64,
    /// Initial temperature per node (θ0 of its region).
    pub theta_init: Vec<f64>,
    /// Per mesh block, its cells' own reference node coordinates (N per cell, in cell order)
    /// where the medium was made again (`remake.rs`), or `None`: measured from the mesh.
    pub cell_reference: Vec<Option<Vec<[f64; 3]>>>,
    /// What the case sets up that is valid but worth saying, each starting "warning:" or
    /// "note:" (a body the medium alone holds in some direction), besides the mesh's warnings.
    pub warnings: Vec<String>,
}

impl Model {
    /// Every term, in the order the assembler runs them: the regions' cells, the boundary
    /// fluxes, heat storage, friction, inertia.
    pub fn terms(&self) -> Vec<Term> {
        (0..self.blocks.len())
            .map(Term::Bulk)
            .chain((0..self.facet_blocks.len()).map(Term::Flux))
            .chain((0..self.capacity_blocks.len()).map(Term::Capacity))
            .chain((0..self.friction_blocks.len()).map(Term::Friction))
            .chain((0..self.inertia_blocks.len()).map(Term::Inertia))
            .collect()
    }

    /// The state at λ = 0: zero displacement, θ = θ0, prescribed values that are not ramped.
    pub fn initial_state(&self) -> Vec<f64> {
        let mut x = vec![0.0; self.dofs.n_dofs];
        if self.dofs.has(Field::Theta) {
            for (n, &t) in self.theta_init.iter().enumerate() {
                x[self.dofs.theta[n] as usize] = t;
            }
        }
        x
    }

    /// Whether a condition prescribes node `n`'s displacement along `i`.
    pub fn held_along(&self, n: usize, i: usize) -> bool {
        let u = self.dofs.u.get(n * self.dofs.dim + i);
        u.is_some_and(|&u| {
            self.cons
                .prescribed
                .get(u as usize)
                .is_some_and(Option::is_some)
        })
    }

    /// Whether bodies rub: the case has a friction layer. A medium made again without friction
    /// takes shorter first steps and, in 3D, asks for a remake by other rules.
    pub fn rubs(&self) -> bool {
        !self.friction_blocks.is_empty()
    }

    /// Whether a friction layer is joined again as it slides (`reconnect`): the run's mesh
    /// changes as it goes.
    pub fn reconnects(&self) -> bool {
        self.friction_blocks.iter().any(|f| f.reconnect)
    }

    /// Per mesh node: whether a cell of a region of `kind` has it. Of the medium: its own
    /// nodes and the solids' faces towards it (where the medium closes, its stiffness and
    /// conductivity across the gap grow without bound: a multigrid hands these rows to a
    /// direct solver).
    pub fn nodes_of(&self, kind: RegionKind) -> Vec<bool> {
        self.mesh.nodes_in(|b| {
            (self.blocks.iter()).any(|info| info.block == b && self.regions[info.region].1 == kind)
        })
    }

    /// External loads at the load factor `lambda`.
    pub fn f_ext(&self, lambda: f64, out: &mut [f64]) {
        for ((o, r), f) in out.iter_mut().zip(&self.f_ramp).zip(&self.f_full) {
            *o = lambda * r + f;
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::case::Case;
    use crate::mesh::gmsh::{MeshOptions, mesh_geo};
    use std::path::Path;

    /// The model of the shipped case `name`, its `.geo` meshed as the case says (with `params`
    /// over its own) into `target/unit-scratch/model/`, a file per test (its thread's name):
    /// tests that mesh the same case run at once, and one's mesh was moved into place from
    /// under the other.
    pub(crate) fn model_of(name: &str, params: &[(&str, f64)]) -> Model {
        case_and_model_of(name, params).1
    }

    /// [`model_of`] with its case.
    pub(crate) fn case_and_model_of(name: &str, params: &[(&str, f64)]) -> (Case, Model) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let case = Case::read(&root.join(format!("cases/{name}.toml"))).unwrap();
        let mut set: std::collections::BTreeMap<String, f64> =
            case.file.mesh_options.params.clone();
        set.extend(params.iter().map(|(k, v)| (k.to_string(), *v)));
        let test = std::thread::current()
            .name()
            .unwrap_or("main")
            .replace("::", "-");
        let out = root.join(format!("target/unit-scratch/model/{test}-{name}.msh"));
        let opts = MeshOptions {
            order: case.file.mesh_options.order.unwrap_or(1),
            incomplete: false,
            set_numbers: set.into_iter().collect(),
            verbose: false,
        };
        let mesh = mesh_geo(&case.mesh_path(), &out, &opts).unwrap().mesh;
        validate::validate(&case, &mesh).unwrap();
        let model = build::build(&case, mesh).unwrap();
        (case, model)
    }

    /// (bulk, flux, capacity, friction, inertia) terms of a model.
    fn kinds(model: &Model) -> [usize; 5] {
        let mut n = [0; 5];
        for t in model.terms() {
            n[kinds_rank(&t) as usize] += 1;
        }
        n
    }

    #[test]
    fn a_model_lists_one_term_per_block_of_what_its_scene_calls_for() {
        let coarse = [("n", 4.0), ("m", 4.0), ("l", 1.0)];
        // (case, mesh parameters, whether each kind of term is there: flux, capacity, friction)
        type Scene<'a> = (&'a str, &'a [(&'a str, f64)], [bool; 3]);
        let scenes: [Scene; 4] = [
            ("block", &coarse, [false, false, false]),
            ("slab-radiation", &[], [true, false, false]),
            ("block-transient", &coarse, [true, true, false]),
            ("friction-heating", &coarse, [false, true, true]),
        ];
        for (name, params, has) in scenes {
            let model = model_of(name, params);
            let terms = model.terms();
            let n = kinds(&model);
            assert_eq!(
                n[0],
                model.blocks.len(),
                "{name}: a bulk term per cell block"
            );
            assert_eq!([n[1] > 0, n[2] > 0, n[3] > 0], has, "{name}: {n:?}");
            assert_eq!(n[4], 0, "{name}: no mass density, no inertia");
            // in the assembler's order: bulk, flux, capacity, friction, inertia
            let ordered = terms
                .windows(2)
                .all(|w| kinds_rank(&w[0]) <= kinds_rank(&w[1]));
            assert!(ordered, "{name}: {terms:?}");
            for t in &terms {
                let (block, layout) = t.block(&model);
                // the term's layout is its mesh block's kind
                assert_eq!(layout.n, block.kind.n_nodes(), "{name}: {t:?}");
                match t {
                    Term::Flux(_) => assert!(layout.has_theta && block.kind.dim() < model.mesh.dim),
                    Term::Capacity(_) => assert!(layout.has_theta),
                    Term::Friction(_) => assert!(layout.has_u),
                    Term::Inertia(_) => assert!(layout.has_u && !layout.has_theta),
                    Term::Bulk(_) => assert_eq!(block.kind.dim(), model.mesh.dim),
                }
            }
        }
    }

    /// A term's place in the assembler's order.
    fn kinds_rank(t: &Term) -> u8 {
        match t {
            Term::Bulk(_) => 0,
            Term::Flux(_) => 1,
            Term::Capacity(_) => 2,
            Term::Friction(_) => 3,
            Term::Inertia(_) => 4,
        }
    }
}
