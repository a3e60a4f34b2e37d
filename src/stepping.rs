//! Adaptive load stepping, separate from Newton: it proposes the next load factor, grows Δλ
//! after easy steps, cuts it after a failed one, and gives up below the minimum. It never
//! accepts a failed step.

use crate::case::Steps;

#[derive(Clone, Debug)]
pub struct Controller {
    pub lambda: f64,
    pub dlambda: f64,
    cfg: Steps,
    pub accepted: usize,
    pub rejected: usize,
}

impl Controller {
    pub fn new(cfg: &Steps) -> Controller {
        Controller {
            lambda: 0.0,
            dlambda: cfg.initial,
            cfg: cfg.clone(),
            accepted: 0,
            rejected: 0,
        }
    }

    pub fn done(&self) -> bool {
        self.lambda >= 1.0
    }

    /// Target load factor of the next attempt.
    pub fn target(&self) -> f64 {
        let t = self.lambda + self.dlambda;
        // do not leave a sliver below 1
        if t > 1.0 - 1e-9 || 1.0 - t < 0.2 * self.dlambda {
            1.0
        } else {
            t
        }
    }

    /// Record a converged step that took `iterations` Newton iterations.
    pub fn accept(&mut self, target: f64, iterations: usize) {
        self.dlambda = target - self.lambda;
        self.lambda = target;
        self.accepted += 1;
        if iterations <= self.cfg.easy_iter {
            self.dlambda *= self.cfg.grow;
        } else if iterations * 4 >= self.cfg.max_iter * 3 {
            self.dlambda *= 0.7; // hard step: be careful next time
        }
        self.dlambda = self.dlambda.clamp(self.cfg.min, self.cfg.max);
    }

    /// Record a failed attempt; `Err` with the Δλ that failed when it is below the minimum.
    pub fn reject(&mut self) -> Result<(), f64> {
        self.rejected += 1;
        let failed = self.dlambda;
        self.dlambda *= self.cfg.cut;
        if self.dlambda < self.cfg.min {
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
        let mut c = Controller::new(&cfg);
        let t = c.target();
        assert!((t - 0.1).abs() < 1e-15);
        c.accept(t, 2);
        assert!((c.dlambda - 0.15).abs() < 1e-12);
        assert!(c.reject().is_ok());
        assert!((c.dlambda - 0.0375).abs() < 1e-12);
        assert!(c.reject().is_err(), "0.0375 * 0.25 < min");
        // last step lands exactly on 1
        let mut c = Controller::new(&cfg);
        while !c.done() {
            let t = c.target();
            c.accept(t, 3);
        }
        assert_eq!(c.lambda, 1.0);
    }
}
