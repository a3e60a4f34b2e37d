//! Adaptive stepping, separate from Newton: it proposes the next time t (pseudo-time, equal to
//! the load factor λ unless the case gives a load path; or physical time with `[time]`), grows
//! Δt after easy steps, cuts it after a failed one, and gives up below the minimum. It never
//! accepts a failed step, and every vertex (of the load path, or a listed time) is reached by
//! a step of its own.

use crate::case::Steps;

/// Where a controller stands: the time reached, the next increment and the steps counted.
/// What a restart carries over (the rest of the controller comes from the case).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Clock {
    pub t: f64,
    pub dt: f64,
    pub accepted: usize,
    pub rejected: usize,
}

#[derive(Clone, Debug)]
pub struct Controller {
    /// Time of the last accepted step.
    pub t: f64,
    /// Next increment Δt.
    pub dt: f64,
    /// End of time.
    pub end: f64,
    /// Times that must be steps, increasing, the last one `end`.
    vertices: Vec<f64>,
    /// Smallest and largest Δt.
    min: f64,
    max: f64,
    cfg: Steps,
    pub accepted: usize,
    pub rejected: usize,
    /// The latest the next step may end at, once (see [`Controller::cap`]).
    cap: Option<f64>,
}

impl Controller {
    /// Where the controller stands.
    pub fn clock(&self) -> Clock {
        Clock {
            t: self.t,
            dt: self.dt,
            accepted: self.accepted,
            rejected: self.rejected,
        }
    }

    /// Continue from `clock` (a restart).
    pub fn set_clock(&mut self, clock: Clock) {
        Clock {
            t: self.t,
            dt: self.dt,
            accepted: self.accepted,
            rejected: self.rejected,
        } = clock;
    }

    /// A controller over pseudo-time t ∈ [0, end], vertices at every integer, Δt as `cfg` says.
    pub fn new(cfg: &Steps, end: f64) -> Controller {
        let vertices = (1..=end.round() as usize).map(|i| i as f64).collect();
        Controller::with_vertices(cfg, vertices, cfg.initial, cfg.min, cfg.max)
    }

    /// A controller over t ∈ [0, last vertex] that steps onto every vertex, starting with Δt =
    /// `initial`, within [`min`, `max`]; growth, cuts and what makes a step easy from `cfg`.
    pub fn with_vertices(
        cfg: &Steps,
        vertices: Vec<f64>,
        initial: f64,
        min: f64,
        max: f64,
    ) -> Controller {
        Controller {
            t: 0.0,
            dt: initial,
            end: *vertices.last().expect("at least the end"),
            vertices,
            min,
            max,
            cfg: cfg.clone(),
            accepted: 0,
            rejected: 0,
            cap: None,
        }
    }

    /// Let the next step end at `until` at the latest (if it is after the last accepted
    /// time): once, the step after it as long as it would have been.
    pub fn cap(&mut self, until: f64) {
        if until > self.t + self.eps() {
            self.cap = Some(self.cap.map_or(until, |c| c.min(until)));
        }
    }

    pub fn done(&self) -> bool {
        self.t >= self.end
    }

    /// Tolerance of "at a vertex", relative to the time scale.
    fn eps(&self) -> f64 {
        1e-9 * self.end.max(1e-300)
    }

    /// The first vertex after the last accepted time.
    fn next_vertex(&self) -> f64 {
        let eps = self.eps();
        let i = self.vertices.partition_point(|&v| v <= self.t + eps);
        self.vertices.get(i).copied().unwrap_or(self.end)
    }

    /// Whether the last accepted time is a vertex before the end: the next step starts a new
    /// segment of the load path.
    pub fn at_vertex(&self) -> bool {
        let eps = self.eps();
        !self.done() && self.vertices.iter().any(|&v| (v - self.t).abs() <= eps)
    }

    /// Target time of the next attempt: never past the next vertex, and no sliver left
    /// before it.
    pub fn target(&self) -> f64 {
        let vertex = self.next_vertex();
        let t = self.t + self.dt;
        if let Some(cap) = self.cap.filter(|&c| c < t.min(vertex)) {
            return cap;
        }
        if t > vertex - self.eps() || vertex - t < 0.2 * self.dt {
            vertex
        } else {
            t
        }
    }

    /// Record a converged step that took `iterations` Newton iterations.
    pub fn accept(&mut self, target: f64, iterations: usize) {
        let taken = target - self.t;
        // a step cut short to land on a vertex says nothing about the step size
        let capped = self.cap.take() == Some(target);
        let at_vertex = capped || self.vertices.contains(&target);
        if !(at_vertex && taken < self.dt) {
            self.dt = taken;
        }
        self.t = target;
        self.accepted += 1;
        if iterations <= self.cfg.easy_iter {
            self.dt *= self.cfg.grow;
        } else if iterations * 4 >= self.cfg.max_iter * 3 {
            self.dt *= 0.7; // hard step: be careful next time
        }
        self.dt = self.dt.clamp(self.min, self.max);
    }

    /// Record a failed attempt that is tried again at the same Δt (from a state changed since).
    pub fn retry(&mut self) {
        self.rejected += 1;
    }

    /// Record a failed attempt; `Err` with the Δt that failed when it is below the minimum.
    pub fn reject(&mut self) -> Result<(), f64> {
        self.rejected += 1;
        let failed = self.dt.min(self.target() - self.t);
        self.dt = failed * self.cfg.cut;
        if self.dt < self.min {
            return Err(failed);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grows_cuts_and_gives_up() {
        let cfg = Steps {
            initial: 0.1,
            min: 0.01,
            max: 0.5,
            ..Default::default()
        };
        let mut c = Controller::new(&cfg, 1.0);
        let t = c.target();
        assert!((t - 0.1).abs() < 1e-15);
        c.accept(t, 2);
        assert!((c.dt - 0.15).abs() < 1e-12);
        assert!(c.reject().is_ok());
        assert!((c.dt - 0.0375).abs() < 1e-12);
        assert!(c.reject().is_err(), "0.0375 * 0.25 < min");
        // last step lands exactly on 1
        let mut c = Controller::new(&cfg, 1.0);
        while !c.done() {
            let t = c.target();
            c.accept(t, 3);
        }
        assert_eq!(c.t, 1.0);
    }

    #[test]
    fn every_path_vertex_is_a_step() {
        let cfg = Steps {
            initial: 0.3,
            min: 0.01,
            max: 0.5,
            ..Default::default()
        };
        let mut c = Controller::new(&cfg, 3.0);
        let mut seen = Vec::new();
        while !c.done() {
            let t = c.target();
            assert!(t > c.t && t - c.t <= 0.5 + 1e-12);
            c.accept(t, 3);
            seen.push(t);
        }
        for v in [1.0, 2.0, 3.0] {
            assert!(seen.contains(&v), "vertex {v} missed: {seen:?}");
        }
        // standing on each vertex but the end, and only there, a new segment is next
        let mut c = Controller::new(&cfg, 3.0);
        assert!(!c.at_vertex(), "the start is no vertex");
        while !c.done() {
            let t = c.target();
            c.accept(t, 3);
            assert_eq!(c.at_vertex(), t == 1.0 || t == 2.0, "at {t}");
        }
        // a step shortened to reach a vertex does not shrink the next one
        let i = seen.iter().position(|&t| t == 1.0).unwrap();
        assert!(seen[i + 1] - 1.0 >= seen[i] - seen[i - 1] - 1e-12);
    }

    #[test]
    fn fixed_time_steps_land_on_listed_times_and_never_exceed_dt() {
        let cfg = Steps::default();
        let (dt, vertices) = (0.1, vec![0.25, 0.5, 1.0]);
        let mut c = Controller::with_vertices(&cfg, vertices.clone(), dt, dt * 1e-3, dt);
        let mut seen = Vec::new();
        while !c.done() {
            let t = c.target();
            assert!(t - c.t <= dt + 1e-12, "step {} > dt", t - c.t);
            c.accept(t, 1);
            seen.push(t);
        }
        for v in vertices {
            assert!(seen.contains(&v), "{v} missed: {seen:?}");
        }
        assert_eq!(c.t, 1.0);
        // 0.1, 0.2, 0.25, 0.35, 0.45, 0.5, 0.6, … 1.0
        assert_eq!(seen.len(), 3 + 5 + 3);
    }

    #[test]
    fn a_cap_cuts_one_step_and_not_the_next() {
        let cfg = Steps {
            initial: 0.1,
            min: 0.001,
            max: 0.1,
            ..Default::default()
        };
        let mut c = Controller::new(&cfg, 1.0);
        c.accept(c.target(), 3);
        // a cap at or before the last accepted time asks nothing
        c.cap(0.1);
        assert!((c.target() - 0.2).abs() < 1e-12);
        c.cap(0.13);
        c.cap(0.17);
        assert_eq!(c.target(), 0.13, "the earlier of two caps");
        assert!(c.reject().is_ok());
        assert!(c.target() < 0.13, "a failed capped step is cut further");
        c.dt = 0.1;
        assert_eq!(c.target(), 0.13);
        c.accept(0.13, 3);
        assert!(
            (c.target() - 0.23).abs() < 1e-12,
            "then a whole step: {}",
            c.target()
        );
        // a cap past the step leaves it as it was
        c.cap(0.5);
        assert!((c.target() - 0.23).abs() < 1e-12);
    }
}
