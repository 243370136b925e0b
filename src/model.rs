//! The discrete model of a scene: the mesh of all bodies (boxes generated, Gmsh files imported),
//! the named faces resolved, Dirichlet constraints and nodal loads. Every face name a scene
//! uses is checked here, with the scene key in the error.

use crate::contact::hold::{self, FreeBody};
use crate::contact::pairing::{self, Contact};
use crate::error::{Error, Result};
use crate::fem::assembly::add_traction;
use crate::fem::material::Lame;
use crate::mesh::{boxgen, gmsh, rigid, Face, Mesh};
use crate::scene::{Component, LoadedScene, Scene};

/// Mesh + boundary conditions, ready for assembly.
#[derive(Clone, Debug)]
pub struct Model {
    pub mesh: Mesh,
    /// The sizes of the whole mesh (they stay when TFETI releases the mesh arrays:
    /// [`Model::release_mesh`]).
    pub size: MeshSize,
    /// Lamé constants of each body.
    pub lame: Vec<Lame>,
    /// (global node, component, prescribed value).
    pub constraints: Vec<(usize, usize, f64)>,
    /// Consistent nodal forces, 3 per node.
    pub loads: Vec<f64>,
    /// Contact pairs as (slave face, master face) indices into `mesh.faces`.
    pub contact: Vec<(usize, usize)>,
    /// The node-to-node pairs, only when contact is enabled.
    pub pairs: Option<Contact>,
    /// The load path; `constraints` and `loads` are its last step.
    pub path: LoadPath,
    /// Bodies whose Dirichlet conditions leave a rigid motion free that contact holds: solved
    /// by TFETI with the orthogonal projector (SMALSE-M), Gλ = e over every row.
    pub floating: Vec<usize>,
}

/// Nodes and elements of the whole mesh.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeshSize {
    pub nodes: usize,
    pub elements: usize,
}

/// The quasi-static load path: at step k (1…K) every Dirichlet value and traction is its
/// entry's times the entry's factor f_k.
#[derive(Clone, Debug, Default)]
pub struct LoadPath {
    pub steps: usize,
    /// The Dirichlet entry of every constraint (parallel to [`Model::constraints`]) and its
    /// value at factor 1.
    constraint_entry: Vec<(usize, f64)>,
    /// f_k of every Dirichlet entry.
    dirichlet: Vec<Vec<f64>>,
    /// f_k of every traction, and its nonzero nodal forces at factor 1.
    traction: Vec<(Vec<f64>, Vec<(usize, f64)>)>,
}

impl LoadPath {
    /// Whether there is more than one load state.
    pub fn is_path(&self) -> bool {
        self.steps > 1
    }

    /// The nodal forces (DOF, value) of every traction at step k (1…K), in the order
    /// [`Model::state`] sums them.
    pub fn forces(&self, k: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.traction.iter().flat_map(move |(f, entries)| entries.iter().map(move |&(d, x)| (d, f[k - 1] * x)))
    }
}

impl Model {
    /// The constraints (same DOFs at every step) and nodal loads at load step k (1…K).
    pub fn state(&self, k: usize) -> (Vec<(usize, usize, f64)>, Vec<f64>) {
        let constraints = self.constraints.iter().zip(self.constraint_values(k)).map(|(&(v, c, _), val)| (v, c, val)).collect();
        let mut loads = vec![0.0; self.ndof()];
        for (d, x) in self.path.forces(k) {
            loads[d] += x;
        }
        (constraints, loads)
    }

    /// The prescribed value of every constraint at load step k (1…K).
    pub fn constraint_values(&self, k: usize) -> Vec<f64> {
        let p = &self.path;
        p.constraint_entry.iter().map(|&(e, val)| val * p.dirichlet[e][k - 1]).collect()
    }

    /// Drops the whole mesh's node and element arrays and the whole load vector: TFETI, once
    /// every rank holds its share of them. `size`, the bodies' ranges, the faces and the load
    /// path stay; [`Model::state`] is gone with the mesh (a share takes its loads from
    /// [`LoadPath::forces`]).
    pub fn release_mesh(&mut self) {
        self.mesh.nodes = Vec::new();
        self.mesh.hexes = Vec::new();
        self.loads = Vec::new();
    }
}

impl Model {
    /// Number of displacement DOFs, 3 per node (the paper's n).
    pub fn ndof(&self) -> usize {
        3 * self.size.nodes
    }
}

fn face_index(mesh: &Mesh, key: String, name: &str) -> Result<usize> {
    mesh.faces.iter().position(|f| f.name == name).ok_or_else(|| {
        Error::scene(key, format!("unknown face \"{name}\"; known faces: {}", mesh.face_names().join(", ")))
    })
}

/// Builds the model of a loaded scene.
pub fn build(ls: &LoadedScene) -> Result<Model> {
    let scene: &Scene = &ls.scene;
    let mut mesh = Mesh::default();
    for (i, b) in scene.bodies.iter().enumerate() {
        let geom = match (&b.boxed, &b.gmsh) {
            (Some(bx), _) => {
                let mut geom = boxgen::try_generate(bx.min, bx.max, bx.nodes.unwrap_or([scene.mesh.n; 3]))?;
                if let Some(c) = &bx.cylinder {
                    // the curved side moves out by the bulge, the nodes between in proportion
                    let (lo, hi) = (bx.min[2], bx.max[2]);
                    for p in &mut geom.nodes {
                        let b = bx.bulge(p[0]);
                        p[2] += if c.side == "zmin" { -b * (hi - p[2]) / (hi - lo) } else { b * (p[2] - lo) / (hi - lo) };
                    }
                }
                geom
            }
            (_, Some(g)) => {
                let path = ls.dir().join(&g.file);
                let mut geom = gmsh::read(&path, g.volume.as_deref())?;
                if let Some(t) = g.translate {
                    for p in &mut geom.nodes {
                        for d in 0..3 {
                            p[d] += t[d];
                        }
                    }
                }
                geom
            }
            _ => return Err(Error::scene(format!("body[{i}]"), "give exactly one of `box` and `gmsh`")),
        };
        mesh.try_push_body(&b.name, geom)?;
    }
    for (i, f) in scene.faces.iter().enumerate() {
        let key = |k: &str| format!("face[{i}].{k}");
        let body = scene
            .bodies
            .iter()
            .position(|b| b.name == f.body)
            .ok_or_else(|| Error::scene(key("body"), format!("unknown body \"{}\"", f.body)))?;
        let full = format!("{}.{}", f.body, f.name);
        if mesh.face(&full).is_some() {
            return Err(Error::scene(key("name"), format!("face \"{full}\" already exists")));
        }
        let src = face_index(&mesh, key("from"), &format!("{}.{}", f.body, f.from))?;
        let inside = |p: [f64; 3]| (0..3).all(|d| p[d] >= f.min[d] && p[d] <= f.max[d]);
        let quads: Vec<_> =
            mesh.faces[src].quads.iter().filter(|q| q.nodes.iter().all(|&v| inside(mesh.nodes[v]))).cloned().collect();
        if quads.is_empty() {
            return Err(Error::scene(key("min"), format!("no quadrilateral of \"{}\" lies inside the given box", mesh.faces[src].name)));
        }
        mesh.faces.push(Face { name: full, body, quads });
    }

    let lame = scene
        .bodies
        .iter()
        .map(|b| {
            let m = scene.material(&b.material).expect("validated");
            Lame::from_young_poisson(m.e, m.nu)
        })
        .collect();

    let steps = scene.load.steps;
    let factors = |f: &Option<Vec<f64>>| -> Vec<f64> { (1..=steps).map(|k| crate::scene::load_factor(f.as_deref(), k, steps)).collect() };
    let mut path = LoadPath { steps, ..Default::default() };
    let mut constraints = Vec::new();
    for (i, d) in scene.dirichlet.iter().enumerate() {
        path.dirichlet.push(factors(&d.factors));
        let f = &mesh.faces[face_index(&mesh, format!("dirichlet[{i}].face"), &d.face)?];
        for v in f.nodes() {
            for c in &d.components {
                let c = match c {
                    Component::X => 0,
                    Component::Y => 1,
                    Component::Z => 2,
                };
                constraints.push((v, c, d.value[c] * path.dirichlet[i][steps - 1]));
                path.constraint_entry.push((i, d.value[c]));
            }
        }
    }

    let mut loads = vec![0.0; 3 * mesh.nodes.len()];
    for (i, t) in scene.traction.iter().enumerate() {
        let f = &mesh.faces[face_index(&mesh, format!("traction[{i}].face"), &t.face)?];
        let mut unit = vec![0.0; loads.len()];
        add_traction(&mesh, f, t.p, 0, &mut unit);
        let fk = factors(&t.factors);
        for (l, u) in loads.iter_mut().zip(&unit) {
            *l += fk[steps - 1] * u;
        }
        path.traction.push((fk, unit.into_iter().enumerate().filter(|x| x.1 != 0.0).collect()));
    }

    let mut contact = Vec::new();
    for (i, p) in scene.contact.pair.iter().enumerate() {
        let s = face_index(&mesh, format!("contact.pair[{i}].slave"), &p.slave)?;
        let m = face_index(&mesh, format!("contact.pair[{i}].master"), &p.master)?;
        if mesh.faces[s].body == mesh.faces[m].body {
            return Err(Error::scene(format!("contact.pair[{i}]"), "slave and master faces belong to the same body (self-contact is not supported)"));
        }
        contact.push((s, m));
    }
    let contact_active = scene.contact.enabled && !contact.is_empty();
    let pairs = if contact_active { Some(pairing::pair(&mesh, &scene.contact.pair, &contact)?) } else { None };

    let mut floating = Vec::new();
    for (b, body) in mesh.bodies.iter().enumerate() {
        let ne = body.elems.len();
        let parts = scene.decomposition.parts(3 * body.nodes.len());
        if parts > ne {
            let key = if scene.decomposition.target_dofs.is_some() { "decomposition.target_dofs" } else { "decomposition.subdomains" };
            return Err(Error::scene(key, format!("{parts} subdomains per body exceed the {ne} elements of body \"{}\"", body.name)));
        }
        let held = constraints.iter().any(|&(v, _, _)| body.nodes.contains(&v));
        let touches = contact_active && contact.iter().any(|&(s, m)| mesh.faces[s].body == b || mesh.faces[m].body == b);
        if !held && !touches {
            return Err(Error::scene(
                "dirichlet",
                format!("body \"{}\" floats: it has no Dirichlet condition{}", body.name, if contact_active { " and no contact" } else { " (contact is off)" }),
            ));
        }
        let dirichlet = constraints.iter().filter(|x| body.nodes.contains(&x.0)).map(|&(v, c, _)| {
            let mut dir = [0.0; 3];
            dir[c] = 1.0;
            (v, dir)
        });
        let free = free_motions(&mesh, b, dirichlet.clone());
        if free.is_empty() {
            continue;
        }
        let Some(c) = pairs.as_ref().filter(|_| touches) else {
            return Err(Error::scene("dirichlet", format!("body \"{}\": its rigid motions {} are held by no Dirichlet condition", body.name, free.join(", "))));
        };
        // the pairs' directions at the body's contact nodes: the normal, and with friction the tangents
        let mut rows = Vec::new();
        for i in 0..c.len() {
            for v in [c.slave[i], c.master[i]].into_iter().filter(|v| body.nodes.contains(v)) {
                rows.push((v, c.normal[i]));
                if c.has_friction() {
                    rows.extend([(v, c.t1[i]), (v, c.t2[i])]);
                }
            }
        }
        let unheld = free_motions(&mesh, b, dirichlet.chain(rows));
        if !unheld.is_empty() {
            let hint = if c.has_friction() { "" } else { " (frictionless contact does not hold a sliding motion)" };
            return Err(Error::scene("dirichlet", format!("body \"{}\": its rigid motions {} are held by neither Dirichlet conditions nor contact{hint}", body.name, unheld.join(", "))));
        }
        floating.push(b);
    }
    let size = MeshSize { nodes: mesh.nodes.len(), elements: mesh.hexes.len() };
    Ok(Model { mesh, size, lame, constraints, loads, contact, pairs, path, floating })
}

/// The rigid motions of body `b` that the `rows` (node, direction) leave free, in words
/// ([`rigid::free_modes`]).
fn free_motions(mesh: &Mesh, b: usize, rows: impl Iterator<Item = (usize, [f64; 3])>) -> Vec<String> {
    match rigid::free_modes(mesh, b, rows) {
        Some(modes) => modes.iter().map(rigid::describe).collect(),
        None => vec!["(eigen-decomposition failed)".into()],
    }
}

impl Model {
    /// Refuses a load that contact and friction cannot hold on the bodies held by contact
    /// alone ([`crate::contact::hold`]): at every load step, before anything is solved. The
    /// whole mesh and load vector must still be there (before TFETI releases them).
    pub fn check_held(&self) -> Result<()> {
        let Some(c) = self.pairs.as_ref().filter(|_| !self.floating.is_empty()) else { return Ok(()) };
        let free: Vec<FreeBody> = self
            .floating
            .iter()
            .map(|&b| {
                let nodes = &self.mesh.bodies[b].nodes;
                let rows = self.constraints.iter().filter(|x| nodes.contains(&x.0)).map(|&(v, k, _)| {
                    let mut dir = [0.0; 3];
                    dir[k] = 1.0;
                    (v, dir)
                });
                FreeBody { body: b, modes: rigid::free_modes(&self.mesh, b, rows).unwrap_or_default() }
            })
            .collect();
        for k in 1..=self.path.steps {
            let loads = if k == self.path.steps { std::borrow::Cow::Borrowed(&self.loads) } else { std::borrow::Cow::Owned(self.state(k).1) };
            if let Some(unheld) = hold::check(&self.mesh, c, &free, &loads)? {
                return Err(unheld.error(&self.mesh, self.path.is_path().then_some((k, self.path.steps))));
            }
        }
        Ok(())
    }
}
