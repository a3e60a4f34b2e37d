//! The run state: everything a run carries from one accepted step to the next, as one value.
//! A checkpoint is this value written whole, and a restart reads it back whole; what is not
//! here (the model, the solvers, the controller's limits) comes again from the case.

use super::records::{EdgeReached, Reactions};
use crate::output::history::Mark;
use crate::solver::newton::Tally;
use crate::solver::stepping::Clock;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunState {
    /// The last accepted state, and the assembler's committed history per block of points.
    pub x: Vec<f64>,
    pub point_history: Vec<Vec<f64>>,
    /// The cells' own references where a medium made again has closed layers that take their
    /// slide into them ([`crate::assembly::Assembler::absorb_closed_layers`]), per mesh block.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub references: Option<Vec<Option<Vec<[f64; 3]>>>>,
    /// The step controller: time reached, next increment, accepted and rejected steps.
    #[serde(flatten)]
    pub clock: Clock,
    pub newton: Tally,
    pub totals: Totals,
    pub files: Files,
    /// Wall seconds of the run at the last accepted step.
    pub wall: f64,
}

/// What the run has done so far, beyond the controller's counts.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Totals {
    /// Newton and Krylov iterations of the accepted steps.
    pub iterations: usize,
    pub krylov: usize,
    /// Assembly seconds of the converged states' reactions (Newton keeps the rest).
    pub t_reactions: f64,
    /// Smallest J over the accepted steps: (solids, medium); `None` while there is none.
    pub min_J: (Option<f64>, Option<f64>),
    /// Work of the forces on the displacements, and the forces of the last accepted state.
    pub work: f64,
    pub f_last: Vec<f64>,
    pub reactions: Reactions,
    /// The last failed attempt's reason.
    pub last_failure: String,
    /// Stored energy of the last accepted state, and the tangents Newton did not refactor.
    pub energy: f64,
    pub tangents_skipped: usize,
    /// Transient scenes, from their first accepted step: the heat stored, and the heat
    /// supplied over the run.
    pub heat_stored: Option<f64>,
    pub heat_in: Option<f64>,
    /// The most medium cells an accepted step left inverted at a corner shared with a solid
    /// (a checkpoint without it had none to count).
    #[serde(default)]
    pub corners_through: usize,
    /// The largest nodal displacement of any accepted state, and whether a node has been told
    /// to have run away (a checkpoint without them had none).
    #[serde(default)]
    pub largest_displacement: f64,
    #[serde(default)]
    pub runaway_told: bool,
    /// Where a solid first stood past the end of the face its reconnected layer slides on
    /// (a checkpoint without it had none).
    #[serde(default)]
    pub overhang: Option<String>,
    /// Where a solid first came up against the edge of the medium drawn around it (a
    /// checkpoint without it had none, or kept it in words, which a restart leaves).
    #[serde(default)]
    pub edge_reached_at: Option<EdgeReached>,
    /// How many times a reconnected friction layer was joined again.
    #[serde(default)]
    pub layer_joins: usize,
    /// How many times the medium was made again as the bodies moved.
    #[serde(default)]
    pub medium_remakes: usize,
    /// The largest relative change of a group's reaction, and of its heat flow, across a
    /// remake of the medium, measured where the mechanics are settled after each (`settle`;
    /// `None` where no remake was).
    #[serde(default)]
    pub remake_force_change: Option<f64>,
    #[serde(default)]
    pub remake_heat_change: Option<f64>,
    /// The wall time the medium's remakes took: from the accepted state at which one was due
    /// to the state the next step starts from (gmsh, the new model, its settling if any).
    #[serde(default)]
    pub remake_seconds: f64,
    /// How many remakes left the mechanics unsettled where they are settled (the settling
    /// did not converge; the next step started from the state as remade).
    #[serde(default)]
    pub remake_unsettled: usize,
    /// How many steps pseudo-transient continuation took where Newton failed at the shortest
    /// step.
    #[serde(default)]
    pub continued: usize,
    /// Whether a step taken by continuation has been said (the first is, without `-v`).
    #[serde(default)]
    pub continued_told: bool,
    /// How many steps ended at a state in balance whose Newton updates did not shrink.
    #[serde(default)]
    pub balanced_only: usize,
    /// Whether such a step has been said (the first is, without `-v`).
    #[serde(default)]
    pub balanced_only_told: bool,
    /// How many times a step that would have stopped the run asked for the medium to be made
    /// again first.
    #[serde(default)]
    pub remade_to_go_on: usize,
    /// Whether such a remake has been said (the first is, without `-v`).
    #[serde(default)]
    pub remade_to_go_on_told: bool,
    /// A medium made again as the bodies move: its watch of the slivers at the last accepted
    /// state before this one (the state a restart decides from, as the run would have).
    #[serde(default)]
    pub medium: Option<crate::model::remake::Medium>,
    /// Transient scenes with a reconnected friction layer: what its joins changed the heat
    /// stored by (its cells re-paired with other nodes' temperatures).
    #[serde(default)]
    pub heat_joined: Option<f64>,
    /// The largest force imbalance of an accepted state, and a steady scene's heat
    /// imbalance, each with the largest size of the flows it balances over the run
    /// (`Balances`; `None` where there is none to check).
    #[serde(default)]
    pub force_imbalance: Option<(f64, f64)>,
    #[serde(default)]
    pub heat_imbalance: Option<(f64, f64)>,
}

impl Totals {
    /// A balance's largest net and largest size so far, with a state's `net` and `size`.
    pub fn widen(kept: Option<(f64, f64)>, net: f64, size: f64) -> Option<(f64, f64)> {
        let (n, s) = kept.unwrap_or((0.0, 0.0));
        Some((n.max(net.abs()), s.max(size)))
    }

    /// A balance kept by [`Totals::widen`], relative: its largest net over its largest size.
    pub fn relative(kept: Option<(f64, f64)>) -> Option<f64> {
        kept.and_then(|(net, size)| (size > 0.0).then(|| net / size))
    }

    /// Take the smallest J of an accepted step (∞ where it has no solid, or no medium).
    pub fn lower_min_J(&mut self, solid: f64, medium: f64) {
        let lower = |so_far: Option<f64>, now: f64| {
            let m = so_far.unwrap_or(f64::INFINITY).min(now);
            m.is_finite().then_some(m)
        };
        self.min_J = (lower(self.min_J.0, solid), lower(self.min_J.1, medium));
    }
}

/// The files written so far: how many steps the `.pvd` lists, the last step written, and how
/// far `history.csv` had got (its length and fingerprint).
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct Files {
    pub series: usize,
    pub written: Option<usize>,
    pub history: Mark,
    /// Wall seconds spent writing the run's files so far (a checkpoint without it: 0).
    #[serde(default)]
    pub seconds: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_smallest_J_ignores_what_a_scene_does_not_have() {
        let mut t = Totals::default();
        t.lower_min_J(0.9, f64::INFINITY);
        t.lower_min_J(0.95, 0.2);
        t.lower_min_J(0.7, 0.3);
        assert_eq!(t.min_J, (Some(0.7), Some(0.2)));
    }

    #[test]
    fn a_run_state_reads_back_to_the_same_bits() {
        let state = RunState {
            x: vec![0.1, -1.0 / 3.0, 1e-300],
            point_history: vec![vec![], vec![2.0_f64.sqrt()]],
            references: Some(vec![None, Some(vec![[0.1, 1.0 / 3.0, -0.0]])]),
            clock: Clock {
                t: 0.3,
                dt: 0.0125,
                accepted: 7,
                rejected: 1,
            },
            newton: Tally {
                run_ref: [1.0 / 7.0, 0.0, 3.0],
                spent: Default::default(),
            },
            totals: Totals {
                min_J: (Some(0.123456789), None),
                heat_in: Some(-2.5e-17),
                ..Default::default()
            },
            files: Files {
                series: 3,
                written: Some(6),
                history: Mark {
                    bytes: 10,
                    hash: u64::MAX,
                },
                seconds: 0.25,
            },
            wall: 12.5,
        };
        let text = serde_json::to_string(&state).unwrap();
        let back: RunState = serde_json::from_str(&text).unwrap();
        assert_eq!(serde_json::to_string(&back).unwrap(), text);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back.x), bits(&state.x));
        assert_eq!(
            back.newton.run_ref[0].to_bits(),
            state.newton.run_ref[0].to_bits()
        );
        assert_eq!(back.clock, state.clock);
        assert_eq!(back.totals.heat_in, state.totals.heat_in);
        assert_eq!(back.files.seconds, state.files.seconds);
        let place = |s: &RunState| s.references.as_ref().unwrap()[1].as_ref().unwrap()[0];
        assert_eq!(
            place(&back).map(f64::to_bits),
            place(&state).map(f64::to_bits)
        );
    }
}
