//! Unit tests of the convex sets: projections against brute force, slant derivatives against
//! finite differences, steps to the boundary, Newton's iteration counts, NaN input.

use super::*;
use std::f64::consts::PI;

/// Deterministic LCG (Knuth's MMIX constants), uniform in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn sym(&mut self) -> f64 {
        2.0 * self.next() - 1.0
    }
    fn angle(&mut self) -> f64 {
        2.0 * PI * self.next()
    }
}

fn norm(v: [f64; 2]) -> f64 {
    v[0].hypot(v[1])
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn proj(set: &impl ConvexSet, y: [f64; 2]) -> [f64; 2] {
    let mut x = [0.0; 2];
    set.project(&y, &mut x);
    x
}

fn slant(set: &impl ConvexSet, y: [f64; 2]) -> [f64; 4] {
    let mut j = [0.0; 4];
    set.slant(&y, &mut j);
    j
}

/// Test points for the set with semi-axes (a, b) (a disc: a = b): inside, near the boundary
/// on both sides, uniform in a box, on and near the axes, and far away.
fn points(a: f64, b: f64, rng: &mut Lcg) -> Vec<[f64; 2]> {
    let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
    let mut v = Vec::new();
    for _ in 0..120 {
        v.push([3.0 * s * rng.sym(), 3.0 * s * rng.sym()]);
    }
    for _ in 0..60 {
        let (t, r) = (rng.angle(), rng.next());
        v.push([r * a * t.cos(), r * b * t.sin()]);
    }
    for k in 0..60 {
        let t = rng.angle();
        let f = 1.0 + if k % 2 == 0 { 1.0 } else { -1.0 } * 10f64.powi(-(3 + k % 10));
        v.push([f * a * t.cos(), f * b * t.sin()]);
    }
    for &t in &[0.0, 0.3, 0.999, 1.0, 1.0 + 1e-9, 1.5, 3.0, 1e3] {
        for &sg in &[1.0, -1.0] {
            v.push([sg * t * a, 0.0]);
            v.push([0.0, sg * t * b]);
            v.push([sg * t * s, 0.0]);
            v.push([0.0, sg * t * s]);
            v.push([sg * t * s, 1e-9 * s]);
            v.push([1e-12 * s, sg * t * s]);
        }
    }
    for k in 1..=12 {
        let t = rng.angle();
        let r = 10f64.powi(k) * s;
        v.push([r * t.cos(), r * t.sin()]);
    }
    v
}

const NS: usize = 100_000;

/// Brute-force distance from y to the ellipse (a, b) (or disc, segment, point): minimum over
/// NS boundary samples, refined by golden-section search on the angle (in units scaled by
/// max(a, b), to avoid overflow). Zero inside a proper ellipse.
fn brute_distance(a: f64, b: f64, y: [f64; 2], cs: &[(f64, f64)]) -> f64 {
    let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
    let (ah, bh) = (a / s, b / s);
    let yh = [y[0] / s, y[1] / s];
    if ah > 0.0 && bh > 0.0 && (yh[0] / ah).hypot(yh[1] / bh) <= 1.0 {
        return 0.0;
    }
    let d2 = |c: f64, sn: f64| (yh[0] - ah * c).powi(2) + (yh[1] - bh * sn).powi(2);
    let mut best = (f64::INFINITY, 0usize);
    for (j, &(c, sn)) in cs.iter().enumerate() {
        let d = d2(c, sn);
        if d < best.0 {
            best = (d, j);
        }
    }
    let h = 2.0 * PI / NS as f64;
    let th = best.1 as f64 * h;
    let f = |t: f64| d2(t.cos(), t.sin());
    let (mut lo, mut hi) = (th - 1.5 * h, th + 1.5 * h);
    let gr = (5f64.sqrt() - 1.0) / 2.0;
    for _ in 0..120 {
        let m1 = hi - gr * (hi - lo);
        let m2 = lo + gr * (hi - lo);
        if f(m1) < f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    best.0.min(f(0.5 * (lo + hi))).sqrt() * s
}

fn samples() -> Vec<(f64, f64)> {
    (0..NS)
        .map(|j| {
            let t = 2.0 * PI * j as f64 / NS as f64;
            (t.cos(), t.sin())
        })
        .collect()
}

/// Kind of the tangent set, for the checks that depend on it.
fn is_proper(a: f64, b: f64) -> bool {
    a.min(b) > DEGENERATE_RATIO * a.max(b)
}

/// Every check except finite differences, for one tangent set with semi-axes (a, b).
fn check_tangent_set(set: TangentSet, a: f64, b: f64, seed: u64, cs: &[(f64, f64)]) {
    let mut rng = Lcg(seed);
    let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
    let proper = is_proper(a, b);
    let ys = points(a, b, &mut rng);
    for &y in &ys {
        let x = proj(&set, y);
        let ny = norm(y);
        let e = sub(y, x);
        let dp = norm(e);
        let db = brute_distance(a, b, y, cs);
        let tol = 1e-14 * (s + ny);
        assert!(dp <= db + tol, "{set:?} y={y:?}: |y-P(y)|={dp:e} > brute {db:e}");
        assert!(db <= dp + 1e-9 * (s + ny), "{set:?} y={y:?}: brute {db:e} << {dp:e}");
        assert!(set.contains(&x, 1e-12 * s), "{set:?} y={y:?}: P(y)={x:?} not in set");
        let outside = set.is_outside(&y);
        if !outside {
            assert_eq!(x, y, "{set:?}: inside point moved");
        } else if proper {
            let q = (x[0] / a).hypot(x[1] / b);
            assert!((q - 1.0).abs() <= 1e-12, "{set:?} y={y:?}: P(y) off boundary {q}");
        }
        // Idempotence.
        let xx = proj(&set, x);
        assert!(norm(sub(xx, x)) <= 1e-14 * s, "{set:?} y={y:?}: P(P(y)) != P(y)");
        // Variational inequality (y − x)·(z − x) ≤ 0 for z in the set (boundary samples).
        for &(c, sn) in cs.iter().step_by(97) {
            let z = [a * c, b * sn];
            let vi = (e[0] / s) * ((z[0] - x[0]) / s) + (e[1] / s) * ((z[1] - x[1]) / s);
            assert!(vi <= 1e-12 * (1.0 + ny / s), "{set:?} y={y:?}: VI {vi:e}");
        }
        if outside && proper && dp > 1e-6 * s {
            // y − x parallel to the constraint's gradient (x₁/a², x₂/b²) (scaled units).
            let g = [x[0] / s / (a / s).powi(2), x[1] / s / (b / s).powi(2)];
            let (gn, en) = (norm(g), dp);
            let cross = (e[0] * g[1] - e[1] * g[0]) / (gn * en);
            let dot = (e[0] * g[0] + e[1] * g[1]) / (gn * en);
            assert!(cross.abs() <= 1e-12 + 1e-15 * ny / dp, "{set:?} y={y:?}: cross {cross:e}");
            assert!(dot > 0.0, "{set:?} y={y:?}: inward normal");
        }
        // Frame and slant consistency.
        match set.frame(&y) {
            None => assert!(!outside),
            Some(f) => {
                assert!(outside);
                assert_eq!(f.point, x);
                let en = norm(e);
                assert!((f.distance - en).abs() <= 1e-10 * en + 1e-14 * (s + ny), "{set:?} y={y:?}: distance {} vs {en}", f.distance);
                assert!((norm(f.normal) - 1.0).abs() < 1e-15);
                assert!(f.tangent[0] * f.normal[0] + f.tangent[1] * f.normal[1] == 0.0);
                if en > 1e-6 * s {
                    let c = (e[0] * f.normal[1] - e[1] * f.normal[0]) / en;
                    assert!(c.abs() <= 1e-12 + 1e-15 * ny / en, "{set:?} y={y:?}: normal");
                }
                assert_eq!(f.slant(), slant(&set, y), "{set:?} y={y:?}");
                let mu2 = 1.0 / (1.0 + f.curvature * f.distance);
                assert!((f.mu - mu2).abs() <= 1e-12 * f.mu.max(mu2) + 1e-300, "{set:?} y={y:?}: mu {} vs 1/(1+κd) {mu2}", f.mu);
                assert!((0.0..=1.0).contains(&f.mu));
                if proper {
                    let k = set.curvature(&x);
                    assert!((k - f.curvature).abs() <= 1e-12 * k, "{set:?} y={y:?}: κ");
                }
            }
        }
        let j = slant(&set, y);
        assert!(j.iter().all(|v| v.is_finite()) && j[1] == j[2], "{set:?}: slant {j:?}");
    }
    check_max_step(set, a, b, &mut rng, &ys);
}

fn check_max_step(set: TangentSet, a: f64, b: f64, rng: &mut Lcg, ys: &[[f64; 2]]) {
    let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
    let proper = is_proper(a, b);
    assert_eq!(set.max_step(&[0.0, 0.0], &[0.0, 0.0]), f64::INFINITY);
    for (k, &y) in ys.iter().enumerate() {
        // A point in the set: P(y), or strictly inside.
        let strict = k % 2 == 0;
        let mut x = proj(&set, y);
        if strict {
            x = [0.9 * x[0], 0.9 * x[1]];
        }
        let mag = 10f64.powi((k % 7) as i32 - 3);
        let t = rng.angle();
        let d = match k % 5 {
            0 => [mag, 0.0],
            1 => [0.0, -mag],
            _ => [mag * t.cos(), mag * t.sin()],
        };
        let alpha = set.max_step(&x, &d);
        assert!(alpha >= 0.0 && alpha.is_finite(), "{set:?} x={x:?} d={d:?}: {alpha}");
        let at = |al: f64| [x[0] - al * d[0], x[1] - al * d[1]];
        assert!(set.contains(&at(alpha), 1e-12 * s), "{set:?} x={x:?} d={d:?}: {alpha}");
        if alpha > 0.0 {
            assert!(set.contains(&at(0.5 * alpha), 1e-12 * s));
        }
        let scale = s / norm(d);
        if alpha > 1e-6 * scale {
            assert!(set.is_outside(&at(alpha * (1.0 + 1e-9) + 1e-12 * scale)));
            if proper {
                let q = (at(alpha)[0] / a).hypot(at(alpha)[1] / b);
                assert!((q - 1.0).abs() <= 1e-12, "{set:?}: x − αd off boundary ({q})");
            }
        }
        if strict && proper {
            // Bisection along the ray.
            let mut hi = scale;
            while !set.is_outside(&at(hi)) {
                hi *= 2.0;
            }
            let mut lo = 0.0;
            for _ in 0..200 {
                let m = 0.5 * (lo + hi);
                if set.is_outside(&at(m)) {
                    hi = m;
                } else {
                    lo = m;
                }
            }
            assert!((alpha - lo).abs() <= 1e-10 * lo, "{set:?} x={x:?} d={d:?}: max_step {alpha:e} vs bisection {lo:e}");
        }
    }
}

/// Sets tested against brute force: (a, b) and the scale factor.
fn ellipses() -> Vec<(f64, f64)> {
    let base = [
        (1.0, 1.0),
        (3.0, 1.0),
        (1.0, 3.0),
        (100.0, 1.0),
        (1.0, 100.0),
        (1e4, 1.0),
        (1.0, 1e4),
        (1.0, 1e-6),
        (2.0, 0.0),
        (0.0, 2.0),
        (0.0, 0.0),
        (1.0, 1e-101),
    ];
    let mut v: Vec<(f64, f64)> = base.to_vec();
    for &f in &[1e-150, 1e150, 0.37] {
        for &(a, b) in &[(3.0, 1.0), (1e4, 1.0), (2.0, 0.0), (1.0, 1.0)] {
            v.push((a * f, b * f));
        }
    }
    v
}

#[test]
fn ellipse_against_brute_force() {
    let cs = samples();
    for (i, (a, b)) in ellipses().into_iter().enumerate() {
        check_tangent_set(Ellipse::new(a, b).into(), a, b, 17 + i as u64, &cs);
    }
}

#[test]
fn disc_against_brute_force() {
    let cs = samples();
    for (i, &g) in [1.0, 0.37, 0.09, 1e-150, 1e150, 0.0].iter().enumerate() {
        check_tangent_set(Disc::new(g).into(), g, g, 5 + i as u64, &cs);
    }
}

/// Central differences with one Richardson extrapolation (error O(h⁴)).
fn fd_jacobian(set: &impl ConvexSet, y: [f64; 2], h: f64) -> [f64; 4] {
    let mut j = [0.0; 4];
    for c in 0..2 {
        let diff = |h: f64| {
            let mut yp = y;
            let mut ym = y;
            yp[c] += h;
            ym[c] -= h;
            let (p, m) = (proj(set, yp), proj(set, ym));
            [(p[0] - m[0]) / (2.0 * h), (p[1] - m[1]) / (2.0 * h)]
        };
        let (d1, d2) = (diff(h), diff(0.5 * h));
        for r in 0..2 {
            j[2 * r + c] = (4.0 * d2[r] - d1[r]) / 3.0;
        }
    }
    j
}

fn check_slant_fd(set: TangentSet, a: f64, b: f64, seed: u64) -> usize {
    let mut rng = Lcg(seed);
    let s = if a.max(b) > 0.0 { a.max(b) } else { 1.0 };
    let mut checked = 0;
    for y in points(a, b, &mut rng) {
        let ny = norm(y);
        let (h, away) = match set.frame(&y) {
            // J varies on the scale distance + radius of curvature (or faster, where the
            // curvature varies; the step is refined below).
            Some(f) => (1e-3 * f.distance.min(1.0 / f.curvature), f.distance > 1e-4 * s),
            None => {
                let m = a.min(b);
                let q = if m > 0.0 { (y[0] / a).hypot(y[1] / b) } else { 1.0 };
                (1e-3 * m, q < 0.5)
            }
        };
        if !away || !(h > 0.0) {
            continue;
        }
        // Refine h until two Richardson estimates agree (or rounding dominates).
        let mut h = h;
        let rounding = |h: f64| 20.0 * EPS * (s + ny) / h;
        for _ in 0..20 {
            let (j1, j2) = (fd_jacobian(&set, y, h), fd_jacobian(&set, y, 0.25 * h));
            let jm = j2.iter().fold(0f64, |m, v| m.max(v.abs()));
            let d = j1.iter().zip(&j2).fold(0f64, |m, (p, q)| m.max((p - q).abs()));
            if d <= 1e-8 * jm + rounding(0.25 * h) {
                break;
            }
            h *= 0.25;
        }
        let j = slant(&set, y);
        let jf = fd_jacobian(&set, y, h);
        let jmax = j.iter().fold(0f64, |m, v| m.max(v.abs()));
        let err = j.iter().zip(&jf).fold(0f64, |m, (p, q)| m.max((p - q).abs()));
        // Truncation ~1e-12·‖J‖; rounding ~eps·(s + |y|)/h.
        let tol = 1e-6 * jmax + rounding(h);
        assert!(err <= tol, "{set:?} y={y:?}: slant {j:?} vs FD {jf:?} (err {err:e})");
        checked += 1;
    }
    checked
}

#[test]
fn slant_against_finite_differences() {
    let mut n = 0;
    for (i, (a, b)) in ellipses().into_iter().enumerate() {
        n += check_slant_fd(Ellipse::new(a, b).into(), a, b, 100 + i as u64);
    }
    for (i, &g) in [1.0, 0.09, 1e-150, 1e150].iter().enumerate() {
        n += check_slant_fd(Disc::new(g).into(), g, g, 200 + i as u64);
    }
    assert!(n > 3000, "only {n} points checked");
}

#[test]
fn ellipse_with_equal_axes_is_the_disc() {
    let mut rng = Lcg(3);
    for &g in &[1.0, 0.09, 7.5, 1e-150, 1e150] {
        let (e, d) = (Ellipse::new(g, g), Disc::new(g));
        for y in points(g, g, &mut rng) {
            let (xe, xd) = (proj(&e, y), proj(&d, y));
            assert!(norm(sub(xe, xd)) <= 1e-14 * g, "g={g} y={y:?}: {xe:?} vs {xd:?}");
            let (je, jd) = (slant(&e, y), slant(&d, y));
            for k in 0..4 {
                assert!((je[k] - jd[k]).abs() <= 1e-14, "g={g} y={y:?}: {je:?} vs {jd:?}");
            }
            if (norm(y) - g).abs() > 4.0 * EPS * g {
                assert_eq!(e.is_outside(&y), d.is_outside(&y));
            }
            if let (Some(fe), Some(fd)) = (e.frame(&y), d.frame(&y)) {
                assert!((fe.mu - fd.mu).abs() <= 1e-14);
                assert!((fe.curvature - fd.curvature).abs() <= 1e-14 * fd.curvature);
                assert!((fe.distance - fd.distance).abs() <= 1e-14 * (g + norm(y)));
            }
        }
    }
}

#[test]
fn ellipse_newton_is_fast_and_scale_covariant() {
    let mut rng = Lcg(11);
    let mut worst = (0, 0.0, 0.0, [0.0; 2]);
    let mut sets = ellipses();
    sets.extend([(1.0, 1e-8), (1.0, 1e-20), (1.0, 1e-50), (1.0, 1e-99), (1e-99, 1.0)]);
    for (a, b) in sets {
        let e = Ellipse::new(a, b);
        let mut ys = points(a, b, &mut rng);
        ys.extend(vertex_points(a, b));
        for y in ys {
            let it = e.newton_iters(&y);
            if it > worst.0 {
                worst = (it, a, b, y);
            }
            // The projection is on the boundary, and y − x is along the normal x_k/a_k².
            let x = proj(&e, y);
            if is_proper(a, b) && e.is_outside(&y) {
                let q = (x[0] / a).hypot(x[1] / b);
                assert!((q - 1.0).abs() <= 1e-14, "({a}, {b}) y={y:?}: {q}");
                let f = e.frame(&y).unwrap();
                let g = [x[0] / a / (a / a.max(b)), x[1] / b / (b / a.max(b))];
                let c = (f.normal[0] * g[1] - f.normal[1] * g[0]) / norm(g);
                assert!(c.abs() <= 1e-13, "({a}, {b}) y={y:?}: normal off by {c:e}");
            }
            if is_proper(a, b) && e.is_outside(&y) {
                // y − x (by subtraction) along the normal at x.
                let s = a.max(b);
                let ed = [(y[0] - x[0]) / s, (y[1] - x[1]) / s];
                let g = [x[0] / a / (a / s), x[1] / b / (b / s)];
                let (en, gn) = (norm(ed), norm(g));
                if en > 1e-6 {
                    let c = (ed[0] * g[1] - ed[1] * g[0]) / (en * gn);
                    let tol = 1e-12 + 1e-15 * norm(y) / s / en;
                    assert!(c.abs() <= tol, "({a}, {b}) y={y:?}: y − x off normal {c:e}");
                }
            }
            // P_{cE}(c y) = c P_E(y), c a power of two (exact) or not.
            for &c in &[0.5f64.powi(40), 1e-3, 7.0] {
                let ec = Ellipse::new(c * a, c * b);
                let xc = proj(&ec, [c * y[0], c * y[1]]);
                let s = a.max(b).max(1e-300);
                assert!(norm(sub(xc, [c * x[0], c * x[1]])) <= 1e-14 * c * s);
            }
        }
    }
    assert!(worst.0 <= 6, "Newton needed {worst:?} steps");
}

/// Points near the major vertex of thin ellipses, where a plain Newton iteration from below
/// creeps.
fn vertex_points(a: f64, b: f64) -> Vec<[f64; 2]> {
    let mut v = Vec::new();
    for i in 0..40 {
        for j in 0..40 {
            let d1 = 10f64.powf(-16.0 + 0.45 * i as f64);
            let d2 = 10f64.powf(-16.0 + 0.45 * j as f64);
            v.push([a * (1.0 + d1), b * d2]);
            v.push([a * (1.0 - d1), b * (1.0 + d2)]);
            v.push([a * d1, b * (1.0 + d2)]);
        }
    }
    v
}

// Cost per call (`cargo test --release --lib qp::sets::tests::timing -- --ignored
// --nocapture`): about 8 ns for a disc, 70–90 ns for an ellipse (2/3 of the points outside).

/// Random ellipses (axis ratio up to 1e8, size 1e-100…1e100) and points at all distances:
/// the projection satisfies the optimality conditions that characterize it (on the boundary,
/// y − x along the outward normal), in few Newton steps; slant = frame's μ t tᵀ, μ ≤ 1.
#[test]
fn random_ellipses_optimality() {
    let mut rng = Lcg(2024);
    let mut worst = 0;
    for _ in 0..200_000 {
        let size = 10f64.powf(200.0 * rng.next() - 100.0);
        let ratio = 10f64.powf(8.0 * rng.next());
        let (a, b) = if rng.next() < 0.5 { (size, size / ratio) } else { (size / ratio, size) };
        let e = Ellipse::new(a, b);
        let t = rng.angle();
        let f = match (rng.next() * 4.0) as u32 {
            0 => 1.0 + 10f64.powf(-15.0 * rng.next()),
            1 => 10f64.powf(12.0 * rng.next()),
            2 => 1.0 + 1e-3 * rng.next(),
            _ => 2.0 * rng.next(),
        };
        let mut y = [f * a * t.cos(), f * b * t.sin()];
        if rng.next() < 0.1 {
            y[(rng.next() * 2.0) as usize] = 0.0;
        }
        if !e.is_outside(&y) {
            assert_eq!(proj(&e, y), y);
            continue;
        }
        worst = worst.max(e.newton_iters(&y));
        let x = proj(&e, y);
        let q = (x[0] / a).hypot(x[1] / b);
        assert!((q - 1.0).abs() <= 4.0 * EPS, "({a:e}, {b:e}) y={y:?}: off boundary {q}");
        let s = a.max(b);
        let ed = [(y[0] - x[0]) / s, (y[1] - x[1]) / s];
        let g = [x[0] / a / (a / s), x[1] / b / (b / s)];
        let (en, gn) = (norm(ed), norm(g));
        if en > 1e-8 {
            let c = (ed[0] * g[1] - ed[1] * g[0]) / (en * gn);
            let dot = (ed[0] * g[0] + ed[1] * g[1]) / (en * gn);
            let tol = 1e-12 + 4.0 * EPS * norm(y) / s / en;
            assert!(c.abs() <= tol && dot > 0.0, "({a:e}, {b:e}) y={y:?}: normal {c:e}");
        }
        let fr = e.frame(&y).unwrap();
        assert_eq!(fr.slant(), slant(&e, y));
        assert!(fr.mu >= 0.0 && fr.mu <= 1.0 && fr.distance >= 0.0);
    }
    assert!(worst <= 6, "Newton needed {worst} steps");
}

#[test]
fn thin_ellipse_tends_to_the_segment() {
    let mut rng = Lcg(23);
    let (thin, seg) = (Ellipse::new(1.0, 1e-99), Ellipse::new(1.0, 1e-101));
    let flat = Ellipse::new(1.0, 0.0);
    for y in points(1.0, 1.0, &mut rng) {
        let x = proj(&thin, y);
        assert!(norm(sub(x, proj(&seg, y))) <= 1e-15 + 1e-98, "y={y:?}");
        assert_eq!(proj(&seg, y), proj(&flat, y));
        assert!((x[0] / 1.0).hypot(x[1] / 1e-99) <= 1.0 + 1e-12);
    }
}

#[test]
fn boundary_tangent_and_curvature() {
    for &(a, b) in &[(1.0, 1.0), (3.0, 1.0), (1.0, 100.0), (1e4, 1.0), (2e-150, 1e-150)] {
        let set = TangentSet::Ellipse(Ellipse::new(a, b));
        for k in 0..1000 {
            let t = 2.0 * PI * k as f64 / 1000.0 + 0.1;
            let x = [a * t.cos(), b * t.sin()];
            // Parametrization derivatives: x' = (−a sin, b cos), x'' = −x.
            let d1 = [-a * t.sin(), b * t.cos()];
            let sp = norm(d1);
            let tt = set.boundary_tangent(&x);
            assert!(norm(sub(tt, [d1[0] / sp, d1[1] / sp])) <= 1e-14, "{a} {b} {t}");
            let kappa = (d1[0] * (-x[1]) - d1[1] * (-x[0])).abs() / sp.powi(3);
            let k2 = set.curvature(&x);
            assert!((k2 - kappa).abs() <= 1e-12 * kappa, "{a} {b} {t}: {k2} vs {kappa}");
        }
    }
    let d = TangentSet::Disc(Disc::new(2.0));
    assert_eq!(d.boundary_tangent(&[2.0, 0.0]), [0.0, 1.0]);
    assert_eq!(d.curvature(&[2.0, 0.0]), 0.5);
    let seg = Ellipse::new(2.0, 0.0);
    assert_eq!(seg.boundary_tangent(&[1.0, 0.0]), [1.0, 0.0]);
    assert_eq!(seg.curvature(&[1.0, 0.0]), 0.0);
    assert_eq!(seg.curvature(&[2.0, 0.0]), f64::INFINITY);
    assert_eq!(Ellipse::new(3.0, 1.0).boundary_tangent(&[0.0, 0.0]), [0.0, 1.0]);
}

#[test]
fn degenerate_sets() {
    // Segment [−2, 2] × {0}.
    let seg = Ellipse::new(2.0, 0.0);
    assert_eq!(proj(&seg, [1.0, 5.0]), [1.0, 0.0]);
    assert_eq!(proj(&seg, [-7.0, 5.0]), [-2.0, 0.0]);
    assert_eq!(slant(&seg, [1.0, 5.0]), [1.0, 0.0, 0.0, 0.0]);
    assert_eq!(slant(&seg, [1.0, 0.0]), [1.0, 0.0, 0.0, 0.0]);
    assert_eq!(slant(&seg, [3.0, 0.0]), [0.0; 4]);
    assert!(!seg.is_outside(&[1.0, 0.0]) && seg.is_outside(&[1.0, 1e-300]));
    assert_eq!(seg.max_step(&[1.0, 0.0], &[1.0, 0.0]), 3.0);
    assert_eq!(seg.max_step(&[1.0, 0.0], &[-2.0, 0.0]), 0.5);
    assert_eq!(seg.max_step(&[1.0, 0.0], &[1.0, 1.0]), 0.0);
    let seg_y = Ellipse::new(0.0, 2.0);
    assert_eq!(proj(&seg_y, [5.0, 1.0]), [0.0, 1.0]);
    assert_eq!(slant(&seg_y, [5.0, 1.0]), [0.0, 0.0, 0.0, 1.0]);
    // Point {0}: the disc of radius 0 and the ellipse (0, 0).
    for set in [TangentSet::Disc(Disc::new(0.0)), TangentSet::Ellipse(Ellipse::new(0.0, 0.0))] {
        assert_eq!(proj(&set, [3.0, -4.0]), [0.0, 0.0]);
        assert_eq!(slant(&set, [3.0, -4.0]), [0.0; 4]);
        assert_eq!(slant(&set, [0.0, 0.0]), [0.0; 4]);
        assert_eq!(set.max_step(&[0.0, 0.0], &[1.0, 2.0]), 0.0);
        assert!(!set.is_outside(&[0.0, 0.0]) && set.is_outside(&[1e-300, 0.0]));
        let f = set.frame(&[3.0, -4.0]).unwrap();
        assert_eq!((f.distance, f.mu, f.curvature), (5.0, 0.0, f64::INFINITY));
        assert!(set.frame(&[0.0, 0.0]).is_none());
    }
}

#[test]
fn half_line() {
    let h = HalfLine;
    assert_eq!(h.dim(), 1);
    let mut rng = Lcg(99);
    let mut ys: Vec<f64> = (0..500).map(|_| 10f64.powf(6.0 * rng.sym()) * rng.sym()).collect();
    ys.extend([0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300]);
    let grid: Vec<f64> = (0..NS).map(|j| j as f64 / NS as f64).collect();
    for &y in &ys {
        let mut x = [0.0];
        h.project(&[y], &mut x);
        let x = x[0];
        // Brute force over a dense grid of [0, 2|y|] (plus 0).
        let r = 2.0 * y.abs();
        let db = grid.iter().fold(y.abs(), |m, &g| m.min((y - g * r).abs()));
        assert!((y - x).abs() <= db + 1e-15 * y.abs(), "y={y}");
        assert!(h.contains(&[x], 0.0) && x >= 0.0);
        assert_eq!(h.is_outside(&[y]), y < 0.0);
        let mut xx = [0.0];
        h.project(&[x], &mut xx);
        assert_eq!(xx[0], x);
        // (y − x)(z − x) ≤ 0 for z ≥ 0: y − x ≤ 0, and = 0 unless x = 0.
        assert!(y - x <= 0.0 && (x == 0.0 || y == x));
        // Slant vs central differences away from 0.
        let mut j = [0.0];
        h.slant(&[y], &mut j);
        assert_eq!(j[0], if y >= 0.0 { 1.0 } else { 0.0 });
        if y != 0.0 {
            let e = 1e-3 * y.abs();
            let (mut p, mut m) = ([0.0], [0.0]);
            h.project(&[y + e], &mut p);
            h.project(&[y - e], &mut m);
            assert!(((p[0] - m[0]) / (2.0 * e) - j[0]).abs() <= 1e-12);
        }
        // max_step from x ≥ 0.
        for &d in &[y, -y, 0.0, 1.0, -1.0, 1e-8] {
            let al = h.max_step(&[x], &[d]);
            if d <= 0.0 {
                assert_eq!(al, f64::INFINITY);
            } else if x == 0.0 {
                assert_eq!(al, 0.0);
            } else if al > 1e200 {
                assert!((al / x - 1.0 / d).abs() <= 1e-15 / d);
            } else {
                assert!(al >= 0.0 && (x - al * d).abs() <= 1e-15 * x);
                // Bisection on the ray.
                let (mut lo, mut hi) = (0.0, 1.0);
                while x - hi * d >= 0.0 {
                    hi *= 2.0;
                }
                for _ in 0..2000 {
                    let m = 0.5 * (lo + hi);
                    if m == lo || m == hi {
                        break;
                    }
                    if x - m * d >= 0.0 {
                        lo = m;
                    } else {
                        hi = m;
                    }
                }
                assert!((al - lo).abs() <= 1e-14 * lo.max(1e-300), "x={x} d={d}");
            }
        }
    }
    assert!(h.contains(&[-1e-10], 1e-9) && !h.contains(&[-1e-8], 1e-9));
    assert_eq!(h.max_step(&[-1e-20], &[1.0]), 0.0);
}

#[test]
fn nan_input_terminates() {
    let nan = f64::NAN;
    let sets = [
        TangentSet::Disc(Disc::new(1.0)),
        TangentSet::Ellipse(Ellipse::new(3.0, 1.0)),
        TangentSet::Ellipse(Ellipse::new(3.0, 0.0)),
        TangentSet::Ellipse(Ellipse::new(0.0, 0.0)),
    ];
    for set in sets {
        for y in [[nan, 0.0], [0.0, nan], [nan, nan], [f64::INFINITY, 1.0]] {
            let _ = proj(&set, y);
            let _ = slant(&set, y);
            let _ = set.frame(&y);
            let _ = set.contains(&y, 0.0);
            let _ = set.max_step(&[0.0, 0.0], &y);
            let _ = set.max_step(&y, &[1.0, 0.0]);
            let _ = set.curvature(&y);
            let _ = set.boundary_tangent(&y);
        }
    }
    let mut x = [0.0];
    HalfLine.project(&[nan], &mut x);
    assert!(x[0].is_nan());
    assert!(HalfLine.max_step(&[0.0], &[nan]).is_nan());
}

#[test]
fn tangent_set_delegates() {
    let mut rng = Lcg(5);
    let (d, e) = (Disc::new(0.7), Ellipse::new(0.7, 0.2));
    let (td, te) = (TangentSet::from(d), TangentSet::from(e));
    assert_eq!((td.dim(), te.dim()), (2, 2));
    for y in points(0.7, 0.2, &mut rng) {
        let dir = [rng.sym(), rng.sym()];
        let x = proj(&e, y);
        assert_eq!(proj(&td, y), proj(&d, y));
        assert_eq!(proj(&te, y), x);
        assert_eq!(slant(&td, y), slant(&d, y));
        assert_eq!(slant(&te, y), slant(&e, y));
        assert_eq!(td.is_outside(&y), d.is_outside(&y));
        assert_eq!(te.contains(&y, 1e-3), e.contains(&y, 1e-3));
        assert_eq!(te.max_step(&x, &dir), e.max_step(&x, &dir));
        assert_eq!(td.max_step(&x, &dir), d.max_step(&x, &dir));
        assert_eq!(te.frame(&y), e.frame(&y));
    }
}
