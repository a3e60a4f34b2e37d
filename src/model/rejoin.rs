//! A friction layer joined again as its faces slide past each other (`reconnect` of a friction
//! region): when it is due, and the mesh and state the run goes on with. The layer is a
//! [`Strip`] (`mesh/strip.rs`: its rows and how its cells follow a shift) between a bottom row
//! (the face slid on) and a top row (a solid's face, and the open medium's free top beside
//! it). The top row is shifted against the bottom one by whole cells as the solid slides: the
//! open medium's free top nodes move to stand above their new partners (those shifted past
//! one end come round to the other), their place across the layer, θ and p taken from the top
//! row as it was.
//!
//! A Lagrangian layer cannot be slid further than a cell: the cell ahead of the solid's
//! leading corner has the bottom face's nodes for its bottom edge and the corner for a top
//! one, and inverts once the corner has passed that edge's far node (docs/THEORY.md, "A layer
//! joined again as it slides").

use super::{Model, RegionKind, SlipNormals};
use crate::dofs::NONE;
use crate::mesh::Mesh;
use crate::mesh::strip::Strip;
use nalgebra::Vector3;

/// A friction region whose layer cannot be joined again, and why.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerError {
    pub region: String,
    pub why: String,
}

impl std::fmt::Display for LayerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "region \"{}\": `friction.reconnect` {}",
            self.region, self.why
        )
    }
}

impl std::error::Error for LayerError {}

/// The reconnected layer of a model.
pub struct Layer {
    strip: Strip,
    /// Top nodes on a solid (they slide with it; never moved).
    on_solid: Vec<bool>,
    /// Each top node's place along the layer past its partner's when last joined.
    leaned: Vec<f64>,
}

impl Layer {
    /// The model's reconnected layer, if a friction region asks for one; an error names the
    /// region whose layer is not one this can join again.
    pub fn find(model: &Model) -> Result<Option<Layer>, LayerError> {
        let blocks: Vec<_> = model
            .friction_blocks
            .iter()
            .filter(|f| f.reconnect)
            .collect();
        let Some(first) = blocks.first() else {
            return Ok(None);
        };
        let refuse = |why: String| {
            Err(LayerError {
                region: model.regions[first.region].0.clone(),
                why,
            })
        };
        if let Err(why) = Strip::planar(&model.mesh) {
            return refuse(why);
        }
        let SlipNormals::Given(normal) = first.normals else {
            return refuse("needs the layer's `normal` given".into());
        };
        if blocks
            .iter()
            .any(|f| !matches!(f.normals, SlipNormals::Given(n) if n == normal))
        {
            return refuse("needs every reconnected region to have the same `normal`".into());
        }
        let cells: Vec<usize> = blocks.iter().map(|f| f.block).collect();
        let strip = match Strip::find(&model.mesh, &cells, normal) {
            Ok(strip) => strip,
            Err(why) => return refuse(why),
        };
        let solid = model.nodes_of(RegionKind::Solid);
        let on_solid: Vec<bool> = strip.top.iter().map(|&n| solid[n]).collect();
        if !on_solid.iter().any(|&s| s) {
            return refuse("joins a layer under a solid; no solid touches its top row".into());
        }
        let leaned = vec![0.0; strip.len()];
        Ok(Some(Layer {
            strip,
            on_solid,
            leaned,
        }))
    }

    /// The layer in words, for `tmc check`.
    pub fn describe(&self) -> String {
        let how = match self.strip.has_triangles() {
            true => " (triangles, zipped node by node)",
            false => "",
        };
        format!(
            "friction layer joined again as it slides: {} cells between rows of {} nodes, \
             {} of them on the solid{how}",
            self.strip.n_cells(),
            self.strip.len(),
            self.on_solid.iter().filter(|&&s| s).count()
        )
    }

    /// Node `n`'s place at the state `x`.
    fn place(model: &Model, x: &[f64], n: usize) -> Vector3<f64> {
        Vector3::from(model.placed(n, x))
    }

    /// Node `n`'s place along the layer at the state `x`.
    fn along(&self, model: &Model, x: &[f64], n: usize) -> f64 {
        self.strip.along.dot(&Self::place(model, x, n))
    }

    /// The shift the solid's slide at the state `x` calls for, when the layer is to be joined
    /// again: the top row moves on by a cell once the solid's nodes stand, on average, a whole
    /// cell past their partners; triangles are zipped again (at the same shift, if the mean
    /// has not moved a cell) once any of the solid's nodes has slid a cell since the last
    /// join. Never while a solid's node stands past the bottom face's end.
    pub fn due(&self, model: &Model, x: &[f64]) -> Option<i64> {
        let (strip, m) = (&self.strip, self.strip.len());
        let solid: Vec<usize> = (0..m).filter(|&j| self.on_solid[j]).collect();
        let lean: Vec<f64> = solid.iter().map(|&j| self.lean(model, x, j)).collect();
        let mean = lean.iter().sum::<f64>() / lean.len() as f64;
        // triangles are zipped node by node: joined again once any of the solid's nodes has
        // slid a cell since they were last joined
        let slid = strip.has_triangles()
            && (solid.iter().zip(&lean)).any(|(&j, l)| (l - self.leaned[j]).abs() >= strip.width);
        let by = (mean / strip.width).trunc() as i64;
        // a solid's node never comes round, nor is a triangle zipped to a solid's node past the
        // bottom face's end: there the layer stays as it is
        let within = (solid.iter()).all(|&j| {
            let i = j as i64 + strip.shift + by;
            (0..m as i64).contains(&i)
        });
        let over = self.overhang(model, x).is_some();
        ((by != 0 || slid) && within && !over).then_some(strip.shift + by)
    }

    /// A node of the solid (the mesh's) that stands, at the state `x`, past an end of the
    /// bottom face it slides on: there the solid rests on the layer's stretched cells and on
    /// no face (the layer is no longer joined), if any does.
    pub fn overhang(&self, model: &Model, x: &[f64]) -> Option<usize> {
        let (strip, m) = (&self.strip, self.strip.len());
        let ends = [strip.bottom[0], strip.bottom[m - 1]].map(|n| self.along(model, x, n));
        (0..m)
            .filter(|&j| self.on_solid[j])
            .map(|j| strip.top[j])
            .find(|&n| {
                let s = self.along(model, x, n);
                s < ends[0] || s > ends[1]
            })
    }

    /// Top node `j`'s place along the layer past its partner's at the state `x`.
    fn lean(&self, model: &Model, x: &[f64], j: usize) -> f64 {
        let below = self.strip.bottom[self.strip.partner(j)];
        self.strip
            .along
            .dot(&(Self::place(model, x, self.strip.top[j]) - Self::place(model, x, below)))
    }

    /// Join the layer's cells with shift `k`: the mesh's connectivity, the free top nodes'
    /// coordinates, and their unknowns in `x` (the state of `model`, whose mesh `mesh` was).
    pub fn join(&mut self, model: &Model, mesh: &mut Mesh, x: &mut [f64], k: i64) {
        let m = self.strip.len();
        let (d, dofs) = (model.dofs.dim, &model.dofs);
        let along = self.strip.along;
        // what the top row carries, by its place along the layer
        let mut row: Vec<(f64, Vector3<f64>, Vec<f64>)> = (self.strip.top.iter())
            .map(|&n| {
                let p = Self::place(model, x, n);
                let values = carried(model, n)
                    .map(|dof| if dof == NONE { 0.0 } else { x[dof as usize] })
                    .collect();
                (along.dot(&p), p, values)
            })
            .collect();
        row.sort_by(|a, b| a.0.total_cmp(&b.0));
        let normal = Vector3::new(along[1], -along[0], 0.0);
        let row_at = |s: f64| -> (f64, Vec<f64>) {
            let i = row.partition_point(|r| r.0 <= s);
            let (a, b) = match i {
                0 => (&row[0], &row[0]),
                i if i == row.len() => (&row[i - 1], &row[i - 1]),
                i => (&row[i - 1], &row[i]),
            };
            let t = if b.0 > a.0 {
                (s - a.0) / (b.0 - a.0)
            } else {
                0.0
            };
            let height = normal.dot(&(a.1 + (b.1 - a.1) * t));
            (
                height,
                a.2.iter().zip(&b.2).map(|(u, v)| u + t * (v - u)).collect(),
            )
        };
        self.strip.shift = k;
        // the free top nodes above their partners, in the new row's order, kept between the
        // solid's nodes beside them
        let gap = 0.1 * self.strip.width;
        let mut behind = f64::NEG_INFINITY;
        // each top node's place along the layer once joined
        let mut along_top = vec![0.0; m];
        for b in 0..m {
            let j = self.strip.above(b);
            let n = self.strip.top[j];
            if self.on_solid[j] {
                behind = self.along(model, x, n);
                along_top[j] = behind;
                continue;
            }
            let next = (j + 1) % m;
            let ahead = match b + 1 < m && self.on_solid[next] {
                true => self.along(model, x, self.strip.top[next]),
                false => f64::INFINITY,
            };
            let wanted = self.along(model, x, self.strip.bottom[b]);
            let s = match ahead - behind < 2.0 * gap {
                true => 0.5 * (behind + ahead),
                false => wanted.clamp(behind + gap, ahead - gap),
            };
            behind = s;
            along_top[j] = s;
            let (height, values) = row_at(s);
            // the node's mesh place: at s along the layer, where it was across it
            let X = Vector3::from(mesh.coords[n]);
            let X_new = X + along * (s - along.dot(&X));
            let u = normal * (height - normal.dot(&X_new));
            for i in 0..3 {
                mesh.coords[n][i] = X_new[i];
            }
            for i in 0..d {
                x[dofs.u[n * d + i] as usize] = u[i];
            }
            for (dof, v) in carried(model, n).zip(values) {
                if dof != NONE {
                    x[dof as usize] = v;
                }
            }
        }
        for j in (0..m).filter(|&j| self.on_solid[j]) {
            self.leaned[j] = self.lean(model, x, j);
        }
        let along_bottom: Vec<f64> = (self.strip.bottom.iter())
            .map(|&n| self.along(model, x, n))
            .collect();
        self.strip.connect(mesh, &along_bottom, &along_top);
    }
}

/// The unknowns node `n` carries besides its displacement (its p, then its θ), `NONE` where
/// it has none.
fn carried(model: &Model, n: usize) -> impl Iterator<Item = u32> + '_ {
    let dofs = &model.dofs;
    let theta = dofs.theta.get(n).copied().unwrap_or(NONE);
    (0..dofs.np)
        .map(move |c| dofs.p[n * dofs.np + c])
        .chain([theta])
}
