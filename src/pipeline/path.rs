//! The quasi-static load path (`[load] steps = K`): what each step leaves behind — this rank's
//! rows of u and of the stresses, the contact state (its slip is the step's increment), the
//! solver's counters — for the report, the live summary line and the result file's `/steps`.
//! [`Walk`] carries what passes from one step to the next in both contact paths (each dual sets
//! the load with its `set_load` and measures the slip with its `jump`).

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::accuracy::Tightening;
use super::monitor::Live;
use super::report::UnitsReport;
use super::{ContactOutcome, LocalFields, Solution};
use crate::contact::pairing::Contact;
use crate::contact::state::{ContactState, CONTACT, OPEN, SLIP, STICK};
use crate::model::LoadPath;
use crate::qp::Params;

/// The walk along a load path: the warm start y and the last step's tangential jump B_T u, the
/// solver's settings with σ_max measured at the first step and reused (A does not change along
/// the path), and the steps' records.
pub struct Walk {
    pub steps: usize,
    /// The steps the scene asked for (more than `steps` on a path stopped short), for messages.
    of: usize,
    /// More than one step: the load is set every step and every step is recorded.
    pub on_path: bool,
    pub y: Vec<f64>,
    pub jump: Vec<f64>,
    pub params: Params,
    /// The scene's units, for the step lines.
    units: Option<UnitsReport>,
    records: Vec<StepOutput>,
    /// Where the accuracy guard tightened ε, every step so far.
    tightenings: Vec<Tightening>,
    start: Instant,
}

impl Walk {
    /// Before the first step, on a dual of length `dim`.
    pub fn new(path: &LoadPath, dim: usize, params: &Params, units: Option<UnitsReport>) -> Self {
        Walk {
            steps: path.steps,
            of: path.asked(),
            on_path: path.is_path(),
            y: vec![0.0; dim],
            jump: vec![0.0; dim],
            params: params.clone(),
            units,
            records: vec![],
            tightenings: vec![],
            start: Instant::now(),
        }
    }

    /// Step k begins (its time starts).
    pub fn begin(&mut self) {
        self.start = Instant::now();
    }

    /// Step k ended: records it (on a path, with its summary line on `live`), keeps y, the jump
    /// and σ_max (`None`: measure again) for the next step. After the last step returns the
    /// records (empty off a path).
    #[allow(clippy::too_many_arguments)]
    pub fn end(
        &mut self,
        k: usize,
        solution: &Solution,
        contact: Option<(&Contact, &ContactOutcome)>,
        live: &Live,
        y: Vec<f64>,
        jump: Vec<f64>,
        sigma: Option<f64>,
    ) -> Option<Vec<StepOutput>> {
        if let Some((_, o)) = contact {
            self.tightenings.extend(o.tightenings.iter().cloned());
        }
        if let (true, Some((c, o))) = (self.on_path, contact) {
            let rec = StepOutput::new(k, solution, c, o, self.start.elapsed().as_secs_f64());
            live.line(&rec.line(self.of, self.units.as_ref()));
            self.records.push(rec);
        }
        if k == self.steps {
            return Some(std::mem::take(&mut self.records));
        }
        (self.y, self.jump) = (y, jump);
        self.params.common.sigma = sigma.filter(|s| s.is_finite() && *s > 0.0);
        None
    }

    /// Continues from checkpoint `c`: y and the jump on this rank's dual rows `rows` (global
    /// ids), σ_max, the records (their rows on rank 0, `root`) and the tightenings so far.
    pub fn resume(&mut self, c: &super::checkpoint::Checkpoint, rows: &[usize], root: bool) -> Option<()> {
        if c.steps != self.steps || c.y.len() != c.jump.len() || rows.iter().any(|&r| r >= c.y.len()) {
            return None;
        }
        self.y = rows.iter().map(|&r| c.y[r]).collect();
        self.jump = rows.iter().map(|&r| c.jump[r]).collect();
        self.params.common.sigma = c.sigma;
        self.records = c.records.iter().map(|r| r.to_step(root)).collect();
        self.tightenings = c.tightenings.clone();
        Some(())
    }

    /// The records of the steps so far.
    pub fn records(&self) -> &[StepOutput] {
        &self.records
    }

    /// The tightenings of ε so far.
    pub fn tightenings(&self) -> &[Tightening] {
        &self.tightenings
    }

    /// Every tightening of ε by the accuracy guard along the path (taken).
    pub fn take_tightenings(&mut self) -> Vec<Tightening> {
        std::mem::take(&mut self.tightenings)
    }

    /// The solver's name in an error, with the load step on a path.
    pub fn name(&self, name: &str, k: usize) -> String {
        if self.on_path {
            format!("{} (load step {k}/{})", name.to_uppercase(), self.of)
        } else {
            name.to_uppercase()
        }
    }
}

/// One step of a load path.
#[derive(Clone, Debug)]
pub struct StepOutput {
    pub report: StepReport,
    /// This rank's rows of u and of the von Mises stress.
    pub local: LocalFields,
    pub state: ContactState,
}

/// The figures of one step (rank 0's; the maximum displacement over all nodes).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct StepReport {
    pub step: usize,
    pub outer_iterations: usize,
    #[serde(rename = "nA")]
    pub n_a: usize,
    pub inner_iterations: usize,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub fixed_point_iterations: usize,
    pub final_relative_reduced_gradient: f64,
    pub kkt_worst: f64,
    pub open: usize,
    /// Closed pairs without friction.
    #[serde(default)]
    pub contact: usize,
    pub stick: usize,
    pub slip: usize,
    pub total_force_on_slave: [f64; 3],
    pub max_displacement: f64,
    /// Wall time of the step (load, iterate, recover, stress, gather).
    pub time_s: f64,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl StepOutput {
    /// The record of step `k` from its solution and contact outcome.
    pub fn new(k: usize, sol: &Solution, contact: &Contact, o: &ContactOutcome, time_s: f64) -> Self {
        let umax = sol.displacement.iter().map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt()).fold(0.0, f64::max);
        let report = StepReport {
            step: k,
            outer_iterations: o.info.iterations,
            n_a: o.info.n_a + o.info.n_a_power,
            inner_iterations: o.info.inner_iterations,
            fixed_point_iterations: o.info.fixed_point_iterations,
            final_relative_reduced_gradient: o.info.err,
            kkt_worst: o.kkt.worst(),
            open: o.state.count(OPEN),
            contact: o.state.count(CONTACT),
            stick: o.state.count(STICK),
            slip: o.state.count(SLIP),
            total_force_on_slave: o.state.total_force(contact),
            max_displacement: umax,
            time_s,
        };
        StepOutput { report, local: sol.local.clone(), state: o.state.clone() }
    }

    /// The live summary line of the step, forces and lengths in the scene's `units`.
    pub fn line(&self, steps: usize, units: Option<&UnitsReport>) -> String {
        let r = &self.report;
        let fp = if r.fixed_point_iterations > 0 { format!(", {} fixed-point", r.fixed_point_iterations) } else { String::new() };
        let f = r.total_force_on_slave;
        format!(
            "load step {}/{steps}: nA {}{fp}, {}, force on slave ({:.4e}, {:.4e}, {:.4e}){}, max |u| {:.4e}{}, {:.2} s",
            r.step,
            r.n_a,
            super::report::counts(r.open, r.contact, r.stick, r.slip),
            f[0],
            f[1],
            f[2],
            UnitsReport::suffix(units, 1),
            r.max_displacement,
            UnitsReport::suffix(units, 0),
            r.time_s
        )
    }
}
