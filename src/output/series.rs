//! The VTU series of a run: one `step_NNNN.vtu` per written state, and the `.pvd` that lists
//! them with their (pseudo-)times, rewritten after each step so an interrupted run leaves a
//! valid collection. On several ranks each rank writes the part of its own cells,
//! `step_NNNN_K.vtu` for rank K, and the first rank the `step_NNNN.pvtu` that puts them
//! together, which the `.pvd` lists.

use super::contact::ContactFaces;
use super::fields::all_cell_fields;
use super::nodal::nodal_fields;
use super::vtu::{Piece, StepFields, ZLIB_LEVEL, pvtu_text, read_pvd, write_pvd, write_vtu};
use super::{OutputError, write_atomic};
use crate::assembly::References;
use crate::case::RegionKind;
use crate::dofs::{Field, NONE};
use crate::model::Model;
use crate::parallel::{Distribution, Ranks};
use crate::post::FrictionCell;
use std::path::{Path, PathBuf};

pub struct Series {
    dir: PathBuf,
    pvd: PathBuf,
    /// (time, file name) of every state written so far.
    written: Vec<(f64, String)>,
    /// Per cell: index of its `[[region]]`, and 1 for the medium, 0 for a solid.
    region: Vec<i32>,
    kind: Vec<i32>,
    region_names: Vec<String>,
    /// zlib level of the `.vtu` data (0: uncompressed); [`ZLIB_LEVEL`] unless changed.
    pub zlib_level: u32,
    /// The cells this process writes: the whole mesh, or its rank's part.
    piece: Piece,
    /// On several ranks: (this rank, ranks).
    ranks: Option<(usize, usize)>,
    /// On the first of several ranks, the step written but not yet collected: its time, its
    /// `.pvtu`'s name and text.
    pending: Option<(f64, String, String)>,
    /// Whether the `.pvd` lacks a state written since it was last written.
    unlisted: bool,
    /// The faces where the solids meet the medium, whose contact pressure and shear each
    /// step's file holds at their nodes.
    contact: Option<ContactFaces>,
    /// On several ranks: the cells this rank owns (in a step's cell order) and the ranks,
    /// over which the medium's forces on the faces are summed (a friction cell's slip plane
    /// is known to its own rank only).
    own: Option<(Vec<bool>, Ranks)>,
}

impl Series {
    /// A series in `dir` named `name.pvd`, with the contact traction on the faces `contact`.
    pub fn new(dir: &Path, name: &str, model: &Model, contact: Option<ContactFaces>) -> Series {
        let region: Vec<i32> = model
            .blocks
            .iter()
            .flat_map(|b| std::iter::repeat_n(b.region as i32, model.mesh.cells[b.block].n_cells()))
            .collect();
        let kind = region
            .iter()
            .map(|&r| (model.regions[r as usize].1 == RegionKind::Medium) as i32)
            .collect();
        Series {
            dir: dir.to_owned(),
            pvd: dir.join(format!("{name}.pvd")),
            written: Vec::new(),
            region,
            kind,
            region_names: model.regions.iter().map(|r| r.0.clone()).collect(),
            zlib_level: ZLIB_LEVEL,
            piece: Piece::whole(&model.mesh),
            ranks: None,
            pending: None,
            unlisted: false,
            contact,
            own: None,
        }
    }

    /// The faces where the solids meet the medium, if any.
    pub fn contact(&self) -> Option<&ContactFaces> {
        self.contact.as_ref()
    }

    /// On several ranks: this process writes the cells `distribution` gives it, as its part
    /// of each step.
    pub fn in_parts(mut self, model: &Model, distribution: &Distribution) -> Series {
        let mine = distribution.my_cells();
        self.piece = Piece::part(&model.mesh, &mine);
        self.ranks = Some((distribution.ranks.rank, distribution.partition.parts));
        self.own = Some((mine, distribution.ranks));
        self
    }

    /// (time, file name) of every state written so far.
    pub fn written(&self) -> &[(f64, String)] {
        &self.written
    }

    /// Continue a run's series: the first `count` states its `.pvd` lists (the rank that
    /// writes the `.pvd` reads it). The error says what is wrong with the `.pvd`.
    pub fn resume(&mut self, count: usize) -> Result<(), String> {
        if matches!(self.ranks, Some((r, _)) if r > 0) {
            return Ok(());
        }
        let mut listed = read_pvd(&self.pvd)?;
        if listed.len() < count {
            return Err(format!(
                "it lists {} steps where the checkpoint counts {count}",
                listed.len()
            ));
        }
        // (a step written after the checkpoint is taken again, and the `.pvd` rewritten then)
        listed.truncate(count);
        self.written = listed;
        Ok(())
    }

    /// The `.pvd` file.
    pub fn pvd(&self) -> &Path {
        &self.pvd
    }

    /// The file of step `step` the `.pvd` lists.
    pub fn file_name(&self, step: usize) -> String {
        match self.ranks {
            None => format!("step_{step:04}.vtu"),
            Some(_) => format!("step_{step:04}.pvtu"),
        }
    }

    /// Every file of step `step`: the one the `.pvd` lists and, on several ranks, the parts.
    pub fn files(&self, step: usize) -> Vec<String> {
        let mut files = vec![self.file_name(step)];
        if let Some((_, ranks)) = self.ranks {
            files.extend((0..ranks).map(|k| part_name(step, k)));
        }
        files
    }

    /// Write the state `x` as step `step` at `time` (with friction, its cells' slip state);
    /// [`Series::list`] then lists it in the `.pvd`. On several ranks, this rank's part only:
    /// once every rank's part is on disk, [`Series::collect`] writes the `.pvtu` (a `.pvtu`
    /// never names a part that is not there, whichever rank dies when).
    pub fn write(
        &mut self,
        model: &Model,
        step: usize,
        references: &References,
        x: &[f64],
        time: f64,
        friction: Option<&[Option<FrictionCell>]>,
    ) -> Result<(), OutputError> {
        let mut cells = all_cell_fields(model, references, x).map_err(|e| OutputError::Fields {
            step,
            msg: e.to_string(),
        })?;
        // a friction cell's stress is the medium's own and its slip plane's
        for (cell, f) in cells.iter_mut().zip(friction.unwrap_or_default()) {
            if let Some(f) = f {
                for (row, plane) in cell.sigma.iter_mut().zip(&f.state.stress) {
                    for (s, p) in row.iter_mut().zip(plane) {
                        *s += p;
                    }
                }
            }
        }
        let (d, dofs) = (model.mesh.dim, &model.dofs);
        let u: Vec<[f64; 3]> = (0..model.mesh.coords.len())
            .map(|n| {
                let mut v = [0.0; 3];
                if dofs.has(Field::U) {
                    for c in 0..d {
                        v[c] = x[dofs.u[n * d + c] as usize];
                    }
                }
                v
            })
            .collect();
        let theta: Option<Vec<f64>> = dofs
            .has(Field::Theta)
            .then(|| dofs.theta.iter().map(|&t| x[t as usize]).collect());
        let p: Option<Vec<f64>> = dofs.has(Field::P).then(|| {
            dofs.p
                .iter()
                .map(|&d| if d == NONE { 0.0 } else { x[d as usize] })
                .collect()
        });
        let medium: Vec<bool> = self.kind.iter().map(|&k| k == 1).collect();
        let nodal = nodal_fields(&model.mesh, &cells, &medium);
        let contact = match &self.contact {
            Some(faces) => {
                let mine = self.own.as_ref().map(|(m, _)| &m[..]);
                let forces = faces.forces(model, references, x, friction, mine);
                // every rank takes part in the sum, a failed one with nothing
                let mut flat: Vec<f64> = match &forces {
                    Ok(f) => f.iter().flatten().copied().collect(),
                    Err(_) => vec![0.0; 3 * faces.node_count()],
                };
                if let Some((_, ranks)) = &self.own {
                    ranks.sum_into(&mut flat);
                }
                forces.map_err(|e| OutputError::Fields {
                    step,
                    msg: e.to_string(),
                })?;
                let forces: Vec<[f64; 3]> = (flat.chunks(3)).map(|f| [f[0], f[1], f[2]]).collect();
                let c = faces.from_forces(model, x, &forces);
                Some(faces.at_nodes(model.mesh.coords.len(), &c))
            }
            None => None,
        };
        let fields = StepFields {
            u: &u,
            theta: theta.as_deref(),
            p: p.as_deref().map(|p| (p, dofs.np)),
            cells: &cells,
            nodal: &nodal,
            region: &self.region,
            kind: &self.kind,
            region_names: &self.region_names,
            friction,
            contact: contact.as_ref().map(|(p, s)| (&p[..], &s[..])),
        };
        let file = self.file_name(step);
        let own = match self.ranks {
            None => file.clone(),
            Some((rank, _)) => part_name(step, rank),
        };
        write_vtu(
            &self.dir.join(&own),
            &model.mesh,
            &fields,
            &self.piece,
            self.zlib_level,
        )?;
        match self.ranks {
            Some((0, ranks)) => {
                let parts: Vec<String> = (0..ranks).map(|k| part_name(step, k)).collect();
                let text = pvtu_text(&model.mesh, &fields, &parts);
                self.pending = Some((time, file, text));
                return Ok(());
            }
            Some(_) => {
                // the first rank writes the collection
                self.written.push((time, file));
                return Ok(());
            }
            None => {}
        }
        self.written.push((time, file));
        self.unlisted = true;
        Ok(())
    }

    /// On the first of several ranks, after every rank's part of the last step is written:
    /// the `.pvtu` that puts them together. Nothing elsewhere.
    pub fn collect(&mut self) -> Result<(), OutputError> {
        let Some((time, file, text)) = self.pending.take() else {
            return Ok(());
        };
        write_atomic(&self.dir.join(&file), text.as_bytes())?;
        self.written.push((time, file));
        self.unlisted = true;
        Ok(())
    }

    /// The `.pvd` rewritten to list every state written (by the process that writes it, once
    /// a step's files are on disk: [`Series::write`] and [`Series::collect`] leave it as it
    /// was, so that a step's files can be taken back until their step is recorded).
    pub fn list(&mut self) -> Result<(), OutputError> {
        if !std::mem::take(&mut self.unlisted) || matches!(self.ranks, Some((r, _)) if r > 0) {
            return Ok(());
        }
        write_pvd(&self.pvd, &self.written)
    }
}

/// Rank `rank`'s part of step `step`.
fn part_name(step: usize, rank: usize) -> String {
    format!("step_{step:04}_{rank}.vtu")
}
