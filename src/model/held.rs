//! Before anything is solved: every connected body must be held. A body that no prescribed
//! displacement holds in some direction (or against some rotation), or whose temperature
//! nothing fixes, makes the tangent singular; the solver would only find out after every step
//! cut. Said here per body, with the direction. A body with mass (`rho`) is held by its
//! inertia: its tangent has ρ/Δt² on every displacement.

use super::{Model, rigid};
use crate::case::RegionKind;
use crate::dofs::{Field, NONE};
use crate::mesh::{centroid, point_text};
use nalgebra::{DMatrix, SymmetricEigen};

/// The first body that is not held, as a sentence; `None` if all are.
pub fn unheld_body(model: &Model) -> Option<String> {
    let mesh = &model.mesh;
    let comp = mesh.components(|_| true);
    let n_comp = comp
        .iter()
        .filter(|&&c| c != usize::MAX)
        .max()
        .map_or(0, |&m| m + 1);
    if n_comp == 0 {
        return None;
    }
    let dofs = &model.dofs;
    let d = mesh.dim;
    let held_dof = |dof: u32| dof != NONE && model.cons.eq[dof as usize] == NONE;
    for c in 0..n_comp {
        let nodes: Vec<usize> = (0..comp.len()).filter(|&n| comp[n] == c).collect();
        let name = || body_name(model, &comp, c, nodes.len(), n_comp);
        let has_mass = || {
            (model.inertia_blocks.iter())
                .any(|ib| mesh.cells[ib.block].conn.iter().any(|&n| comp[n] == c))
        };
        if model.physics.mechanics && dofs.has(Field::U) && !has_mass() {
            let held: Vec<(usize, usize)> = nodes
                .iter()
                .flat_map(|&n| (0..d).map(move |i| (n, i)))
                .filter(|&(n, i)| held_dof(dofs.u[n * d + i]))
                .collect();
            if let Some(mode) = free_rigid_mode(model, &nodes, &held) {
                return Some(format!(
                    "{} is not held: it can {mode}; prescribe displacements on its boundary \
                     groups that stop it",
                    name()
                ));
            }
        }
        if model.physics.conduction && dofs.has(Field::Theta) {
            let fixed = nodes.iter().any(|&n| held_dof(dofs.theta[n]));
            // h = 0 is an insulated boundary: it holds no temperature
            let convects = model.facet_blocks.iter().any(|fb| {
                fb.law.anchors_temperature()
                    && mesh.facets[fb.block].conn.iter().any(|&n| comp[n] == c)
            });
            let stores = model.capacity_blocks.iter().any(|cb| {
                mesh.cells[cb.block]
                    .conn
                    .first()
                    .is_some_and(|&n| comp[n] == c)
            });
            if !(fixed || convects || stores) {
                return Some(format!(
                    "the temperature of {} is not fixed: no `theta` is prescribed on it and no \
                     boundary of it convects (`h` > 0) or radiates, so a stationary solution is not unique",
                    name()
                ));
            }
        }
    }
    None
}

/// The solid bodies (connected solid cells) whose prescribed displacements leave a rigid
/// motion free, which only the third medium around them resists: by its small stiffness, so
/// they slide or turn under any force that way. A body held in part (pressed down, free to slide
/// sideways: the usual slip) gives a warning; one held nowhere (floating or wedged in the
/// medium, as the paper's discs) a note, or a warning where the medium is made again
/// (`remade`): a remake sets its open cells' stress back to nil, and with it what holds such a
/// body until it touches another.
pub fn held_by_medium_alone(model: &Model, remade: bool) -> Vec<String> {
    let mesh = &model.mesh;
    let has_medium = model.regions.iter().any(|r| r.1 == RegionKind::Medium);
    if !has_medium || !model.physics.mechanics || !model.dofs.has(Field::U) {
        return Vec::new();
    }
    let mut region = vec![None; mesh.cells.len()];
    for info in &model.blocks {
        if model.regions[info.region].1 == RegionKind::Solid {
            region[info.block] = Some(info.region);
        }
    }
    let comp = mesh.components(|b| region[b].is_some());
    let n_comp = comp
        .iter()
        .filter(|&&c| c != usize::MAX)
        .max()
        .map_or(0, |&m| m + 1);
    let d = mesh.dim;
    let mut out = Vec::new();
    for c in 0..n_comp {
        let nodes: Vec<usize> = (0..comp.len()).filter(|&n| comp[n] == c).collect();
        let held: Vec<(usize, usize)> = nodes
            .iter()
            .flat_map(|&n| (0..d).map(move |i| (n, i)))
            .filter(|&(n, i)| {
                let dof = model.dofs.u[n * d + i];
                dof != NONE && model.cons.eq[dof as usize] == NONE
            })
            .collect();
        let Some(mode) = free_rigid_mode(model, &nodes, &held) else {
            continue;
        };
        let body = format!(
            "the solid body of {} ({} nodes around {})",
            region_names(model, &comp, c, |k| k == RegionKind::Solid).join(", "),
            nodes.len(),
            point_text(&centroid(&mesh.coords, &nodes), d)
        );
        // measured: docs/notes/2026-12-06-a-floating-body-and-a-medium-made-again.md
        let remake = "the medium is made again (`remake`): each remake sets its open cells' \
                      stress back to nil, and with it what holds the body until it touches \
                      another, so a remake before then may leave it without an equilibrium \
                      (`cases/discs-ellipse.toml` with `remake` stops at λ = 0.33)";
        out.push(match (held.is_empty(), remade) {
            (true, false) => format!(
                "note: {body} has no prescribed displacement: the third medium alone holds it \
                 (as it should a body floating or wedged in it)"
            ),
            (true, true) => format!(
                "warning: {body} has no prescribed displacement: the third medium alone holds \
                 it, and {remake}; prescribe displacements on it, or leave out `remake` where \
                 nothing slides far"
            ),
            (false, _) => format!(
                "warning: {body} is held in part: it can {mode} but for the third medium, \
                 whose small stiffness lets it slip; prescribe displacements on its boundary \
                 that stop it{}",
                match remade {
                    true => format!(" ({remake})"),
                    false => String::new(),
                }
            ),
        });
    }
    out
}

/// A rigid motion of the body (`nodes`) that the held (node, direction) pairs do not stop,
/// in words; `None` if they stop every one.
fn free_rigid_mode(model: &Model, nodes: &[usize], held: &[(usize, usize)]) -> Option<String> {
    let x = &model.mesh.coords;
    let d = model.mesh.dim;
    // centre and size of the body, so that rotations and translations weigh alike
    let c = centroid(x, nodes);
    let h = nodes
        .iter()
        .map(|&n| (0..3).map(|i| (x[n][i] - c[i]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    // the rigid modes' value at (node, direction): translations, then rotations
    let modes = rigid::count(d);
    let value = |n: usize, i: usize, m: usize| -> f64 {
        let r = std::array::from_fn(|k| (x[n][k] - c[k]) / h);
        rigid::motion(d, m, &r)[i]
    };
    let mut g = DMatrix::<f64>::zeros(modes, modes);
    for &(n, i) in held {
        for p in 0..modes {
            let vp = value(n, i, p);
            if vp == 0.0 {
                continue;
            }
            for q in 0..modes {
                g[(p, q)] += vp * value(n, i, q);
            }
        }
    }
    let axis = ["x", "y", "z"];
    if held.is_empty() {
        return Some("move freely: no displacement is prescribed anywhere on it".to_string());
    }
    let scale = 1.0 + held.len() as f64;
    if let Some(i) = (0..d).find(|&i| g[(i, i)] <= 1e-10 * scale) {
        return Some(format!("move freely in {}", axis[i]));
    }
    let eig = SymmetricEigen::new(g);
    let (k, &lmin) = eig
        .eigenvalues
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    if lmin > 1e-10 * scale {
        return None;
    }
    // every translation is held: the free motion turns; name the axis it turns about most
    let v = eig.eigenvectors.column(k);
    let (m, _) = v
        .iter()
        .enumerate()
        .skip(d)
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))?;
    let a = rigid::axis(d, m);
    Some(format!(
        "rotate freely about an axis along {} (what holds it lies on one point or line)",
        axis[a]
    ))
}

/// "the body made of region(s) …", with its size, numbered if there are several.
fn body_name(model: &Model, comp: &[usize], c: usize, n_nodes: usize, n_comp: usize) -> String {
    let regions = region_names(model, comp, c, |_| true);
    let which = if n_comp > 1 {
        format!("body {} of {n_comp}", c + 1)
    } else {
        "the body".to_string()
    };
    format!(
        "{which} (region{} {}, {n_nodes} nodes)",
        if regions.len() > 1 { "s" } else { "" },
        regions.join(", ")
    )
}

/// The quoted names of the regions (of the kinds `keep` accepts) whose cells begin in
/// component `c`, in block order.
fn region_names(
    model: &Model,
    comp: &[usize],
    c: usize,
    keep: impl Fn(RegionKind) -> bool,
) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for info in &model.blocks {
        let (name, k) = &model.regions[info.region];
        let first = model.mesh.cells[info.block].conn.first();
        let name = format!("\"{name}\"");
        if keep(*k) && first.is_some_and(|&n| comp[n] == c) && !names.contains(&name) {
            names.push(name);
        }
    }
    names
}
