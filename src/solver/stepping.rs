//! Adaptive load stepping, separate from Newton: it proposes the next pseudo-time t (equal to
//! the load factor λ unless the case gives a load path), grows Δt after easy steps, cuts it
//! after a failed one, and gives up below the minimum. It never accepts a failed step, and
//! every integer t (a vertex of the load path) is reached by a step of its own.

use crate::case::Steps;

#[derive(Clone, Debug)]
pub struct Controller {
    /// Pseudo-time of the last accepted step.
    pub t: f64,
    /// Next increment Δt.
    pub dt: f64,
    /// End of pseudo-time.
    pub end: f64,
    cfg: Steps,
    pub accepted: usize,
    pub rejected: usize,
}

impl Controller {
    /// A controller over t ∈ [0, end].
    pub fn new(cfg: &Steps, end: f64) -> Controller {
        Controller {
            t: 0.0,
            dt: cfg.initial,
            end,
            cfg: cfg.clone(),
            accepted: 0,
            rejected: 0,
        }
    }

    pub fn done(&self) -> bool {
        self.t >= self.end
    }

    /// Target pseudo-time of the next attempt: never past the next path vertex, and no sliver
    /// left before it.
    pub fn target(&self) -> f64 {
        let vertex = (self.t + 1e-9).floor() + 1.0;
        let t = self.t + self.dt;
        if t > vertex - 1e-9 || vertex - t < 0.2 * self.dt {
            vertex
        } else {
            t
        }
    }

    /// Record a converged step that took `iterations` Newton iterations.
    pub fn accept(&mut self, target: f64, iterations: usize) {
        let taken = target - self.t;
        // a step cut short to land on a path vertex says nothing about the step size
        if !(target.fract() == 0.0 && taken < self.dt) {
            self.dt = taken;
        }
        self.t = target;
        self.accepted += 1;
        if iterations <= self.cfg.easy_iter {
            self.dt *= self.cfg.grow;
        } else if iterations * 4 >= self.cfg.max_iter * 3 {
            self.dt *= 0.7; // hard step: be careful next time
        }
        self.dt = self.dt.clamp(self.cfg.min, self.cfg.max);
    }

    /// Record a failed attempt; `Err` with the Δλ that failed when it is below the minimum.
    pub fn reject(&mut self) -> Result<(), f64> {
        self.rejected += 1;
        let failed = self.dt.min(self.target() - self.t);
        self.dt = failed * self.cfg.cut;
        if self.dt < self.cfg.min {
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
        // a step shortened to reach a vertex does not shrink the next one
        let i = seen.iter().position(|&t| t == 1.0).unwrap();
        assert!(seen[i + 1] - 1.0 >= seen[i] - seen[i - 1] - 1e-12);
    }
}
