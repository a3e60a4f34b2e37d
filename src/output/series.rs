//! The VTU series of a run: one `step_NNNN.vtu` per written state, and the `.pvd` that lists
//! them with their (pseudo-)times, rewritten after each step so an interrupted run leaves a
//! valid collection.

use super::OutputError;
use super::fields::all_cell_fields;
use super::nodal::nodal_fields;
use super::vtu::{StepFields, ZLIB_LEVEL, write_pvd, write_vtu};
use crate::case::RegionKind;
use crate::dofs::{Field, NONE};
use crate::model::Model;
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
}

impl Series {
    /// A series in `dir` named `name.pvd`.
    pub fn new(dir: &Path, name: &str, model: &Model) -> Series {
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
        }
    }

    /// (time, file name) of every state written so far.
    pub fn written(&self) -> &[(f64, String)] {
        &self.written
    }

    /// Continue a run's series: the states it has written.
    pub fn resume(&mut self, written: Vec<(f64, String)>) {
        self.written = written;
    }

    /// The file of step `step`.
    pub fn file_name(step: usize) -> String {
        format!("step_{step:04}.vtu")
    }

    /// Write the state `x` as step `step` at `time`, and the updated `.pvd`.
    pub fn write(
        &mut self,
        model: &Model,
        step: usize,
        x: &[f64],
        time: f64,
    ) -> Result<(), OutputError> {
        let cells = all_cell_fields(model, x).map_err(|e| OutputError::Fields {
            step,
            msg: e.to_string(),
        })?;
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
        let file = Series::file_name(step);
        write_vtu(
            &self.dir.join(&file),
            &model.mesh,
            &StepFields {
                u: &u,
                theta: theta.as_deref(),
                p: p.as_deref().map(|p| (p, dofs.np)),
                cells: &cells,
                nodal: &nodal,
                region: &self.region,
                kind: &self.kind,
                region_names: &self.region_names,
            },
            self.zlib_level,
        )?;
        self.written.push((time, file));
        write_pvd(&self.pvd, &self.written)
    }
}
