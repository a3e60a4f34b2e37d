//! History per quadrature point: values a kernel reads from the last accepted step
//! (`committed`) and writes for the state being tried (`trial`). Accepting a step commits the
//! trial values; rejecting one restores them, so a failed attempt leaves no trace.

/// The history of one assembler block: `width` values per cell.
#[derive(Clone, Debug)]
pub struct Slab {
    pub width: usize,
    pub committed: Vec<f64>,
    pub trial: Vec<f64>,
}

impl Slab {
    /// `cells` cells of `width` values each, all `value`.
    pub fn new(cells: usize, width: usize, value: f64) -> Slab {
        Slab {
            width,
            committed: vec![value; cells * width],
            trial: vec![value; cells * width],
        }
    }
}

/// The history of every block that has one.
#[derive(Clone, Debug, Default)]
pub struct PointHistory {
    pub slabs: Vec<Slab>,
}

impl PointHistory {
    /// The trial values become the committed ones (a step was accepted).
    pub fn commit(&mut self) {
        for s in &mut self.slabs {
            s.committed.copy_from_slice(&s.trial);
        }
    }

    /// The trial values go back to the committed ones (a step was rejected).
    pub fn restore(&mut self) {
        for s in &mut self.slabs {
            s.trial.copy_from_slice(&s.committed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commit_keeps_and_restore_discards_the_trial_values() {
        let mut h = PointHistory {
            slabs: vec![Slab::new(3, 2, 1.0), Slab::new(1, 4, -2.0)],
        };
        h.slabs[0].trial[5] = 7.0;
        h.slabs[1].trial[0] = 3.0;
        h.restore();
        assert_eq!(h.slabs[0].trial, vec![1.0; 6]);
        assert_eq!(h.slabs[1].trial, vec![-2.0; 4]);
        h.slabs[0].trial[5] = 7.0;
        h.commit();
        assert_eq!(h.slabs[0].committed[5], 7.0);
        h.slabs[0].trial[5] = 9.0;
        h.restore();
        assert_eq!(h.slabs[0].trial[5], 7.0, "restored to the last commit");
    }
}
