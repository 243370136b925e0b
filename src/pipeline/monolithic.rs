//! The contact solve on the monolithic dual (one piece per body, Dirichlet eliminated): the
//! bodies factorized, A and b built (phase `dual`), the load path walked by the shared driver
//! ([`super::steps`]), and the dual's exports (`output.export_dual`, `output.export_fclib`).

use super::accuracy::{self, Verdict};
use super::monitor::Live;
use super::steps::{self, Solved, StepDual};
use super::{assemble_and_factorize, finish_bodies, preconditioner, solver_for, ContactOutcome, DualKind, LocalBody, Solution, Timings};
use crate::comm::Comm;
use crate::contact::pairing::Contact;
use crate::contact::state::contact_state;
use crate::dual::monolithic::MonolithicDual;
use crate::dual::{DualProblem, Recovered};
use crate::error::{Error, Result};
use crate::fem::assembly::DofMap;
use crate::model::{self, Model};
use crate::qp::{self, cone::Coefficient, Lambda, Operator, Params, Qp, QpError, QpSolution, Space};
use crate::scene::LoadedScene;

/// The contact solve on the monolithic dual: factorize, build A and b (phase `dual`), then walk
/// the load path ([`steps::walk`]). The outcome is the last step's, with every step's record.
pub fn solve_contact<C: Comm>(comm: &C, ls: &LoadedScene, model: &Model, t: &mut Timings) -> Result<(Solution, ContactOutcome)> {
    solve_contact_from(comm, ls, model, None, t)
}

/// [`solve_contact`] from the step after checkpoint `resume`'s where given.
pub(crate) fn solve_contact_from<C: Comm>(
    comm: &C,
    ls: &LoadedScene,
    model: &Model,
    resume: Option<&super::checkpoint::Checkpoint>,
    t: &mut Timings,
) -> Result<(Solution, ContactOutcome)> {
    let contact = model.pairs.as_ref().expect("contact is active");
    if let Some(g) = model.floating.first() {
        return Err(Error::scene(
            "decomposition",
            format!(
                "{} is held by contact alone: it is solved by TFETI with the orthogonal projector (pipeline::held_by_contact)",
                crate::contact::hold::group_name(&model.mesh, g)
            ),
        ));
    }
    let s = &solver_for(ls, model);
    let bodies = assemble_and_factorize(comm, model, ls.scene.factorization.ordering, true, t)?;
    preconditioner(s.params.method(), s.preconditioner, DualKind::Monolithic)?;
    let (mut dual, b) = t.phase(comm, "dual", || {
        let (mut dual, b) = MonolithicDual::new(comm, contact, bodies);
        if s.precision != crate::scene::Precision::Double {
            dual.keep_single();
        }
        Ok((dual, b))
    })?;
    let dim = dual.dim();
    let set = contact.constraint_set();
    let coulomb = contact.is_coulomb().then_some(contact.coulomb.as_slice());
    let mut steps = Steps { comm, ls, model, contact, dual: &mut dual, set, coulomb, method: s.params.method().name() };
    let (solution, outcome) = steps::walk(comm, ls, model, &s.params, &mut steps, b, dim, resume, t)?;
    Ok((solution, outcome.expect("a contact solve has an outcome")))
}

/// The monolithic dual along a load path ([`StepDual`]).
struct Steps<'a, 'c, C: Comm> {
    comm: &'c C,
    ls: &'a LoadedScene,
    model: &'a Model,
    contact: &'a Contact,
    dual: &'a mut MonolithicDual<'c, C>,
    set: Lambda,
    coulomb: Option<&'a [Coefficient]>,
    method: &'static str,
}

impl<C: Comm> StepDual for Steps<'_, '_, C> {
    type Extra = ();
    /// The Coulomb bounds cut at the solution (none with Tresca) and the KKT residuals.
    type Judged = (Option<Lambda>, qp::kkt::Kkt);

    fn what(&self) -> String {
        self.method.to_string()
    }

    fn norm(&self, b: &[f64]) -> f64 {
        self.dual.space().norm(b)
    }

    fn set_load(&mut self, k: usize, jump: &[f64]) -> Result<Vec<f64>> {
        let model = self.model;
        let (cons, loads) = model.state(k);
        let by_body = model::constraints_by_body(&model.mesh, &cons);
        Ok(self.dual.set_load(
            self.contact,
            |lb| {
                let body = &model.mesh.bodies[lb.body];
                let dofs = DofMap::new(body.nodes.clone(), &by_body[lb.body]);
                let f = crate::fem::assembly::body_rhs(&model.mesh, lb.body, model.lame[lb.body], &dofs, &loads[3 * body.nodes.start..3 * body.nodes.end]);
                (dofs, f)
            },
            jump,
        ))
    }

    fn iterate(
        &self,
        b: &[f64],
        x0: &[f64],
        _first: bool,
        _warm: Option<&()>,
        params: &Params,
        monitor: &mut Live,
    ) -> std::result::Result<(QpSolution, ()), QpError> {
        qp::solve_friction(&Qp::new(&*self.dual, b, &self.set), self.coulomb, x0, params, monitor).map(|s| (s, ()))
    }

    fn recover(&self, sol: &QpSolution) -> Result<Recovered> {
        Ok(self.dual.recover(&sol.lambda))
    }

    fn judge(&self, rec: &Recovered, sol: &QpSolution, bnorm: f64, eps: f64) -> (Verdict, Self::Judged) {
        // Coulomb: the cones cut at the solution's λν (the bounds it was solved with, to ε)
        let coulomb_set = self.coulomb.map(|mu| qp::cone::bounds(&self.set, mu, &sol.lambda));
        let set_k = coulomb_set.as_ref().unwrap_or(&self.set);
        let kkt = qp::kkt::residuals_scaled(set_k, &rec.lambda, &rec.gap, bnorm, accuracy::force_scale(bnorm, sol.info.sigma_est));
        let pieces: Vec<_> =
            self.dual.blocks.iter().zip(&rec.u).zip(&rec.rhs).map(|((blk, u), f)| accuracy::Equilibrium::of(&blk.local.sys.k, u, f, &[])).collect();
        (Verdict::new(self.comm, &pieces, kkt.worst(), eps), (coulomb_set, kkt))
    }

    fn rows(&self) -> Vec<usize> {
        // λ is whole on every rank
        (0..self.dual.dim()).collect()
    }

    fn kept_sigma(&self, sigma: f64) -> Option<f64> {
        Some(sigma)
    }

    fn finish(&mut self, last: bool, b: &[f64], step: &Solved<Self>, t: &mut Timings) -> Result<(Solution, Option<ContactOutcome>, Vec<f64>)> {
        let (comm, ls, contact) = (self.comm, self.ls, self.contact);
        let (sol, rec, (coulomb_set, kkt)) = (&step.sol, &step.rec, &step.judged);
        let set_k = coulomb_set.as_ref().unwrap_or(&self.set);
        if last {
            if let Some(path) = &ls.scene.output.export_dual {
                t.phase(comm, "export", || export_dual(comm, self.dual, b, contact, &sol.lambda, path))?;
            }
            if let Some(path) = &ls.scene.output.export_fclib {
                t.phase(comm, "export", || crate::dual::fclib::write_global(comm, path, self.dual, contact, &sol.lambda, &ls.scene.title))?;
            }
        }
        let refs: Vec<&LocalBody> = self.dual.blocks.iter().map(|blk| &blk.local).collect();
        let rhs_refs: Vec<&[f64]> = rec.rhs.iter().map(Vec::as_slice).collect();
        let mut solution = finish_bodies(comm, self.model, &refs, &rec.u, &rhs_refs, t)?;
        solution.single_precision_error = self.dual.single_error();
        solution.explicit_products = self.dual.explicit_dofs();
        // the status cannot be sharper than the solution: classify at the solver's tolerance
        let (bnorm, eps) = (step.bnorm, step.params.common.eps);
        let state = contact_state(contact, set_k, &rec.lambda, &rec.gap, eps.max(1e-9), bnorm, accuracy::force_scale(bnorm, sol.info.sigma_est));
        let outcome =
            ContactOutcome { dim: self.dual.dim(), state, info: sol.info.clone(), bnorm, kkt: *kkt, steps: vec![], tightenings: step.tightenings.clone() };
        Ok((solution, Some(outcome), self.dual.jump(&rec.gap)))
    }
}

/// `output.export_dual`: the Coulomb problem on the monolithic dual in the local form of the
/// frictional-contact literature, u = W r + q with per contact (normal, t₁, t₂): W = A (by
/// 3m products), q = −b, μ, our r = λ and u = W r + q; rank 0 writes.
fn export_dual<C: Comm>(
    comm: &C,
    dual: &MonolithicDual<'_, C>,
    b: &[f64],
    contact: &crate::contact::pairing::Contact,
    lambda: &[f64],
    path: &std::path::Path,
) -> Result<()> {
    use crate::qp::cone::Coefficient;
    let m = contact.len();
    let mu: Vec<f64> = contact
        .coulomb
        .iter()
        .map(|c| match *c {
            Coefficient::Isotropic(mu) => Ok(mu),
            _ => Err(Error::scene("output.export_dual", "exports isotropic Coulomb friction on every pair (friction = { type = \"coulomb\", mu })")),
        })
        .collect::<Result<_>>()?;
    let layout = qp::Layout::contact(m, true);
    let idx = |k: usize| -> usize {
        let (a, i) = (k / 3, k % 3);
        if i == 0 {
            layout.normal(a)
        } else {
            layout.tangent(a, i - 1)
        }
    };
    let n = 3 * m;
    let mut w = vec![0.0; n * n];
    let (mut e, mut col) = (vec![0.0; n], vec![0.0; n]);
    for j in 0..n {
        e[idx(j)] = 1.0;
        dual.apply(&e, &mut col);
        e[idx(j)] = 0.0;
        for i in 0..n {
            w[i * n + j] = col[idx(i)];
        }
    }
    let q: Vec<f64> = (0..n).map(|k| -b[idx(k)]).collect();
    let r: Vec<f64> = (0..n).map(|k| lambda[idx(k)]).collect();
    let u: Vec<f64> = (0..n).map(|i| q[i] + (0..n).map(|j| w[i * n + j] * r[j]).sum::<f64>()).collect();
    if comm.is_root() {
        crate::output::hdf5::write_arrays(path, &[("W", vec![n, n], &w), ("q", vec![n], &q), ("mu", vec![m], &mu), ("r", vec![n], &r), ("u", vec![n], &u)])?;
    }
    Ok(())
}
