//! The discrete problem built from a case and its mesh: active physics, materials per cell
//! block, dof numbering, constraints and external loads. Nothing here changes during a solve.

use crate::case::{Case, CaseError, RegionKind};
use crate::dofs::{Constraints, DofMap, Field, NONE, Prescribed};
use crate::element::{RefElement, facet_measure};
use crate::kernel::{CellMaterial, Layout};
use crate::material::{Conductivity, Regularization, ThermoElastic};
use crate::mesh::{CellKind, Mesh};
use serde::Serialize;

/// Which effects the scene calls for, decided from the case before anything is assembled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Physics {
    /// Displacement unknowns exist.
    pub mechanics: bool,
    /// Temperature unknowns exist.
    pub conduction: bool,
    /// Deformation changes conduction (J C⁻¹, k(J)): whenever both fields are on.
    pub mechanics_to_heat: bool,
    /// Temperature drives deformation through thermal expansion (some α ≠ 0 and θ varies).
    pub heat_to_mechanics: bool,
    /// A third-medium region exists.
    pub medium: bool,
    /// Regularization fields p_i exist (linear medium elements).
    pub regularization: bool,
}

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

/// The discrete problem.
#[derive(Debug)]
pub struct Model {
    pub mesh: Mesh,
    pub physics: Physics,
    pub dofs: DofMap,
    pub cons: Constraints,
    pub blocks: Vec<BlockInfo>,
    /// Region names and kinds, in case order.
    pub regions: Vec<(String, RegionKind)>,
    /// The load factor and the groups' own amplitudes over pseudo-time.
    pub path: LoadPath,
    /// External loads on all dofs: f_ext(t) = λ(t) f_ramp + f_full.
    pub f_ramp: Vec<f64>,
    pub f_full: Vec<f64>,
    /// Dirichlet groups, indexed by `Prescribed::bc`.
    pub bc_groups: Vec<BcGroup>,
    /// Largest undeformed extent d (eq. 21).
    pub d: f64,
    /// Initial temperature per node (θ0 of its region).
    pub theta_init: Vec<f64>,
}

impl Model {
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

    /// Mesh node and field kind of every free equation, for the linear solver.
    pub fn equation_structure(&self) -> crate::linsolve::Structure {
        let node_of_dof = self.dofs.node_of_dof();
        let n = self.cons.n_eq;
        let (mut node, mut thermal) = (vec![0u32; n], vec![false; n]);
        for (d, &e) in self.cons.eq.iter().enumerate() {
            if e != NONE {
                node[e as usize] = node_of_dof[d];
                thermal[e as usize] = self.dofs.field[d] == Field::Theta;
            }
        }
        crate::linsolve::Structure { node, thermal }
    }

    /// External loads at pseudo-time `t`.
    pub fn f_ext(&self, t: f64, out: &mut [f64]) {
        let lambda = self.path.lambda(t);
        for ((o, r), f) in out.iter_mut().zip(&self.f_ramp).zip(&self.f_full) {
            *o = lambda * r + f;
        }
    }
}

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

/// Decide the active physics from the case.
pub fn decide_physics(case: &Case) -> Physics {
    let f = &case.file;
    let conduction =
        f.bc.iter()
            .any(|b| b.theta.is_some() || b.heat_flux.is_some())
            || f.region
                .iter()
                .any(|r| r.heat_source.is_some_and(|q| q != 0.0));
    // θ can differ from θ0 somewhere only if some prescribed θ or supplied heat is non-trivial
    let theta0s: Vec<f64> = f.region.iter().map(|r| r.theta0).collect();
    let theta_varies = f.bc.iter().any(|b| {
        b.theta.is_some_and(|t| theta0s.iter().any(|&t0| t != t0))
            || b.heat_flux.is_some_and(|q| q != 0.0)
    }) || f
        .region
        .iter()
        .any(|r| r.heat_source.is_some_and(|q| q != 0.0));
    let expansion = f.region.iter().any(|r| r.alpha != 0.0) && conduction && theta_varies;
    let mechanical_load =
        f.bc.iter()
            .any(|b| b.ux.is_some() || b.uy.is_some() || b.uz.is_some() || b.traction.is_some())
            || f.region.iter().any(|r| {
                r.body_force
                    .as_ref()
                    .is_some_and(|b| b.iter().any(|&v| v != 0.0))
            });
    let mechanics = mechanical_load || expansion;
    let medium = f.region.iter().any(|r| r.kind == RegionKind::Medium);
    Physics {
        mechanics,
        conduction,
        mechanics_to_heat: mechanics && conduction,
        heat_to_mechanics: expansion && mechanics,
        medium,
        // every medium element is linear so far, and p only regularizes a deforming medium
        regularization: medium && mechanics,
    }
}

/// Build the model. The case must already be validated against the mesh.
pub fn build(case: &Case, mesh: Mesh) -> Result<Model, CaseError> {
    let physics = decide_physics(case);
    let f = &case.file;
    let k_max_default = f
        .region
        .iter()
        .filter(|r| r.kind == RegionKind::Solid)
        .filter_map(|r| r.k.as_ref().map(|k| *k.get_ref()))
        .fold(0.0f64, f64::max);
    if physics.conduction {
        for r in &f.region {
            if r.k.is_none() {
                return case.error(
                    r.group.span(),
                    format!(
                        "region \"{}\": the scene conducts heat, so `k` is required",
                        r.group.get_ref()
                    ),
                );
            }
        }
    }
    let d = mesh.extent();
    let materials: Vec<CellMaterial> = f
        .region
        .iter()
        .map(|r| {
            let k = r.k.as_ref().map(|k| *k.get_ref()).unwrap_or(1.0);
            match r.kind {
                RegionKind::Solid => CellMaterial {
                    law: ThermoElastic {
                        K: *r.K.as_ref().expect("checked").get_ref(),
                        mu: *r.mu.as_ref().expect("checked").get_ref(),
                        alpha: r.alpha,
                        theta0: r.theta0,
                    },
                    cond: Conductivity::Constant(k),
                    medium: false,
                    reg: None,
                    reg_direct: None,
                },
                RegionKind::Medium => {
                    let gamma = *r.gamma.as_ref().expect("checked").get_ref();
                    let k_max = r
                        .k_max
                        .as_ref()
                        .map(|v| *v.get_ref())
                        .unwrap_or(k_max_default.max(k));
                    CellMaterial {
                        law: ThermoElastic {
                            K: gamma,
                            mu: gamma,
                            alpha: r.alpha,
                            theta0: r.theta0,
                        },
                        cond: Conductivity::Medium { k_tm: k, k_max },
                        medium: true,
                        reg: Some(Regularization {
                            beta1: r.beta1.as_ref().map(|v| *v.get_ref()).unwrap_or(1.0),
                            beta2: r.beta2.as_ref().map(|v| *v.get_ref()).unwrap_or(1e-2),
                            d,
                        }),
                        reg_direct: None,
                    }
                }
            }
        })
        .collect();

    // element orders must agree: a linear cell next to a quadratic one is not conforming
    let orders: std::collections::BTreeSet<usize> =
        mesh.cells.iter().map(|b| b.kind.order()).collect();
    if orders.len() > 1 {
        let kinds: Vec<&str> = mesh.cells.iter().map(|b| b.kind.name()).collect();
        return case.error(
            case.file.mesh.span(),
            format!(
                "the mesh mixes linear and quadratic cells ({}), which do not conform; mesh all with one order",
                kinds.join(", ")
            ),
        );
    }
    let region_of_group = |g: usize| {
        f.region
            .iter()
            .position(|r| mesh.group(r.group.get_ref()) == Some(g))
    };
    // regularization: p fields (f1 in 2D, f1..f3 in 3D per node) on linear medium cells, the
    // direct gradient regularization of eq. 18 on quadratic ones (no unknowns)
    let linear = mesh.cells.iter().all(|b| b.kind.order() == 1);
    let mut physics = physics;
    physics.regularization &= linear;
    let np = if physics.regularization {
        if mesh.dim == 2 { 1 } else { 3 }
    } else {
        0
    };
    let mut blocks = Vec::new();
    let mut p_nodes = vec![false; mesh.coords.len()];
    for (bi, b) in mesh.cells.iter().enumerate() {
        let region = b
            .groups
            .iter()
            .find_map(|&g| region_of_group(g))
            .expect("validated");
        let mut mat = materials[region];
        let medium = mat.medium;
        if medium && np > 0 {
            for &n in &b.conn {
                p_nodes[n] = true;
            }
        }
        if medium && b.kind.order() == 2 && physics.mechanics {
            // γ α_r: given, or β2 d² so that it weighs |∇f|² like eq. 20 with p = d f
            let r = &f.region[region];
            let gamma = *r.gamma.as_ref().expect("checked").get_ref();
            let beta2 = mat.reg.map_or(1e-2, |g| g.beta2);
            mat.reg_direct = Some(
                r.alpha_r
                    .as_ref()
                    .map_or(beta2 * d * d, |a| gamma * *a.get_ref()),
            );
            mat.reg = None;
        }
        blocks.push(BlockInfo {
            block: bi,
            region,
            mat,
            layout: Layout {
                n: b.kind.n_nodes(),
                dim: mesh.dim,
                has_u: physics.mechanics,
                has_theta: physics.conduction,
                np: if medium { np } else { 0 },
            },
        });
    }

    let dofs = DofMap::new(&mesh, physics.mechanics, physics.conduction, np, &p_nodes);

    // initial temperature of each node: θ0 of its region (the last region listed wins on shared nodes)
    let mut theta_init = vec![0.0; mesh.coords.len()];
    for info in &blocks {
        for &n in &mesh.cells[info.block].conn {
            theta_init[n] = info.mat.law.theta0;
        }
    }

    // Dirichlet conditions
    let mut path = LoadPath {
        lambda: f.steps.path.clone().unwrap_or_else(|| vec![0.0, 1.0]),
        own: Vec::new(),
    };
    let mut prescribed: Vec<Option<Prescribed>> = vec![None; dofs.n_dofs];
    let mut bc_groups: Vec<BcGroup> = Vec::new();
    for bc in &f.bc {
        let comps: Vec<(&'static str, f64, Field, usize)> = [
            ("ux", bc.ux, Field::U, 0),
            ("uy", bc.uy, Field::U, 1),
            ("uz", bc.uz, Field::U, 2),
            ("theta", bc.theta, Field::Theta, 0),
        ]
        .into_iter()
        .filter_map(|(n, v, fl, c)| v.map(|v| (n, v, fl, c)))
        .collect();
        if comps.is_empty() {
            continue;
        }
        let g = mesh.group(bc.group.get_ref()).expect("validated");
        let nodes = mesh.group_nodes(g);
        let index = bc_groups.len();
        let amp = match (&bc.path, bc.ramp) {
            (Some(own), _) => {
                path.own.push(own.get_ref().clone());
                LoadPath::RAMPED + path.own.len()
            }
            (None, true) => LoadPath::RAMPED,
            (None, false) => LoadPath::HELD,
        };
        bc_groups.push(BcGroup {
            name: bc.group.get_ref().clone(),
            fields: comps.iter().map(|c| c.0).collect(),
        });
        for &(name, value, field, c) in &comps {
            if !dofs.has(field) {
                continue; // e.g. ux = 0 in a pure conduction scene: nothing to hold
            }
            for &n in &nodes {
                let dof = match field {
                    Field::U => dofs.u[n * dofs.dim + c],
                    _ => dofs.theta[n],
                } as usize;
                let new = Prescribed {
                    value,
                    start: match field {
                        Field::Theta => theta_init[n],
                        _ => 0.0,
                    },
                    amp,
                    bc: index,
                };
                if let Some(old) = prescribed[dof] {
                    if old.value != new.value || old.amp != new.amp {
                        let other = &bc_groups[old.bc].name;
                        return case.error(
                            bc.group.span(),
                            format!(
                                "groups \"{other}\" and \"{}\" share a node at {:?} but prescribe different {name} ({} and {})",
                                bc.group.get_ref(),
                                mesh.coords[n],
                                old.value,
                                new.value
                            ),
                        );
                    }
                    continue;
                }
                prescribed[dof] = Some(new);
            }
        }
    }
    let cons = Constraints::new(prescribed);

    // external loads
    let mut f_ramp = vec![0.0; dofs.n_dofs];
    let mut f_full = vec![0.0; dofs.n_dofs];
    for bc in &f.bc {
        if bc.traction.is_none() && bc.heat_flux.is_none() {
            continue;
        }
        let g = mesh.group(bc.group.get_ref()).expect("validated");
        let target = if bc.ramp { &mut f_ramp } else { &mut f_full };
        for b in mesh.facets.iter().filter(|b| b.groups.contains(&g)) {
            for c in 0..b.n_cells() {
                let nodes = b.cell(c);
                // ∫ N_I dA for each facet node
                let w = facet_weights(b.kind, nodes, &mesh);
                for (&n, wi) in nodes.iter().zip(&w) {
                    if let (Some(t), true) = (&bc.traction, dofs.has(Field::U)) {
                        for (i, ti) in t.get_ref().iter().enumerate() {
                            target[dofs.u[n * dofs.dim + i] as usize] += ti * wi;
                        }
                    }
                    if let (Some(q), true) = (bc.heat_flux, dofs.has(Field::Theta)) {
                        target[dofs.theta[n] as usize] += q * wi;
                    }
                }
            }
        }
    }
    for (bi, b) in mesh.cells.iter().enumerate() {
        let r = &f.region[blocks[bi].region];
        if r.body_force.is_none() && r.heat_source.is_none() {
            continue;
        }
        for c in 0..b.n_cells() {
            let nodes = b.cell(c);
            let w = facet_weights(b.kind, nodes, &mesh);
            for (&n, wi) in nodes.iter().zip(&w) {
                if let (Some(bf), true) = (&r.body_force, dofs.has(Field::U)) {
                    for (i, bi) in bf.iter().enumerate() {
                        f_ramp[dofs.u[n * dofs.dim + i] as usize] += bi * wi;
                    }
                }
                if let (Some(q), true) = (r.heat_source, dofs.has(Field::Theta)) {
                    f_ramp[dofs.theta[n] as usize] += q * wi;
                }
            }
        }
    }
    for (dof, p) in cons.prescribed.iter().enumerate() {
        if p.is_some() {
            f_ramp[dof] = 0.0;
            f_full[dof] = 0.0;
        }
    }
    debug_assert!(cons.eq.iter().filter(|&&e| e != NONE).count() == cons.n_eq);
    Ok(Model {
        physics,
        dofs,
        cons,
        blocks,
        regions: f
            .region
            .iter()
            .map(|r| (r.group.get_ref().clone(), r.kind))
            .collect(),
        path,
        f_ramp,
        f_full,
        bc_groups,
        d,
        theta_init,
        mesh,
    })
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
