//! The quasi-static load path (`[load] steps = K`): what each step leaves behind — this rank's
//! rows of u and of the stresses, the contact state (its slip is the step's increment), the
//! solver's counters — for the report, the live summary line and the result file's `/steps`.
//! The steps themselves run inside the two contact paths (each dual's `set_load` and `jump`).

use serde::{Deserialize, Serialize};

use super::{ContactOutcome, LocalFields, Solution};
use crate::contact::pairing::Contact;
use crate::contact::state::{ContactState, OPEN, SLIP, STICK};

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
            stick: o.state.count(STICK),
            slip: o.state.count(SLIP),
            total_force_on_slave: o.state.total_force(contact),
            max_displacement: umax,
            time_s,
        };
        StepOutput { report, local: sol.local.clone(), state: o.state.clone() }
    }

    /// The live summary line of the step.
    pub fn line(&self, steps: usize) -> String {
        let r = &self.report;
        let fp = if r.fixed_point_iterations > 0 { format!(", {} fixed-point", r.fixed_point_iterations) } else { String::new() };
        format!(
            "load step {}/{steps}: nA {}{fp}, open/stick/slip {}/{}/{}, force on slave ({:.4e}, {:.4e}, {:.4e}), max |u| {:.4e}, {:.2} s",
            r.step, r.n_a, r.open, r.stick, r.slip, r.total_force_on_slave[0], r.total_force_on_slave[1], r.total_force_on_slave[2], r.max_displacement, r.time_s
        )
    }
}
