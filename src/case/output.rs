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
    /// The group whose reaction a force ratio splits.
    pub group: Option<String>,
    /// The contact's normal a force ratio splits the reaction along.
    pub normal: Option<Vec<f64>>,
}

/// What a probe measures, as its keys say.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Measure<'a> {
    /// The displacement's component (0, 1, 2: x, y, z) at a point.
    U(usize, &'a [f64]),
    /// The temperature at a point.
    Theta(&'a [f64]),
    /// The distance along an axis (0, 1, 2) between two material points.
    Distance(usize, &'a [f64], &'a [f64]),
    /// F_t/F_n of a group's reaction split along a normal.
    ForceRatio(&'a str, &'a [f64]),
}

impl Probe {
    /// What the probe measures; the error says which key is missing or wrong.
    pub fn measure(&self) -> Result<Measure<'_>, String> {
        let name = self.name.get_ref();
        let field = self.field.get_ref().as_str();
        let at = || {
            (self.at.as_deref())
                .ok_or_else(|| format!("probe \"{name}\": field \"{field}\" needs `at`"))
        };
        match field {
            "ux" | "uy" | "uz" => Ok(Measure::U(usize::from(field.as_bytes()[1] - b'x'), at()?)),
            "theta" => Ok(Measure::Theta(at()?)),
            "distance" => {
                let (Some(from), Some(to), Some(axis)) = (&self.from, &self.to, &self.axis) else {
                    return Err(format!(
                        "probe \"{name}\": a distance needs `from`, `to` and `axis`"
                    ));
                };
                let axis = match axis.as_str() {
                    "x" => 0,
                    "y" => 1,
                    "z" => 2,
                    _ => {
                        return Err(format!(
                            "probe \"{name}\": axis must be \"x\", \"y\" or \"z\""
                        ));
                    }
                };
                Ok(Measure::Distance(axis, from, to))
            }
            "force_ratio" => {
                let (Some(group), Some(normal)) = (&self.group, &self.normal) else {
                    return Err(format!(
                        "probe \"{name}\": a force ratio needs `group` and `normal`"
                    ));
                };
                let length = normal.iter().map(|v| v * v).sum::<f64>().sqrt();
                if !(length > 0.0 && length.is_finite() && (2..=3).contains(&normal.len())) {
                    return Err(format!(
                        "probe \"{name}\": `normal` must be 2 or 3 finite numbers, not all 0"
                    ));
                }
                Ok(Measure::ForceRatio(group, normal))
            }
            other => Err(format!(
                "probe \"{name}\": unknown field \"{other}\" (ux, uy, uz, theta, distance, \
                 force_ratio)"
            )),
        }
    }
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
            match p.measure() {
                Err(msg) => return self.error(p.field.span(), msg),
                Ok(Measure::ForceRatio(group, _)) => {
                    let held = (f.bc.iter()).any(|b| b.group.get_ref() == group && b.displaces());
                    if !held {
                        return self.error(
                            p.field.span(),
                            format!(
                                "probe \"{}\": no [[bc]] prescribes a displacement of group \
                                 \"{group}\", so it has no reaction to split",
                                p.name.get_ref()
                            ),
                        );
                    }
                }
                Ok(_) => {}
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
    use super::Measure;

    const PROBE: &str = "[[probe]]\nname = \"gap\"\n";

    #[test]
    fn probes_are_checked_and_units_are_names() {
        let case = parsed(&format!("{PROBE}field = \"distance\"\nfrom = [0, 0]\nto = [0, 1]\naxis = \"y\"\n[units]\nlength = \"mm\"\n")).unwrap();
        assert_eq!(case.file.units.length.as_deref(), Some("mm"));
        // what each probe measures, read once from its keys
        let measure = case.file.probe[0].measure();
        assert_eq!(
            measure,
            Ok(Measure::Distance(1, &[0.0, 0.0][..], &[0.0, 1.0][..]))
        );
        let uz = parsed(&format!("{PROBE}field = \"uz\"\nat = [1, 2, 3]\n")).unwrap();
        assert_eq!(
            uz.file.probe[0].measure(),
            Ok(Measure::U(2, &[1.0, 2.0, 3.0][..]))
        );
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
            (
                "field = \"force_ratio\"\ngroup = \"top\"\n",
                "a force ratio needs `group` and `normal`",
            ),
            (
                "field = \"force_ratio\"\ngroup = \"top\"\nnormal = [0, 0]\n",
                "`normal` must be 2 or 3 finite numbers, not all 0",
            ),
            (
                "field = \"force_ratio\"\ngroup = \"side\"\nnormal = [0, 1]\n",
                "no [[bc]] prescribes a displacement of group \"side\"",
            ),
        ] {
            let e = refused(&format!("{PROBE}{keys}"));
            assert!(e.contains(says), "{keys}: {e}");
        }
        let ratio = parsed(&format!(
            "{PROBE}field = \"force_ratio\"\ngroup = \"top\"\nnormal = [0, 2]\n\
             [[bc]]\ngroup = \"top\"\nuy = -0.1\n"
        ))
        .unwrap();
        assert_eq!(
            ratio.file.probe[0].measure(),
            Ok(Measure::ForceRatio("top", &[0.0, 2.0][..]))
        );
        let twice =
            format!("{PROBE}field = \"ux\"\nat = [0, 0]\n{PROBE}field = \"uy\"\nat = [0, 0]\n");
        assert!(refused(&twice).contains("probe name \"gap\" is used twice"));
    }
}
