//! The accuracy guard: what every returned result must satisfy, judged after the recovery and
//! before anything is written — the recovered equilibrium K_s u_s = f_s − B_sᵀλ of every piece
//! and, with contact, the KKT residuals of λ — and what the pipeline does when a solve that met
//! its stopping test misses it: tighten ε and continue from the last λ (at most
//! [`MAX_TIGHTENINGS`] times, each recorded in the report), then refuse with the reason.
//!
//! A piece's equilibrium passes when its relative residual ‖K x − rhs‖/‖rhs‖ is at most
//! [`EQUILIBRIUM_BOUND`], or when the residual is at the level of the rounding in forming K x
//! over the whole problem: ‖K x − rhs‖ at most [`ROUNDING_BOUND`] times the largest
//! ‖ |K||x| + |rhs| ‖ of any piece (the forces of a piece that moves rigidly, or of one that
//! carries nothing, nearly cancel, so its own ‖rhs‖ is no scale there).

use crate::comm::Comm;
use crate::linalg::sparse::SymCsc;

/// The largest relative residual of a piece's recovered equilibrium.
pub const EQUILIBRIUM_BOUND: f64 = 1e-6;
/// A residual at most this times the problem's largest ‖ |K||x| + |rhs| ‖ is rounding, whatever
/// the relative residual.
pub const ROUNDING_BOUND: f64 = 1e-12;
/// KKT residuals up to this multiple of ε pass (the stability suite's default factor).
pub const KKT_FACTOR: f64 = 100.0;
/// ... and never fail below this (the rounding of r = Aλ − b relative to ‖b‖).
pub const KKT_FLOOR: f64 = 1e-10;
/// Times ε is tightened for one solve before the result is refused.
pub const MAX_TIGHTENINGS: usize = 2;
/// ε is never tightened below this.
pub const EPS_FLOOR: f64 = 1e-14;

/// The recovered equilibrium of one piece.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Equilibrium {
    /// ‖K x − rhs‖.
    pub residual: f64,
    /// ‖rhs‖.
    pub rhs: f64,
    /// ‖ |K||x| + |rhs| ‖: the size of the terms whose cancellation gives the residual.
    pub scale: f64,
}

impl Equilibrium {
    /// K x against rhs; `held` entries of x are prescribed (their rows carry reactions and are
    /// not checked).
    pub fn of(k: &SymCsc, x: &[f64], rhs: &[f64], held: &[usize]) -> Self {
        let mut kx = k.mul(x);
        let mut scale = k.abs_mul(x);
        for &d in held {
            kx[d] = rhs[d];
            scale[d] = 0.0;
        }
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|a| a * a).sum::<f64>().sqrt();
        Equilibrium {
            residual: norm(&mut kx.iter().zip(rhs).map(|(a, b)| a - b)),
            rhs: norm(&mut rhs.iter().copied()),
            scale: norm(&mut scale.iter().zip(rhs).map(|(a, b)| a + b.abs())),
        }
    }

    /// ‖K x − rhs‖ / ‖rhs‖ (the residual itself where rhs = 0).
    pub fn relative(&self) -> f64 {
        if self.rhs > 0.0 {
            self.residual / self.rhs
        } else {
            self.residual
        }
    }

    /// How far past the guard it lies, with `scale` the largest [`Equilibrium::scale`] of the
    /// problem: ≤ 1 passes (the smaller of the two ratios to their bounds; NaN counts as
    /// infinitely far).
    pub fn excess(&self, scale: f64) -> f64 {
        let rounding = if scale > 0.0 { self.residual / (scale * ROUNDING_BOUND) } else { f64::INFINITY };
        let e = (self.relative() / EQUILIBRIUM_BOUND).min(rounding);
        if e.is_nan() {
            f64::INFINITY
        } else {
            e
        }
    }

    /// Whether it passes on its own (its own scale the problem's).
    #[cfg(test)]
    pub fn passes(&self) -> bool {
        self.excess(self.scale) <= 1.0
    }
}

/// The largest KKT residual that passes at tolerance ε.
pub fn kkt_bound(eps: f64) -> f64 {
    (KKT_FACTOR * eps).max(KKT_FLOOR)
}

/// A result judged over all ranks: the worst piece's equilibrium and the KKT residual (0
/// without contact).
#[derive(Clone, Copy, Debug, Default)]
pub struct Verdict {
    /// The largest [`Equilibrium::excess`] over every piece of every rank.
    pub excess: f64,
    /// The worst piece's relative residual.
    pub relative: f64,
    pub kkt: f64,
    pub eps: f64,
}

impl Verdict {
    /// The verdict on this rank's `pieces` (reduced over the ranks: every rank gets the same)
    /// with the KKT residual `kkt` (the same on every rank) of a solve at tolerance `eps`.
    pub fn new<C: Comm>(comm: &C, pieces: &[Equilibrium], kkt: f64, eps: f64) -> Self {
        let mut scale = [pieces.iter().map(|e| e.scale).fold(0.0, f64::max)];
        comm.max_f64(&mut scale);
        let (mut excess, mut relative) = (0.0f64, 0.0f64);
        for e in pieces {
            if e.excess(scale[0]) >= excess {
                (excess, relative) = (e.excess(scale[0]), e.relative());
            }
        }
        // `TRESCA_FETI_FAULT=accuracy@<rank>`: that rank's equilibrium reads as missed (to test
        // the guard's refusal end to end)
        let injected = std::env::var("TRESCA_FETI_FAULT")
            .is_ok_and(|f| f.split_once('@').is_some_and(|(p, r)| p == "accuracy" && r.parse::<usize>().ok() == Some(comm.rank())));
        if injected {
            (excess, relative) = (f64::INFINITY, f64::INFINITY);
        }
        let mut v = [excess, relative];
        comm.max_f64(&mut v);
        Verdict { excess: v[0], relative: v[1], kkt, eps }
    }

    pub fn passes(&self) -> bool {
        self.excess <= 1.0 && self.kkt <= kkt_bound(self.eps)
    }

    /// What it missed, in words (for the report and the refusal).
    pub fn reason(&self) -> String {
        let mut why = Vec::new();
        if self.excess.is_nan() || self.excess > 1.0 {
            why.push(format!("the recovered equilibrium K u = f − Bᵀλ has relative residual {:.1e} > {EQUILIBRIUM_BOUND:.0e}", self.relative));
        }
        if self.kkt.is_nan() || self.kkt > kkt_bound(self.eps) {
            why.push(format!("KKT residual {:.1e} > {:.0e} ({KKT_FACTOR}·ε, at least {KKT_FLOOR:.0e})", self.kkt, kkt_bound(self.eps)));
        }
        why.join(" and ")
    }

    /// The tighter ε to continue with: ε divided by ten times the larger miss (between 10 and
    /// 1000), not below [`EPS_FLOOR`]; None when ε is already there or the miss is not finite.
    pub fn tighter_eps(&self) -> Option<f64> {
        let miss = self.excess.max(self.kkt / kkt_bound(self.eps));
        if !miss.is_finite() || self.excess.is_nan() || self.kkt.is_nan() || self.eps <= EPS_FLOOR {
            return None;
        }
        Some((self.eps / (10.0 * miss).clamp(10.0, 1000.0)).max(EPS_FLOOR))
    }
}

/// One tightening of ε by the guard, as the report records it.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Tightening {
    /// The load step (1 without a load path).
    pub step: usize,
    pub from_eps: f64,
    pub to_eps: f64,
    /// What the result at `from_eps` missed.
    pub reason: String,
}

impl Tightening {
    /// The summary's line.
    pub fn line(&self) -> String {
        format!("accuracy guard: ε tightened {:.1e} → {:.1e} at load step {}: {}", self.from_eps, self.to_eps, self.step, self.reason)
    }
}

/// The guard of one solve (a load step): how often it tightened ε, and the record.
#[derive(Clone, Debug, Default)]
pub struct Guard {
    pub tightenings: Vec<Tightening>,
    tries: usize,
}

impl Guard {
    /// After a solve of load step `step` judged by `verdict`: `Ok(None)` when it passes, `Ok(Some(ε'))`
    /// to continue from its λ at the tighter ε' (recorded and shown on `live`), an error naming
    /// `what` (the solver) and the reason when no tightening is left.
    pub fn next(&mut self, step: usize, verdict: &Verdict, what: &str, live: &super::monitor::Live) -> crate::Result<Option<f64>> {
        if verdict.passes() {
            return Ok(None);
        }
        let tighter = verdict.tighter_eps().filter(|_| self.tries < MAX_TIGHTENINGS);
        let Some(eps) = tighter else {
            let floor = if verdict.eps <= EPS_FLOOR { ", the smallest ε double precision reaches" } else { "" };
            let tried = if self.tries > 0 { format!(" after tightening ε to {:.1e}{floor}", verdict.eps) } else { String::new() };
            return Err(crate::Error::numerical(what, format!("the result fails its accuracy check{tried}: {}", verdict.reason())));
        };
        self.tries += 1;
        let t = Tightening { step, from_eps: verdict.eps, to_eps: eps, reason: verdict.reason() };
        live.line(&t.line());
        self.tightenings.push(t);
        Ok(Some(eps))
    }
}

/// The problem's force scale for the KKT residuals: ‖b‖/σ_max(A) (0 when σ is unknown).
pub fn force_scale(bnorm: f64, sigma: f64) -> f64 {
    if sigma > 0.0 && sigma.is_finite() {
        bnorm / sigma
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2 × 2 K = [[2, −1], [−1, 2]] (lower triangle).
    fn k() -> SymCsc {
        SymCsc { n: 2, col_ptr: vec![0, 2, 3], row_idx: vec![0, 1, 1], values: vec![2.0, -1.0, 2.0] }
    }

    #[test]
    fn an_exact_solution_passes_and_a_wrong_one_does_not() {
        let e = Equilibrium::of(&k(), &[1.0, 1.0], &[1.0, 1.0], &[]);
        assert_eq!(e.relative(), 0.0);
        assert!(e.passes());
        let e = Equilibrium::of(&k(), &[1.0, 1.0], &[1.0, 1.1], &[]);
        assert!(e.relative() > 0.05 && !e.passes(), "{e:?}");
        // a held entry's row is a reaction: not checked
        let e = Equilibrium::of(&k(), &[1.0, 1.0], &[1.0, 5.0], &[1]);
        assert!(e.passes(), "{e:?}");
    }

    #[test]
    fn a_rounding_level_residual_passes_where_the_forces_cancel() {
        // x nearly in the kernel of a nearly singular K: K x is all cancellation
        let k = SymCsc { n: 2, col_ptr: vec![0, 2, 3], row_idx: vec![0, 1, 1], values: vec![1.0, -1.0, 1.0] };
        let x = [1.0, 1.0];
        let e = Equilibrium::of(&k, &x, &[1e-17, -1e-17], &[]);
        assert!(e.relative() > 0.5, "relative to ‖rhs‖ it is all residual: {e:?}");
        assert!(e.passes(), "{e:?}");
        // the same rhs off by 1e-9 of the forces formed is not rounding
        assert!(!Equilibrium::of(&k, &x, &[1e-9, 0.0], &[]).passes());
        // a piece that carries nothing (x, rhs of round-off size) against the problem's scale
        let idle = Equilibrium::of(&k, &[1e-15, 0.0], &[1e-18, 0.0], &[]);
        assert!(idle.excess(1.0) <= 1.0 && idle.excess(1e-12) > 1.0, "{idle:?}");
    }

    #[test]
    fn the_verdict_tightens_by_the_miss_and_stops_at_the_floor() {
        let v = Verdict { excess: 3.0, relative: 3e-6, kkt: 0.0, eps: 1e-8 };
        assert!(!v.passes());
        let near = |a: Option<f64>, b: f64| a.is_some_and(|a| (a - b).abs() <= 1e-12 * b);
        assert!(near(v.tighter_eps(), 1e-8 / 30.0), "{:?}", v.tighter_eps());
        let v = Verdict { excess: 0.5, relative: 5e-7, kkt: 1e-3, eps: 1e-8 };
        assert!(!v.passes() && v.reason().contains("KKT"), "{}", v.reason());
        assert!(near(v.tighter_eps(), 1e-11), "{:?}", v.tighter_eps());
        assert_eq!(Verdict { excess: f64::NAN, relative: f64::NAN, kkt: 0.0, eps: 1e-8 }.tighter_eps(), None);
        assert_eq!(Verdict { excess: 2.0, relative: 2e-6, kkt: 0.0, eps: 1e-14 }.tighter_eps(), None);
        assert!(Verdict { excess: 1.0, relative: 1e-6, kkt: 1e-6, eps: 1e-8 }.passes());
    }
}
