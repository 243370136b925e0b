//! Pressure loads (`[[traction]] pressure = p`) against Lamé's thick-walled pipe and hollow
//! sphere, in hexahedra and in 10-node tetrahedra with curved faces.

mod common;

use common::{f64_field, fields, root, solve, tmpdir};

/// Radial displacement errors at every node (worst and mean, relative) and the worst relative
/// von Mises error at the cell centres, against the exact `u_r(r)` and `vm(r)`.
fn against(out: &std::path::Path, axisym: bool, ur: impl Fn(f64) -> f64, vm: impl Fn(f64) -> f64) -> (f64, f64, f64) {
    let data = fields(out);
    let radius = |x: [f64; 3]| if axisym { x[0].hypot(x[1]) } else { (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt() };
    let u = f64_field(&data, "displacement");
    let (mut worst, mut sum) = (0.0f64, 0.0);
    for (x, u) in data.coordinates.iter().zip(u.chunks(3)) {
        let r = radius(*x);
        let k = if axisym { 2 } else { 3 };
        let radial = (0..k).map(|c| u[c] * x[c]).sum::<f64>() / r;
        let e = radial / ur(r) - 1.0;
        worst = worst.max(e.abs());
        sum += e;
    }
    let von_mises = f64_field(&data, "von_mises");
    let mut vm_worst = 0.0f64;
    for (cell, s) in data.cells.iter().zip(von_mises) {
        let c = cell.kind.corners();
        let mut x = [0.0; 3];
        for &v in &cell.nodes()[..c] {
            for k in 0..3 {
                x[k] += data.coordinates[v][k] / c as f64;
            }
        }
        vm_worst = vm_worst.max((s / vm(radius(x)) - 1.0).abs());
    }
    (worst, sum / data.coordinates.len() as f64, vm_worst)
}

/// A pipe (a = 1, b = 2, E = 1000, ν = 0.3) under internal pressure p = 1 in plane strain,
/// `run/validation/pipe.toml`: the radial displacement at every node and the von Mises stress
/// at every cell centre against Lamé, in 8 × 16 hexahedra (faceted arcs) and the same
/// divisions in 10-node tetrahedra (quadratic arcs); the check prints the resultant p·a·t on
/// each symmetry axis.
#[test]
fn a_pipe_under_internal_pressure_matches_lame() {
    let scene = root().join("run/validation/pipe.toml");
    let dir = tmpdir("pipe");
    let (e, nu, p, a, b) = (1000.0f64, 0.3f64, 1.0f64, 1.0f64, 2.0f64);
    let k = p * a * a / (b * b - a * a);
    let ur = |r: f64| (1.0 + nu) * k / e * ((1.0 - 2.0 * nu) * r + b * b / r);
    let vm = |r: f64| {
        let (sr, st) = (k * (1.0 - b * b / (r * r)), k * (1.0 + b * b / (r * r)));
        let sz = nu * (sr + st);
        (0.5 * ((sr - st).powi(2) + (st - sz).powi(2) + (sz - sr).powi(2))).sqrt()
    };
    // measured 2026-12-05: hex8 u_r −0.33 % at the bore (the faceted arc), von Mises 0.44 %;
    // tet10 0.018 % and 0.17 %
    for (mesh, tol_u, tol_vm) in [("pipe.msh", 0.005, 0.01), ("pipe_tet10.msh", 5e-4, 0.005)] {
        let out = dir.join(format!("{mesh}.h5"));
        let file = format!("body.0.gmsh.file={}", root().join("mesh").join(mesh).display());
        solve(&scene, &[&file], &out);
        let (worst, mean, vm_worst) = against(&out, true, ur, vm);
        eprintln!("{mesh}: u_r worst {:.3} % mean {:.3} %, von Mises worst {:.2} %", 100.0 * worst, 100.0 * mean, 100.0 * vm_worst);
        assert!(worst <= tol_u, "{mesh}: u_r {:.3} % from Lamé", 100.0 * worst);
        assert!(vm_worst <= tol_vm, "{mesh}: von Mises {:.2} % from Lamé", 100.0 * vm_worst);
    }
    let o = common::run(&["check", scene.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out.lines().find(|l| l.starts_with("traction[0]")).unwrap_or_else(|| panic!("{out}"));
    assert!(line.contains("pressure 1 MPa") && line.contains("resultant (1.000000e-1, 1.000000e-1, "), "{line}");
}

/// A hollow sphere (a = 1, b = 2) under internal pressure p = 1, an octant in 10-node
/// tetrahedra of size 0.3 (`run/validation/hollow_sphere.toml`): u_r at every node against
/// Lamé's p a³/(E (b³ − a³)) ((1 − 2ν) r + (1 + ν) b³/(2r²)); the resultant on each axis is
/// p·πa²/4 to the quadrature of the curved facets.
#[test]
fn a_hollow_sphere_under_internal_pressure_matches_lame() {
    let scene = root().join("run/validation/hollow_sphere.toml");
    let dir = tmpdir("hollow-sphere");
    let (e, nu, a, b) = (1000.0f64, 0.3f64, 1.0f64, 2.0f64);
    let k = a.powi(3) / (b.powi(3) - a.powi(3));
    let ur = |r: f64| k / e * ((1.0 - 2.0 * nu) * r + (1.0 + nu) * b.powi(3) / (2.0 * r * r));
    let vm = |r: f64| 1.5 * k * b.powi(3) / r.powi(3);
    let out = dir.join("shell.h5");
    solve(&scene, &[], &out);
    let (worst, mean, vm_worst) = against(&out, false, ur, vm);
    eprintln!("hollow sphere: u_r worst {:.3} % mean {:.3} %, von Mises worst {:.2} %", 100.0 * worst, 100.0 * mean, 100.0 * vm_worst);
    // measured 2026-12-05: worst 0.97 % at the bore (0.18 % at size 0.15), mean −0.09 %, von
    // Mises 3.1 % (cell centres of curved tetrahedra)
    assert!(worst <= 0.012 && mean.abs() <= 0.002, "u_r {:.3} % (mean {:.3} %) from Lamé", 100.0 * worst, 100.0 * mean);
    assert!(vm_worst <= 0.05, "von Mises {:.2} % from Lamé", 100.0 * vm_worst);
    let o = common::run(&["check", scene.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    let line = out.lines().find(|l| l.starts_with("traction[0]")).unwrap_or_else(|| panic!("{out}"));
    let r: Vec<f64> = line.split("resultant (").nth(1).unwrap().split(')').next().unwrap().split(", ").map(|v| v.parse().unwrap()).collect();
    for f in r {
        assert!((f - std::f64::consts::FRAC_PI_4).abs() <= 1e-4, "{line}");
    }
}

/// `p` and `pressure` together, or neither, or a pressure that is no number, are refused naming
/// the key.
#[test]
fn a_traction_takes_a_vector_or_a_pressure() {
    let scene = root().join("run/validation/pipe.toml");
    let text = std::fs::read_to_string(&scene).unwrap().replace("../../mesh", &root().join("mesh").display().to_string());
    let dir = tmpdir("traction-forms");
    let neither = dir.join("neither.toml");
    std::fs::write(&neither, text.replace("pressure = 1.0", "")).unwrap();
    for (path, set, key) in [
        (&scene, "traction.0.p=[1.0, 0.0, 0.0]", "traction[0].pressure: give either"),
        (&scene, "traction.0.pressure=nan", "traction[0].pressure"),
        (&neither, "title=\"x\"", "traction[0].p: give `p`"),
    ] {
        let o = common::run(&["check", path.to_str().unwrap(), "--set", set]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.lines().count() == 1 && err.contains(key), "{set}: {err}");
    }
}
