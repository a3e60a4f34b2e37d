//! `[solver]`: the linear solver, the coupling strategy and the engine, with the PETSc
//! engine's options; their check.

use super::{Case, CaseError};
use serde::Deserialize;
use toml::Spanned;

/// `[solver]`: linear solver choice.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Solver {
    /// "auto" (LDLᵀ when the tangent is symmetric, else block-preconditioned GMRES), "gmres",
    /// "lu", "ldlt"; with where it is written, for the errors about it.
    pub linear: Spanned<LinearChoice>,
    /// "auto" (one-way coupled scenes solve mechanics, then heat, per step) or "monolithic".
    pub coupling: CouplingChoice,
    /// "auto" (the default: faer, unless its factors would not fit in the memory the run
    /// has, then PETSc's multigrid where it is built), "faer" (one process) or "petsc" (the
    /// distributed engine; what `mpirun` runs on whatever this says).
    pub engine: Spanned<EngineChoice>,
    /// `[solver.petsc]`: the PETSc engine's options.
    pub petsc: PetscOptions,
}

impl Default for Solver {
    fn default() -> Self {
        Solver {
            linear: Spanned::new(0..0, LinearChoice::Auto),
            coupling: CouplingChoice::Auto,
            engine: Spanned::new(0..0, EngineChoice::Auto),
            petsc: PetscOptions::default(),
        }
    }
}

#[derive(Clone, Copy, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum EngineChoice {
    #[default]
    Auto,
    Faer,
    Petsc,
}

/// `[solver.petsc]`.
#[derive(Clone, Debug, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct PetscOptions {
    /// PETSc's own options, as on its command line (`"-ksp_type cg -pc_type gamg"`); added to
    /// those of the `PETSC_OPTIONS` environment variable, and taking precedence over them.
    pub options: Option<Spanned<String>>,
    /// tmc's defaults under the options: "direct" (MUMPS) or "multigrid" (GMRES with a field
    /// split: smoothed-aggregation multigrid on the mechanics, BoomerAMG on heat).
    pub method: PetscMethod,
}

#[derive(Clone, Copy, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum PetscMethod {
    #[default]
    Direct,
    Multigrid,
}

#[derive(Clone, Copy, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum CouplingChoice {
    #[default]
    Auto,
    Monolithic,
}

#[derive(Clone, Copy, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum LinearChoice {
    #[default]
    Auto,
    Lu,
    Ldlt,
    Gmres,
}

impl Case {
    /// `[solver.petsc] options` in PETSc's command-line syntax: every word an option (`-name`)
    /// or the value right after one. PETSc skips a word that is neither without a word.
    pub(super) fn check_petsc_options(&self) -> Result<(), CaseError> {
        let Some(o) = &self.file.solver.petsc.options else {
            return Ok(());
        };
        let is_option = |w: &str| w.starts_with('-') && w.parse::<f64>().is_err();
        let mut after_option = false;
        for w in o.get_ref().split_whitespace() {
            if is_option(w) {
                after_option = true;
            } else if after_option {
                after_option = false;
            } else {
                return self.error(
                    o.span(),
                    format!(
                        "[solver.petsc] options: \"{w}\" is neither an option nor an option's \
                         value (options start with a dash: \"-{w}\"?)"
                    ),
                );
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{parsed, refused};
    use super::{EngineChoice, LinearChoice, PetscMethod};

    #[test]
    fn the_solver_s_choices_and_petsc_s_options() {
        let s = parsed("[solver]\nlinear = \"lu\"\nengine = \"petsc\"\n[solver.petsc]\nmethod = \"multigrid\"\noptions = \"-ksp_type cg -ksp_rtol 1e-10 -pc_type gamg\"\n")
            .unwrap()
            .file
            .solver;
        assert_eq!(
            (*s.linear.get_ref(), *s.engine.get_ref(), s.petsc.method),
            (
                LinearChoice::Lu,
                EngineChoice::Petsc,
                PetscMethod::Multigrid
            )
        );
        let e = refused("[solver.petsc]\noptions = \"-ksp_type cg pc_type gamg\"\n");
        assert!(
            e.contains("\"pc_type\" is neither an option nor an option's value")
                && e.contains("\"-pc_type\"?"),
            "{e}"
        );
        let e = refused("[solver]\nengine = \"cuda\"\n");
        assert!(e.contains("cuda"), "{e}");
    }
}
