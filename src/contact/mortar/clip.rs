//! The polygons of the segment-based integration: the signed area and convexity of a projected
//! facet polygon, Sutherland–Hodgman clipping of a master polygon by the slave's, and the removal
//! of (nearly) repeated vertices — all in the 2D coordinates of a slave facet's auxiliary plane.

use super::V2;

pub(super) fn cross2(a: V2, b: V2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

pub(super) fn sub2(a: V2, b: V2) -> V2 {
    [a[0] - b[0], a[1] - b[1]]
}

pub(super) fn polygon_area(p: &[V2]) -> f64 {
    let n = p.len();
    0.5 * (0..n).map(|i| cross2(p[i], p[(i + 1) % n])).sum::<f64>()
}

/// Counter-clockwise and convex (every turn to the left).
pub(super) fn is_convex(p: &[V2]) -> bool {
    let n = p.len();
    let a = polygon_area(p);
    a > 0.0
        && (0..n).all(|i| {
            let (u, v) = (sub2(p[(i + 1) % n], p[i]), sub2(p[(i + 2) % n], p[(i + 1) % n]));
            cross2(u, v) > 1e-12 * a
        })
}

/// Sutherland–Hodgman: `subject` clipped by the convex counter-clockwise polygon `clip`.
pub(super) fn clip_polygon(subject: &[V2], clip: &[V2]) -> Vec<V2> {
    let mut out = subject.to_vec();
    for i in 0..clip.len() {
        if out.is_empty() {
            break;
        }
        let (a, b) = (clip[i], clip[(i + 1) % clip.len()]);
        let e = sub2(b, a);
        let tol = 1e-14 * (e[0] * e[0] + e[1] * e[1]);
        let side = |p: V2| cross2(e, sub2(p, a));
        let input = std::mem::take(&mut out);
        for k in 0..input.len() {
            let (s, q) = (input[k], input[(k + 1) % input.len()]);
            let (ds, dq) = (side(s), side(q));
            if ds >= -tol {
                out.push(s);
            }
            if (ds >= -tol) != (dq >= -tol) {
                let t = ds / (ds - dq);
                out.push([s[0] + t * (q[0] - s[0]), s[1] + t * (q[1] - s[1])]);
            }
        }
    }
    out
}

/// The polygon without (nearly) repeated consecutive vertices.
pub(super) fn dedup(p: Vec<V2>, tol: f64) -> Vec<V2> {
    let mut out: Vec<V2> = Vec::with_capacity(p.len());
    for v in p {
        if out.last().is_none_or(|l| (v[0] - l[0]).abs() + (v[1] - l[1]).abs() > tol) {
            out.push(v);
        }
    }
    while out.len() > 1 {
        let (f, l) = (out[0], out[out.len() - 1]);
        if (f[0] - l[0]).abs() + (f[1] - l[1]).abs() > tol {
            break;
        }
        out.pop();
    }
    out
}
