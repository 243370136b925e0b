//! The load-step driver that the monolithic and the TFETI dual share ([`walk`]): each step of a
//! load path (one without `[load]`) sets the load, iterates warm-started from the last step,
//! recovers u and judges the result (the pieces' equilibrium, the contact KKT residuals); a
//! result that misses its checks is continued from its λ at a tighter ε (the accuracy guard).
//! What differs between the duals sits behind [`StepDual`].

use super::accuracy::{self, Verdict};
use super::checkpoint;
use super::monitor::Live;
use super::path::Walk;
use super::{ContactOutcome, Solution, Timings};
use crate::comm::Comm;
use crate::contact::pairing::Contact;
use crate::dual::Recovered;
use crate::error::{Error, Result};
use crate::model::Model;
use crate::qp::{self, Params, QpError, QpSolution};
use crate::scene::LoadedScene;

/// A dual problem as the load-step driver sees it.
pub(crate) trait StepDual {
    /// What an iteration leaves beside λ (SMALSE-M's counters).
    type Extra;
    /// What judging the result leaves for the step's end (the contact set, λ and gap on it, the
    /// KKT residuals).
    type Judged;

    /// The solver's name in messages.
    fn what(&self) -> String;
    /// ‖b‖ in the dual's space.
    fn norm(&self, b: &[f64]) -> f64;
    /// The load of step `k` with the last step's tangential jump: the new b.
    fn set_load(&mut self, k: usize, jump: &[f64]) -> Result<Vec<f64>>;
    /// One solve from `x0`; `first`: the path's first solve (no step nor tightening before it);
    /// `warm`: what the solve that stopped at `x0` on the same b left beside it (the accuracy
    /// guard's re-solve continues from it).
    fn iterate(
        &self,
        b: &[f64],
        x0: &[f64],
        first: bool,
        warm: Option<&Self::Extra>,
        params: &Params,
        monitor: &mut Live,
    ) -> std::result::Result<(QpSolution, Self::Extra), QpError>;
    /// u (and the gap) from λ.
    fn recover(&self, sol: &QpSolution) -> Result<Recovered>;
    /// The verdict on a recovered solve at ε = `eps` (collective).
    fn judge(&self, rec: &Recovered, sol: &QpSolution, bnorm: f64, eps: f64) -> (Verdict, Self::Judged);
    /// The global ids of this rank's dual entries (`Space::global_index`): a checkpoint stores
    /// λ by them, so a resume on another rank count finds its rows.
    fn rows(&self) -> Vec<usize>;
    /// σ_max(A) measured by a solve, as the next solve may reuse it (`None`: measure again).
    fn kept_sigma(&self, sigma: f64) -> Option<f64>;
    /// Step `k` (on b) solved and judged: the solution (stresses, gathered fields) and the
    /// contact outcome, and the tangential jump the next step starts from.
    fn finish(&mut self, last: bool, b: &[f64], step: &Solved<Self>, t: &mut Timings) -> Result<(Solution, Option<ContactOutcome>, Vec<f64>)>;
}

/// One load step solved and judged: what [`StepDual::finish`] reads.
pub(crate) struct Solved<D: StepDual + ?Sized> {
    /// λ of the last solve with the counters of all the step's solves (the guard's included).
    pub sol: QpSolution,
    pub extra: D::Extra,
    pub rec: Recovered,
    pub judged: D::Judged,
    pub bnorm: f64,
    /// The settings of the last solve (ε as the guard left it).
    pub params: Params,
    /// Where the guard tightened ε in this step.
    pub tightenings: Vec<accuracy::Tightening>,
}

/// Walks the scene's load path on `dual` from b = `b`: the last step's solution and contact
/// outcome (with every step's record and tightening); from the step after `resume`'s when given.
pub(crate) fn walk<C: Comm, D: StepDual>(
    comm: &C,
    ls: &LoadedScene,
    model: &Model,
    params: &Params,
    dual: &mut D,
    mut b: Vec<f64>,
    dim: usize,
    resume: Option<&checkpoint::Checkpoint>,
    t: &mut Timings,
) -> Result<(Solution, Option<ContactOutcome>)> {
    let contact: Option<&Contact> = model.pairs.as_ref();
    let what = dual.what();
    let mut walk = Walk::new(&model.path, dim, params, super::report::UnitsReport::of(&ls.scene.units));
    let rows = dual.rows();
    let mut saver = checkpoint::Saver::new(comm, ls, walk.on_path)?;
    let first = match resume {
        Some(c) => {
            let shown = c.path.display().to_string();
            let resumed = walk.resume(c, &rows, comm.is_root()).map(|()| saver.resumed(c));
            comm.agree(resumed.ok_or_else(|| Error::output(shown, "cannot resume from this checkpoint: its load path or dual does not fit this run")))?;
            c.step + 1
        }
        None => 1,
    };
    for k in first..=walk.steps {
        walk.begin();
        if walk.on_path {
            b = t.phase(comm, "load", || dual.set_load(k, &walk.jump))?;
        }
        let step = solve_step(comm, dual, &b, &walk, k, &what, t)?;
        let (solution, mut outcome, jump) = dual.finish(k == walk.steps, &b, &step, t)?;
        let sigma = dual.kept_sigma(step.sol.info.sigma_est);
        if let Some(records) = walk.end(k, &solution, contact.zip(outcome.as_ref()), &t.live, step.sol.lambda, jump, sigma) {
            if let Some(o) = &mut outcome {
                o.steps = records;
                o.tightenings = walk.take_tightenings();
            }
            return Ok((solution, outcome));
        }
        if saver.active() {
            t.phase(comm, "checkpoint", || saver.save(&walk, k, &rows))?;
        }
    }
    unreachable!("a load path has at least one step")
}

/// Step `k` on b: solves from the walk's warm start, recovers, judges; where the result misses
/// its checks, continues from its λ at the tighter ε the guard gives.
fn solve_step<C: Comm, D: StepDual>(comm: &C, dual: &D, b: &[f64], walk: &Walk, k: usize, what: &str, t: &mut Timings) -> Result<Solved<D>> {
    let (mut params, mut x0, mut guard, mut total) = (walk.params.clone(), walk.y.clone(), accuracy::Guard::default(), qp::Info::default());
    let mut warm: Option<D::Extra> = None;
    let bnorm = dual.norm(b);
    loop {
        let mut monitor = t.monitor();
        let first = k == 1 && guard.tightenings.is_empty();
        let (mut sol, extra) =
            t.phase(comm, "iterate", || dual.iterate(b, &x0, first, warm.as_ref(), &params, &mut monitor).map_err(|e| Error::solver(walk.name(what, k), e)))?;
        let rec = t.phase(comm, "recover", || dual.recover(&sol))?;
        total.absorb(&sol.info);
        let (verdict, judged) = dual.judge(&rec, &sol, bnorm, params.common.eps);
        match guard.next(k, &verdict, &walk.name(what, k), &t.live)? {
            None => {
                sol.info = total;
                return Ok(Solved { sol, extra, rec, judged, bnorm, params, tightenings: guard.tightenings });
            }
            Some(eps) => {
                params.common.eps = eps;
                params.common.sigma = dual.kept_sigma(sol.info.sigma_est).filter(|s| s.is_finite() && *s > 0.0);
                x0 = sol.lambda;
                warm = Some(extra);
            }
        }
    }
}
