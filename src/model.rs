//! The discrete model of a scene: the mesh of all bodies (boxes generated, Gmsh files imported),
//! the named faces resolved, Dirichlet constraints and nodal loads. Every face name a scene
//! uses is checked here, with the scene key in the error.

use crate::contact::pairing::{self, Contact};
use crate::error::{Error, Result};
use crate::fem::assembly::add_traction;
use crate::fem::material::Lame;
use crate::mesh::{boxgen, gmsh, Face, Mesh};
use crate::scene::{Component, LoadedScene, Scene};

/// Mesh + boundary conditions, ready for assembly.
#[derive(Clone, Debug)]
pub struct Model {
    pub mesh: Mesh,
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
}

impl Model {
    /// Number of displacement DOFs, 3 per node (the paper's n).
    pub fn ndof(&self) -> usize {
        3 * self.mesh.nodes.len()
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
                let mut geom = boxgen::generate(bx.min, bx.max, bx.nodes.unwrap_or([scene.mesh.n; 3]));
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
        mesh.push_body(&b.name, geom);
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

    let mut constraints = Vec::new();
    for (i, d) in scene.dirichlet.iter().enumerate() {
        let f = &mesh.faces[face_index(&mesh, format!("dirichlet[{i}].face"), &d.face)?];
        for v in f.nodes() {
            for c in &d.components {
                let c = match c {
                    Component::X => 0,
                    Component::Y => 1,
                    Component::Z => 2,
                };
                constraints.push((v, c, d.value[c]));
            }
        }
    }

    let mut loads = vec![0.0; 3 * mesh.nodes.len()];
    for (i, t) in scene.traction.iter().enumerate() {
        let f = &mesh.faces[face_index(&mesh, format!("traction[{i}].face"), &t.face)?];
        add_traction(&mesh, f, t.p, 0, &mut loads);
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
    }
    Ok(Model { mesh, lame, constraints, loads, contact, pairs })
}
