//! The model from a validated case and its mesh, step by step: materials per region, cell
//! blocks with their local layouts, dofs, Dirichlet constraints, external loads.
#![allow(non_snake_case)]

use super::{
    BcGroup, BlockInfo, CapacityBlock, FacetBlock, FluxGroup, FrictionBlock, InertiaBlock,
    LoadPath, Model, Physics, SlipNormals, decide_physics, facet_weights,
};
use crate::case::{Bc, Case, CaseError, Material, RegionKind, SlipNormal};
use crate::dofs::{Constraints, DofMap, Field, Layout, NONE, Prescribed};
use crate::kernel::CellMaterial;
use crate::kernel::friction::FrictionMaterial;
use crate::mesh::Mesh;
use crate::mesh::faces::{Face, NearestFace, shared_faces};
use crate::mesh::{centroid, extent_of};
use nalgebra::Vector3;

/// Build the model. The case must already be validated against the mesh.
pub fn build(case: &Case, mesh: Mesh) -> Result<Model, CaseError> {
    let d = mesh.extent();
    build_with_extent(case, mesh, d)
}

/// [`build`] with the extent d of eq. 21 given: a mesh whose medium was made again keeps the
/// d of the mesh the run started on.
pub fn build_with_extent(case: &Case, mesh: Mesh, d: f64) -> Result<Model, CaseError> {
    let mut physics = decide_physics(case);
    if !physics.mechanics && !physics.conduction {
        return case.error(
            case.file.mesh.span(),
            "the case loads nothing: no displacement, traction or body force, no temperature, \
             heat flux, convection or heat source; there is nothing to solve",
        );
    }
    require_conductivities(case, &physics)?;
    let materials = region_materials(case, d);
    check_one_order(case, &mesh)?;
    // regularization: p fields (f1 in 2D, f1..f3 in 3D per node) on linear medium cells, the
    // direct gradient regularization of eq. 18 on quadratic ones (no unknowns)
    let linear = mesh.cells.iter().all(|b| b.kind.order() == 1);
    physics.regularization &= linear;
    let np = if physics.regularization {
        if mesh.dim == 2 { 1 } else { 3 }
    } else {
        0
    };
    let (blocks, p_nodes) = cell_blocks(case, &mesh, &physics, &materials, np, d);
    let dofs = DofMap::new(&mesh, physics.mechanics, physics.conduction, np, &p_nodes);
    let theta_init = initial_temperatures(&mesh, &blocks);
    let mut path = load_path(case);
    let (cons, bc_groups) = dirichlet(case, &mesh, &dofs, &theta_init, &mut path)?;
    let (f_ramp, f_full, mut flux_groups) = external_loads(case, &mesh, &dofs, &blocks, &cons);
    let facet_blocks = boundary_flux_blocks(case, &mesh, &physics, &mut flux_groups);
    let capacity_blocks = capacity_blocks(case, &mesh, &physics, &blocks);
    let friction_blocks = friction_blocks(case, &mesh, &physics, &blocks)?;
    let inertia_blocks = inertia_blocks(case, &mesh, &physics, &blocks);
    debug_assert!(cons.eq.iter().filter(|&&e| e != NONE).count() == cons.n_eq);
    let mut model = Model {
        physics,
        dofs,
        cons,
        blocks,
        facet_blocks,
        flux_groups,
        capacity_blocks,
        friction_blocks,
        inertia_blocks,
        regions: case
            .file
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
        cell_reference: vec![None; mesh.cells.len()],
        mesh,
        warnings: Vec::new(),
    };
    if let Some(msg) = super::held::unheld_body(&model) {
        return case.error(case.file.mesh.span(), msg);
    }
    let remade = case.remade_medium().is_some();
    model.warnings = super::held::held_by_medium_alone(&model, remade);
    model.warnings.extend(unused_keys(case, &model));
    model.warnings.extend(massless_friction(case, &model));
    model.warnings.extend(layered_friction(case, &model));
    model.warnings.extend(heavy_solids(case, &model));
    Ok(model)
}

/// A solid region whose `rho` makes its cells' inertia over the largest step outweigh their
/// stiffness, ρ h² / ((K + μ) Δt²) > 1 (h the cells' mean size): the region barely follows
/// its loads within a step, a dynamic scene. Said, with the `rho` that keeps it at 1, since a
/// `rho` raised to carry a drag through its slip events can overshoot (section "Time" of
/// THEORY.md: inertia there is meant to be small).
fn heavy_solids(case: &Case, model: &Model) -> Vec<String> {
    if !model.physics.inertia {
        return Vec::new();
    }
    let dt = match &case.file.time {
        Some(time) => time.dt_max(),
        None => case.file.steps.max,
    };
    let mut notes = Vec::new();
    for (i, r) in case.file.region.iter().enumerate() {
        let Some(rho) = &r.rho else { continue };
        if model.regions[i].1 != RegionKind::Solid {
            continue;
        }
        let sizes: Vec<f64> = (model.blocks.iter())
            .filter(|b| b.region == i)
            .flat_map(|b| {
                let blk = &model.mesh.cells[b.block];
                (0..blk.n_cells())
                    .map(|c| extent_of(blk.cell(c).iter().map(|&n| &model.mesh.coords[n])))
            })
            .collect();
        if sizes.is_empty() {
            continue;
        }
        let h = sizes.iter().sum::<f64>() / sizes.len() as f64;
        let stiffness = case.materials[i].law().stiffness_scale();
        let ratio = rho.get_ref() * h * h / (stiffness * dt * dt);
        if ratio > 1.0 {
            notes.push(format!(
                "note: {}: region[{i}] (\"{}\"): with `rho` = {:e} its cells' inertia over a \
                 step of {dt} is {ratio:.1e} times their stiffness: the region barely follows its \
                 loads within a step (a dynamic scene). For a load path meant to be \
                 quasi-static, keep `rho` well below {:.1e} (THEORY.md, \"Time\")",
                case.place(rho.span()),
                r.group.get_ref(),
                rho.get_ref(),
                stiffness * dt * dt / (h * h)
            ));
        }
    }
    notes
}

/// A medium region with friction but no `rho` in a scene with inertia: the folds that turn a
/// drag's path are inside the layer, so the solids' mass alone does not carry drags through
/// (measured: docs/notes/2026-11-29-friction-measurements.md, "Inertia through slip events"). A
/// note naming the region.
fn massless_friction(case: &Case, model: &Model) -> Vec<String> {
    if !model.physics.inertia || !model.physics.friction {
        return Vec::new();
    }
    let line = |span| case.place(span);
    (case.file.region.iter().enumerate())
        .filter(|(_, r)| r.rho.is_none())
        .filter_map(|(i, r)| {
            let fr = r.friction.as_ref()?;
            Some(format!(
                "note: {}: region[{i}] (\"{}\") has friction but no `rho`: inertia carries \
                 drags through their slip events only where the medium has mass too (give it \
                 the solids' `rho`; docs/notes/2026-11-29-friction-measurements.md, \"Inertia \
                 through slip events\")",
                line(fr.span()),
                r.group.get_ref()
            ))
        })
        .collect()
}

/// A friction region with a given normal whose layer is several cells across it (its extent
/// along the normal over its cells' mean extent): over a long slide the slip spreads over the
/// rows in series and the force ratio falls below μ, where one cell across holds it
/// (measured: docs/notes/2026-11-29-friction-measurements.md, "The block with one cell across"). A
/// note naming the region.
fn layered_friction(case: &Case, model: &Model) -> Vec<String> {
    let mut notes = Vec::new();
    for (i, r) in case.file.region.iter().enumerate() {
        let Some(fr) = &r.friction else { continue };
        let blocks: Vec<_> = (model.friction_blocks.iter())
            .filter(|f| f.region == i)
            .collect();
        let Some(SlipNormals::Given(normal)) = blocks.first().map(|f| &f.normals) else {
            continue;
        };
        let across = |n: usize| normal.dot(&Vector3::from(model.mesh.coords[n]));
        let (mut low, mut high, mut extents, mut cells) =
            (f64::INFINITY, f64::NEG_INFINITY, 0.0, 0);
        for f in &blocks {
            let blk = &model.mesh.cells[f.block];
            for c in 0..blk.n_cells() {
                let (a, b) = (blk.cell(c).iter())
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &n| {
                        (a.min(across(n)), b.max(across(n)))
                    });
                (low, high) = (low.min(a), high.max(b));
                extents += b - a;
                cells += 1;
            }
        }
        let rows = (high - low) / (extents / cells as f64);
        if cells > 0 && rows.round() >= 2.0 {
            notes.push(format!(
                "note: {}: region[{i}] (\"{}\"): its friction layer is {} cells across its \
                 slip plane: over a slide longer than its thickness ({:.3e}) the force ratio \
                 falls below μ, the slip spread over its rows; one cell across holds \
                 it (docs/CASE.md, \"How far friction slides\")",
                case.place(fr.span()),
                r.group.get_ref(),
                rows.round(),
                high - low
            ));
        }
    }
    notes
}

/// Keys the case gives that this scene does not use, each as a note with its line: the
/// capacity without `[time]` or without conduction, the heat fraction of friction whose heat
/// goes nowhere.
fn unused_keys(case: &Case, model: &Model) -> Vec<String> {
    let mut notes = Vec::new();
    let line = |span| case.place(span);
    for (i, r) in case.file.region.iter().enumerate() {
        let g = r.group.get_ref();
        if let Some(rho_c) = &r.rho_c
            && !model.physics.transient
        {
            let why = if case.file.time.is_none() {
                "without [time] the heat is stationary"
            } else {
                "the scene conducts no heat"
            };
            notes.push(format!(
                "note: {}: region[{i}] (\"{g}\"): `rho_c` has no effect: {why}",
                line(rho_c.span())
            ));
        }
        if let Some(rho) = &r.rho
            && !model.physics.inertia
        {
            notes.push(format!(
                "note: {}: region[{i}] (\"{g}\"): `rho` has no effect: the scene does not \
                 deform",
                line(rho.span())
            ));
        }
        if let Some(fr) = &r.friction
            && let Some(eta) = &fr.get_ref().heat_fraction
            && !model.physics.frictional_heating
        {
            notes.push(format!(
                "note: {}: region[{i}] (\"{g}\"): `friction.heat_fraction` has no effect: \
                 frictional heat needs [time] and a scene that conducts",
                line(eta.span())
            ));
        }
    }
    notes
}

/// The load factor over time: `[time] lambda` (default: from 0 at t = 0 to 1 at the end), or
/// `[steps] path` over pseudo-time (default `[0, 1]`).
fn load_path(case: &Case) -> LoadPath {
    match &case.file.time {
        Some(time) => {
            let end = *time.end.get_ref();
            let table = time
                .lambda
                .as_ref()
                .map(|l| l.get_ref().iter().map(|r| [r[0], r[1]]).collect())
                .unwrap_or_else(|| vec![[0.0, 0.0], [end, 1.0]]);
            LoadPath {
                times: table.iter().map(|v| v[0]).collect(),
                lambda: table.iter().map(|v| v[1]).collect(),
                own: Vec::new(),
            }
        }
        None => LoadPath::pseudo(
            case.file
                .steps
                .path
                .clone()
                .unwrap_or_else(|| vec![0.0, 1.0]),
        ),
    }
}

/// A scene that conducts heat needs `k` in every region.
fn require_conductivities(case: &Case, physics: &Physics) -> Result<(), CaseError> {
    if !physics.conduction {
        return Ok(());
    }
    let without_k =
        (case.file.region.iter().zip(&case.materials)).find(|(_, m)| !m.gives_conductivity());
    match without_k {
        Some((r, _)) => case.error(
            r.group.span(),
            format!(
                "region \"{}\": the scene conducts heat, so `k` is required",
                r.group.get_ref()
            ),
        ),
        None => Ok(()),
    }
}

/// The material of each `[[region]]`, in case order; `d` is the mesh's extent (eq. 21).
fn region_materials(case: &Case, d: f64) -> Vec<CellMaterial> {
    // the solids' largest k: a medium's cap unless it gives `k_max`
    let solids_k = (case.materials.iter())
        .filter_map(|m| match m {
            Material::Solid(s) => s.k,
            Material::Medium(_) => None,
        })
        .fold(0.0f64, f64::max);
    (case.materials.iter().zip(&case.file.region))
        .map(|(m, r)| {
            let medium = m.medium();
            CellMaterial {
                law: m.law(),
                cond: m.conductivity(solids_k),
                medium: medium.is_some(),
                reg: medium.map(|md| md.regularization(d, r.remakes())),
                reg_direct: None,
            }
        })
        .collect()
}

/// Element orders must agree: a linear cell next to a quadratic one is not conforming.
fn check_one_order(case: &Case, mesh: &Mesh) -> Result<(), CaseError> {
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
    Ok(())
}

/// Each mesh cell block with its region's material and its local layout (`np` regularization
/// components on medium cells), and the nodes that carry p.
fn cell_blocks(
    case: &Case,
    mesh: &Mesh,
    physics: &Physics,
    materials: &[CellMaterial],
    np: usize,
    d: f64,
) -> (Vec<BlockInfo>, Vec<bool>) {
    let f = &case.file;
    let region_of_group = |g: usize| {
        f.region
            .iter()
            .position(|r| mesh.group(r.group.get_ref()) == Some(g))
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
        if let Some(md) = case.materials[region].medium()
            && b.kind.order() == 2
            && physics.mechanics
        {
            mat.reg_direct = Some(md.direct_regularization(d));
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
    (blocks, p_nodes)
}

/// Initial temperature of each node: θ0 of its region (the last region listed wins on shared
/// nodes).
fn initial_temperatures(mesh: &Mesh, blocks: &[BlockInfo]) -> Vec<f64> {
    let mut theta_init = vec![0.0; mesh.coords.len()];
    for info in blocks {
        for &n in &mesh.cells[info.block].conn {
            theta_init[n] = info.mat.law.theta0();
        }
    }
    theta_init
}

/// The prescribed dofs of every `[[bc]]` with prescribed components, and those groups (for
/// reactions). Groups with their own amplitude add it to `path`.
fn dirichlet(
    case: &Case,
    mesh: &Mesh,
    dofs: &DofMap,
    theta_init: &[f64],
    path: &mut LoadPath,
) -> Result<(Constraints, Vec<BcGroup>), CaseError> {
    let mut prescribed: Vec<Option<Prescribed>> = vec![None; dofs.n_dofs];
    let mut bc_groups: Vec<BcGroup> = Vec::new();
    for bc in &case.file.bc {
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
        let own = bc.path.as_ref().map(|own| {
            path.own.push(own.get_ref().clone());
            LoadPath::RAMPED + path.own.len()
        });
        let amp = |name: &str| match own {
            Some(own) => own,
            None if bc.ramped(name) => LoadPath::RAMPED,
            None => LoadPath::HELD,
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
                    amp: amp(name),
                    bc: index,
                };
                if let Some(old) = prescribed[dof] {
                    // two prescriptions conflict where their values differ somewhere on the
                    // load path (amplitudes are linear between its vertices); flags alone
                    // (held, ramped, a path of its own) do not
                    if let Some((t, a, b)) = first_difference(path, &old, &new) {
                        let other = &bc_groups[old.bc].name;
                        return case.error(
                            bc.group.span(),
                            format!(
                                "groups \"{other}\" and \"{}\" share a node at {:?} but prescribe different {name}: {a} and {b} at t = {t} (λ = {}), {} apart",
                                bc.group.get_ref(),
                                mesh.coords[n],
                                path.lambda(t),
                                (a - b).abs()
                            ),
                        );
                    }
                    continue;
                }
                prescribed[dof] = Some(new);
            }
        }
    }
    Ok((Constraints::new(prescribed), bc_groups))
}

/// The first vertex time of the load path at which two prescriptions of one dof differ, with
/// their values there (the same to 1e-12 of the larger counts as equal).
fn first_difference(path: &LoadPath, a: &Prescribed, b: &Prescribed) -> Option<(f64, f64, f64)> {
    path.times.iter().find_map(|&t| {
        let amps = path.amplitudes(t);
        let (va, vb) = (a.at(&amps), b.at(&amps));
        ((va - vb).abs() > 1e-12 * va.abs().max(vb.abs())).then_some((t, va, vb))
    })
}

/// Whether a `[[bc]]` has a flux condition (and so a `FluxGroup`, in case order).
fn has_flux(bc: &Bc) -> bool {
    bc.traction.is_some() || bc.heat_flux.is_some() || bc.exchanges_heat()
}

/// Nodal external loads from tractions, heat fluxes, body forces and heat sources:
/// (ramped by λ, held at full value), zero on prescribed dofs; and the groups with flux
/// conditions, with their loads on free dofs.
fn external_loads(
    case: &Case,
    mesh: &Mesh,
    dofs: &DofMap,
    blocks: &[BlockInfo],
    cons: &Constraints,
) -> (Vec<f64>, Vec<f64>, Vec<FluxGroup>) {
    const AXES: [&str; 3] = ["x", "y", "z"];
    let f = &case.file;
    let mut f_ramp = vec![0.0; dofs.n_dofs];
    let mut f_full = vec![0.0; dofs.n_dofs];
    let mut groups = Vec::new();
    for bc in &f.bc {
        if !has_flux(bc) {
            continue;
        }
        let g = mesh.group(bc.group.get_ref()).expect("validated");
        let mut loads: Vec<(usize, &'static str, f64, bool)> = Vec::new();
        let (ramp_t, ramp_q) = (bc.ramped("traction"), bc.ramped("heat_flux"));
        for b in mesh.facets.iter().filter(|b| b.groups.contains(&g)) {
            for c in 0..b.n_cells() {
                let nodes = b.cell(c);
                // ∫ N_I dA for each facet node
                let w = facet_weights(b.kind, nodes, mesh);
                for (&n, wi) in nodes.iter().zip(&w) {
                    if let (Some(t), true) = (&bc.traction, dofs.has(Field::U)) {
                        for (i, ti) in t.get_ref().iter().enumerate() {
                            let dof = dofs.u[n * dofs.dim + i] as usize;
                            let target = if ramp_t { &mut f_ramp } else { &mut f_full };
                            target[dof] += ti * wi;
                            loads.push((dof, AXES[i], ti * wi, ramp_t));
                        }
                    }
                    if let (Some(q), true) = (bc.heat_flux, dofs.has(Field::Theta)) {
                        let dof = dofs.theta[n] as usize;
                        let target = if ramp_q { &mut f_ramp } else { &mut f_full };
                        target[dof] += q * wi;
                        loads.push((dof, "heat", q * wi, ramp_q));
                    }
                }
            }
        }
        loads.retain(|&(dof, _, _, _)| cons.prescribed[dof].is_none());
        groups.push(FluxGroup {
            name: bc.group.get_ref().clone(),
            loads,
            convects: bc.exchanges_heat() && dofs.has(Field::Theta),
        });
    }
    for (bi, b) in mesh.cells.iter().enumerate() {
        let r = &f.region[blocks[bi].region];
        if r.body_force.is_none() && r.heat_source.is_none() {
            continue;
        }
        for c in 0..b.n_cells() {
            let nodes = b.cell(c);
            let w = facet_weights(b.kind, nodes, mesh);
            for (&n, wi) in nodes.iter().zip(&w) {
                if let (Some(bf), true) = (&r.body_force, dofs.has(Field::U)) {
                    for (i, bi) in bf.get_ref().iter().enumerate() {
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
    (f_ramp, f_full, groups)
}

/// The cell blocks of the regions with `rho`, in a scene that deforms.
fn inertia_blocks(
    case: &Case,
    mesh: &Mesh,
    physics: &Physics,
    blocks: &[BlockInfo],
) -> Vec<InertiaBlock> {
    if !physics.inertia {
        return Vec::new();
    }
    blocks
        .iter()
        .filter_map(|info| {
            let rho = *case.file.region[info.region].rho.as_ref()?.get_ref();
            Some(InertiaBlock {
                block: info.block,
                region: info.region,
                rho,
                layout: Layout {
                    n: mesh.cells[info.block].kind.n_nodes(),
                    dim: mesh.dim,
                    has_u: true,
                    has_theta: false,
                    np: 0,
                },
            })
        })
        .collect()
}

/// The cell blocks of the regions with `rho_c`, in a transient scene.
fn capacity_blocks(
    case: &Case,
    mesh: &Mesh,
    physics: &Physics,
    blocks: &[BlockInfo],
) -> Vec<CapacityBlock> {
    if !physics.transient {
        return Vec::new();
    }
    blocks
        .iter()
        .filter_map(|info| {
            let r = &case.file.region[info.region];
            let rho_c = *r.rho_c.as_ref()?.get_ref();
            Some(CapacityBlock {
                block: info.block,
                region: info.region,
                rho_c,
                theta_ref: r.theta0,
                layout: Layout {
                    n: mesh.cells[info.block].kind.n_nodes(),
                    dim: mesh.dim,
                    has_u: false,
                    has_theta: true,
                    np: 0,
                },
            })
        })
        .collect()
}

/// The cell blocks of the medium regions with `friction`, in a scene that deforms.
fn friction_blocks(
    case: &Case,
    mesh: &Mesh,
    physics: &Physics,
    blocks: &[BlockInfo],
) -> Result<Vec<FrictionBlock>, CaseError> {
    if !physics.friction {
        return Ok(Vec::new());
    }
    // the solids' surfaces against the medium, found once if some region asks for them
    let mut surface: Option<Vec<Face>> = None;
    let mut out = Vec::new();
    for info in blocks {
        let region = &case.file.region[info.region];
        let Some(fr) = region.friction.as_ref().map(|f| f.get_ref()) else {
            continue;
        };
        let normals = match fr.normal.get_ref() {
            SlipNormal::Given(n) => {
                let mut normal = Vector3::zeros();
                normal.as_mut_slice()[..n.len()].copy_from_slice(n);
                SlipNormals::Given(normal.normalize())
            }
            SlipNormal::Word(_) => {
                let faces = surface.get_or_insert_with(|| solid_surface(case, mesh, blocks));
                if faces.is_empty() {
                    return case.error(
                        fr.normal.span(),
                        format!(
                            "region[{}] (\"{}\"): `friction.normal = \"auto\"` takes each cell's \
                             normal from the nearest solid surface, but no solid region borders a \
                             medium region; give the normal as a vector",
                            info.region,
                            region.group.get_ref()
                        ),
                    );
                }
                SlipNormals::PerCell(nearest_normals(mesh, info.block, faces))
            }
        };
        out.push(FrictionBlock {
            block: info.block,
            region: info.region,
            mat: FrictionMaterial {
                mu: *fr.mu.get_ref(),
                medium: case.materials[info.region].law(),
                c_f: fr.c_f.as_ref().map_or(1.0, |v| *v.get_ref()),
                viscosity: fr.viscosity(),
                lagged: fr.lagged_limit(),
                forget_slip: fr.forget_slip(),
                traction_only: region.remakes(),
            },
            normals,
            reconnect: fr.reconnect(),
            heat_fraction: if physics.frictional_heating {
                fr.heat_fraction()
            } else {
                0.0
            },
            layout: Layout {
                np: 0,
                ..info.layout
            },
        });
    }
    Ok(out)
}

/// The faces where a solid region's cells meet a medium region's, normals out of the solid.
fn solid_surface(case: &Case, mesh: &Mesh, blocks: &[BlockInfo]) -> Vec<Face> {
    let of_kind = |kind: RegionKind| -> Vec<usize> {
        blocks
            .iter()
            .filter(|b| case.file.region[b.region].kind == kind)
            .map(|b| b.block)
            .collect()
    };
    shared_faces(
        mesh,
        &of_kind(RegionKind::Solid),
        &of_kind(RegionKind::Medium),
    )
}

/// Each cell of mesh block `block`: the normal of the face of `faces` nearest to its centre.
fn nearest_normals(mesh: &Mesh, block: usize, faces: &[Face]) -> Vec<Vector3<f64>> {
    let near = NearestFace::new(faces);
    let blk = &mesh.cells[block];
    (0..blk.n_cells())
        .map(|c| {
            let x = centroid(&mesh.coords, &blk.cell(c)[..blk.kind.corners()]);
            let f = near.to(&x).expect("faces is not empty");
            Vector3::from(f.normal)
        })
        .collect()
}

/// The facet blocks of the groups that convect or radiate (`flux_groups` as
/// [`external_loads`] lists them: one per `[[bc]]` with a flux condition, in case order), one
/// per law and mesh facet block.
fn boundary_flux_blocks(
    case: &Case,
    mesh: &Mesh,
    physics: &Physics,
    flux_groups: &mut [FluxGroup],
) -> Vec<FacetBlock> {
    let mut out = Vec::new();
    if !physics.conduction {
        return out;
    }
    let with_flux = case.file.bc.iter().filter(|bc| has_flux(bc));
    for (gi, bc) in with_flux.enumerate() {
        let g = mesh.group(bc.group.get_ref()).expect("validated");
        for law in bc.boundary_fluxes() {
            for (fb, b) in mesh.facets.iter().enumerate() {
                if !b.groups.contains(&g) {
                    continue;
                }
                out.push(FacetBlock {
                    block: fb,
                    group: gi,
                    law,
                    layout: Layout {
                        n: b.kind.n_nodes(),
                        dim: mesh.dim,
                        has_u: physics.mechanics,
                        has_theta: true,
                        np: 0,
                    },
                });
            }
            debug_assert!(flux_groups[gi].convects);
        }
    }
    out
}
