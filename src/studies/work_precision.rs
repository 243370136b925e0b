//! `tresca-feti work-precision`: run time against error. For each mesh size N of a scene (the
//! seed scene by default) and each solver — the dual solvers of [`crate::qp`] with the scene's
//! settings, and Clarabel on the primal SOCP ([`crate::studies::socp`]) — sweep the tolerance ε and
//! record the wall time of the solve, the A-products, the error in u (max-norm, relative) and in
//! λ (2-norm, relative) against a tight reference (SSN-BiCGSTAB at `reference_eps`), and the KKT
//! residual measured the same way for every solver. A solver is one more [`Solver`] value.
//! The dual solvers run on the monolithic dual and, for each S of `subdomains`, on the TFETI
//! dual with S subdomains per body (u of every subdomain copy against the same reference).
//!
//! Time is that of the solve on one rank (σ_max's power iterations included); the set-up every
//! dual solver shares (assembly, factorization) and Clarabel's (building the SOCP) are recorded
//! beside it. A solver's sweep stops (the tighter ε are recorded as skipped) once a solve fails
//! or (dual solvers) takes longer than `max_seconds`.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::comm::Comm;
use crate::contact::pairing::Contact;
use crate::dual::monolithic::MonolithicDual;
use crate::dual::DualProblem;
use crate::error::{Error, Result};
use crate::model::Model;
use crate::pipeline::tfeti::setup;
use crate::pipeline::{assemble_and_factorize, preconditioner, DualKind, Timings};
use crate::qp::cone::Coefficient;
use crate::qp::{self, kkt, Lambda, Method, Operator, Params, Preconditioner, Qp, QpSolution, Silent, Space};
use crate::scene::{LoadedScene, Projector};
use crate::studies::socp::PrimalSocp;
use crate::studies::table1::{u_error, Column};

/// One row of the study: a dual solver (with its parameter preset) or Clarabel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solver {
    /// A dual solver with its parameter preset.
    Dual(Column),
    /// Clarabel's interior-point method on the primal SOCP.
    Clarabel,
}

impl Solver {
    /// `clarabel`, or a dual solver's name with an optional `:paper` preset.
    pub fn parse(s: &str) -> std::result::Result<Solver, String> {
        if s == "clarabel" {
            return Ok(Solver::Clarabel);
        }
        Column::parse(s).map(Solver::Dual).map_err(|e| format!("{e}, or clarabel"))
    }

    /// The row's name in the table and the CSV.
    pub fn label(&self) -> String {
        match self {
            Solver::Dual(c) => c.label(),
            Solver::Clarabel => "clarabel".into(),
        }
    }
}

/// What `work-precision` is asked to do.
#[derive(Clone, Debug)]
pub struct Args {
    /// The scene (its `mesh.n` is set per size).
    pub scene: PathBuf,
    /// `--set` overrides of the scene.
    pub sets: Vec<String>,
    /// Mesh sizes N (nodes per edge of each block).
    pub sizes: Vec<usize>,
    /// The duals to run the dual solvers on: 0 the monolithic dual, S ≥ 1 TFETI with S
    /// subdomains per body (oblique projector; Clarabel runs with the monolithic one only).
    pub subdomains: Vec<usize>,
    /// Tolerances, swept from the loosest to the tightest.
    pub eps: Vec<f64>,
    /// Clarabel's (its time hardly depends on ε: a few points suffice).
    pub clarabel_eps: Vec<f64>,
    /// The rows of the study.
    pub solvers: Vec<Solver>,
    /// Where the CSV goes (none: not written).
    pub csv: Option<PathBuf>,
    /// ε of the reference solve.
    pub reference_eps: f64,
    /// A-products a dual solve may use.
    pub max_products: usize,
    /// A dual solve slower than this ends its solver's sweep at that N.
    pub max_seconds: f64,
    /// Accuracies in u the summary reports the time to.
    pub targets: Vec<f64>,
}

/// How one point of the sweep ended.
#[derive(Clone, Debug, PartialEq)]
pub enum Status {
    /// Converged to its ε.
    Ok,
    /// Stopped with this reason (no convergence, breakdown, a limit).
    Failed(String),
    /// Not run: a looser ε of the same solver failed or took longer than `max_seconds`.
    Skipped,
}

/// One solve: a solver at one ε on the problem of size N.
#[derive(Clone, Debug)]
pub struct Point {
    /// Mesh size N.
    pub n: usize,
    /// 0: the monolithic dual; S: TFETI with S subdomains per body.
    pub subdomains: usize,
    /// The row's solver.
    pub solver: Solver,
    /// The tolerance it ran at.
    pub eps: f64,
    /// How it ended.
    pub status: Status,
    /// Outer iterations (Clarabel: its interior-point iterations).
    pub iterations: usize,
    /// A-products of the solve, σ_max's estimate included.
    pub n_a: usize,
    /// A-products of σ_max's estimate alone.
    pub n_a_power: usize,
    /// Inner (Krylov) iterations.
    pub inner: usize,
    /// Seconds of the set-up the solve stands on (the dual's: assembly and factors, or TFETI's
    /// set-up and preconditioner; Clarabel: building the SOCP).
    pub setup_s: f64,
    /// Seconds of the solve.
    pub solve_s: f64,
    /// Max-norm error of u relative to the reference's.
    pub err_u: f64,
    /// Euclidean error of λ relative to the reference's.
    pub err_lambda: f64,
    /// The worst KKT residual of the solution.
    pub kkt: f64,
    /// The solver's own final measure (dual: ‖r̃_ρ‖/‖b‖; Clarabel: NaN).
    pub residual: f64,
}

/// The problem at one N.
#[derive(Clone, Debug)]
pub struct Problem {
    /// Mesh size N.
    pub n: usize,
    /// 0: the monolithic dual; S: TFETI with S subdomains per body.
    pub subdomains: usize,
    /// DOFs of the model.
    pub dofs: usize,
    /// Contact pairs.
    pub pairs: usize,
    /// The set-up the dual solvers share: assembly and factorization (monolithic), or
    /// decomposition, factorization, coarse problem and b̃ (TFETI).
    pub factorize_s: f64,
    /// The reference solve's counters.
    pub reference: qp::Info,
    /// The scene's solver: the default the summary compares with.
    pub default: Method,
}

/// ‖λ − λ_ref‖ / ‖λ_ref‖.
fn lambda_error(lambda: &[f64], reference: &[f64]) -> f64 {
    let d: f64 = lambda.iter().zip(reference).map(|(a, b)| (a - b) * (a - b)).sum();
    let r: f64 = reference.iter().map(|v| v * v).sum();
    (d / r.max(f64::MIN_POSITIVE)).sqrt()
}

/// The error of one dual solution: (err(u), err(λ), KKT), all against the monolithic reference.
type Measure<'m> = dyn Fn(&QpSolution) -> (f64, f64, f64) + 'm;

/// A point not yet run.
fn blank(n: usize, subdomains: usize, solver: Solver, setup_s: f64) -> Point {
    Point {
        n,
        subdomains,
        solver,
        eps: f64::NAN,
        status: Status::Skipped,
        iterations: 0,
        n_a: 0,
        n_a_power: 0,
        inner: 0,
        setup_s,
        solve_s: f64::NAN,
        err_u: f64::NAN,
        err_lambda: f64::NAN,
        kkt: f64::NAN,
        residual: f64::NAN,
    }
}

/// One dual solver's ε sweep (loose → tight) on the operator `a`; the sweep stops once a solve
/// fails or takes longer than `max_seconds`.
#[allow(clippy::too_many_arguments)]
fn sweep<A: Operator>(
    qp: &Qp<'_, A>,
    coulomb: Option<&[Coefficient]>,
    column: Column,
    base: &Params,
    args: &Args,
    eps: &[f64],
    template: &Point,
    measure: &Measure<'_>,
    on_point: &mut impl FnMut(&Point),
    points: &mut Vec<Point>,
) {
    let zero = vec![0.0; qp.a.dim()];
    let mut stop = false;
    for &e in eps {
        let mut pt = Point { eps: e, ..template.clone() };
        if !stop {
            let mut p = column.params(base, e);
            p.common.max_outer = usize::MAX;
            p.common.max_products = args.max_products;
            let t0 = Instant::now();
            let r = qp::solve_friction(qp, coulomb, &zero, &p, &mut Silent);
            pt.solve_s = t0.elapsed().as_secs_f64();
            match r {
                Ok(sol) => {
                    pt.status = Status::Ok;
                    let i = &sol.info;
                    (pt.iterations, pt.n_a, pt.n_a_power, pt.inner, pt.residual) = (i.iterations, i.n_a, i.n_a_power, i.inner_iterations, i.err);
                    (pt.err_u, pt.err_lambda, pt.kkt) = measure(&sol);
                }
                Err(err) => pt.status = Status::Failed(err.to_string()),
            }
            stop = pt.status != Status::Ok || pt.solve_s > args.max_seconds;
        }
        on_point(&pt);
        points.push(pt);
    }
}

/// Runs the study; `on_problem` sees each problem when it is set up and `on_point` each point
/// when it is done.
pub fn run<C: Comm>(comm: &C, args: &Args, on_problem: impl FnMut(&Problem), on_point: impl FnMut(&Point)) -> Result<(Vec<Problem>, Vec<Point>)> {
    if comm.size() != 1 {
        return Err(Error::scene("work-precision", "runs on one rank (Clarabel needs every body on it): run it without mpirun"));
    }
    let sorted = |v: &[f64]| {
        let mut v = v.to_vec();
        v.sort_by(|a, b| b.total_cmp(a));
        v
    };
    let (eps_dual, eps_clarabel) = (sorted(&args.eps), sorted(&args.clarabel_eps));
    let sets_at = |n: usize| std::iter::once(format!("mesh.n={n}")).chain(args.sets.iter().cloned()).collect::<Vec<_>>();
    // a scene the TFETI rows cannot use fails before any solve
    if let (Some(&s), Some(&n)) = (args.subdomains.iter().find(|&&s| s > 0), args.sizes.first()) {
        tfeti_scene(args, &sets_at(n), s)?;
    }
    let mut study = Study { args, eps_dual, eps_clarabel, on_problem, on_point, problems: Vec::new(), points: Vec::new() };
    for &n in &args.sizes {
        let sets = sets_at(n);
        let ls = crate::scene::load(&args.scene, &sets)?;
        let model = crate::model::build(&ls)?;
        let contact = model.pairs.as_ref().ok_or_else(|| Error::scene("contact", "work-precision needs a scene with contact"))?;
        // Coulomb: every solve (the reference too) is the fixed point on the slip bounds
        let coulomb = contact.is_coulomb().then(|| contact.coulomb.clone());
        if coulomb.is_some() && args.solvers.contains(&Solver::Clarabel) {
            return Err(Error::scene("--solvers", "clarabel solves the Tresca SOCP: leave it out for a Coulomb scene"));
        }
        let r = Reference::new(comm, args, n, &ls, &model, contact, coulomb)?;
        for &s in &args.subdomains {
            let problem = if s == 0 { study.monolithic_rows(comm, &r, &ls)? } else { study.tfeti_rows(comm, &r, &ls, &sets, s)? };
            study.problems.push(problem);
        }
    }
    Ok((study.problems, study.points))
}

/// The study's settings and what it has run so far.
struct Study<'s, P, Q> {
    args: &'s Args,
    /// The dual solvers' and Clarabel's tolerances, loose → tight.
    eps_dual: Vec<f64>,
    eps_clarabel: Vec<f64>,
    on_problem: P,
    on_point: Q,
    problems: Vec<Problem>,
    points: Vec<Point>,
}

/// One mesh size's monolithic dual and its reference solution, against which every row of the
/// size is measured.
struct Reference<'a, C: Comm> {
    n: usize,
    contact: &'a Contact,
    /// The contact's friction coefficients, for a Coulomb scene.
    coulomb: Option<Vec<Coefficient>>,
    dual: MonolithicDual<'a, C>,
    b: Vec<f64>,
    set: Lambda,
    /// Assembly and factorization of the monolithic dual.
    factorize_s: f64,
    bnorm: f64,
    solution: QpSolution,
    /// The reference displacements of each body, and per mesh node (for the subdomains' copies).
    u_ref: Vec<Vec<f64>>,
    u_nodes: Vec<[f64; 3]>,
    /// The largest reference displacement component (the TFETI rows' scale of err(u)).
    u_max: f64,
    dofs: usize,
}

impl<'a, C: Comm> Reference<'a, C> {
    /// Assembles and factorizes the monolithic dual at size `n` and solves it to the reference
    /// tolerance (SSN-BiCGSTAB).
    fn new(comm: &'a C, args: &Args, n: usize, ls: &LoadedScene, model: &Model, contact: &'a Contact, coulomb: Option<Vec<Coefficient>>) -> Result<Self> {
        let mut t = Timings::default();
        let bodies = assemble_and_factorize(comm, model, ls.scene.factorization.ordering, true, &mut t)?;
        let factorize_s: f64 = t.phases.iter().map(|p| p.1).sum();
        let (dual, b) = MonolithicDual::new(comm, contact, bodies);
        let set = contact.constraint_set();
        let qp_mono = Qp::new(&dual, &b, &set);
        let base = &ls.scene.solver.params;
        let zero = vec![0.0; dual.dim()];
        let bnorm = dual.space().norm(&b);
        let mut p = base.with_method(Method::SsnBicgstab);
        p.common.eps = args.reference_eps;
        p.common.max_outer = 10_000;
        let what = format!("the reference solve (SSN-BiCGSTAB, ε = {:.0e}) at N = {n}", args.reference_eps);
        let solution = qp::solve_friction(&qp_mono, coulomb.as_deref(), &zero, &p, &mut Silent).map_err(|e| Error::solver(&what, e))?;
        let u_ref = dual.recover(&solution.lambda).u;
        // the reference per mesh node, for the subdomains' copies
        let mut u_nodes = vec![[0.0; 3]; model.mesh.nodes.len()];
        for (blk, u) in dual.blocks.iter().zip(&u_ref) {
            let d = &blk.local.dofs;
            u_nodes[d.nodes.clone()].copy_from_slice(&d.expand(u));
        }
        let u_max = u_nodes.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        let dofs = 3 * model.mesh.nodes.len();
        Ok(Reference { n, contact, coulomb, dual, b, set, factorize_s, bnorm, solution, u_ref, u_nodes, u_max, dofs })
    }

    /// The cones the KKT residuals are taken against: cut at each solution's λν (Coulomb).
    fn cones(&self, set: &Lambda, l: &[f64]) -> Lambda {
        match &self.coulomb {
            Some(mu) => crate::qp::cone::bounds(set, mu, l),
            None => set.clone(),
        }
    }

    /// The problem of `subdomains` (0: the monolithic dual) with this set-up time and default.
    fn problem(&self, subdomains: usize, factorize_s: f64, default: Method) -> Problem {
        Problem { n: self.n, subdomains, dofs: self.dofs, pairs: self.contact.len(), factorize_s, reference: self.solution.info.clone(), default }
    }
}

impl<P: FnMut(&Problem), Q: FnMut(&Point)> Study<'_, P, Q> {
    /// Every solver's sweep on the monolithic dual of `r`.
    fn monolithic_rows<C: Comm>(&mut self, comm: &C, r: &Reference<'_, C>, ls: &LoadedScene) -> Result<Problem> {
        let (n, args) = (r.n, self.args);
        let problem = r.problem(0, r.factorize_s, default_method(ls, DualKind::Monolithic));
        (self.on_problem)(&problem);
        let (dual, set) = (&r.dual, &r.set);
        let qp_mono = Qp::new(dual, &r.b, set);
        let base = &ls.scene.solver.params;
        let measure = |sol: &QpSolution| {
            let e_u = u_error(comm, &dual.recover(&sol.lambda).u, &r.u_ref);
            (e_u, lambda_error(&sol.lambda, &r.solution.lambda), kkt::residuals(&r.cones(set, &sol.lambda), &sol.lambda, &sol.gradient, r.bnorm).worst())
        };
        for &solver in &args.solvers {
            let template = blank(n, 0, solver, r.factorize_s);
            match solver {
                // the monolithic dual has no preconditioner
                Solver::Dual(c) if preconditioner(c.method, c.preconditioner(), DualKind::Monolithic).is_err() => {}
                Solver::Dual(c) => {
                    sweep(&qp_mono, r.coulomb.as_deref(), c, base, args, &self.eps_dual, &template, &measure, &mut self.on_point, &mut self.points)
                }
                Solver::Clarabel => {
                    clarabel(comm, dual, &r.b, set, &r.solution.lambda, &r.u_ref, r.bnorm, &self.eps_clarabel, &template, &mut self.on_point, &mut self.points)?
                }
            }
        }
        Ok(problem)
    }

    /// Every dual solver's sweep on TFETI with `s` subdomains per body (the scene `ls` with
    /// `sets` on the TFETI path; the solver settings of `ls`), measured against `r`.
    fn tfeti_rows<C: Comm>(&mut self, comm: &C, r: &Reference<'_, C>, ls: &LoadedScene, sets: &[String], s: usize) -> Result<Problem> {
        let (n, args) = (r.n, self.args);
        let tls = tfeti_scene(args, sets, s)?;
        let mut tmodel = crate::model::build(&tls)?;
        let mut tt = Timings::default();
        let mut prob = setup(comm, &tls, &mut tmodel, &mut tt)?;
        let setup_s: f64 = tt.phases.iter().map(|p| p.1).sum();
        let problem = r.problem(s, setup_s, default_method(&tls, DualKind::of(&tls, &tmodel)));
        (self.on_problem)(&problem);
        let base = &ls.scene.solver.params;
        let ni = r.set.layout.dim();
        for &solver in &args.solvers {
            let Solver::Dual(c) = solver else { continue };
            let t0 = Instant::now();
            let pc = preconditioner(c.method, c.preconditioner(), DualKind::Tfeti { orthogonal: false, contact: true, projected: true })?;
            prob.dual.set_preconditioner(pc.unwrap_or(crate::scene::Preconditioner::None), &prob.constraints, prob.weights.clone())?;
            let pc_s = t0.elapsed().as_secs_f64();
            let (dual_t, share) = (&prob.dual, &prob.share);
            let measure = |sol: &QpSolution| {
                // the seed's bodies are held by Dirichlet conditions: α always exists; were
                // it not, the row reads NaN (no panic)
                let Some(rec) = dual_t.recover_with(&sol.lambda, None) else { return (f64::NAN, f64::NAN, f64::NAN) };
                let mut e = 0.0f64;
                for (piece, uc) in dual_t.pieces.iter().zip(&rec.u) {
                    for (m, sub) in piece.sys.subs.iter().enumerate() {
                        let us = piece.sys.part(uc, m);
                        for (l, &v) in share.layout[share.position(sub.index)].nodes.iter().enumerate() {
                            for c in 0..3 {
                                e = e.max((us[3 * l + c] - r.u_nodes[v][c]).abs());
                            }
                        }
                    }
                }
                let (li, ri) = (dual_t.dist.all_rows(&rec.lambda, ni), dual_t.dist.all_rows(&rec.gap, ni));
                (e / r.u_max, lambda_error(&li, &r.solution.lambda), kkt::residuals(&r.cones(&r.set, &li), &li, &ri, r.bnorm).worst())
            };
            let m = prob.dual.preconditioner();
            let dk = DualKind::Tfeti { orthogonal: false, contact: true, projected: true };
            let coarse = crate::pipeline::projected(c.method, dk).then_some(&prob.dual as &dyn crate::qp::Coarse);
            let qp = Qp::new(&prob.dual, &prob.b, &prob.set).with_preconditioner(m.as_ref().map(|m| m as &dyn Preconditioner)).with_coarse(coarse);
            let mu = r.coulomb.as_ref().map(|_| r.contact.coefficients(&prob.dual.dist.pairs));
            let template = blank(n, s, solver, setup_s + pc_s);
            sweep(&qp, mu.as_deref(), c, base, args, &self.eps_dual, &template, &measure, &mut self.on_point, &mut self.points);
        }
        Ok(problem)
    }
}

/// The scene with S subdomains per body on the TFETI path (oblique projector, no preconditioner:
/// the rows set theirs).
fn tfeti_scene(args: &Args, sets: &[String], s: usize) -> Result<crate::scene::LoadedScene> {
    let mut sets = sets.to_vec();
    sets.extend([format!("decomposition.subdomains={s}"), "decomposition.tfeti=true".into(), "solver.preconditioner=\"none\"".into()]);
    let ls = crate::scene::load(&args.scene, &sets)?;
    let d = &ls.scene.decomposition;
    if d.target_dofs.is_some() || d.projector != Projector::Oblique {
        return Err(Error::scene(
            "--subdomains",
            "the TFETI rows need decomposition.projector = \"oblique\" and no decomposition.target_dofs (--subdomains sets the count)",
        ));
    }
    Ok(ls)
}

/// Clarabel on the primal SOCP at each of its tolerances (its time hardly depends on ε: only a
/// failure ends its sweep).
#[allow(clippy::too_many_arguments)]
fn clarabel<C: Comm>(
    comm: &C,
    dual: &MonolithicDual<'_, C>,
    b: &[f64],
    set: &Lambda,
    lambda_ref: &[f64],
    u_ref: &[Vec<f64>],
    bnorm: f64,
    eps: &[f64],
    template: &Point,
    on_point: &mut impl FnMut(&Point),
    points: &mut Vec<Point>,
) -> Result<()> {
    let socp = PrimalSocp::new(dual, b, set)?;
    let mut stop = false;
    for &e in eps {
        let mut pt = Point { eps: e, setup_s: socp.build_s, ..template.clone() };
        if !stop {
            let t0 = Instant::now();
            match socp.solve(e) {
                Ok(sol) => {
                    pt.solve_s = sol.solve_s;
                    pt.status = Status::Ok;
                    pt.iterations = sol.iterations as usize;
                    pt.err_u = u_error(comm, &sol.u, u_ref);
                    pt.err_lambda = lambda_error(&sol.lambda, lambda_ref);
                    pt.kkt = kkt::residuals(set, &sol.lambda, &sol.gradient, bnorm).worst();
                }
                Err(err) => {
                    pt.solve_s = t0.elapsed().as_secs_f64();
                    pt.status = Status::Failed(err.to_string());
                }
            }
            stop = pt.status != Status::Ok;
        }
        on_point(&pt);
        points.push(pt);
    }
    Ok(())
}

/// "monolithic" or "TFETI S = s".
pub fn dual_label(subdomains: usize) -> String {
    if subdomains == 0 {
        "monolithic".into()
    } else {
        format!("TFETI S = {subdomains}")
    }
}

/// The fastest solve of `solver` at size `n` on dual `subdomains` whose error in u is at most
/// `target`.
pub fn time_to(points: &[Point], n: usize, subdomains: usize, solver: Solver, target: f64) -> Option<&Point> {
    points
        .iter()
        .filter(|p| p.n == n && p.subdomains == subdomains && p.solver == solver && p.status == Status::Ok && p.err_u <= target)
        .min_by(|a, b| a.solve_s.total_cmp(&b.solve_s))
}

/// One printed line per point.
pub fn format_point(p: &Point) -> String {
    let head = format!("N = {:>2} {:<14} {:<18} ε = {:.0e}", p.n, dual_label(p.subdomains), p.solver.label(), p.eps);
    match &p.status {
        Status::Ok => format!(
            "{head}: {:>5} it {:>6} nA {:>9.3} s  err(u) {:.1e}  err(λ) {:.1e}  KKT {:.1e}",
            p.iterations, p.n_a, p.solve_s, p.err_u, p.err_lambda, p.kkt
        ),
        Status::Failed(e) => format!("{head}: failed after {:.1} s: {e}", p.solve_s),
        Status::Skipped => format!("{head}: skipped (a looser ε failed or took longer than the limit)"),
    }
}

/// The summary: per N and solver, the time (and ε, nA) to reach each target error in u, and the
/// ratio to the default solver's time.
pub fn summary(problems: &[Problem], points: &[Point], solvers: &[Solver], targets: &[f64]) -> String {
    let mut s = String::new();
    for pr in problems {
        let default = Solver::Dual(Column { method: pr.default, preset: crate::studies::table1::Preset::Default });
        let setup = if pr.subdomains == 0 { "assembly + factorization" } else { "TFETI set-up" };
        s += &format!(
            "N = {}, {} (n = {}, m = {}; {setup} {:.2} s; reference {}/{} nA, ‖r̃‖/‖b‖ = {:.1e})\n",
            pr.n,
            dual_label(pr.subdomains),
            pr.dofs,
            pr.pairs,
            pr.factorize_s,
            pr.reference.iterations,
            pr.reference.n_a,
            pr.reference.err
        );
        s += &format!("  {:<18}", "solver");
        for t in targets {
            s += &format!(" | {:<36}", format!("err(u) ≤ {t:.0e}: time (ε, nA) ×default"));
        }
        s += "\n";
        let run_here = |solver: &Solver| points.iter().any(|p| p.n == pr.n && p.subdomains == pr.subdomains && p.solver == *solver);
        for &solver in solvers.iter().filter(|s| run_here(s)) {
            s += &format!("  {:<18}", solver.label() + if solver == default { " (default)" } else { "" });
            for &t in targets {
                let cell = match (time_to(points, pr.n, pr.subdomains, solver, t), time_to(points, pr.n, pr.subdomains, default, t)) {
                    (Some(p), d) => {
                        let ratio = d.map(|d| format!(" {:.1}×", p.solve_s / d.solve_s)).unwrap_or_default();
                        let na = if matches!(solver, Solver::Clarabel) { format!("{} it", p.iterations) } else { format!("{} nA", p.n_a) };
                        format!("{:.3} s ({:.0e}, {na}){ratio}", p.solve_s, p.eps)
                    }
                    (None, _) => "not reached".into(),
                };
                s += &format!(" | {cell:<36}");
            }
            s += "\n";
        }
    }
    s
}

/// Writes the CSV (one line per point).
pub fn write_csv(path: &Path, problems: &[Problem], points: &[Point]) -> Result<()> {
    let mut f = Vec::new();
    let io = |e| Error::io(path.display().to_string(), e);
    writeln!(f, "N,S,n,m,solver,default,eps,status,iter,nA,nA_power,inner,setup_s,solve_s,err_u,err_lambda,kkt,residual").map_err(io)?;
    for p in points {
        let pr = problems.iter().find(|pr| pr.n == p.n && pr.subdomains == p.subdomains).expect("a point's problem");
        let is_default = matches!(p.solver, Solver::Dual(c) if c.method == pr.default && c.preset == crate::studies::table1::Preset::Default);
        let status = match &p.status {
            Status::Ok => "ok".to_string(),
            Status::Skipped => "skipped".to_string(),
            // one field without quotes: the plot script splits at commas
            Status::Failed(e) => format!("failed: {}", e.replace(['"', ','], ";")),
        };
        writeln!(
            f,
            "{},{},{},{},{},{},{:e},{status},{},{},{},{},{:.4},{:.5},{:e},{:e},{:e},{:e}",
            p.n,
            p.subdomains,
            pr.dofs,
            pr.pairs,
            p.solver.label(),
            is_default as u8,
            p.eps,
            p.iterations,
            p.n_a,
            p.n_a_power,
            p.inner,
            p.setup_s,
            p.solve_s,
            p.err_u,
            p.err_lambda,
            p.kkt,
            p.residual
        )
        .map_err(io)?;
    }
    crate::output::write_atomically(path, &f)
}

/// The method a `solve` of the scene takes on that dual (`pipeline::resolve_method`).
fn default_method(ls: &crate::scene::LoadedScene, kind: DualKind) -> Method {
    let mut solver = ls.scene.solver.clone();
    crate::pipeline::resolve_method(&mut solver, kind);
    solver.params.method()
}
