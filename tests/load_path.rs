//! Quasi-static load paths (`[load] steps`): a path of a frictionless scene ends where the
//! one-step solve is (monolithic and TFETI), the Cattaneo–Mindlin partial-slip solution
//! (plane strain, cylinder on a flat, pressed then sheared), and the path dependence friction
//! brings (press-then-shear against a proportional path).

mod common;

use std::path::Path;

use common::{fields, max_abs, root, solve, tmpdir};
use tresca_feti::output::Values;

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn a_frictionless_path_ends_at_the_one_step_solution() {
    // without friction the solution depends on the last load state only: a path that overshoots
    // and comes back (every load ×0.5, ×1.5, then ×1) must end where one
    // step is, on both duals — this checks each dual's set_load (f, the lifted Dirichlet values,
    // TFETI's e = Rᵀf, λ̂ and c)
    let seed = root().join("run/seed.toml");
    let dir = tmpdir("path-frictionless");
    for dec in ["decomposition.subdomains=1", "decomposition.subdomains=3"] {
        let base = ["mesh.n=6", "contact.pair.0.friction={type=\"none\"}", "dirichlet.1.value=[0.0, 0.0, 0.002]", "solver.eps=1e-10", dec];
        let one = solve(&seed, &base, &dir.join("one.h5"));
        let mut sets = base.to_vec();
        sets.extend(["load.steps=3", "traction.0.factors=[0.5, 1.5, 1.0]", "traction.1.factors=[0.5, 1.5, 1.0]", "dirichlet.1.factors=[0.5, 1.5, 1.0]"]);
        let path = solve(&seed, &sets, &dir.join("path.h5"));
        let steps = path.report.load_path.as_ref().expect("per-step report");
        assert_eq!(steps.len(), 3);
        assert!(steps[1].max_displacement > steps[2].max_displacement, "the overshoot step moves further");
        let (u1, up) = (&one.solution.displacement, &path.solution.displacement);
        let d = max_diff(u1, up) / max_abs(u1);
        eprintln!("{dec}: path vs one step {d:.2e}");
        assert!(d <= 1e-7, "{dec}: the path ends {d:.2e} away from the one-step solution");
        // the file holds every step, the last one also at /fields
        let f = fields(&dir.join("path.h5"));
        assert_eq!(f.steps.len(), 3);
        let last = f.steps[2].fields.iter().find(|x| x.name == "displacement").unwrap();
        let now = f.fields.iter().find(|x| x.name == "displacement").unwrap();
        assert_eq!(last.values, now.values);
    }
}

/// Nodes of the y = 0 row of the contact face with (x − centre, status, pressure, shear traction).
fn contact_row(h5: &Path) -> Vec<(f64, i32, f64, f64)> {
    let f = fields(h5);
    let get = |name: &str| f.fields.iter().find(|x| x.name == name).unwrap_or_else(|| panic!("field {name}")).values.clone();
    let (Values::I32(status), Values::F64(p), Values::F64(q)) = (get("contact_status"), get("contact_pressure"), get("contact_traction")) else {
        panic!("field types")
    };
    let xc = f.coordinates.iter().map(|x| x[0]).fold(0.0, f64::max) / 2.0;
    let mut row: Vec<_> = (0..f.coordinates.len())
        .filter(|&v| status[v] > 0 && f.coordinates[v][1] == 0.0)
        .map(|v| (f.coordinates[v][0] - xc, status[v], p[v], q[3 * v]))
        .collect();
    row.sort_by(|a, b| a.0.total_cmp(&b.0));
    row
}

const CM_MESH: [&str; 2] = ["body.0.box.nodes=[129, 2, 25]", "body.1.box.nodes=[129, 2, 25]"];

#[test]
fn cattaneo_mindlin_stick_zone_and_shear_traction() {
    use tresca_feti::contact::state::{SLIP, STICK};
    let scene = root().join("run/validation/cattaneo_mindlin.toml");
    let dir = tmpdir("cattaneo-mindlin");
    let s = solve(&scene, &CM_MESH, &dir.join("cm.h5"));
    let (e, nu, r, mu, t, h) = (50000.0, 0.3, 8.0, 0.3, 0.03125, 4.0 / 128.0);
    let force = s.report.contact.as_ref().unwrap().total_force_on_slave;
    let (p, q) = (force[2] / t, force[0].abs() / t);
    assert!(q < mu * p, "partial slip needs Q < μP");
    // Hertz (plane strain, identical materials: 1/E* = 2(1 − ν²)/E) and Cattaneo–Mindlin
    let es = e / (2.0 * (1.0 - nu * nu));
    let a = (4.0 * p * r / (std::f64::consts::PI * es)).sqrt();
    let c = a * (1.0 - q / (mu * p)).sqrt();
    let p0 = 2.0 * p / (std::f64::consts::PI * a);
    let row = contact_row(&dir.join("cm.h5"));
    // the stick zone: its ends halfway between the outermost sticking node and the first
    // slipping one; the finite blocks shift it a little (the top is held), its half-width is c
    let stick: Vec<f64> = row.iter().filter(|x| x.1 == STICK).map(|x| x.0).collect();
    let (l, rr) = (stick[0] - h / 2.0, stick[stick.len() - 1] + h / 2.0);
    assert!(row.iter().all(|x| x.1 != SLIP || x.0 < l || x.0 > rr), "one stick zone");
    let half = (rr - l) / 2.0;
    eprintln!("P = {p:.1}, Q/(μP) = {:.3}, a = {a:.4}, c = {c:.4}, stick zone [{l:.4}, {rr:.4}], half-width {half:.4}, h = {h}", q / (mu * p));
    assert!((half - c).abs() <= h, "stick half-width {half:.4} vs c = {c:.4} (h = {h})");
    // the profiles: pressure against Hertz, shear traction against Cattaneo–Mindlin (relative
    // 2-norm over the contact row; the shear is the looser one: the 2 m blocks are not
    // half-spaces for a = 0.65 m, and the held top adds a moment), and exactly μp where a node
    // slips
    let hertz = |x: f64| p0 * (1.0 - x * x / (a * a)).max(0.0).sqrt();
    let cm = |x: f64| mu * hertz(x) - if x.abs() < c { mu * p0 * (c / a) * (1.0 - x * x / (c * c)).sqrt() } else { 0.0 };
    let rel = |f: &dyn Fn(&(f64, i32, f64, f64)) -> (f64, f64)| {
        let (num, den) = row.iter().map(f).fold((0.0, 0.0), |s, (v, w)| (s.0 + (v - w) * (v - w), s.1 + w * w));
        (num / den).sqrt()
    };
    let (ep, eq) = (rel(&|x| (x.2, hertz(x.0))), rel(&|x| (x.3.abs(), cm(x.0))));
    eprintln!("pressure vs Hertz {ep:.3}, shear traction vs Cattaneo–Mindlin {eq:.3} (relative 2-norms)");
    assert!(ep <= 0.1 && eq <= 0.25, "pressure {ep:.3}, shear {eq:.3}");
    for x in row.iter().filter(|x| x.1 == SLIP) {
        assert!((x.3.abs() - mu * x.2).abs() <= 1e-6 * mu * p0, "slipping node at {:.4}: |q| = {} vs μp = {}", x.0, x.3.abs(), mu * x.2);
    }
}

#[test]
fn press_then_shear_slips_more_than_a_proportional_path() {
    // Mindlin–Deresiewicz: raising Q and P together with dQ/dP < μ leaves (in the half-space)
    // the whole contact stuck; pressing first and shearing after opens a slip annulus. Same
    // last load state, different paths, different results.
    let scene = root().join("run/validation/cattaneo_mindlin.toml");
    let dir = tmpdir("path-dependence");
    let shear = solve(&scene, &CM_MESH, &dir.join("a.h5"));
    let mut sets = CM_MESH.to_vec();
    sets.extend(["load.steps=4", "dirichlet.1.factors=[0.25, 0.5, 0.75, 1.0]", "dirichlet.2.factors=[0.25, 0.5, 0.75, 1.0]"]);
    let prop = solve(&scene, &sets, &dir.join("b.h5"));
    let (a, b) = (shear.report.contact.as_ref().unwrap(), prop.report.contact.as_ref().unwrap());
    eprintln!(
        "press then shear: {} stick, {} slip, Fx {:.4}; proportional: {} stick, {} slip, Fx {:.4}",
        a.stick, a.slip, a.total_force_on_slave[0], b.stick, b.slip, b.total_force_on_slave[0]
    );
    assert!(b.slip < a.slip, "the proportional path slips less");
    assert!(b.total_force_on_slave[0].abs() < a.total_force_on_slave[0].abs(), "and carries less shear for the same last displacement");
    assert!(
        (a.total_force_on_slave[2] - b.total_force_on_slave[2]).abs() <= 1e-3 * a.total_force_on_slave[2].abs(),
        "the normal problem does not depend on the path (identical materials)"
    );
}

#[test]
fn reversed_tangential_load_slides_both_ways_on_both_duals() {
    // run/stress/coulomb_load_reversal.toml: pressed, dragged +x until the whole face slides,
    // back to the start (the friction now holds it the other way: hysteresis), then sliding −x;
    // the monolithic dual and TFETI (4 subdomains per body) follow the same path
    let scene = root().join("run/stress/coulomb_load_reversal.toml");
    let dir = tmpdir("reversal");
    let mono = solve(&scene, &["decomposition.subdomains=1"], &dir.join("m.h5"));
    let tfeti = solve(&scene, &["decomposition.subdomains=4"], &dir.join("t.h5"));
    let d = max_diff(&mono.solution.displacement, &tfeti.solution.displacement) / max_abs(&mono.solution.displacement);
    eprintln!("reversal: monolithic vs TFETI max|Δu|/max|u| = {d:.2e}");
    assert!(d <= 1e-7, "the duals differ by {d:.2e}");
    let mu = 0.3;
    for s in [&mono, &tfeti] {
        let steps = s.report.load_path.as_ref().unwrap();
        let f = |k: usize| steps[k - 1].total_force_on_slave;
        for k in [3, 6] {
            // every pair slides: the friction force is μ times the normal force
            assert_eq!(steps[k - 1].slip, 100, "step {k} slides");
            assert!((f(k)[0].abs() - mu * f(k)[2]).abs() <= 1e-3 * mu * f(k)[2], "step {k}: |Fx| = {} vs μFz = {}", f(k)[0].abs(), mu * f(k)[2]);
        }
        assert!(f(3)[0] < 0.0 && f(6)[0] > 0.0, "the friction force reverses");
        // back at the start after sliding +x, the block is held the other way: a one-step
        // solve of that state carries no shear at all
        assert!(f(4)[0] > 0.1 * mu * f(4)[2], "hysteresis at step 4: Fx = {}", f(4)[0]);
        assert_eq!(steps[0].slip + steps[1].slip, 0, "sticks while |Fx| < μFz");
    }
}

/// A path that ends above the friction limit (`run/validation/floating_block.toml`: N = 2,
/// μ = 0.3, the push along x at 0, 0.5, 0.9, 0.99 and 1.1 × μN): steps 1–4 are solved and
/// written whole (`/steps/0001…0004`, `/fields` = step 4, the attribute `path_stopped`), the run
/// exits 1 with one line naming step 5 and the limit μN = 0.6 — the same limit whatever the
/// applied load. `check` says where the path stops. Before: the whole path refused, nothing
/// written, and a "capacity" that grew with the load (the nearest point of a cone problem).
#[test]
fn a_path_past_the_friction_limit_writes_the_steps_before_it() {
    let dir = tmpdir("path-past-limit");
    let scene = std::fs::read_to_string(root().join("run/validation/floating_block.toml"))
        .unwrap()
        .replace("n = 7", "n = 5")
        .replace("p = [0.0, 0.0, -1.0]\n", "p = [0.0, 0.0, -1.0]\nfactors = [1.0, 1.0, 1.0, 1.0, 1.0]\n")
        .replace("p = [0.3, 0.0, 0.0]\n", "p = [0.6, 0.0, 0.0]\nfactors = [0.0, 0.5, 0.9, 0.99, 1.1]\n")
        + "\n[load]\nsteps = 5\n";
    let path = dir.join("past.toml");
    std::fs::write(&path, scene).unwrap();
    let out = dir.join("out").join("past.h5");
    let o = common::run(&["solve", path.to_str().unwrap(), "--out", out.to_str().unwrap(), "--quiet"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    for want in [
        "body \"upper\": no equilibrium exists at load step 5/5",
        "the applied force along x is 6.6000e-1",
        "hold at most 6.0000e-1 along it",
        "steps 1–4 are solved and written to",
    ] {
        assert!(err.contains(want), "`{want}` not in {err}");
    }
    let f = fields(&out);
    assert_eq!(f.steps.len(), 4);
    let u = |fs: &[tresca_feti::output::Field]| match &fs.iter().find(|x| x.name == "displacement").unwrap().values {
        Values::F64(v) => v.clone(),
        _ => panic!("displacement"),
    };
    assert_eq!(u(&f.fields), u(&f.steps[3].fields), "/fields is the last solved step");
    let stopped = f.attributes.iter().find(|a| a.0 == "path_stopped").map(|a| a.1.clone()).unwrap_or_default();
    assert!(stopped.starts_with("stopped before load step 5/5: body \"upper\": no equilibrium exists"), "{stopped}");
    let left: Vec<_> = std::fs::read_dir(out.parent().unwrap()).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    assert!(left.iter().all(|n| !n.contains(".tmp")), "no staging names left: {left:?}");
    // the limit stays μN = 0.6 however far the last step goes past it; check says where it stops
    for (last, applied) in [("1.02", "6.1200e-1"), ("10.0", "6.0000e0")] {
        let o = common::run(&["check", path.to_str().unwrap(), "--set", &format!("traction.1.factors=[0.0, 0.5, 0.9, 0.99, {last}]")]);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let line = text.lines().find(|l| l.starts_with("warning: load path stopped before load step 5/5")).unwrap_or_else(|| panic!("{text}"));
        assert!(
            line.contains(&format!("applied force along x is {applied}"))
                && line.contains("hold at most 6.0000e-1 along it")
                && line.contains("solve writes steps 1–4"),
            "{line}"
        );
    }
}
