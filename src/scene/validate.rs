//! [`Scene::validate`]: every value that can be checked without the mesh, one check per section,
//! each error naming the offending key. The sections are checked in a fixed order (units, mesh,
//! materials, bodies, faces, load path, Dirichlet, traction, ties, contact, decomposition,
//! output), so a scene with several errors always reports the same one first.

use std::collections::HashSet;

use super::{
    range, Body, BoxDef, ContactPair, Cylinder, DecompositionSettings, Dirichlet, FaceDef, Fit, Friction, Material, OutputSettings, Scene, Sphere, Tie,
    Traction, Units, FIELDS, MAX_BODY_NODES, MAX_LOAD_STEPS,
};
use crate::error::{Error, Result};

impl Scene {
    /// Checks every value that can be checked without the mesh.
    pub fn validate(&self) -> Result<()> {
        units(&self.units)?;
        if self.mesh.n < 2 {
            return Err(Error::scene("mesh.n", format!("must be at least 2 nodes per edge, got {}", self.mesh.n)));
        }
        let material_names = materials(&self.materials)?;
        if self.bodies.is_empty() {
            return Err(Error::scene("body", "at least one [[body]] is required"));
        }
        let mut body_names = HashSet::with_capacity(self.bodies.len());
        for (i, b) in self.bodies.iter().enumerate() {
            body(i, b, &material_names, &mut body_names, self.mesh.n)?;
        }
        for (i, f) in self.faces.iter().enumerate() {
            face(i, f)?;
        }
        self.load_path()?;
        for (i, d) in self.dirichlet.iter().enumerate() {
            dirichlet(i, d)?;
        }
        for (i, t) in self.traction.iter().enumerate() {
            traction(i, t)?;
        }
        for (i, t) in self.ties.iter().enumerate() {
            tie(i, t)?;
        }
        for (i, p) in self.contact.pair.iter().enumerate() {
            contact_pair(i, p)?;
        }
        decomposition(&self.decomposition)?;
        output(&self.output)
    }

    /// `[load]` and the `factors` of every Dirichlet entry, then of every traction entry.
    fn load_path(&self) -> Result<()> {
        let steps = self.load.steps;
        if steps == 0 || steps > MAX_LOAD_STEPS {
            return Err(Error::scene("load.steps", format!("must lie in 1..={MAX_LOAD_STEPS}, got {steps}")));
        }
        let dirichlet = self.dirichlet.iter().map(|d| ("dirichlet", &d.factors)).enumerate();
        let traction = self.traction.iter().map(|t| ("traction", &t.factors)).enumerate();
        for (i, (what, f)) in dirichlet.chain(traction) {
            if let Some(f) = f {
                let key = format!("{what}[{i}].factors");
                finite(key.clone(), f)?;
                if f.len() != steps {
                    return Err(Error::scene(key, format!("needs one factor per load step (load.steps = {steps}), got {}", f.len())));
                }
            }
        }
        Ok(())
    }
}

/// The one-line reason for a value outside [`range`].
fn out_of_range(what: &str, v: f64, unit: &str) -> String {
    format!(
        "{what} {v:e}{unit} lies outside {:e} … {:e}{unit}, the range double precision carries through the stiffness, loads and norms (scale the units)",
        range::MIN,
        range::MAX
    )
}

fn finite(key: String, v: &[f64]) -> Result<()> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(Error::scene(key, format!("must be finite, got {v:?}")))
    }
}

/// A nonzero load or prescribed value outside the range (see [`range`]).
fn carried(key: String, what: &str, v: &[f64], unit: &str) -> Result<()> {
    match v.iter().find(|x| !range::carries(**x, true)) {
        Some(&x) => Err(Error::scene(key, out_of_range(what, x, unit))),
        None => Ok(()),
    }
}

/// `[units]`: names of 1–16 printable characters.
fn units(u: &Units) -> Result<()> {
    for (key, v) in [("units.length", &u.length), ("units.force", &u.force)] {
        if let Some(v) = v {
            if v.trim().is_empty() || v.chars().count() > 16 || v.chars().any(char::is_control) {
                return Err(Error::scene(key, format!("a unit's name of 1–16 printable characters, got {v:?}")));
            }
        }
    }
    Ok(())
}

/// `[[material]]`: at least one, E and ν physical and carried by double precision, names
/// unique; returns the names.
fn materials(materials: &[Material]) -> Result<HashSet<&str>> {
    if materials.is_empty() {
        return Err(Error::scene("material", "at least one [[material]] is required"));
    }
    // name → index (a set per kind: linear, not a scan of the entries before each)
    let mut names = HashSet::with_capacity(materials.len());
    for (i, m) in materials.iter().enumerate() {
        let k = |f: &str| format!("material[{i}].{f}");
        finite(k("E"), &[m.e])?;
        finite(k("nu"), &[m.nu])?;
        if m.e <= 0.0 {
            return Err(Error::scene(k("E"), format!("Young's modulus must be > 0, got {}", m.e)));
        }
        if !(m.nu > -1.0 && m.nu < 0.5) {
            return Err(Error::scene(k("nu"), format!("Poisson's ratio must lie in (-1, 0.5), got {}", m.nu)));
        }
        if !range::carries(m.e, false) {
            return Err(Error::scene(k("E"), out_of_range("Young's modulus", m.e, " MPa")));
        }
        for (what, margin) in [("1 − 2ν", 1.0 - 2.0 * m.nu), ("1 + ν", 1.0 + m.nu)] {
            if margin < range::POISSON_MARGIN {
                return Err(Error::scene(
                    k("nu"),
                    format!(
                        "Poisson's ratio {} leaves {what} = {margin:.1e} < {:e}: λ = Eν/((1+ν)(1−2ν)) would swamp the stiffness (double precision cannot solve it)",
                        m.nu,
                        range::POISSON_MARGIN
                    ),
                ));
            }
        }
        if !names.insert(m.name.as_str()) {
            return Err(Error::scene(k("name"), format!("duplicate material name \"{}\"", m.name)));
        }
    }
    Ok(names)
}

/// `[[body]]` number `i`: a unique name, a known material, exactly one of `box`, `mesh` and
/// `gmsh`, a mesh file of a known format.
fn body<'a>(i: usize, b: &'a Body, materials: &HashSet<&str>, names: &mut HashSet<&'a str>, mesh_n: usize) -> Result<()> {
    let k = |f: &str| format!("body[{i}].{f}");
    if b.name.is_empty() || b.name.contains('.') {
        return Err(Error::scene(k("name"), format!("body names must be non-empty and contain no '.', got \"{}\"", b.name)));
    }
    if !names.insert(b.name.as_str()) {
        return Err(Error::scene(k("name"), format!("duplicate body name \"{}\"", b.name)));
    }
    if !materials.contains(b.material.as_str()) {
        return Err(Error::scene(k("material"), format!("unknown material \"{}\"", b.material)));
    }
    let given = [b.boxed.is_some(), b.mesh.is_some(), b.gmsh.is_some()].iter().filter(|&&g| g).count();
    if given != 1 {
        return Err(Error::scene(format!("body[{i}]"), "give exactly one of `box`, `mesh` and `gmsh`"));
    }
    if let Some(bx) = &b.boxed {
        return box_body(&k, &b.name, bx, mesh_n);
    }
    let Some((key, m)) = b.mesh_file() else { return Ok(()) };
    if m.resolved_format().is_none() {
        return Err(Error::scene(
            k(&format!("{key}.file")),
            format!(
                "cannot tell the format of \"{}\" from its extension (known: .inp for abaqus, .msh for gmsh, .med for med, .exo/.e/.ex2 for exodus); give `format = \"abaqus\"`, `\"gmsh\"`, `\"med\"` or `\"exodus\"`",
                m.file.display()
            ),
        ));
    }
    match m.translate {
        Some(t) => finite(k(&format!("{key}.translate")), &t),
        None => Ok(()),
    }
}

/// `body.box`: finite corners, at most one curved side, a positive extent, and nodes that give
/// elements double precision can carry.
fn box_body(k: &impl Fn(&str) -> String, name: &str, bx: &BoxDef, mesh_n: usize) -> Result<()> {
    finite(k("box.min"), &bx.min)?;
    finite(k("box.max"), &bx.max)?;
    if let Some(c) = &bx.cylinder {
        cylinder(k, bx, c)?;
    }
    if let Some(s) = &bx.sphere {
        if bx.cylinder.is_some() {
            return Err(Error::scene(k("box.sphere"), "give at most one of `cylinder` and `sphere`"));
        }
        sphere(k, bx, s)?;
    }
    if (0..3).any(|d| bx.max[d] <= bx.min[d]) {
        return Err(Error::scene(k("box"), "max must exceed min in every direction"));
    }
    if (0..3).any(|d| !(bx.max[d] - bx.min[d]).is_finite()) {
        return Err(Error::scene(k("box"), "max − min overflows: the box is too large for floating point"));
    }
    match bx.nodes {
        Some(n) => box_nodes(k, name, bx, n, mesh_n),
        None => Ok(()),
    }
}

/// `body.box.cylinder`: a radius of at least the box's half-width, bulging less
/// than the box is high.
fn cylinder(k: &impl Fn(&str) -> String, bx: &BoxDef, c: &Cylinder) -> Result<()> {
    let (h, t) = (0.5 * (bx.max[0] - bx.min[0]), bx.max[2] - bx.min[2]);
    if !(c.radius.is_finite() && c.radius >= h) {
        return Err(Error::scene(k("box.cylinder.radius"), format!("must be finite and at least the half-width {h} of the box in x, got {}", c.radius)));
    }
    if !range::carries(c.radius, false) {
        return Err(Error::scene(k("box.cylinder.radius"), out_of_range("radius", c.radius, " m")));
    }
    if bx.bulge(0.5 * (bx.min[0] + bx.max[0]), bx.min[1]) >= t {
        return Err(Error::scene(k("box.cylinder.radius"), format!("the curved side would bulge more than the box's height {t}")));
    }
    Ok(())
}

/// `body.box.sphere`: a pole within range and a radius beyond the side's farthest
/// corner, bulging less than the box is high.
fn sphere(k: &impl Fn(&str) -> String, bx: &BoxDef, s: &Sphere) -> Result<()> {
    if let Some(c) = s.centre {
        finite(k("box.sphere.centre"), &c)?;
        if c.iter().any(|v| v.abs() > range::MAX) {
            return Err(Error::scene(k("box.sphere.centre"), format!("coordinates beyond ±{:e} m, got {c:?}", range::MAX)));
        }
    }
    let h = s.reach(bx);
    if !(s.radius.is_finite() && s.radius > h) {
        return Err(Error::scene(
            k("box.sphere.radius"),
            format!("must be finite and exceed the distance {h} from the pole to the side's farthest corner, got {}", s.radius),
        ));
    }
    if !range::carries(s.radius, false) {
        return Err(Error::scene(k("box.sphere.radius"), out_of_range("radius", s.radius, " m")));
    }
    let pole = s.pole(bx);
    let t = bx.max[2] - bx.min[2];
    if bx.bulge(pole[0], pole[1]) >= t {
        return Err(Error::scene(k("box.sphere.radius"), format!("the curved side would bulge more than the box's height {t}")));
    }
    Ok(())
}

/// `body.box.nodes` (or `mesh.n`): at least 2 per direction, element edges and coordinates
/// within [`range`], at most [`MAX_BODY_NODES`], and edges not too thin against each other.
fn box_nodes(k: &impl Fn(&str) -> String, name: &str, bx: &BoxDef, n: [usize; 3], mesh_n: usize) -> Result<()> {
    if n.iter().any(|&v| v < 2) {
        return Err(Error::scene(k("box.nodes"), format!("need at least 2 nodes per direction, got {n:?}")));
    }
    // the length scale: element edges (extent / (nodes − 1)) and coordinates
    let edges: Vec<f64> = (0..3).map(|d| (bx.max[d] - bx.min[d]) / (n[d] - 1) as f64).collect();
    let (lo, hi) = edges.iter().fold((f64::INFINITY, 0.0f64), |(a, b), &h| (a.min(h), b.max(h)));
    for (h, bad) in [(lo, lo < range::MIN), (hi, hi > range::MAX)] {
        if bad {
            return Err(Error::scene(
                k("box"),
                format!("body \"{name}\": element edges of {h:.3e} m (extent / (nodes − 1)) lie outside {:e} … {:e} m, the length scale double precision carries through element volumes (∝ h³) and stiffness (∝ E·h); scale the units", range::MIN, range::MAX),
            ));
        }
    }
    let far = bx.min.iter().chain(&bx.max).fold(0.0f64, |a, v| a.max(v.abs()));
    if far > range::MAX {
        return Err(Error::scene(
            k("box"),
            format!("body \"{name}\": coordinates up to {far:.3e} m lie outside ±{:e} m; move the box nearer the origin or scale the units", range::MAX),
        ));
    }
    let total: f64 = n.iter().map(|&v| v as f64).product();
    if total > MAX_BODY_NODES as f64 {
        // the nodes come from mesh.n unless the box gives its own
        let key = if n == [mesh_n; 3] { "mesh.n".to_string() } else { k("box.nodes") };
        return Err(Error::scene(key, format!("body \"{name}\" would have {total:.3e} nodes ({n:?}); at most {MAX_BODY_NODES} are supported")));
    }
    if hi / lo > range::MAX_ASPECT {
        return Err(Error::scene(
            k("box"),
            format!("body \"{name}\": element edges of {lo:.3e} against {hi:.3e} m (ratio {:.1e}) are thinner than the element can represent (ratio at most {:e}: the stiffness's condition number grows with its square); use more nodes along the long sides, fewer across, or a thicker body", hi / lo, range::MAX_ASPECT),
        ));
    }
    Ok(())
}

/// `[[face]]` number `i`: one region ([`FaceDef::region`]), a name without '.'.
fn face(i: usize, f: &FaceDef) -> Result<()> {
    f.region(i)?;
    if f.name.is_empty() || f.name.contains('.') {
        return Err(Error::scene(format!("face[{i}].name"), "face names must be non-empty and contain no '.'"));
    }
    Ok(())
}

/// `[[dirichlet]]` number `i`: a finite value within range, at least one component.
fn dirichlet(i: usize, d: &Dirichlet) -> Result<()> {
    finite(format!("dirichlet[{i}].value"), &d.value)?;
    carried(format!("dirichlet[{i}].value"), "a nonzero prescribed displacement", &d.value, " m")?;
    if d.components.is_empty() {
        return Err(Error::scene(format!("dirichlet[{i}].components"), "must name at least one of x, y, z"));
    }
    Ok(())
}

/// `[[traction]]` number `i`: exactly one of `p` and `pressure`, finite and within range.
fn traction(i: usize, t: &Traction) -> Result<()> {
    match (&t.p, t.pressure) {
        (Some(p), None) => {
            finite(format!("traction[{i}].p"), p)?;
            carried(format!("traction[{i}].p"), "a nonzero traction", p, " MPa")
        }
        (None, Some(p)) => {
            finite(format!("traction[{i}].pressure"), &[p])?;
            carried(format!("traction[{i}].pressure"), "a nonzero pressure", &[p], " MPa")
        }
        (p, _) => {
            let why = if p.is_some() {
                "give either `p` (a traction vector) or `pressure`, not both"
            } else {
                "give `p` (a traction vector) or `pressure` (normal, positive into the body)"
            };
            Err(Error::scene(format!("traction[{i}].{}", if p.is_some() { "pressure" } else { "p" }), why))
        }
    }
}

/// `[[tie]]` number `i`: two different faces, a positive search distance.
fn tie(i: usize, t: &Tie) -> Result<()> {
    if t.slave == t.master {
        return Err(Error::scene(format!("tie[{i}].master"), "slave and master must be different faces"));
    }
    if let Some(d) = t.search_distance {
        if !(d.is_finite() && d > 0.0) {
            return Err(Error::scene(format!("tie[{i}].search_distance"), format!("must be > 0, got {d}")));
        }
    }
    Ok(())
}

/// `[[contact.pair]]` number `i`: its faces, tolerances, press fit and friction law.
fn contact_pair(i: usize, p: &ContactPair) -> Result<()> {
    let k = |f: &str| format!("contact.pair[{i}].{f}");
    pair_faces(&k, p)?;
    if let Some(t) = p.tolerance {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::scene(k("tolerance"), format!("must be > 0, got {t}")));
        }
    }
    if let Some(t) = p.search_distance {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::scene(k("search_distance"), format!("must be > 0, got {t}")));
        }
    }
    if let Some(t) = p.max_overlap {
        if !(0.0..1.0).contains(&t) {
            return Err(Error::scene(k("max_overlap"), format!("a fraction of the element size in [0, 1), got {t}")));
        }
    }
    if let Fit::Stated(d) = p.interference {
        if !(d.is_finite() && d > 0.0) {
            return Err(Error::scene(k("interference"), format!("true, false or a length > 0, got {d}")));
        }
    }
    friction(&k, &p.friction)
}

/// A contact pair's faces: `slave` and `master`, or `faces` with at most one of them naming
/// one of its two (different) faces.
fn pair_faces(k: &impl Fn(&str) -> String, p: &ContactPair) -> Result<()> {
    match (&p.faces, p.slave.is_empty(), p.master.is_empty()) {
        (None, false, false) => {}
        (None, _, _) => {
            return Err(Error::scene(
                k(if p.slave.is_empty() { "slave" } else { "master" }),
                "name both `slave` and `master`, or the two faces as `faces = [\"a.x\", \"b.y\"]`",
            ))
        }
        (Some(f), s, m) => {
            if f[0] == f[1] {
                return Err(Error::scene(k("faces"), "the two faces must be different"));
            }
            if !s && !m {
                return Err(Error::scene(k("faces"), "with `faces`, name at most one of `slave` and `master`"));
            }
            let named = if s { &p.master } else { &p.slave };
            if !named.is_empty() && !f.contains(named) {
                return Err(Error::scene(k(if s { "master" } else { "slave" }), format!("\"{named}\" is not one of `faces`")));
            }
        }
    }
    if p.slave == p.master && !p.slave.is_empty() {
        return Err(Error::scene(k("master"), "slave and master must be different faces"));
    }
    Ok(())
}

/// A contact pair's `friction`: slip bounds and coefficients finite and ≥ 0 (bounds within
/// range), directions nonzero, Coulomb isotropic or orthotropic.
fn friction(k: &impl Fn(&str) -> String, f: &Friction) -> Result<()> {
    let bound = |name: &str, g: f64| {
        let key = k(&format!("friction.{name}"));
        if !(g.is_finite() && g >= 0.0) {
            return Err(Error::scene(key, format!("slip bound must be finite and ≥ 0, got {g}")));
        }
        carried(key, "a nonzero slip bound", &[g], " MPa")
    };
    let coef = |name: &str, v: f64| {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(Error::scene(k(&format!("friction.{name}")), format!("friction coefficient must be finite and ≥ 0, got {v}")))
        }
    };
    let direction = |d: &[f64; 3]| {
        finite(k("friction.direction"), d)?;
        if d.iter().all(|&v| v == 0.0) {
            return Err(Error::scene(k("friction.direction"), "must be a non-zero vector"));
        }
        Ok(())
    };
    match f {
        Friction::None => Ok(()),
        Friction::Tresca { g } => bound("g", *g),
        Friction::Orthotropic { g1, g2, direction: d } => {
            bound("g1", *g1)?;
            bound("g2", *g2)?;
            direction(d)
        }
        Friction::Coulomb { mu, mu1, mu2, direction: d } => match (mu, mu1, mu2, d) {
            (Some(m), None, None, None) => coef("mu", *m),
            (None, Some(a), Some(b), Some(d)) => {
                coef("mu1", *a)?;
                coef("mu2", *b)?;
                direction(d)
            }
            _ => Err(Error::scene(k("friction"), "coulomb takes either mu, or mu1, mu2 and direction")),
        },
    }
}

/// `[decomposition]`: subdomains (or a target size) and clusters of at least one, a positive
/// penalty.
fn decomposition(d: &DecompositionSettings) -> Result<()> {
    if d.subdomains == Some(0) {
        return Err(Error::scene("decomposition.subdomains", "must be at least 1"));
    }
    if d.subdomains_per_cluster == 0 {
        return Err(Error::scene("decomposition.subdomains_per_cluster", "must be at least 1"));
    }
    if !(d.penalty > 0.0 && d.penalty.is_finite()) {
        return Err(Error::scene("decomposition.penalty", format!("must be a positive number, got {}", d.penalty)));
    }
    if let Some(t) = d.target_dofs {
        if t < 24 {
            return Err(Error::scene("decomposition.target_dofs", format!("must be at least 24 (one element), got {t}")));
        }
        if d.subdomains.is_some() {
            return Err(Error::scene("decomposition.target_dofs", "give either `subdomains` or `target_dofs`, not both"));
        }
    }
    Ok(())
}

/// `[output]`: every field one of [`FIELDS`].
fn output(o: &OutputSettings) -> Result<()> {
    for (i, f) in o.fields.iter().enumerate() {
        if !FIELDS.contains(&f.as_str()) {
            return Err(Error::scene(format!("output.fields[{i}]"), format!("unknown field \"{f}\"; known: {}", FIELDS.join(", "))));
        }
    }
    Ok(())
}
