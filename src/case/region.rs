//! `[[region]]`: the material of one physical group of cells, a solid's law and moduli or
//! the medium's, its conduction and friction; their checks, which turn a region's keys into
//! its [`Material`].
//!
//! A region is read by serde as one table of optional keys ([`Region`]) and becomes a
//! variant ([`Material`]: a solid with its law, or the medium with its conductivity law)
//! only in [`Case`]'s checks. serde's tagged enums would do it in the parse, but they buffer
//! a table before choosing the variant, which loses every key's position (`toml::Spanned`
//! refuses to be read from the buffer) and reports a wrong key at the table's header: the
//! checks keep the line of the key at fault. Past the checks, only the material is read: a
//! law's keys are private to this file.

use super::{Case, CaseError};
use crate::material::conduction::TABLE_POINTS;
use crate::material::{Conductivity, MooneyRivlin, Regularization, SolidLaw, ThermoElastic};
use serde::Deserialize;
use toml::Spanned;

/// Region kinds.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum RegionKind {
    Solid,
    Medium,
}

/// `law` of a solid region.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SolidLawKey {
    /// Eq. (12), with `K` and `mu` (the default).
    NeoHooke,
    /// Abaqus' compressible Mooney-Rivlin, with `C10`, `C01` and `K`.
    MooneyRivlin,
}

/// `[[region]]`: the material of one physical group of cells.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, expecting = "a [[region]] table")]
#[allow(non_snake_case)]
pub struct Region {
    pub group: Spanned<String>,
    pub kind: RegionKind,
    /// Bulk modulus (solid).
    K: Option<Spanned<f64>>,
    /// Shear modulus (solid, Neo-Hooke).
    mu: Option<Spanned<f64>>,
    /// A solid's stress law (default: Neo-Hooke).
    law: Option<Spanned<SolidLawKey>>,
    /// Mooney-Rivlin's coefficients of Ī₁ − 3 and Ī₂ − 3.
    C10: Option<Spanned<f64>>,
    C01: Option<Spanned<f64>>,
    /// Conductivity k (solid) or gas conductivity k_TM (medium).
    k: Option<Spanned<f64>>,
    /// Thermal expansion coefficient α_t.
    #[serde(default)]
    pub alpha: f64,
    /// Reference temperature θ0.
    #[serde(default)]
    pub theta0: f64,
    /// Medium stiffness γ (K = μ = γ).
    gamma: Option<Spanned<f64>>,
    /// Cap of the medium's conductivity (default: largest solid k).
    k_max: Option<Spanned<f64>>,
    /// A medium's conductivity as a table of `[J, k]` rows, linear in J between them (instead
    /// of `k` and `k_max`).
    k_table: Option<Spanned<Vec<Vec<f64>>>>,
    /// A medium's conductance across its closed layer h_c (heat per area, time and degree),
    /// with `thickness`, the layer's undeformed thickness t0: k ≤ h_c t0 J.
    h_closed: Option<Spanned<f64>>,
    thickness: Option<Spanned<f64>>,
    /// A medium made again between the bodies as they move (`model/remake.rs`).
    remake: Option<Spanned<bool>>,
    /// With `remake`: the mechanics settled at the same load after each remake, and what the
    /// remake changed measured there.
    settle: Option<Spanned<bool>>,
    /// Regularization weights β1, β2 (eq. 20) and α_r (eq. 18).
    beta1: Option<Spanned<f64>>,
    beta2: Option<Spanned<f64>>,
    alpha_r: Option<Spanned<f64>>,
    /// Body force per reference volume (ramped).
    pub body_force: Option<Spanned<Vec<f64>>>,
    /// Heat source per reference volume (ramped).
    pub heat_source: Option<f64>,
    /// Heat capacity ρc per reference volume: with `[time]`, the region stores heat
    /// (ρc θ̇ by backward Euler); without, it is stationary.
    pub rho_c: Option<Spanned<f64>>,
    /// Mass per reference volume ρ: the region's displacements carry inertia, ρ ü by backward
    /// Euler, over `[time]`'s time or the pseudo-time of a quasi-static path.
    pub rho: Option<Spanned<f64>>,
    /// Coulomb friction in a slip plane of the medium (medium regions only).
    pub friction: Option<Spanned<FrictionKey>>,
}

/// `friction = { mu = 0.3, normal = [0, 1] }` (or `normal = "auto"`) of a medium region.
#[derive(Clone, Debug, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table such as { mu = 0.3, normal = [0, 1] }"
)]
pub struct FrictionKey {
    /// Coulomb coefficient μ_f ≥ 0.
    pub mu: Spanned<f64>,
    /// The slip plane's normal in the undeformed mesh: a vector of the mesh's dimension (need
    /// not be of unit length), or `"auto"`: each cell's from the solid surface nearest to it.
    pub normal: Spanned<SlipNormal>,
    /// Fraction of the dissipated work that becomes heat, in [0, 1] (default 1); heat is made
    /// only in scenes with `[time]` that conduct.
    pub heat_fraction: Option<Spanned<f64>>,
    /// Stick stiffness factor c_f > 0 of the friction modulus (c_f K (1 − ln J)/J² where the
    /// medium is compressed; default 1).
    pub c_f: Option<Spanned<f64>>,
    /// Slip viscosity η_s ≥ 0 (stress × time): slipping takes a traction μ p_n + η_s |ġ_p|,
    /// ġ_p the slip rate per reference thickness (default 0: rate-independent Coulomb).
    pub viscosity: Option<Spanned<f64>>,
    /// The normal traction Coulomb's limit takes: `"current"` (default) or `"lagged"`, the
    /// last accepted step's (the limit then stays put within a step).
    pub limit: Option<Spanned<String>>,
    /// Join the layer's cells again as its faces slide past each other (default false): a 2D
    /// layer of quadrilaterals or triangles one cell across, between a solid's face and the
    /// one it slides on, with a given `normal`.
    pub reconnect: Option<Spanned<bool>>,
    /// The medium's own law at the elastic part of its deformation, F (I − g⊗N) with g the
    /// slip accepted so far (default false): the medium neither resists the slide nor pushes
    /// the faces apart as the slide shears it.
    pub forget_slip: Option<Spanned<bool>>,
}

/// `normal` of a `friction`: given, or `"auto"` (any other word is an error at validation).
#[derive(Clone, Debug, Deserialize)]
#[serde(
    untagged,
    expecting = "`normal` must be \"auto\" or the slip plane's normal as numbers, such as [0, 1]"
)]
pub enum SlipNormal {
    Given(Vec<f64>),
    Word(String),
}

impl Region {
    /// Whether the region is a medium made again between the bodies as they move.
    pub fn remakes(&self) -> bool {
        self.remake.as_ref().is_some_and(|r| *r.get_ref())
    }

    /// Whether the region is a medium made again whose mechanics are settled after each
    /// remake (`settle`), what the remake changed measured there.
    pub fn settles(&self) -> bool {
        self.remakes() && self.settle.as_ref().is_some_and(|s| *s.get_ref())
    }
}

impl FrictionKey {
    /// The fraction of the dissipation that becomes heat.
    pub fn heat_fraction(&self) -> f64 {
        self.heat_fraction.as_ref().map_or(1.0, |v| *v.get_ref())
    }

    /// The slip viscosity η_s (0 when not given).
    pub fn viscosity(&self) -> f64 {
        self.viscosity.as_ref().map_or(0.0, |v| *v.get_ref())
    }

    /// Whether the limit takes the last accepted step's normal traction.
    pub fn lagged_limit(&self) -> bool {
        self.limit.as_ref().is_some_and(|w| w.get_ref() == "lagged")
    }

    /// Whether the layer's cells are joined again as its faces slide.
    pub fn reconnect(&self) -> bool {
        self.reconnect.as_ref().is_some_and(|r| *r.get_ref())
    }

    /// Whether the medium's own law takes the elastic part of its deformation.
    pub fn forget_slip(&self) -> bool {
        self.forget_slip.as_ref().is_some_and(|r| *r.get_ref())
    }
}

/// A region's material: what its keys give once checked (a law a variant, every modulus it
/// needs present and in range, defaults filled in).
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    Solid(SolidMaterial),
    Medium(MediumMaterial),
}

/// A solid region's material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolidMaterial {
    /// `law` with its moduli, `alpha` and `theta0`.
    pub law: SolidLaw,
    /// `k`, where given.
    pub k: Option<f64>,
}

/// A medium region's material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumMaterial {
    /// Eq. (12) with K = μ = `gamma` (eq. 13).
    pub law: ThermoElastic,
    pub conduction: MediumConduction,
    /// The regularization weights β1 and β2 of eq. (20) (1 and 1e-2 unless given).
    pub beta1: f64,
    pub beta2: f64,
    /// α_r of eq. (18), where given.
    pub alpha_r: Option<f64>,
}

/// A medium region's conductivity law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MediumConduction {
    /// The paper's k_TM (1 + ln² J) with k_TM = `k` where given, capped at `k_max` where given
    /// (else at the solids' largest k), and at h_c t0 J (`h_closed` × `thickness`) where given.
    Paper {
        k_tm: Option<f64>,
        k_max: Option<f64>,
        hc_t0: Option<f64>,
    },
    /// `k_table`: k against J ([`Conductivity::Table`]).
    Table(Conductivity),
}

impl Material {
    /// The stress law: a solid's, or the medium's eq. (13).
    pub fn law(&self) -> SolidLaw {
        match self {
            Material::Solid(s) => s.law,
            Material::Medium(m) => SolidLaw::NeoHooke(m.law),
        }
    }

    /// The medium's material, if the region is one.
    pub fn medium(&self) -> Option<&MediumMaterial> {
        match self {
            Material::Solid(_) => None,
            Material::Medium(m) => Some(m),
        }
    }

    /// Whether the region gives its conductivity (`k`, or a medium's `k_table`): a scene that
    /// conducts needs it.
    pub fn gives_conductivity(&self) -> bool {
        match self {
            Material::Solid(s) => s.k.is_some(),
            Material::Medium(m) => match m.conduction {
                MediumConduction::Paper { k_tm, .. } => k_tm.is_some(),
                MediumConduction::Table(_) => true,
            },
        }
    }

    /// The conductivity law: a solid's constant `k` (1 unless given), a medium's with k_TM =
    /// `k` (1 unless given) capped at `k_max`, or else at the largest of `solids_k`, the solids'
    /// largest k, and its own k_TM.
    pub fn conductivity(&self, solids_k: f64) -> Conductivity {
        match self {
            Material::Solid(s) => Conductivity::Constant(s.k.unwrap_or(1.0)),
            Material::Medium(m) => match m.conduction {
                MediumConduction::Table(table) => table,
                MediumConduction::Paper { k_tm, k_max, hc_t0 } => {
                    let k_tm = k_tm.unwrap_or(1.0);
                    let k_max = k_max.unwrap_or(solids_k.max(k_tm));
                    match hc_t0 {
                        Some(hc_t0) => Conductivity::Closed { k_tm, k_max, hc_t0 },
                        None => Conductivity::Medium { k_tm, k_max },
                    }
                }
            },
        }
    }
}

impl MediumMaterial {
    /// The regularization of eq. (20) over the mesh's extent `d` (eq. 21); `remade`: the
    /// region is made again as the bodies move, and its penalty is taken per current volume.
    pub fn regularization(&self, d: f64, remade: bool) -> Regularization {
        Regularization {
            beta1: self.beta1,
            beta2: self.beta2,
            d,
            volume_power: if remade { 2 } else { 0 },
        }
    }

    /// A quadratic medium's weight γ α_r of eq. (18): `alpha_r` given, or β2 d², which weighs
    /// |∇f|² as eq. (20) does with p = d f.
    pub fn direct_regularization(&self, d: f64) -> f64 {
        match self.alpha_r {
            Some(a) => self.law.K * a,
            None => self.beta2 * d * d,
        }
    }
}

/// Keys by name.
type Keys<'a> = [(&'a str, &'a Option<Spanned<f64>>)];

/// The checks of one region's keys, with what names it in a message.
struct RegionKeys<'a> {
    case: &'a Case,
    i: usize,
    r: &'a Region,
}

impl RegionKeys<'_> {
    fn fail<T>(&self, span: std::ops::Range<usize>, msg: String) -> Result<T, CaseError> {
        let (i, name) = (self.i, self.r.group.get_ref());
        self.case
            .error(span, format!("region[{i}] (\"{name}\"): {msg}"))
    }

    fn positive_if_given(&self, key: &str, v: &Option<Spanned<f64>>) -> Result<(), CaseError> {
        self.check_if_given(key, v, |v| v > 0.0, "positive")
    }

    /// An error at `v` when it is given and not `ok`: "`key` must be `must`, got …".
    fn check_if_given(
        &self,
        key: &str,
        v: &Option<Spanned<f64>>,
        ok: impl Fn(f64) -> bool,
        must: &str,
    ) -> Result<(), CaseError> {
        match v {
            Some(v) if !ok(*v.get_ref()) => self.fail(
                v.span(),
                format!("`{key}` must be {must}, got {}", v.get_ref()),
            ),
            _ => Ok(()),
        }
    }

    fn need(&self, key: &str, v: &Option<Spanned<f64>>) -> Result<(), CaseError> {
        if v.is_none() {
            return self.fail(self.r.group.span(), format!("`{key}` is required"));
        }
        self.positive_if_given(key, v)
    }

    /// An error at the first of `keys` given, saying `why` it does not belong.
    fn refuse(&self, keys: &Keys, why: &str) -> Result<(), CaseError> {
        match keys
            .iter()
            .find_map(|(key, v)| v.as_ref().map(|v| (key, v)))
        {
            Some((key, v)) => self.fail(v.span(), format!("`{key}` {why}")),
            None => Ok(()),
        }
    }

    /// A solid's material: `K`, its law's moduli, no medium key.
    fn solid(&self) -> Result<Material, CaseError> {
        let r = self.r;
        self.need("K", &r.K)?;
        let law = self.solid_law()?;
        self.positive_if_given("k", &r.k)?;
        self.refuse(
            &[
                ("gamma", &r.gamma),
                ("k_max", &r.k_max),
                ("h_closed", &r.h_closed),
                ("thickness", &r.thickness),
                ("beta1", &r.beta1),
                ("beta2", &r.beta2),
                ("alpha_r", &r.alpha_r),
            ],
            "is a medium key; this region is a solid",
        )?;
        // the medium keys that are not numbers
        let spans = [
            (
                "k_table",
                r.k_table.as_ref().map(|v| v.span()),
                " (its conductivity is `k`)",
            ),
            ("remake", r.remake.as_ref().map(|v| v.span()), ""),
            ("settle", r.settle.as_ref().map(|v| v.span()), ""),
        ];
        if let Some((key, span, hint)) = (spans.into_iter()).find_map(|(k, s, h)| Some((k, s?, h)))
        {
            return self.fail(
                span,
                format!("`{key}` is a medium key; this region is a solid{hint}"),
            );
        }
        Ok(Material::Solid(SolidMaterial {
            law,
            k: given(&r.k),
        }))
    }

    /// A medium's material: `gamma`, its conductivity law, its weights, no solid key.
    fn medium(&self) -> Result<Material, CaseError> {
        let r = self.r;
        self.need("gamma", &r.gamma)?;
        for (key, v) in [
            ("k", &r.k),
            ("k_max", &r.k_max),
            ("beta1", &r.beta1),
            ("beta2", &r.beta2),
            ("alpha_r", &r.alpha_r),
        ] {
            self.positive_if_given(key, v)?;
        }
        let conduction = self.medium_conduction()?;
        self.refuse(
            &[("K", &r.K), ("mu", &r.mu), ("C10", &r.C10), ("C01", &r.C01)],
            "is a solid key; the medium's moduli are `gamma`",
        )?;
        if r.remakes() {
            self.refuse(
                &[("rho", &r.rho), ("rho_c", &r.rho_c)],
                "is not carried across a remake yet: a medium made again takes none (give \
                 it to the solids)",
            )?;
        } else if let Some(settle) = &r.settle {
            return self.fail(
                settle.span(),
                "`settle` settles the mechanics after each remake of the medium; it needs \
                 `remake = true`"
                    .into(),
            );
        }
        if let Some(law) = &r.law {
            return self.fail(
                law.span(),
                "`law` chooses a solid's law; the medium's is eq. (13), Neo-Hooke with K = μ = \
                 `gamma`"
                    .into(),
            );
        }
        let or = |v: &Option<Spanned<f64>>, default: f64| given(v).unwrap_or(default);
        let gamma = or(&r.gamma, 0.0);
        Ok(Material::Medium(MediumMaterial {
            law: ThermoElastic {
                K: gamma,
                mu: gamma,
                alpha: r.alpha,
                theta0: r.theta0,
            },
            conduction,
            beta1: or(&r.beta1, 1.0),
            beta2: or(&r.beta2, 1e-2),
            alpha_r: given(&r.alpha_r),
        }))
    }
}

/// A key's value, where given.
fn given(v: &Option<Spanned<f64>>) -> Option<f64> {
    v.as_ref().map(|v| *v.get_ref())
}

impl Case {
    /// Every region's material, in case order: its kind's required moduli positive, no key of
    /// the other kind, a positive finite `rho_c` and `rho`.
    pub(super) fn check_regions(&self) -> Result<Vec<Material>, CaseError> {
        let f = &self.file;
        let mut materials = Vec::with_capacity(f.region.len());
        for (i, r) in f.region.iter().enumerate() {
            let keys = RegionKeys { case: self, i, r };
            keys.check_if_given(
                "rho_c",
                &r.rho_c,
                |v| v > 0.0 && v.is_finite(),
                "positive and finite",
            )?;
            keys.check_if_given(
                "rho",
                &r.rho,
                |v| v > 0.0 && v.is_finite(),
                "positive and finite",
            )?;
            if let Some(fr) = &r.friction {
                if r.kind == RegionKind::Solid {
                    return keys.fail(
                        fr.span(),
                        "`friction` acts in a medium's slip plane; this region is a solid (give \
                         it to the medium region between the bodies)"
                            .into(),
                    );
                }
                keys.friction(fr.get_ref())?;
            }
            materials.push(match r.kind {
                RegionKind::Solid => keys.solid()?,
                RegionKind::Medium => keys.medium()?,
            });
        }
        self.alike_on_every_medium()?;
        Ok(materials)
    }

    /// The medium region that asks to be made again as the bodies move (`remake`), if any
    /// (then every medium region asks, as `alike_on_every_medium` checks).
    pub fn remade_medium(&self) -> Option<&str> {
        (self.file.region.iter())
            .find(|r| r.remakes())
            .map(|r| r.group.get_ref().as_str())
    }

    /// `remake` and `settle` given alike on every medium region: a remake makes every medium
    /// region again and settles them all, so either given on one region acts on the others
    /// too (a medium not asking for it was made again, its `rho` with it, and the run then
    /// failed with words about a restart).
    fn alike_on_every_medium(&self) -> Result<(), CaseError> {
        let media: Vec<(usize, &Region)> = (self.file.region.iter().enumerate())
            .filter(|(_, r)| r.kind == RegionKind::Medium)
            .collect();
        type Asks = fn(&Region) -> bool;
        let asked: [(&str, Asks); 2] = [("remake", Region::remakes), ("settle", Region::settles)];
        for (key, asks) in asked {
            let (Some((i, first)), Some((j, other))) = (
                media.iter().find(|(_, r)| asks(r)),
                media.iter().find(|(_, r)| !asks(r)),
            ) else {
                continue;
            };
            let keys = RegionKeys {
                case: self,
                i: *j,
                r: other,
            };
            return keys.fail(
                other.group.span(),
                format!(
                    "has no `{key} = true` while region[{i}] (\"{}\") has it: `{key}` acts on \
                     the whole medium (a remake makes every medium region again), so give it on \
                     every medium region or on none",
                    first.group.get_ref()
                ),
            );
        }
        Ok(())
    }
}

impl RegionKeys<'_> {
    /// A medium's conductivity law: the paper's (`k`, `k_max`), capped by a closed layer's
    /// conductance (`h_closed` with `thickness`), or a table (`k_table`, alone).
    #[allow(non_snake_case)]
    fn medium_conduction(&self) -> Result<MediumConduction, CaseError> {
        let r = self.r;
        for (key, v) in [("h_closed", &r.h_closed), ("thickness", &r.thickness)] {
            self.check_if_given(key, v, |v| v > 0.0 && v.is_finite(), "positive")?;
        }
        match (&r.h_closed, &r.thickness) {
            (Some(h), None) => {
                return self.fail(
                    h.span(),
                    "`h_closed` needs `thickness`, the layer's undeformed thickness".into(),
                );
            }
            (None, Some(t)) => {
                return self.fail(
                    t.span(),
                    "`thickness` is that of a closed layer whose conductance is `h_closed`; give `h_closed` too".into(),
                );
            }
            _ => {}
        }
        let Some(table) = &r.k_table else {
            return Ok(MediumConduction::Paper {
                k_tm: given(&r.k),
                k_max: given(&r.k_max),
                hc_t0: given(&r.h_closed)
                    .zip(given(&r.thickness))
                    .map(|(h, t)| h * t),
            });
        };
        self.refuse(
            &[("k", &r.k), ("k_max", &r.k_max), ("h_closed", &r.h_closed)],
            "and `k_table` are two conductivity laws; give one",
        )?;
        let bad = |why: &str| {
            self.fail(
                table.span(),
                format!(
                    "`k_table` {why} (rows [J, k]: 2 to {TABLE_POINTS}, J > 0 all different, k > 0)"
                ),
            )
        };
        let mut rows = table.get_ref().clone();
        if !(2..=TABLE_POINTS).contains(&rows.len()) {
            return bad(&format!("has {} rows", rows.len()));
        }
        if let Some((n, row)) = rows
            .iter()
            .enumerate()
            .find(|(_, row)| row.len() != 2 || !row.iter().all(|v| *v > 0.0 && v.is_finite()))
        {
            return bad(&format!("row {n} is {row:?}"));
        }
        rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
        if let Some(w) = rows.windows(2).find(|w| w[0][0] == w[1][0]) {
            return bad(&format!("gives J = {} twice", w[0][0]));
        }
        let (mut J, mut k) = ([0.0; TABLE_POINTS], [0.0; TABLE_POINTS]);
        for (i, row) in rows.iter().enumerate() {
            (J[i], k[i]) = (row[0], row[1]);
        }
        Ok(MediumConduction::Table(Conductivity::Table {
            n: rows.len(),
            J,
            k,
        }))
    }

    /// A solid region's law and its moduli: Neo-Hooke's `mu` > 0, or Mooney-Rivlin's `C10` > 0
    /// and `C01` ≥ 0; no key of the other law.
    #[allow(non_snake_case)]
    fn solid_law(&self) -> Result<SolidLaw, CaseError> {
        let r = self.r;
        let law = r
            .law
            .as_ref()
            .map_or(SolidLawKey::NeoHooke, |l| *l.get_ref());
        type Needed<'a> = &'a [(&'a str, &'a Option<Spanned<f64>>, bool)];
        let (needed, other): (Needed, &Keys) = match law {
            SolidLawKey::NeoHooke => (&[("mu", &r.mu, true)], &[("C10", &r.C10), ("C01", &r.C01)]),
            SolidLawKey::MooneyRivlin => (
                &[("C10", &r.C10, true), ("C01", &r.C01, false)],
                &[("mu", &r.mu)],
            ),
        };
        let law_name = match law {
            SolidLawKey::NeoHooke => "neo-hooke",
            SolidLawKey::MooneyRivlin => "mooney-rivlin",
        };
        self.refuse(
            other,
            &format!(
                "is not a key of law \"{law_name}\" (neo-hooke takes `K` and `mu`; mooney-rivlin \
                 `K`, `C10` and `C01`)"
            ),
        )?;
        for &(key, v, positive) in needed {
            let Some(v) = v else {
                let at = r.law.as_ref().map_or(r.group.span(), |l| l.span());
                return self.fail(at, format!("law \"{law_name}\" needs `{key}`"));
            };
            let x = *v.get_ref();
            let ok = x.is_finite() && if positive { x > 0.0 } else { x >= 0.0 };
            if !ok {
                let must = if positive { "positive" } else { "≥ 0" };
                return self.fail(v.span(), format!("`{key}` must be {must}, got {x}"));
            }
        }
        let v = |key: &Option<Spanned<f64>>| given(key).unwrap_or(0.0);
        let (K, alpha, theta0) = (v(&r.K), r.alpha, r.theta0);
        Ok(match law {
            SolidLawKey::NeoHooke => SolidLaw::NeoHooke(ThermoElastic {
                K,
                mu: v(&r.mu),
                alpha,
                theta0,
            }),
            SolidLawKey::MooneyRivlin => SolidLaw::MooneyRivlin(MooneyRivlin {
                C10: v(&r.C10),
                C01: v(&r.C01),
                K,
                alpha,
                theta0,
            }),
        })
    }

    /// A medium region's `friction`: μ ≥ 0, a normal of 2 or 3 finite components not all
    /// zero or "auto", `heat_fraction` in [0, 1], `c_f` positive, `viscosity` ≥ 0, `limit`
    /// "current" or "lagged" (the normal's dimension is checked against the mesh's in
    /// `model::validate`).
    fn friction(&self, fr: &FrictionKey) -> Result<(), CaseError> {
        let mu = *fr.mu.get_ref();
        if !(mu >= 0.0 && mu.is_finite()) {
            return self.fail(
                fr.mu.span(),
                format!("`friction.mu` must be finite and ≥ 0, got {mu}"),
            );
        }
        let bad_normal = |got: String| {
            self.fail(
                fr.normal.span(),
                format!(
                    "`friction.normal` must be \"auto\" or a vector of 2 (2D) or 3 (3D) finite components, not all zero; got {got}"
                ),
            )
        };
        match fr.normal.get_ref() {
            SlipNormal::Given(n) => {
                let length = n.iter().map(|v| v * v).sum::<f64>().sqrt();
                if !(2..=3).contains(&n.len())
                    || !n.iter().all(|v| v.is_finite())
                    || !(length > 0.0)
                {
                    return bad_normal(format!("{n:?}"));
                }
            }
            SlipNormal::Word(w) if w != "auto" => return bad_normal(format!("\"{w}\"")),
            SlipNormal::Word(_) => {}
        }
        self.check_if_given(
            "friction.heat_fraction",
            &fr.heat_fraction,
            |v| (0.0..=1.0).contains(&v),
            "in [0, 1]",
        )?;
        self.check_if_given(
            "friction.c_f",
            &fr.c_f,
            |v| v > 0.0 && v.is_finite(),
            "positive and finite",
        )?;
        self.check_if_given(
            "friction.viscosity",
            &fr.viscosity,
            |v| v >= 0.0 && v.is_finite(),
            "finite and ≥ 0",
        )?;
        if let Some(r) = &fr.reconnect
            && *r.get_ref()
            && matches!(fr.normal.get_ref(), SlipNormal::Word(_))
        {
            return self.fail(
                r.span(),
                "`friction.reconnect` joins a flat layer's cells again along one direction: \
                 give the layer's `normal` (such as [0, 1]), not \"auto\""
                    .to_string(),
            );
        }
        if let Some(f) = &fr.forget_slip
            && *f.get_ref()
            && fr.reconnect()
        {
            return self.fail(
                f.span(),
                "`friction.forget_slip` cannot go with `friction.reconnect`: a join rewrites \
                 each point's slip as the negative of its elastic shear, which a forgotten slip \
                 would then take for distortion; choose one"
                    .to_string(),
            );
        }
        if let Some(w) = &fr.limit
            && !["current", "lagged"].contains(&w.get_ref().as_str())
        {
            return self.fail(
                w.span(),
                format!(
                    "`friction.limit` must be \"current\" or \"lagged\", got \"{}\"",
                    w.get_ref()
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{parsed, refused};
    use super::{Material, MediumMaterial};
    use crate::material::{Conductivity, SolidLaw};

    const SOLID: &str = "[[region]]\ngroup = \"s\"\nkind = \"solid\"\n";
    const MEDIUM: &str = "[[region]]\ngroup = \"m\"\nkind = \"medium\"\ngamma = 1e-4\n";

    fn region(body: &str) -> super::Region {
        parsed(body).unwrap().file.region.remove(0)
    }

    fn material(body: &str) -> Material {
        parsed(body).unwrap().materials.remove(0)
    }

    fn medium(body: &str) -> MediumMaterial {
        *material(body).medium().expect("a medium")
    }

    #[test]
    fn a_solid_s_keys_give_its_law() {
        let nh = material(&format!(
            "{SOLID}K = 20.0\nmu = 10.0\nalpha = 1e-5\ntheta0 = 20.0\n"
        ));
        let SolidLaw::NeoHooke(l) = nh.law() else {
            panic!("neo-hooke is the default")
        };
        assert_eq!((l.K, l.mu, l.alpha, l.theta0), (20.0, 10.0, 1e-5, 20.0));
        let mr = material(&format!(
            "{SOLID}law = \"mooney-rivlin\"\nK = 20.0\nC10 = 3.0\nC01 = 1.0\n"
        ));
        let SolidLaw::MooneyRivlin(l) = mr.law() else {
            panic!("mooney-rivlin asked for")
        };
        assert_eq!((l.C10, l.C01, l.K), (3.0, 1.0, 20.0));
    }

    #[test]
    fn remake_and_settle_are_given_on_every_medium_region_or_on_none() {
        let second = "[[region]]\ngroup = \"far\"\nkind = \"medium\"\ngamma = 1e-4\n";
        let e = refused(&format!("{MEDIUM}remake = true\n\n{second}"));
        assert_eq!(
            e,
            "t.toml:9: region[1] (\"far\"): has no `remake = true` while region[0] (\"m\") has \
             it: `remake` acts on the whole medium (a remake makes every medium region again), \
             so give it on every medium region or on none"
        );
        // the other way round, and `settle` alike
        let e = refused(&format!("{MEDIUM}\n{second}remake = true\n"));
        assert!(
            e.starts_with("t.toml:3: region[0] (\"m\"): has no `remake"),
            "{e}"
        );
        let e = refused(&format!(
            "{MEDIUM}remake = true\nsettle = true\n\n{second}remake = true\n"
        ));
        assert!(e.contains("(\"far\"): has no `settle = true` while"), "{e}");
        // alike on both, or a solid beside them, is read
        for body in [
            format!("{MEDIUM}remake = true\n\n{second}remake = true\n\n{SOLID}K = 1.0\nmu = 1.0\n"),
            format!("{MEDIUM}\n{second}"),
        ] {
            parsed(&body).unwrap();
        }
    }

    #[test]
    fn a_medium_s_regularization_has_its_defaults_and_its_direct_weight() {
        let plain = medium(MEDIUM);
        // eq. (13): Neo-Hooke with K = μ = γ
        assert_eq!((plain.law.K, plain.law.mu), (1e-4, 1e-4));
        assert!(matches!(material(MEDIUM).law(), SolidLaw::NeoHooke(l) if l == plain.law));
        let reg = plain.regularization(2.0, false);
        assert_eq!((reg.beta1, reg.beta2, reg.d), (1.0, 1e-2, 2.0));
        // eq. (18) weighs like eq. (20) with p = d f: β2 d²
        assert_eq!(plain.direct_regularization(2.0), 1e-2 * 4.0);
        let given = medium(&format!(
            "{MEDIUM}beta1 = 0.5\nbeta2 = 0.1\nalpha_r = 3.0\n"
        ));
        let reg = given.regularization(2.0, false);
        assert_eq!((reg.beta1, reg.beta2), (0.5, 0.1));
        // α_r given: γ α_r
        assert_eq!(given.direct_regularization(2.0), 1e-4 * 3.0);
    }

    #[test]
    fn a_region_refuses_the_keys_of_another_law_or_kind() {
        let e = refused(&format!("{SOLID}K = 20.0\nmu = 10.0\ngamma = 1e-4\n"));
        assert!(
            e.starts_with("t.toml:7:")
                && e.contains("`gamma` is a medium key; this region is a solid"),
            "{e}"
        );
        let e = refused(&format!(
            "{SOLID}law = \"mooney-rivlin\"\nK = 20.0\nC01 = 1.0\n"
        ));
        assert!(e.contains("law \"mooney-rivlin\" needs `C10`"), "{e}");
        let e = refused(&format!(
            "{SOLID}law = \"mooney-rivlin\"\nK = 20.0\nC10 = 3.0\nmu = 1.0\n"
        ));
        assert!(
            e.contains("`mu` is not a key of law \"mooney-rivlin\""),
            "{e}"
        );
        let e = refused(&format!("{MEDIUM}K = 1.0\n"));
        assert!(
            e.contains("`K` is a solid key; the medium's moduli are `gamma`"),
            "{e}"
        );
        let e = refused(&format!("{SOLID}mu = 10.0\n"));
        assert!(e.contains("`K` is required"), "{e}");
    }

    #[test]
    fn a_region_s_conductivity_defaults_from_its_kind() {
        // a solid: its k, or 1
        let solid = material(&format!("{SOLID}K = 1.0\nmu = 1.0\n"));
        assert!(matches!(solid.conductivity(50.0), Conductivity::Constant(k) if k == 1.0));
        assert!(!solid.gives_conductivity());
        let solid = material(&format!("{SOLID}K = 1.0\nmu = 1.0\nk = 3.0\n"));
        assert!(matches!(solid.conductivity(50.0), Conductivity::Constant(k) if k == 3.0));
        assert!(solid.gives_conductivity());
        // a medium: capped by the solids' largest k, or its own k_TM if larger, or `k_max`
        let capped = |keys: &str, solids_k: f64| match material(&format!("{MEDIUM}{keys}"))
            .conductivity(solids_k)
        {
            Conductivity::Medium { k_tm, k_max } => (k_tm, k_max),
            other => panic!("{other:?}"),
        };
        assert_eq!(capped("k = 1e-4\n", 50.0), (1e-4, 50.0));
        assert_eq!(capped("k = 80.0\n", 50.0), (80.0, 80.0));
        assert_eq!(capped("k = 1e-4\nk_max = 5.0\n", 50.0), (1e-4, 5.0));
    }

    #[test]
    fn a_medium_s_conductivity_is_the_law_its_keys_name() {
        let paper = material(&format!("{MEDIUM}k = 1e-4\n"));
        assert!(matches!(
            paper.conductivity(50.0),
            Conductivity::Medium { k_tm, k_max } if k_tm == 1e-4 && k_max == 50.0
        ));
        let closed = material(&format!(
            "{MEDIUM}k = 1e-4\nh_closed = 40.0\nthickness = 0.25\n"
        ));
        assert!(matches!(
            closed.conductivity(50.0),
            Conductivity::Closed { hc_t0, .. } if hc_t0 == 10.0
        ));
        // a table's rows in any order, kept sorted by J
        let table = material(&format!(
            "{MEDIUM}k_table = [[1.0, 1e-4], [1e-3, 2.0], [0.1, 0.5]]\n"
        ));
        assert!(table.gives_conductivity() && !material(MEDIUM).gives_conductivity());
        let Conductivity::Table { n, J, k } = table.conductivity(0.0) else {
            panic!("a table")
        };
        assert_eq!(
            (n, &J[..3], &k[..3]),
            (3, &[1e-3, 0.1, 1.0][..], &[2.0, 0.5, 1e-4][..])
        );
        for (keys, says) in [
            ("h_closed = 40.0\n", "`h_closed` needs `thickness`"),
            (
                "k = 1.0\nk_table = [[0.1, 1.0], [1.0, 2.0]]\n",
                "two conductivity laws",
            ),
            ("k_table = [[0.1, 1.0]]\n", "has 1 rows"),
            (
                "k_table = [[0.1, 1.0], [0.1, 2.0]]\n",
                "gives J = 0.1 twice",
            ),
        ] {
            let e = refused(&format!("{MEDIUM}{keys}"));
            assert!(e.contains(says), "{keys}: {e}");
        }
    }

    #[test]
    fn friction_is_a_medium_s_and_its_values_are_checked() {
        let ok = region(&format!(
            "{MEDIUM}friction = {{ mu = 0.3, normal = \"auto\", heat_fraction = 0.5 }}\n"
        ));
        let fr = ok.friction.unwrap().into_inner();
        assert_eq!(fr.heat_fraction(), 0.5);
        assert!(fr.viscosity() == 0.0 && !fr.lagged_limit(), "the defaults");
        let ok = region(&format!(
            "{MEDIUM}friction = {{ mu = 0.3, normal = [0, 1], viscosity = 1e-3, limit = \"lagged\" }}\n"
        ));
        let fr = ok.friction.unwrap().into_inner();
        assert!(fr.viscosity() == 1e-3 && fr.lagged_limit());
        for (friction, says) in [
            (
                "{ mu = -0.1, normal = [0, 1] }",
                "`friction.mu` must be finite and ≥ 0",
            ),
            (
                "{ mu = 0.3, normal = \"up\" }",
                "`friction.normal` must be \"auto\"",
            ),
            (
                "{ mu = 0.3, normal = [0, 0] }",
                "not all zero; got [0.0, 0.0]",
            ),
            (
                "{ mu = 0.3, normal = [0, 1], heat_fraction = 2.0 }",
                "must be in [0, 1]",
            ),
            (
                "{ mu = 0.3, normal = [0, 1], c_f = 0.0 }",
                "`friction.c_f` must be positive",
            ),
            (
                "{ mu = 0.3, normal = [0, 1], viscosity = -1e-3 }",
                "`friction.viscosity` must be finite and ≥ 0, got -0.001",
            ),
            (
                "{ mu = 0.3, normal = [0, 1], limit = \"late\" }",
                "`friction.limit` must be \"current\" or \"lagged\", got \"late\"",
            ),
        ] {
            let e = refused(&format!("{MEDIUM}friction = {friction}\n"));
            assert!(e.contains(says), "{friction}: {e}");
        }
        let e = refused(&format!(
            "{SOLID}K = 1.0\nmu = 1.0\nfriction = {{ mu = 0.3, normal = [0, 1] }}\n"
        ));
        assert!(e.contains("this region is a solid"), "{e}");
    }
}
