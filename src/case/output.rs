//! What a run reports: `[[probe]]`, `[output]` and `[units]`; the probes' checks.

use super::{Case, CaseError};
use serde::Deserialize;
use toml::Spanned;

/// `[[probe]]`: a named scalar output evaluated after every converged step.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [[probe]] table")]
pub struct Probe {
    pub name: Spanned<String>,
    /// "ux", "uy", "uz", "theta" (value at `at`) or "distance" (between `from` and `to`).
    pub field: Spanned<String>,
    pub at: Option<Vec<f64>>,
    pub from: Option<Vec<f64>>,
    pub to: Option<Vec<f64>>,
    /// Axis of the distance: "x", "y" or "z".
    pub axis: Option<String>,
}

/// `[units]`: the names of the case's units, for plot axes and `summary.json` only. tmc
/// converts nothing: the numbers are read and written in whatever consistent set the case uses.
#[derive(Clone, Debug, Deserialize, Default, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct Units {
    pub length: Option<String>,
    pub force: Option<String>,
    pub time: Option<String>,
    pub temperature: Option<String>,
    /// Default: force·length.
    pub energy: Option<String>,
    /// Of heat flows; default: energy/time.
    pub power: Option<String>,
}

/// `[output]`: which steps get a `.vtu` (history.csv has every step).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "the [output] table")]
pub struct Output {
    /// A `.vtu` every this many accepted steps (default 1: every step); step 0 and the last
    /// step reached are always written.
    pub every: Spanned<i64>,
}

impl Default for Output {
    fn default() -> Self {
        Output {
            every: Spanned::new(0..0, 1),
        }
    }
}

impl Case {
    /// Probes: a known field with the points it needs, names used once.
    pub(super) fn check_probes(&self) -> Result<(), CaseError> {
        let f = &self.file;
        for p in &f.probe {
            let field = p.field.get_ref().as_str();
            match field {
                "ux" | "uy" | "uz" | "theta" => {
                    if p.at.is_none() {
                        return self.error(
                            p.field.span(),
                            format!(
                                "probe \"{}\": field \"{field}\" needs `at`",
                                p.name.get_ref()
                            ),
                        );
                    }
                }
                "distance" => {
                    if p.from.is_none() || p.to.is_none() || p.axis.is_none() {
                        return self.error(
                            p.field.span(),
                            format!(
                                "probe \"{}\": a distance needs `from`, `to` and `axis`",
                                p.name.get_ref()
                            ),
                        );
                    }
                    if !matches!(p.axis.as_deref(), Some("x" | "y" | "z")) {
                        return self.error(
                            p.field.span(),
                            format!(
                                "probe \"{}\": axis must be \"x\", \"y\" or \"z\"",
                                p.name.get_ref()
                            ),
                        );
                    }
                }
                other => {
                    return self.error(
                        p.field.span(),
                        format!(
                            "probe \"{}\": unknown field \"{other}\" (ux, uy, uz, theta, distance)",
                            p.name.get_ref()
                        ),
                    );
                }
            }
        }
        let mut names: Vec<&str> = f.probe.iter().map(|p| p.name.get_ref().as_str()).collect();
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            let p = f
                .probe
                .iter()
                .find(|p| p.name.get_ref() == w[0])
                .expect("found");
            return self.error(
                p.name.span(),
                format!("probe name \"{}\" is used twice", w[0]),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{parsed, refused};

    const PROBE: &str = "[[probe]]\nname = \"gap\"\n";

    #[test]
    fn probes_are_checked_and_units_are_names() {
        let case = parsed(&format!("{PROBE}field = \"distance\"\nfrom = [0, 0]\nto = [0, 1]\naxis = \"y\"\n[units]\nlength = \"mm\"\n")).unwrap();
        assert_eq!(case.file.units.length.as_deref(), Some("mm"));
        for (keys, says) in [
            ("field = \"ux\"\n", "field \"ux\" needs `at`"),
            (
                "field = \"distance\"\nfrom = [0, 0]\n",
                "a distance needs `from`, `to` and `axis`",
            ),
            (
                "field = \"distance\"\nfrom = [0, 0]\nto = [0, 1]\naxis = \"w\"\n",
                "axis must be",
            ),
            (
                "field = \"pressure\"\nat = [0, 0]\n",
                "unknown field \"pressure\"",
            ),
        ] {
            let e = refused(&format!("{PROBE}{keys}"));
            assert!(e.contains(says), "{keys}: {e}");
        }
        let twice =
            format!("{PROBE}field = \"ux\"\nat = [0, 0]\n{PROBE}field = \"uy\"\nat = [0, 0]\n");
        assert!(refused(&twice).contains("probe name \"gap\" is used twice"));
    }
}
