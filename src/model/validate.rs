//! The case against its mesh, before any work: every group a region or a condition names
//! exists with the right dimension, every cell has a material, prescribed components and
//! probe points fit the mesh's dimension, sizes stay within what a run can hold.

use crate::case::{Case, CaseError, SlipNormal};
use crate::mesh::Mesh;

/// Checks against the mesh: groups exist and have the right dimension, every cell has a
/// material, prescribed components exist in this dimension.
pub fn validate(case: &Case, mesh: &Mesh) -> Result<(), CaseError> {
    let region_groups = validate_regions(case, mesh)?;
    validate_cells(case, mesh, &region_groups)?;
    validate_bcs(case, mesh)?;
    validate_probes(case, mesh)?;
    validate_sizes(case, mesh)
}

/// No probe of a z quantity in a 2D mesh; points with the mesh's number of coordinates.
fn validate_probes(case: &Case, mesh: &Mesh) -> Result<(), CaseError> {
    for p in &case.file.probe {
        let z = p.field.get_ref() == "uz" || p.axis.as_deref() == Some("z");
        if mesh.dim == 2 && z {
            return case.error(
                p.field.span(),
                format!(
                    "probe \"{}\": a z quantity in a 2D mesh (x and y only)",
                    p.name.get_ref()
                ),
            );
        }
    }
    Ok(())
}

/// The groups of `mesh` of a dimension `dim_ok` accepts, quoted, for error messages.
fn groups_of(mesh: &Mesh, dim_ok: &dyn Fn(usize) -> bool) -> String {
    let names: Vec<String> = mesh
        .groups
        .iter()
        .filter(|g| dim_ok(g.dim))
        .map(|g| format!("\"{}\"", g.name))
        .collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

/// Every region names a group of cells of the mesh, once; returns those groups.
fn validate_regions(case: &Case, mesh: &Mesh) -> Result<Vec<usize>, CaseError> {
    let available = |dim_ok: &dyn Fn(usize) -> bool| groups_of(mesh, dim_ok);
    let mut region_groups = Vec::new();
    for (i, r) in case.file.region.iter().enumerate() {
        let name = r.group.get_ref();
        let Some(g) = mesh.group(name) else {
            return case.error(
                r.group.span(),
                format!(
                    "region[{i}]: physical group \"{name}\" is not in the mesh {} (its {}D groups: {})",
                    mesh.source.display(),
                    mesh.dim,
                    available(&|d| d == mesh.dim)
                ),
            );
        };
        if mesh.groups[g].dim != mesh.dim {
            return case.error(
                r.group.span(),
                format!(
                    "region[{i}]: group \"{name}\" has dimension {}, a region needs a {}D group of cells",
                    mesh.groups[g].dim, mesh.dim
                ),
            );
        }
        if region_groups.contains(&g) {
            return case.error(
                r.group.span(),
                format!("region[{i}]: group \"{name}\" is given twice"),
            );
        }
        if let Some(fr) = &r.friction
            && let SlipNormal::Given(n) = fr.get_ref().normal.get_ref()
            && n.len() != mesh.dim
        {
            return case.error(
                fr.get_ref().normal.span(),
                format!(
                    "region[{i}] (\"{name}\"): `friction.normal` has {} components; the mesh is {}D",
                    n.len(),
                    mesh.dim
                ),
            );
        }
        region_groups.push(g);
    }
    Ok(region_groups)
}

/// Every block of cells belongs to exactly one region.
fn validate_cells(case: &Case, mesh: &Mesh, region_groups: &[usize]) -> Result<(), CaseError> {
    for b in &mesh.cells {
        let n = b
            .groups
            .iter()
            .filter(|g| region_groups.contains(g))
            .count();
        if n != 1 {
            let names: Vec<&str> = b
                .groups
                .iter()
                .map(|&g| mesh.groups[g].name.as_str())
                .collect();
            let at = case.text.find("[[region]]").unwrap_or(0);
            return case.error(
                at..at,
                if n == 0 {
                    format!(
                        "{} cells of groups [{}] have no [[region]]; every cell needs exactly one material",
                        b.n_cells(),
                        names.join(", ")
                    )
                } else {
                    format!("cells belong to several regions [{}]", names.join(", "))
                },
            );
        }
    }
    Ok(())
}

/// Every `[[bc]]` names a boundary group of a dimension its conditions can act on.
fn validate_bcs(case: &Case, mesh: &Mesh) -> Result<(), CaseError> {
    let available = |dim_ok: &dyn Fn(usize) -> bool| groups_of(mesh, dim_ok);
    for (i, bc) in case.file.bc.iter().enumerate() {
        let name = bc.group.get_ref();
        let Some(g) = mesh.group(name) else {
            return case.error(
                bc.group.span(),
                format!(
                    "bc[{i}]: physical group \"{name}\" is not in the mesh {} (boundary groups: {})",
                    mesh.source.display(),
                    available(&|d| d < mesh.dim)
                ),
            );
        };
        let gdim = mesh.groups[g].dim;
        if gdim >= mesh.dim {
            return case.error(
                bc.group.span(),
                format!("bc[{i}]: group \"{name}\" is a {gdim}D group of cells; boundary conditions go on curves/surfaces/points"),
            );
        }
        if mesh.group_nodes(g).is_empty() {
            return case.error(
                bc.group.span(),
                format!("bc[{i}]: group \"{name}\" has no elements in the mesh {} (its entities carry no mesh, or none of its nodes belongs to a cell)", mesh.source.display()),
            );
        }
        if mesh.dim == 2 && bc.uz.is_some() {
            return case.error(
                bc.group.span(),
                format!("bc[{i}] (\"{name}\"): `uz` in a 2D mesh"),
            );
        }
        let natural = bc.traction.is_some() || bc.heat_flux.is_some();
        if natural && gdim + 1 != mesh.dim {
            return case.error(
                bc.group.span(),
                format!("bc[{i}] (\"{name}\"): traction and heat_flux need a {}D boundary group, this one is {gdim}D", mesh.dim - 1),
            );
        }
        if let Some(h) = &bc.h
            && gdim + 1 != mesh.dim
        {
            return case.error(
                h.span(),
                format!("bc[{i}] (\"{name}\"): convection `h` needs a {}D boundary group, this one is {gdim}D", mesh.dim - 1),
            );
        }
        if let Some(r) = &bc.radiation
            && gdim + 1 != mesh.dim
        {
            return case.error(
                r.span(),
                format!("bc[{i}] (\"{name}\"): `radiation` needs a {}D boundary group, this one is {gdim}D", mesh.dim - 1),
            );
        }
        if let Some(t) = &bc.traction
            && t.get_ref().len() != mesh.dim
        {
            return case.error(
                t.span(),
                format!("bc[{i}]: traction needs {} components", mesh.dim),
            );
        }
        let any = bc.ux.is_some()
            || bc.uy.is_some()
            || bc.uz.is_some()
            || bc.theta.is_some()
            || bc.exchanges_heat()
            || natural;
        if !any {
            return case.error(
                bc.group.span(),
                format!("bc[{i}] (\"{name}\"): prescribes nothing"),
            );
        }
    }
    Ok(())
}

/// Vectors and points have the mesh's dimension.
fn validate_sizes(case: &Case, mesh: &Mesh) -> Result<(), CaseError> {
    for (i, r) in case.file.region.iter().enumerate() {
        if let Some(b) = &r.body_force
            && b.get_ref().len() != mesh.dim
        {
            return case.error(
                b.span(),
                format!(
                    "region[{i}] (\"{}\"): body_force has {} components; this mesh is {}D and \
                     needs {}",
                    r.group.get_ref(),
                    b.get_ref().len(),
                    mesh.dim,
                    mesh.dim
                ),
            );
        }
    }
    for p in &case.file.probe {
        for pt in [&p.at, &p.from, &p.to].into_iter().flatten() {
            if pt.len() != mesh.dim {
                return case.error(
                    p.name.span(),
                    format!(
                        "probe \"{}\": points need {} coordinates",
                        p.name.get_ref(),
                        mesh.dim
                    ),
                );
            }
        }
    }
    Ok(())
}
