//! `[steps]` and `[time]`: the load path and how it is stepped, or physical time; their
//! checks.

use super::{Case, CaseError, MAX_STEPS, MIN_STEP};
use serde::Deserialize;
use toml::Spanned;

/// `[steps]`: load stepping and Newton controls.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, default, expecting = "the [steps] table")]
pub struct Steps {
    /// First load increment Δλ.
    pub initial: f64,
    /// Smallest Δλ before the run gives up.
    pub min: f64,
    /// Largest Δλ.
    pub max: f64,
    /// Relative tolerance of the per-field residual and update norms.
    pub tol: f64,
    /// Newton iterations per step before the step is cut (a few more in Newton's quadratic
    /// tail: `solver::newton`).
    pub max_iter: usize,
    /// Steps converging in at most this many iterations grow Δλ.
    pub easy_iter: usize,
    /// Growth factor after an easy step.
    pub grow: f64,
    /// Cut factor after a failed step.
    pub cut: f64,
    /// Where Newton fails at the shortest step (and a medium made again does not settle),
    /// the step is taken by pseudo-transient continuation (`solver::newton::continuation`)
    /// before the run gives up; `false`: the run stops there.
    pub continuation: bool,
    /// Load path: λ at pseudo-times t = 0, 1, …, T, linear in between (default `[0, 1]`).
    /// Every value is reached by a step: e.g. `[0, 1, 0.2]` loads, then unloads to 0.2, and
    /// `[0, 0.25, 0.5, 1]` also writes the states at λ = 0.25 and 0.5.
    pub path: Option<Vec<f64>>,
}

impl Default for Steps {
    fn default() -> Self {
        Steps {
            initial: 0.1,
            min: 1e-5,
            max: 1.0,
            tol: 1e-9,
            max_iter: 16,
            easy_iter: 7,
            grow: 1.5,
            cut: 0.25,
            continuation: true,
            path: None,
        }
    }
}

/// `[time]`: physical time t ∈ [0, end] replaces the load parameter as what the steps
/// advance; loads follow λ(t).
#[derive(Clone, Debug, Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "the [time] table (end, dt, times, lambda)"
)]
pub struct Time {
    /// End time, > 0.
    pub end: Spanned<f64>,
    /// Step size Δt: steps are cut after a failure and grow back, never beyond Δt.
    pub dt: Option<Spanned<f64>>,
    /// Times that are steps of their own (and written), increasing in (0, end].
    pub times: Option<Spanned<Vec<f64>>>,
    /// The load factor over time as [[t, λ], …], piecewise linear, t increasing from 0
    /// (default `[[0, 0], [end, 1]]`).
    /// (Rows are read as lists and checked to hold two values each: a fixed-size array would
    /// drop a third silently.)
    pub lambda: Option<Spanned<Vec<Vec<f64>>>>,
}

impl Time {
    /// The times every run of this case steps onto: the `times`, the vertices of `lambda`
    /// inside (0, end), and `end`.
    pub fn vertices(&self) -> Vec<f64> {
        let end = *self.end.get_ref();
        let mut v: Vec<f64> = self
            .times
            .as_ref()
            .map_or(Vec::new(), |t| t.get_ref().clone());
        if let Some(l) = &self.lambda {
            v.extend(l.get_ref().iter().filter_map(|r| r.first().copied()));
        }
        v.push(end);
        v.retain(|&t| t > 0.0 && t <= end);
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    }

    /// The largest step: `dt`, or the longest interval between vertices.
    pub fn dt_max(&self) -> f64 {
        match &self.dt {
            Some(dt) => *dt.get_ref(),
            None => {
                let v = self.vertices();
                let mut last = 0.0;
                let mut m = 0.0f64;
                for t in v {
                    m = m.max(t - last);
                    last = t;
                }
                m
            }
        }
    }
}

impl Case {
    /// `[steps]` and `[time]`; returns how many values a group's own `path` needs.
    pub(super) fn check_steps(&self) -> Result<usize, CaseError> {
        let f = &self.file;
        let s = &f.steps;
        // each refusal at the line of the key it is about (the table's, where it is not given)
        let bad_at = |key: &str, msg: &str| {
            let at = self.key_at("steps", key);
            self.error::<()>(at..at, format!("[steps]: {msg}"))
        };
        if !(s.min > 0.0 && s.min <= s.initial && s.initial <= s.max && s.max <= 1.0) {
            let key = if !(s.min > 0.0) {
                "min"
            } else if !(s.min <= s.initial) {
                "initial"
            } else {
                "max"
            };
            bad_at(key, "need 0 < min <= initial <= max <= 1")?;
        }
        if s.min < MIN_STEP {
            bad_at(
                "min",
                &format!(
                    "min = {:e} is below {MIN_STEP:e}: a step that small changes nothing a double \
                 can hold, and cutting down to it takes thousands of failed attempts",
                    s.min
                ),
            )?;
        }
        if let Some(p) = &s.path
            && p.len() > MAX_STEPS
        {
            bad_at(
                "path",
                &format!(
                    "path has {} values; at most {MAX_STEPS} (each is at least one load step)",
                    p.len()
                ),
            )?;
        }
        if !(s.tol > 0.0 && s.tol < 1.0) {
            bad_at("tol", "tol must be in (0, 1)")?;
        }
        if s.max_iter < 2 {
            bad_at("max_iter", "max_iter must be at least 2")?;
        }
        if !(s.grow >= 1.0 && s.cut > 0.0 && s.cut < 1.0) {
            let key = if s.grow >= 1.0 { "cut" } else { "grow" };
            bad_at(key, "need grow >= 1 and 0 < cut < 1")?;
        }
        let n_path = match (&s.path, &f.time) {
            (Some(_), Some(_)) => {
                bad_at(
                    "path",
                    "`path` is over pseudo-time; with [time], give the load factor as [time] lambda = [[t, λ], …]",
                )?;
                0
            }
            (Some(p), None) if p.len() < 2 || p[0] != 0.0 || p.iter().any(|v| !v.is_finite()) => {
                bad_at(
                    "path",
                    "path needs at least two finite values, the first 0 (the unloaded state)",
                )?;
                0
            }
            (Some(p), None) => p.len(),
            (None, Some(t)) => {
                self.check_time(t)?;
                t.lambda.as_ref().map_or(2, |l| l.get_ref().len())
            }
            (None, None) => 2,
        };
        Ok(n_path)
    }

    /// `[time]`: a positive end, steps (`dt` or `times`) inside it, and a load table that
    /// starts at t = 0 and increases.
    pub(super) fn check_time(&self, t: &Time) -> Result<(), CaseError> {
        let end = *t.end.get_ref();
        if !(end > 0.0 && end.is_finite()) {
            return self.error(
                t.end.span(),
                format!("[time]: `end` must be positive and finite, got {end}"),
            );
        }
        if t.dt.is_none() && t.times.is_none() {
            return self.error(
                t.end.span(),
                "[time]: no steps; give the step size `dt` or the step times `times`",
            );
        }
        if let Some(dt) = &t.dt {
            let v = *dt.get_ref();
            if !(v > 0.0 && v <= end) {
                return self.error(
                    dt.span(),
                    format!("[time]: `dt` must be positive and at most `end` ({end}), got {v}"),
                );
            }
            if end / v > MAX_STEPS as f64 {
                return self.error(
                    dt.span(),
                    format!(
                        "[time]: end / dt = {:.3e} steps; at most {MAX_STEPS}",
                        end / v
                    ),
                );
            }
        }
        if let Some(times) = &t.times {
            let v = times.get_ref();
            if v.len() > MAX_STEPS {
                return self.error(
                    times.span(),
                    format!("[time]: {} `times`; at most {MAX_STEPS}", v.len()),
                );
            }
            let increasing = v.windows(2).all(|w| w[0] < w[1]);
            if v.is_empty() || !increasing || !(v[0] > 0.0) || !(v[v.len() - 1] <= end) {
                return self.error(
                    times.span(),
                    format!("[time]: `times` must increase within (0, end = {end}]"),
                );
            }
        }
        if let Some(l) = &t.lambda {
            let v = l.get_ref();
            if let Some((i, r)) = v.iter().enumerate().find(|(_, r)| r.len() != 2) {
                return self.error(
                    l.span(),
                    format!(
                        "[time]: `lambda` row {} has {} value{}; each row is [t, λ]",
                        i + 1,
                        r.len(),
                        if r.len() == 1 { "" } else { "s" }
                    ),
                );
            }
            let ok = v.len() >= 2
                && v[0][0] == 0.0
                && v.windows(2).all(|w| w[0][0] < w[1][0])
                && v.iter().flatten().all(|x| x.is_finite());
            if !ok {
                return self.error(
                    l.span(),
                    "[time]: `lambda` needs at least two finite [t, λ] rows, t increasing from 0",
                );
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{parsed, refused};

    #[test]
    fn time_steps_onto_its_times_the_vertices_of_lambda_and_its_end() {
        let case = parsed("[time]\nend = 4.0\ntimes = [0.5, 3.0]\nlambda = [[0.0, 0.0], [1.0, 1.0], [4.0, 1.0]]\n").unwrap();
        let time = case.file.time.unwrap();
        assert_eq!(time.vertices(), [0.5, 1.0, 3.0, 4.0]);
        // without dt, the longest interval between them
        assert_eq!(time.dt_max(), 2.0);
    }

    #[test]
    fn steps_and_time_are_checked() {
        for (body, says) in [
            (
                "[steps]\ninitial = 0.5\nmax = 0.25\n",
                "need 0 < min <= initial <= max <= 1",
            ),
            ("[steps]\ntol = 1.0\n", "tol must be in (0, 1)"),
            ("[steps]\nmax_iter = 1\n", "max_iter must be at least 2"),
            ("[steps]\ncut = 1.0\n", "0 < cut < 1"),
            ("[steps]\npath = [0.5, 1.0]\n", "the first 0"),
            ("[time]\nend = 0.0\n", "`end` must be positive"),
            ("[time]\nend = 1.0\ndt = 2.0\n", "at most `end`"),
            (
                "[time]\nend = 1.0\ntimes = [0.5, 0.2]\n",
                "`times` must increase",
            ),
        ] {
            let e = refused(body);
            assert!(e.contains(says), "{body}: {e}");
        }
    }
}
