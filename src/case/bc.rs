//! `[[bc]]`: what is held, applied or exchanged on one physical group of the boundary; the
//! checks of its values.

use super::{Case, CaseError};
use crate::material::{BoundaryFlux, Convection, Radiation};
use serde::Deserialize;
use toml::Spanned;

/// `[[bc]]`: conditions on one physical group of the boundary (or of points).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [[bc]] table")]
pub struct Bc {
    pub group: Spanned<String>,
    /// A name to address this entry by (`--set bc.NAME.KEY`, a study's `set`) where its group
    /// has several `[[bc]]`.
    pub name: Option<String>,
    pub ux: Option<f64>,
    pub uy: Option<f64>,
    pub uz: Option<f64>,
    pub theta: Option<f64>,
    /// Nominal traction (force per reference area).
    pub traction: Option<Spanned<Vec<f64>>>,
    /// Heat supplied per reference area (positive = into the body).
    pub heat_flux: Option<f64>,
    /// Convection: heat transfer coefficient h ≥ 0, heat leaving per unit current area and
    /// degree, h (θ − θ∞). Acts in full from the start (not scaled by λ). Needs `theta_inf`.
    pub h: Option<Spanned<f64>>,
    /// Ambient temperature θ∞ of the convection.
    pub theta_inf: Option<Spanned<f64>>,
    /// Radiation to surroundings: heat leaving per unit current area ε σ (θ⁴ − θ∞⁴), in
    /// full from the start.
    pub radiation: Option<Spanned<RadiationKey>>,
    /// Scale by the load factor λ (true, the default) or hold at full value from the start
    /// (false): for every value of the block (`ramp = false`), or per value
    /// (`ramp = { theta = false }`: the values not named are ramped).
    pub ramp: Option<Spanned<Ramp>>,
    /// This group's own amplitude at pseudo-times 0, 1, …, T (as `[steps] path`), instead of
    /// λ: e.g. press first, then slide. Prescribed values only.
    pub path: Option<Spanned<Vec<f64>>>,
}

/// `radiation = { emissivity = 0.8, theta_inf = 293.15, sigma = 5.670374419e-8 }` of a
/// `[[bc]]`: temperatures absolute, σ in the case's units.
#[derive(Clone, Debug, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table such as { emissivity = 0.8, theta_inf = 293.15, sigma = 5.670374419e-8 }"
)]
pub struct RadiationKey {
    /// Emissivity ε in (0, 1].
    pub emissivity: Spanned<f64>,
    /// Temperature of the surroundings θ∞ > 0.
    pub theta_inf: Spanned<f64>,
    /// The Stefan–Boltzmann constant in the case's units (5.670374419e-8 in SI).
    pub sigma: Spanned<f64>,
}

/// `ramp` of a `[[bc]]`: one choice for the block, or one per value.
#[derive(Clone, Debug, Deserialize)]
#[serde(
    untagged,
    expecting = "`ramp` must be true, false, or a table such as { theta = false }"
)]
pub enum Ramp {
    All(bool),
    Per(std::collections::BTreeMap<String, bool>),
}

/// The values of a `[[bc]]` that `ramp` may name.
pub const RAMPED_VALUES: [&str; 6] = ["ux", "uy", "uz", "theta", "traction", "heat_flux"];

impl Bc {
    /// Whether the block prescribes a displacement component (so its group has a reaction).
    pub fn displaces(&self) -> bool {
        self.ux.is_some() || self.uy.is_some() || self.uz.is_some()
    }

    /// Whether `value` (one of [`RAMPED_VALUES`]) grows with λ (else it is held at full value
    /// from the start).
    pub fn ramped(&self, value: &str) -> bool {
        match self.ramp.as_ref().map(|r| r.get_ref()) {
            None => true,
            Some(Ramp::All(r)) => *r,
            Some(Ramp::Per(m)) => m.get(value).copied().unwrap_or(true),
        }
    }

    /// Whether heat leaves through the group by a law of its temperature (convection,
    /// radiation): assembled, not prescribed.
    pub fn exchanges_heat(&self) -> bool {
        self.h.is_some() || self.radiation.is_some()
    }

    /// The laws by which heat leaves through the group (convection, radiation), as its keys
    /// give them.
    pub fn boundary_fluxes(&self) -> impl Iterator<Item = BoundaryFlux> {
        let convection = self.h.as_ref().zip(self.theta_inf.as_ref()).map(|(h, t)| {
            BoundaryFlux::Convection(Convection {
                h: *h.get_ref(),
                theta_inf: *t.get_ref(),
            })
        });
        let radiation = self.radiation.as_ref().map(|r| {
            let r = r.get_ref();
            BoundaryFlux::Radiation(Radiation {
                emissivity: *r.emissivity.get_ref(),
                theta_inf: *r.theta_inf.get_ref(),
                sigma: *r.sigma.get_ref(),
            })
        });
        convection.into_iter().chain(radiation)
    }

    /// Whether any value of the block is held at full value.
    pub fn holds_any(&self) -> bool {
        RAMPED_VALUES.iter().any(|v| self.has(v) && !self.ramped(v))
    }

    /// Whether the block gives `value`.
    pub fn has(&self, value: &str) -> bool {
        match value {
            "traction" => self.traction.is_some(),
            _ => self.scalar(value).is_some(),
        }
    }

    /// The scalar `value` of the block (`ux`, `uy`, `uz`, `theta`, `heat_flux`), if given.
    fn scalar(&self, value: &str) -> Option<f64> {
        match value {
            "ux" => self.ux,
            "uy" => self.uy,
            "uz" => self.uz,
            "theta" => self.theta,
            "heat_flux" => self.heat_flux,
            _ => None,
        }
    }

    /// The block's non-zero values that `ramp` holds at full value from the start, as
    /// `uy = -0.2 on "top"`.
    pub fn held_in_full(&self) -> Vec<String> {
        let g = self.group.get_ref();
        RAMPED_VALUES
            .iter()
            .filter(|&&v| !self.ramped(v))
            .filter_map(|&v| match (v, &self.traction) {
                ("traction", Some(t)) if t.get_ref().iter().any(|&x| x != 0.0) => {
                    Some(format!("traction = {:?} on \"{g}\"", t.get_ref()))
                }
                ("traction", _) => None,
                _ => self
                    .scalar(v)
                    .filter(|&x| x != 0.0)
                    .map(|x| format!("{v} = {x} on \"{g}\"")),
            })
            .collect()
    }
}

impl Case {
    /// Each `[[bc]]`'s own `path` (`n_path` values), `ramp` and convection.
    pub(super) fn check_bc_values(&self, n_path: usize) -> Result<(), CaseError> {
        let f = &self.file;
        for (i, bc) in f.bc.iter().enumerate() {
            let Some(r) = &bc.ramp else { continue };
            if let Ramp::Per(m) = r.get_ref() {
                let given: Vec<&str> = RAMPED_VALUES
                    .iter()
                    .copied()
                    .filter(|v| bc.has(v))
                    .collect();
                if let Some(k) = m.keys().find(|k| !given.contains(&k.as_str())) {
                    let g = bc.group.get_ref();
                    let why = if ["h", "theta_inf", "radiation"].contains(&k.as_str()) {
                        format!(
                            "\"{k}\" is an exchange with the surroundings, which acts in full \
                             from the start and is never ramped"
                        )
                    } else if !RAMPED_VALUES.contains(&k.as_str()) && !given.is_empty() {
                        format!(
                            "\"{k}\" is no value a block gives (this one: it gives {})",
                            given.join(", ")
                        )
                    } else if !RAMPED_VALUES.contains(&k.as_str()) {
                        format!("\"{k}\" is no value a block gives")
                    } else if given.is_empty() {
                        "this block gives no value that ramps".to_string()
                    } else {
                        format!(
                            "this block does not give it (it gives {})",
                            given.join(", ")
                        )
                    };
                    return self.error(
                        r.span(),
                        format!(
                            "bc[{i}] (\"{g}\"): `ramp` names \"{k}\": {why}; `ramp` takes the \
                             values the block gives of {}",
                            RAMPED_VALUES.join(", ")
                        ),
                    );
                }
            }
        }
        for bc in &f.bc {
            let Some(own) = &bc.path else { continue };
            let g = bc.group.get_ref();
            let v = own.get_ref();
            if v.len() != n_path || v[0] != 0.0 || v.iter().any(|v| !v.is_finite()) {
                return self.error(
                    own.span(),
                    format!("bc on \"{g}\": `path` needs {n_path} finite values (one per value of [steps] path, or per row of [time] lambda), the first 0"),
                );
            }
            if bc.traction.is_some()
                || bc.heat_flux.is_some()
                || bc.exchanges_heat()
                || bc.holds_any()
            {
                return self.error(
                    own.span(),
                    format!("bc on \"{g}\": `path` applies to prescribed values (ux, uy, uz, theta) only, not to `traction`, `heat_flux`, `h`, `radiation` or `ramp = false`"),
                );
            }
        }
        for bc in &f.bc {
            self.check_convection(bc)?;
            self.check_radiation(bc)?;
        }
        // a group that convects in one [[bc]] and holds θ in another: the held θ wins, and
        // the convected heat would be in no balance
        for bc in f.bc.iter().filter(|b| b.theta.is_some()) {
            let g = bc.group.get_ref();
            let exchanging = f.bc.iter().filter(|b| b.group.get_ref() == g);
            let law = exchanging
                .flat_map(|b| {
                    let h = b.h.as_ref().map(|h| ("convects (`h`)", h.span()));
                    let r = b
                        .radiation
                        .as_ref()
                        .map(|r| ("radiates (`radiation`)", r.span()));
                    h.into_iter().chain(r)
                })
                .next();
            if let Some((what, at)) = law {
                let theta_line = self.place(bc.group.span());
                return self.error(
                    at,
                    format!(
                        "bc on \"{g}\": the group {what} here and has a prescribed \
                         `theta` in the [[bc]] at {theta_line}; a boundary is either held \
                         at a temperature or lets heat out by a law"
                    ),
                );
            }
        }
        Ok(())
    }

    /// A radiation condition: emissivity in (0, 1], θ∞ and σ positive and finite.
    pub(super) fn check_radiation(&self, bc: &Bc) -> Result<(), CaseError> {
        let Some(rad) = &bc.radiation else {
            return Ok(());
        };
        let g = bc.group.get_ref();
        let rad = rad.get_ref();
        let e = *rad.emissivity.get_ref();
        if !(e > 0.0 && e <= 1.0) {
            return self.error(
                rad.emissivity.span(),
                format!("bc on \"{g}\": `radiation.emissivity` must be in (0, 1], got {e}"),
            );
        }
        for (key, v) in [("theta_inf", &rad.theta_inf), ("sigma", &rad.sigma)] {
            let x = *v.get_ref();
            if !(x > 0.0 && x.is_finite()) {
                let why = if key == "theta_inf" {
                    " (an absolute temperature, e.g. in kelvin)"
                } else {
                    " (5.670374419e-8 in SI units)"
                };
                return self.error(
                    v.span(),
                    format!(
                        "bc on \"{g}\": `radiation.{key}` must be positive and finite{why}, got {x}"
                    ),
                );
            }
        }
        Ok(())
    }

    /// A convection condition has both `h` (finite, ≥ 0) and `theta_inf` (finite), and no
    /// prescribed θ on the same group.
    pub(super) fn check_convection(&self, bc: &Bc) -> Result<(), CaseError> {
        let g = bc.group.get_ref();
        match (&bc.h, &bc.theta_inf) {
            (None, None) => Ok(()),
            (Some(h), None) => self.error(
                h.span(),
                format!("bc on \"{g}\": convection `h` needs `theta_inf`, the ambient temperature"),
            ),
            (None, Some(t)) => self.error(
                t.span(),
                format!("bc on \"{g}\": `theta_inf` is the ambient temperature of a convection; give `h` too"),
            ),
            (Some(h), Some(t)) => {
                let hv = *h.get_ref();
                if !(hv >= 0.0) || !hv.is_finite() {
                    return self.error(
                        h.span(),
                        format!("bc on \"{g}\": `h` must be finite and ≥ 0, got {hv}"),
                    );
                }
                if !t.get_ref().is_finite() {
                    return self.error(
                        t.span(),
                        format!("bc on \"{g}\": `theta_inf` must be finite, got {}", t.get_ref()),
                    );
                }
                if bc.theta.is_some() {
                    return self.error(
                        h.span(),
                        format!("bc on \"{g}\": a group with a prescribed `theta` cannot also convect (`h`)"),
                    );
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{parsed, refused};
    use crate::material::BoundaryFlux;

    fn bc(body: &str) -> super::Bc {
        parsed(&format!("[[bc]]\ngroup = \"top\"\n{body}"))
            .unwrap()
            .file
            .bc
            .remove(0)
    }

    #[test]
    fn a_ramp_that_names_what_the_block_cannot_ramp_says_why() {
        for (keys, says) in [
            (
                "theta = 1.0\nramp = { ux = false }\n",
                "`ramp` names \"ux\": this block does not give it (it gives theta)",
            ),
            (
                "h = 5.0\ntheta_inf = 20.0\nramp = { h = false }\n",
                "\"h\" is an exchange with the surroundings, which acts in full from the start",
            ),
            (
                "radiation = { emissivity = 0.8, theta_inf = 300.0, sigma = 5.67e-8 }\n\
                 ramp = { radiation = false }\n",
                "`ramp` names \"radiation\": \"radiation\" is an exchange with the surroundings",
            ),
            (
                "h = 5.0\ntheta_inf = 20.0\nramp = { theta = false }\n",
                "`ramp` names \"theta\": this block gives no value that ramps",
            ),
            (
                "theta = 1.0\nramp = { tehta = false }\n",
                "\"tehta\" is no value a block gives (this one: it gives theta); `ramp` takes \
                 the values the block gives of ux, uy, uz, theta, traction, heat_flux",
            ),
        ] {
            let e = refused(&format!("[[bc]]\ngroup = \"top\"\n{keys}"));
            assert!(e.contains(says), "{keys}: {e}");
            assert!(!e.contains("(it gives )"), "{e}");
        }
    }

    #[test]
    fn a_boundary_s_keys_give_its_heat_laws_in_order() {
        let both = bc(
            "h = 5.0\ntheta_inf = 20.0\nradiation = { emissivity = 0.8, theta_inf = 300.0, sigma = 5.67e-8 }\n",
        );
        let laws: Vec<BoundaryFlux> = both.boundary_fluxes().collect();
        assert!(matches!(
            laws[..],
            [BoundaryFlux::Convection(c), BoundaryFlux::Radiation(r)]
                if c.h == 5.0 && c.theta_inf == 20.0 && r.emissivity == 0.8 && r.sigma == 5.67e-8
        ));
        assert!(both.exchanges_heat());
        let held = bc("theta = 100.0\n");
        assert_eq!(held.boundary_fluxes().count(), 0);
        assert!(!held.exchanges_heat());
    }

    #[test]
    fn ramp_holds_the_values_it_names_at_full_value() {
        let per = bc("uy = -0.2\ntheta = 100.0\nramp = { theta = false }\n");
        assert!(per.ramped("uy") && !per.ramped("theta"));
        assert_eq!(per.held_in_full(), ["theta = 100 on \"top\""]);
        let all = bc("uy = -0.2\nux = 0.0\nramp = false\n");
        assert!(!all.ramped("ux") && all.holds_any());
        // a zero held in full is nothing to announce
        assert_eq!(all.held_in_full(), ["uy = -0.2 on \"top\""]);
    }

    #[test]
    fn a_boundary_s_values_are_checked() {
        for (keys, says) in [
            ("h = 5.0\n", "theta_inf"),
            (
                "radiation = { emissivity = 1.5, theta_inf = 300.0, sigma = 5.67e-8 }\n",
                "emissivity",
            ),
            (
                "radiation = { emissivity = 0.5, theta_inf = -3.0, sigma = 5.67e-8 }\n",
                "theta_inf",
            ),
        ] {
            let e = refused(&format!("[[bc]]\ngroup = \"top\"\n{keys}"));
            assert!(e.contains(says) && e.starts_with("t.toml:"), "{keys}: {e}");
        }
    }
}
