//! The accounts of an accepted step: the reactions at the converged state, the work of the
//! forces on the displacements, the heat balance of a transient scene, what the points'
//! history holds (friction's work and heat, the kinetic energy), and the watches on the state
//! (medium cells a solid's corner passed into, a node that ran away, a body come up against
//! the medium's edge). They add to the run's [`Totals`]; the recorder writes them.

use super::SolveError;
use super::records::{BEYOND, EdgeReached};
use super::state::Totals;
use super::stepper::Stepper;
use crate::assembly::AssemblyError;
use crate::case::RegionKind;
use crate::dofs::{Field, NONE};
use crate::mesh::point_text;
use crate::model::{Model, StepContext};
use crate::post::edge::MediumEdge;
use crate::post::{corners_through_medium, friction_work, heat_stored, kinetic_energy};
use crate::solver::newton::StepReport;
use std::time::Instant;

/// What the points' committed history holds at the last accepted step: the kinetic energy
/// (with inertia), the work friction dissipated and the heat it made (with friction, and
/// frictional heating).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PointTotals {
    pub kinetic_energy: Option<f64>,
    pub friction_work: Option<f64>,
    pub friction_heat: Option<f64>,
}

/// The accounts of a run: its totals, and the displacement dofs whose forces do work.
pub(super) struct Accounts {
    pub totals: Totals,
    u_dofs: Vec<usize>,
    /// The medium's free edge, watched for a body that comes up against it.
    edge: MediumEdge,
}

/// A converged state that cannot be assembled again (it was, to converge).
fn invalid(e: AssemblyError) -> SolveError {
    SolveError::Setup(format!("converged state is invalid: {e}"))
}

impl Accounts {
    pub(super) fn new(model: &Model) -> Accounts {
        Accounts {
            totals: Totals::default(),
            u_dofs: (0..model.dofs.n_dofs)
                .filter(|&d| model.dofs.field[d] == Field::U)
                .collect(),
            edge: MediumEdge::of(model),
        }
    }

    /// The counts of a step's Newton iterations.
    pub(super) fn count(&mut self, rep: &StepReport) {
        let tot = &mut self.totals;
        tot.iterations += rep.iterations;
        tot.krylov += rep.krylov;
        tot.tangents_skipped += rep.tangents_skipped;
    }

    /// The forces on the displacement dofs, f_int = r + f_ext, from the stepper's last
    /// assembly, whose external loads were `fe`.
    pub(super) fn forces(&self, st: &Stepper, fe: &[f64]) -> Vec<f64> {
        self.u_dofs
            .iter()
            .map(|&d| st.asm.r_full[d] + fe[d])
            .collect()
    }

    /// The step `step`, from the state `x_last` to the stepper's, just accepted with the
    /// report `rep`: its counts, the reactions and the history of the converged state (the
    /// history is committed here: it is what the next step starts from), the heat and the work
    /// done, the watches. Returns a warning to print, if the state calls for one.
    pub(super) fn step(
        &mut self,
        st: &mut Stepper,
        step: &StepContext,
        x_last: &[f64],
        rep: &StepReport,
    ) -> Result<Option<String>, SolveError> {
        let model = st.model;
        self.count(rep);
        let tot = &mut self.totals;
        tot.energy = rep.stats.energy;
        tot.lower_min_J(rep.stats.min_J_solid, rep.stats.min_J_medium);
        // reactions at the converged state (the residual of the last assembly)
        let t0 = Instant::now();
        st.asm
            .assemble(model, &st.x, step, false, None)
            .map_err(invalid)?;
        self.totals.t_reactions += t0.elapsed().as_secs_f64();
        let convected;
        (self.totals.reactions, convected) = st.flows_assembled(step.t).map_err(invalid)?;
        // the history of the converged state (just assembled) is what the next step starts from
        st.asm.commit();
        let mut fe = vec![0.0; model.dofs.n_dofs];
        model.f_ext(step.lambda, &mut fe);
        if model.physics.transient {
            self.heat(st, step, &fe, convected)?;
        }
        self.balance(st, &fe, convected);
        let f_now = self.forces(st, &fe);
        let tot = &mut self.totals;
        tot.work += self
            .u_dofs
            .iter()
            .zip(tot.f_last.iter().zip(&f_now))
            .map(|(&d, (a, b))| 0.5 * (a + b) * (st.x[d] - x_last[d]))
            .sum::<f64>();
        tot.f_last = f_now;
        let through = corners_through_medium(model, &st.asm.reference, &st.x);
        tot.corners_through = tot.corners_through.max(through);
        let warnings = [
            self.watch_displacement(st, step.t),
            self.watch_edge(st, step.t),
        ];
        let said: Vec<String> = warnings.into_iter().flatten().collect();
        Ok((!said.is_empty()).then(|| said.join("\n")))
    }

    /// Heat balance of a transient scene after the accepted `step` (of length Δt): the heat
    /// stored, and the heat supplied over the run, Σ Δt × (rate at the step's end) as backward
    /// Euler takes it. The rate is Σ over θ dofs of the reactions and the external heat `fe`,
    /// plus the heat `convected` in (negative: out): at convergence, exactly the rate of the
    /// stored heat.
    fn heat(
        &mut self,
        st: &Stepper,
        step: &StepContext,
        fe: &[f64],
        convected: f64,
    ) -> Result<(), SolveError> {
        let model = st.model;
        let mut rate = 0.0;
        for &d in &model.dofs.theta {
            let d = d as usize;
            rate += fe[d];
            if model.cons.prescribed[d].is_some() {
                rate += st.asm.r_full[d];
            }
        }
        rate += convected;
        let tot = &mut self.totals;
        tot.heat_in = Some(tot.heat_in.unwrap_or(0.0) + step.dt * rate);
        tot.heat_stored = Some(heat_stored(model, &st.asm.reference, &st.x).map_err(invalid)?);
        Ok(())
    }

    /// The accepted state's force balance (without inertia) and a steady scene's heat balance,
    /// each widened into the run's ([`Totals::widen`]): the net Σ over the held dofs' reactions
    /// and every dof's external load `fe` (and the heat `convected` in), and the sum of their
    /// sizes. Translation leaves the internal forces summing to zero, so what is left is the
    /// residual Newton left at the free dofs.
    fn balance(&mut self, st: &Stepper, fe: &[f64], convected: f64) {
        let model = st.model;
        let r = &st.asm.r_full;
        let sum = |dofs: &mut dyn Iterator<Item = usize>| {
            let (mut net, mut size) = (0.0, 0.0);
            for d in dofs {
                let held = if model.cons.prescribed[d].is_some() {
                    r[d]
                } else {
                    0.0
                };
                net += held + fe[d];
                size += held.abs() + fe[d].abs();
            }
            (net, size)
        };
        // flows below what Newton leaves as round-off at every node are not judged by
        // themselves (a component no load acts along sums round-off to round-off); a state's
        // net is judged against the largest flows of the run, as Newton judges its residuals
        let nodes = model.dofs.n_nodes as f64;
        let tot = &mut self.totals;
        if !model.physics.inertia && !model.dofs.u.is_empty() {
            let dim = model.mesh.dim;
            let sums: Vec<(f64, f64)> = (0..dim)
                .map(|c| {
                    let mut dofs = (0..model.dofs.n_nodes)
                        .map(|n| model.dofs.u[n * dim + c])
                        .filter(|&d| d != NONE)
                        .map(|d| d as usize);
                    sum(&mut dofs)
                })
                .collect();
            // each component's net against every component's flows: the forces balanced
            let size: f64 = sums.iter().map(|s| s.1).sum();
            let net = sums.iter().fold(0.0f64, |a, s| a.max(s.0.abs()));
            let size = size.max(nodes * st.newton.floor(Field::U));
            tot.force_imbalance = Totals::widen(tot.force_imbalance, net, size);
        }
        if !model.physics.transient && !model.dofs.theta.is_empty() {
            let mut dofs = (model.dofs.theta.iter())
                .filter(|&&d| d != NONE)
                .map(|&d| d as usize);
            let (net, size) = sum(&mut dofs);
            let size = (size + convected.abs()).max(nodes * st.newton.floor(Field::Theta));
            tot.heat_imbalance = Totals::widen(tot.heat_imbalance, net + convected, size);
        }
    }

    /// The largest nodal displacement of the accepted state at `t`, kept for the summary; the
    /// first time it exceeds the mesh's extent ([`BEYOND`]), a warning naming the node: in
    /// a medium, a node that barely resists (a free corner of an open medium) has run away and
    /// its cells are no solution; in a solid, its body moves far (held by its mass alone).
    fn watch_displacement(&mut self, st: &Stepper, t: f64) -> Option<String> {
        let model = st.model;
        let dim = model.mesh.dim;
        if model.dofs.u.is_empty() {
            return None;
        }
        let (node, largest) = (0..model.dofs.n_nodes)
            .map(|n| {
                let u = &model.dofs.u[n * dim..(n + 1) * dim];
                let size = u.iter().map(|&d| st.x[d as usize].powi(2)).sum::<f64>();
                (n, size.sqrt())
            })
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let tot = &mut self.totals;
        tot.largest_displacement = tot.largest_displacement.max(largest);
        if largest <= BEYOND * model.d || tot.runaway_told {
            return None;
        }
        tot.runaway_told = true;
        let at = point_text(&model.mesh.coords[node], dim);
        let block = (model.blocks.iter()).find(|b| model.mesh.cells[b.block].conn.contains(&node));
        let (name, medium) = block.map_or(("", false), |b| {
            let (name, kind) = &model.regions[b.region];
            (name.as_str(), *kind == RegionKind::Medium)
        });
        let when = when(st, t);
        let what = if medium {
            "a node of the medium that barely resists (a free corner of an open medium, most \
             likely) runs away. The forces where the solids are held may still hold; that \
             node's cells are no solution. A [[bc]] on that boundary of the medium holds it."
        } else {
            "its body moves far, held by its mass or by little else. If it should stay in \
             place, hold it (a [[bc]]) or check its loads."
        };
        Some(format!(
            "warning: step {} ({when}): node {node} of region \"{name}\" (at {at} in the \
             undeformed mesh) has moved {largest:.3e}, {:.1} times the mesh's extent: {what}",
            st.ctl.accepted,
            largest / model.d
        ))
    }

    /// The first accepted state (at `t`) where a body has come up against the edge of the
    /// medium drawn around it ([`MediumEdge::watch`]): kept for a stop's words, and a warning.
    /// Past the edge nothing is in contact, and the medium there is pushed ahead of the body
    /// until the run stops.
    fn watch_edge(&mut self, st: &Stepper, t: f64) -> Option<String> {
        if self.totals.edge_reached_at.is_some() {
            return None;
        }
        let model = st.model;
        let near = self.edge.watch(model, &st.x)?;
        let reached = EdgeReached {
            solid: model.regions[near.region].0.clone(),
            step: st.ctl.accepted,
            time: t,
            at: near.at,
            distance: near.distance,
        };
        let what = format!(
            "a node of the medium's free edge stands {:.1e} from its face, at {}",
            near.distance,
            point_text(&near.at, model.mesh.dim)
        );
        let said = format!(
            "warning: step {} ({}): {}: {what}. Past that edge nothing is in contact, and the \
             medium there is pushed ahead of the solid; draw the medium past where the solid \
             goes.",
            reached.step,
            when(st, t),
            reached.came()
        );
        self.totals.edge_reached_at = Some(reached);
        Some(said)
    }
}

/// Where the accepted state at `t` stands, for a warning: "t = 1.25" or "λ = 0.5000".
pub(super) fn when(st: &Stepper, t: f64) -> String {
    match st.show_t() {
        true => format!("t = {}", st.t_text(t)),
        false => format!("λ = {:.4}", st.model.path.lambda(t)),
    }
}

/// What the points' committed history holds at the step last committed.
pub(super) fn point_totals(st: &Stepper) -> PointTotals {
    let model = st.model;
    let mut points = PointTotals {
        kinetic_energy: (model.physics.inertia).then(|| kinetic_energy(model, &st.asm)),
        ..PointTotals::default()
    };
    if model.physics.friction {
        let works = friction_work(model, &st.asm);
        let heat = works
            .iter()
            .zip(&model.friction_blocks)
            .map(|(w, fb)| w * fb.heat_fraction)
            .sum();
        points.friction_work = Some(works.iter().sum());
        points.friction_heat = model.physics.frictional_heating.then_some(heat);
    }
    points
}

/// The heat stored at the stepper's last accepted state, in a transient scene (whose layer
/// joins change it: its cells' temperatures are other nodes' once joined); `None` in others.
pub(super) fn joined_heat(st: &Stepper) -> Option<f64> {
    let model = st.model;
    (model.physics.transient)
        .then(|| heat_stored(model, &st.asm.reference, &st.x).ok())
        .flatten()
}
