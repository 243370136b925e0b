//! The rigid motions of one body, or of a group of bodies tied together that move as one: its
//! frame (centroid, size), the six modes as 6-vectors (translations, then rotations about the
//! centroid scaled by the group's size), the motions a set of constraint rows (node, direction)
//! leaves free (the kernel of their Gram matrix), and a motion in words.

use super::Mesh;

/// A body's rigid-motion frame: mode r = (t, ω) moves node x by t + ω × (x − c)/size.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub centroid: [f64; 3],
    pub size: f64,
}

impl Frame {
    /// The frame of the bodies `group` of `mesh` (centroid of their nodes, largest distance
    /// from it).
    pub fn of(mesh: &Mesh, group: &[usize]) -> Self {
        let nodes = || group.iter().flat_map(|&b| mesh.bodies[b].nodes.clone());
        let n = nodes().count() as f64;
        let c: [f64; 3] = std::array::from_fn(|d| nodes().map(|v| mesh.nodes[v][d]).sum::<f64>() / n);
        let size = nodes().map(|v| (0..3).map(|d| (mesh.nodes[v][d] - c[d]).powi(2)).sum::<f64>()).fold(0.0, f64::max).sqrt().max(f64::MIN_POSITIVE);
        Frame { centroid: c, size }
    }

    /// The row of a constraint on the displacement of the node at `x` along `dir`, in mode
    /// space: its value at mode r is `row · r` (the translations `dir`, the rotations
    /// dir · (ω × x̂), x̂ the scaled position).
    pub fn row(&self, x: [f64; 3], dir: [f64; 3]) -> [f64; 6] {
        let x: [f64; 3] = std::array::from_fn(|d| (x[d] - self.centroid[d]) / self.size);
        let mut r = [0.0; 6];
        r[..3].copy_from_slice(&dir);
        let rot = [[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]];
        for k in 0..3 {
            r[3 + k] = (0..3).map(|d| rot[k][d] * dir[d]).sum();
        }
        r
    }
}

/// The rigid motions of the bodies `group` (moving as one) that the `rows` (node, direction)
/// leave free: an orthonormal basis of the kernel of the 6 × 6 Gram matrix of their mode-space
/// rows ([`Frame::row`]). `None` where the eigen-decomposition fails.
pub fn free_modes(mesh: &Mesh, group: &[usize], rows: impl Iterator<Item = (usize, [f64; 3])>) -> Option<Vec<[f64; 6]>> {
    let frame = Frame::of(mesh, group);
    let mut gram = faer::Mat::<f64>::zeros(6, 6);
    for (v, dir) in rows {
        let r = frame.row(mesh.nodes[v], dir);
        for i in 0..6 {
            for j in 0..6 {
                gram[(i, j)] += r[i] * r[j];
            }
        }
    }
    let eig = gram.self_adjoint_eigen(faer::Side::Lower).ok()?;
    let (vals, vecs) = (eig.S(), eig.U());
    let top = (0..6).map(|i| vals[i]).fold(0.0, f64::max);
    Some((0..6).filter(|&i| vals[i] <= 1e-10 * top.max(1.0)).map(|i| std::array::from_fn(|k| vecs[(k, i)])).collect())
}

/// A mode-space motion in words: "translation along x", "rotation about z", "rotation about an
/// axis along (…)", "screw motion (…)".
pub fn describe(u: &[f64; 6]) -> String {
    let axis = |w: [f64; 3]| {
        let names = ["x", "y", "z"];
        let big: Vec<usize> = (0..3).filter(|&d| w[d].abs() > 1e-6).collect();
        if big.len() == 1 {
            names[big[0]].to_string()
        } else {
            format!("({:.3}, {:.3}, {:.3})", w[0], w[1], w[2])
        }
    };
    let (t, w) = ([u[0], u[1], u[2]], [u[3], u[4], u[5]]);
    let (nt, nw) = (t.iter().map(|a| a * a).sum::<f64>().sqrt(), w.iter().map(|a| a * a).sum::<f64>().sqrt());
    if nw <= 1e-6 * nt {
        format!("translation along {}", axis(t.map(|a| a / nt)))
    } else if nt <= 1e-6 * nw {
        format!("rotation about {}", axis(w.map(|a| a / nw)))
    } else if (0..3).map(|d| t[d] * w[d]).sum::<f64>().abs() <= 1e-6 * nt * nw {
        // a translation across the axis only moves the axis
        format!("rotation about an axis along {}", axis(w.map(|a| a / nw)))
    } else {
        format!("screw motion (rotation about {}, translation along {})", axis(w.map(|a| a / nw)), axis(t.map(|a| a / nt)))
    }
}

/// A mode-space motion by its largest parts among the six natural ones (translations along and
/// rotations about the axes through the centroid, rotations scaled by the body's size): the
/// largest, then every other at least a third of it, e.g. "translation along x with rotation
/// about y".
pub fn dominant(u: &[f64; 6]) -> String {
    let names = ["translation along x", "translation along y", "translation along z", "rotation about x", "rotation about y", "rotation about z"];
    let top = u.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut parts: Vec<usize> = (0..6).filter(|&i| u[i].abs() >= top / 3.0 && top > 0.0).collect();
    parts.sort_by(|&a, &b| u[b].abs().total_cmp(&u[a].abs()));
    let words: Vec<&str> = parts.iter().map(|&i| names[i]).collect();
    if words.is_empty() {
        "no motion".into()
    } else {
        words.join(" with ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn motions_are_named_by_their_largest_parts() {
        assert_eq!(dominant(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]), "translation along x");
        assert_eq!(dominant(&[0.9, 0.0, 0.05, 0.0, -0.4, 0.0]), "translation along x with rotation about y");
        assert_eq!(describe(&[0.0, 0.0, 0.0, 0.0, 0.0, 2.0]), "rotation about z");
        assert_eq!(describe(&[0.0, 3.0, 0.0, 0.0, 0.0, 0.0]), "translation along y");
    }
}
