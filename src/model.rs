//! The discrete model of a scene: the mesh of all bodies (boxes generated, Gmsh files imported),
//! the named faces resolved, Dirichlet constraints and nodal loads. Every face name a scene
//! uses is checked here, with the scene key in the error.

use std::collections::HashMap;
use std::sync::OnceLock;

use crate::contact::hold::{self, FreeBody};
use crate::contact::pairing::{self, Contact, SlipBound, Tied};
use crate::error::{Error, Result};
use crate::fem::assembly::{add_pressure, add_traction};
use crate::fem::facet::{facet_area_inside, facet_centre, facet_nodal_areas};
use crate::fem::material::Lame;
use crate::linalg::ordering::NodeOrder;
use crate::mesh::{abaqus, boxgen, exodus, gmsh, med, rigid, BodyGeometry, Face, Mesh};
use crate::qp::cone::Coefficient;
use crate::scene::{Component, LoadedScene, MeshFormat, Scene, Side};

/// Mesh + boundary conditions, ready for assembly.
#[derive(Clone, Debug)]
pub struct Model {
    /// The bodies' nodes, cells and named faces (released under TFETI once every rank holds its share).
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
    /// The contact rows (node-to-node or mortar), only when contact is enabled.
    pub pairs: Option<Contact>,
    /// The equality rows of the `[[tie]]` interfaces (empty: none).
    pub ties: Tied,
    /// The load path; `constraints` and `loads` are its last step.
    pub path: LoadPath,
    /// Bodies, or groups of bodies joined by ties, whose Dirichlet conditions leave a rigid
    /// motion of the group free that contact holds (each group ascending): solved by TFETI with
    /// the orthogonal projector (SMALSE-M), Gλ = e over every row.
    pub floating: Vec<Vec<usize>>,
    /// Every group of bodies joined by `[[tie]]` (two bodies or more), each ascending.
    pub tied_groups: Vec<Vec<usize>>,
    /// Why the slave of each pair given by `faces` is the one it is (pair index, words).
    pub slave_choice: Vec<(usize, String)>,
    /// The faces `[[face]]` cut from others, in scene order.
    pub cut_faces: Vec<CutFace>,
    /// Each body's node order for its factor, computed once: `[plain, contact nodes last]`
    /// (`pipeline::body_order`; the plan counts its fill, the factorization uses it).
    pub orders: Vec<[OnceLock<NodeOrder>; 2]>,
    /// The partition the plan made for the count it chose (subdomains per body, the
    /// decomposition): the decompose phase takes it instead of partitioning again.
    pub partition: OnceLock<(Vec<usize>, crate::feti::decomposition::Decomposition)>,
}

/// A face cut from another by a region: the facets whose centres lie in it.
#[derive(Clone, Debug)]
pub struct CutFace {
    /// Its index in `mesh.faces`.
    pub face: usize,
    /// The index in `mesh.faces` of the face it is cut from.
    pub from: usize,
    /// The region, in words.
    pub region: String,
    /// The area of `from` inside the region (what the user means by the face).
    pub region_area: f64,
}

/// How far a cut face's area may differ from its region's before `check` warns of a traction on it.
pub const CUT_AREA_TOLERANCE: f64 = 0.02;

/// The facets of `face` whose centres lie in `region`, and the area of `face` inside `region`
/// (sampled where the region's boundary crosses a facet: [`facet_area_inside`]).
fn cut(mesh: &Mesh, face: &Face, region: &crate::scene::Region) -> (Vec<crate::mesh::Facet>, f64) {
    let mut kept = Vec::new();
    let mut area = 0.0;
    for q in &face.facets {
        let x = mesh.facet_coords(q);
        let centre = region.contains(facet_centre(q.kind, &x));
        if centre {
            kept.push(*q);
        }
        let inside = x.iter().filter(|&&p| region.contains(p)).count();
        area += if inside == x.len() && centre {
            facet_nodal_areas(q.kind, &x).iter().sum()
        } else if inside == 0 && !centre {
            0.0
        } else {
            facet_area_inside(q.kind, &x, |p| region.contains(p))
        };
    }
    (kept, area)
}

/// Nodes and elements of the whole mesh.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeshSize {
    /// Nodes of all bodies.
    pub nodes: usize,
    /// Cells (volume elements) of all bodies.
    pub elements: usize,
    /// Cells of each type, in [`crate::mesh::CellKind::ALL`] order.
    pub by_kind: [usize; crate::mesh::CellKind::COUNT],
}

impl MeshSize {
    /// "1000 hexahedra", "24 4-node tetrahedra and 8 wedges".
    pub fn describe(&self) -> String {
        crate::mesh::describe_counts(crate::mesh::CellKind::ALL.iter().zip(self.by_kind).map(|(k, n)| (n, k.plural())), "no cells")
    }
}

/// The quasi-static load path: at step k (1…K) every Dirichlet value and traction is its
/// entry's times the entry's factor f_k.
#[derive(Clone, Debug, Default)]
pub struct LoadPath {
    /// The load steps solved (those before a stop, on a path cut short).
    pub steps: usize,
    /// The Dirichlet entry of every constraint (parallel to [`Model::constraints`]) and its
    /// value at factor 1.
    constraint_entry: Vec<(usize, f64)>,
    /// f_k of every Dirichlet entry.
    dirichlet: Vec<Vec<f64>>,
    /// f_k of every traction, and its nonzero nodal forces at factor 1.
    traction: Vec<(Vec<f64>, Vec<(usize, f64)>)>,
    /// A path cut short before a step without equilibrium ([`Model::check_held`]): `steps`
    /// are the steps before it.
    pub stopped: Option<Stopped>,
}

/// Where a load path stops: the step that has no equilibrium, of how many, and why (the body or
/// group, and the reason).
#[derive(Clone, Debug)]
pub struct Stopped {
    /// The first step without equilibrium (1-based).
    pub at: usize,
    /// The steps the scene asked for.
    pub of: usize,
    /// The body or tied group that is not held.
    pub what: String,
    /// Why: the load it carries that nothing holds.
    pub why: String,
}

impl Stopped {
    /// The attribute and report text: "step 5/5: body \"block\": no equilibrium …".
    pub fn describe(&self) -> String {
        format!("stopped before load step {}/{}: {}: {}", self.at, self.of, self.what, self.why)
    }
}

impl LoadPath {
    /// Whether there is more than one load state.
    pub fn is_path(&self) -> bool {
        self.steps > 1 || self.stopped.is_some()
    }

    /// The number of steps the scene asked for (more than `steps` where the path stopped).
    pub fn asked(&self) -> usize {
        self.stopped.as_ref().map_or(self.steps, |s| s.of)
    }

    /// The resultant force of traction entry `i` at factor 1 (the sum of its nodal forces).
    pub fn traction_resultant(&self, i: usize) -> [f64; 3] {
        let mut f = [0.0; 3];
        for &(d, x) in &self.traction[i].1 {
            f[d % 3] += x;
        }
        f
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
        self.mesh.cells = Vec::new();
        self.loads = Vec::new();
    }
}

impl Model {
    /// Number of displacement DOFs, 3 per node (the paper's n).
    pub fn ndof(&self) -> usize {
        3 * self.size.nodes
    }
}

/// `constraints` (node, component, value) split by the body whose node range holds the node,
/// each body's in their order (so that "a later entry for the same DOF wins" still holds): one
/// pass, instead of a scan of every constraint per body.
pub fn constraints_by_body(mesh: &Mesh, constraints: &[(usize, usize, f64)]) -> Vec<Vec<(usize, usize, f64)>> {
    let mut out = vec![Vec::new(); mesh.bodies.len()];
    for &x in constraints {
        let b = mesh.bodies.partition_point(|b| b.nodes.end <= x.0);
        if let Some(o) = out.get_mut(b) {
            o.push(x);
        }
    }
    out
}

/// Face name → index into `mesh.faces` (built once: every entry's lookup is then O(1)).
type FaceIndex = HashMap<String, usize>;

fn face_index(mesh: &Mesh, faces: &FaceIndex, key: String, name: &str) -> Result<usize> {
    faces.get(name).copied().ok_or_else(|| Error::scene(key, format!("unknown face \"{name}\"; known faces: {}", mesh.face_names().join(", "))))
}

/// The component's letter.
fn axis_name(c: usize) -> &'static str {
    ["x", "y", "z"][c]
}

/// The mesh's cell type of a box's `cells`.
pub fn cell_kind(c: crate::scene::BoxCells) -> crate::mesh::CellKind {
    use crate::mesh::CellKind;
    use crate::scene::BoxCells;
    match c {
        BoxCells::Hex8 => CellKind::Hex8,
        BoxCells::Tet4 => CellKind::Tet4,
        BoxCells::Tet10 => CellKind::Tet10,
        BoxCells::Hex20 => CellKind::Hex20,
        BoxCells::Hex27 => CellKind::Hex27,
    }
}

/// Builds the model of a loaded scene.
pub fn build(ls: &LoadedScene) -> Result<Model> {
    build_timed(ls, &mut Vec::new(), &|_, _| ())
}

/// [`build`], adding the wall time of its large parts to `times`: `mesh read` (the files read
/// and parsed, the boxes generated), `pairing` (the contact and tie pairs) and `hold buckets`
/// (what holds each body, the floating groups). `read(done, total)` hears the bytes read of each
/// Gmsh or Abaqus file as the reader goes (for the monitor; it must not print into the mesh).
pub fn build_timed(ls: &LoadedScene, times: &mut Vec<(&'static str, f64)>, read: &dyn Fn(u64, u64)) -> Result<Model> {
    let scene: &Scene = &ls.scene;
    let clock = std::time::Instant::now();
    let mut mesh = read_bodies(ls, read)?;
    times.push(("mesh read", clock.elapsed().as_secs_f64()));
    let (faces, cut_faces) = cut_scene_faces(scene, &mut mesh)?;
    let lame = body_lame(scene);
    let mut path = LoadPath { steps: scene.load.steps, ..Default::default() };
    let constraints = dirichlet_constraints(scene, &mesh, &faces, &mut path)?;
    let loads = traction_loads(scene, &mesh, &faces, &mut path)?;
    let (contact, slave_choice) = contact_faces(scene, &mesh, &faces, &lame)?;
    let tie_faces = tie_faces(scene, &mesh, &faces)?;
    overlapping_rows(&mesh, &tie_faces, &contact)?;
    let contact_active = scene.contact.enabled && !contact.is_empty();
    let clock = std::time::Instant::now();
    let pairs = contact_rows(scene, &mesh, &contact, &constraints, &path, contact_active)?;
    let ties = pairing::tie(&mesh, &scene.ties, &tie_faces)?;
    times.push(("pairing", clock.elapsed().as_secs_f64()));
    // bodies joined by ties move as one in the question of what holds them
    let groups = tie_groups(mesh.bodies.len(), tie_faces.iter().map(|&(s, m)| (mesh.faces[s].body, mesh.faces[m].body)));
    let clock = std::time::Instant::now();
    let buckets = HoldBuckets::new(&mesh, &constraints, &contact, pairs.as_ref(), contact_active);
    check_parts(scene, &mesh)?;
    let floating = floating_groups(&mesh, &groups, &buckets, pairs.as_ref(), contact_active)?;
    times.push(("hold buckets", clock.elapsed().as_secs_f64()));
    let mut by_kind = [0; crate::mesh::CellKind::COUNT];
    for (k, n) in mesh.cell_counts() {
        by_kind[k.code()] = n;
    }
    let size = MeshSize { nodes: mesh.nodes.len(), elements: mesh.cells.len(), by_kind };
    let orders = mesh.bodies.iter().map(|_| Default::default()).collect();
    let tied_groups = groups.into_iter().filter(|g| g.len() > 1).collect();
    Ok(Model {
        mesh,
        size,
        lame,
        constraints,
        loads,
        contact,
        pairs,
        ties,
        path,
        floating,
        tied_groups,
        slave_choice,
        cut_faces,
        orders,
        partition: OnceLock::new(),
    })
}

/// The mesh of every body, boxes generated and mesh files read, in scene order. Each file is
/// read and parsed once, at its first body, and every body that names it is built from it.
fn read_bodies(ls: &LoadedScene, progress: &dyn Fn(u64, u64)) -> Result<Mesh> {
    let scene: &Scene = &ls.scene;
    let mut mesh = Mesh::default();
    // the bodies built from a file already parsed, by body index
    let mut read: HashMap<usize, Result<BodyGeometry>> = HashMap::new();
    for (i, b) in scene.bodies.iter().enumerate() {
        let geom = match (&b.boxed, b.mesh_file()) {
            (Some(bx), _) => box_geometry(scene, bx)?,
            (_, Some((_, m))) => match read.remove(&i) {
                Some(geom) => geom?,
                None => {
                    read.extend(file_bodies(ls, i, &m, progress)?);
                    read.remove(&i).expect("the file's first body is among its bodies")?
                }
            },
            _ => return Err(Error::scene(format!("body[{i}]"), "give exactly one of `box`, `mesh` and `gmsh`")),
        };
        let geom = match b.mesh_file() {
            Some((key, m)) if b.boxed.is_none() => translated(i, b, key, &m, geom)?,
            _ => geom,
        };
        mesh.try_push_body(&b.name, geom)?;
    }
    Ok(mesh)
}

/// Every body from body `first` on that reads the same file, in the same format, as body
/// `first` (its mesh `g`), built from one parse of the file (translations not yet applied);
/// `progress` hears the bytes read.
fn file_bodies(ls: &LoadedScene, first: usize, g: &crate::scene::MeshDef, progress: &dyn Fn(u64, u64)) -> Result<Vec<(usize, Result<BodyGeometry>)>> {
    let path = ls.dir().join(&g.file);
    let format = g.resolved_format();
    let same: Vec<(usize, crate::scene::MeshDef)> = ls.scene.bodies[first..]
        .iter()
        .enumerate()
        .filter(|(_, b)| b.boxed.is_none())
        .filter_map(|(k, b)| b.mesh_file().map(|(_, m)| (first + k, m)))
        .filter(|(_, m)| ls.dir().join(&m.file) == path && m.resolved_format() == format)
        .collect();
    let volumes: Vec<Option<&str>> = same.iter().map(|(_, m)| m.volume.as_deref()).collect();
    let bodies = match format {
        Some(MeshFormat::Abaqus) => abaqus::read_many_with(&path, &volumes, progress)?,
        Some(MeshFormat::Gmsh) => gmsh::read_many_with(&path, &volumes, progress)?,
        Some(MeshFormat::Med) => med::read_many(&path, &volumes)?,
        Some(MeshFormat::Exodus) => exodus::read_many(&path, &volumes)?,
        None => {
            let key = ls.scene.bodies[first].mesh_file().map_or("mesh", |(k, _)| k);
            return Err(Error::scene(format!("body[{first}].{key}.file"), "unknown mesh format (known: abaqus, gmsh, med, exodus)"));
        }
    };
    Ok(same.into_iter().map(|(k, _)| k).zip(bodies).collect())
}

/// A box body's generated cells, its curved side (if any) bulged out.
fn box_geometry(scene: &Scene, bx: &crate::scene::BoxDef) -> Result<BodyGeometry> {
    let mut geom = boxgen::try_generate_cells(bx.min, bx.max, bx.nodes.unwrap_or([scene.mesh.n; 3]), cell_kind(bx.cells.unwrap_or(scene.mesh.cells)))?;
    if let Some(side) = bx.curved_side() {
        // the curved side moves out by the bulge, the nodes between in proportion
        let (lo, hi) = (bx.min[2], bx.max[2]);
        for p in &mut geom.nodes {
            let b = bx.bulge(p[0], p[1]);
            p[2] += if side == Side::Zmin { -b * (hi - p[2]) / (hi - lo) } else { b * (p[2] - lo) / (hi - lo) };
        }
    }
    Ok(geom)
}

/// A mesh-file body's cells `geom` as read from its file, shifted by its `translate` (kept in
/// coordinate range); `key` is the scene key it was given under (`mesh`, `gmsh`).
fn translated(i: usize, b: &crate::scene::Body, key: &str, g: &crate::scene::MeshDef, mut geom: BodyGeometry) -> Result<BodyGeometry> {
    if let Some(t) = g.translate {
        for p in &mut geom.nodes {
            for d in 0..3 {
                p[d] += t[d];
            }
        }
        // the file's coordinates were checked by the reader; the shift must keep them in range
        let far = geom.nodes.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
        if far > crate::scene::range::MAX {
            return Err(Error::scene(
                format!("body[{i}].{key}.translate"),
                format!(
                    "moves body \"{}\" to coordinates up to {far:.3e} m, outside ±{:e} m (the element sizes would be lost in them)",
                    b.name,
                    crate::scene::range::MAX
                ),
            ));
        }
    }
    Ok(geom)
}

/// The face index of the mesh's faces, and the `[[face]]` entries cut from them (added to `mesh`).
fn cut_scene_faces(scene: &Scene, mesh: &mut Mesh) -> Result<(FaceIndex, Vec<CutFace>)> {
    let body_index: HashMap<&str, usize> = scene.bodies.iter().enumerate().map(|(i, b)| (b.name.as_str(), i)).collect();
    // the first face of each name (as `Mesh::face` finds it)
    let mut faces: FaceIndex = HashMap::with_capacity(mesh.faces.len() + scene.faces.len());
    for (k, f) in mesh.faces.iter().enumerate() {
        faces.entry(f.name.clone()).or_insert(k);
    }
    let mut cut_faces = Vec::with_capacity(scene.faces.len());
    for (i, f) in scene.faces.iter().enumerate() {
        let key = |k: &str| format!("face[{i}].{k}");
        let body = *body_index.get(f.body.as_str()).ok_or_else(|| Error::scene(key("body"), format!("unknown body \"{}\"", f.body)))?;
        let full = format!("{}.{}", f.body, f.name);
        if faces.contains_key(&full) {
            return Err(Error::scene(key("name"), format!("face \"{full}\" already exists")));
        }
        let src = face_index(mesh, &faces, key("from"), &format!("{}.{}", f.body, f.from))?;
        let region = f.region(i)?;
        let (facets, region_area) = cut(mesh, &mesh.faces[src], &region);
        if facets.is_empty() {
            return Err(Error::scene(format!("face[{i}]"), format!("no facet of \"{}\" has its centre inside {}", mesh.faces[src].name, region.describe())));
        }
        faces.insert(full.clone(), mesh.faces.len());
        cut_faces.push(CutFace { face: mesh.faces.len(), from: src, region: region.describe(), region_area });
        mesh.faces.push(Face { name: full, body, facets });
    }
    Ok((faces, cut_faces))
}

/// The Lamé constants of each body's material.
fn body_lame(scene: &Scene) -> Vec<Lame> {
    let materials = scene.material_index();
    scene
        .bodies
        .iter()
        .map(|b| {
            let m = &scene.materials[*materials.get(b.material.as_str()).expect("validated")];
            Lame::from_young_poisson(m.e, m.nu)
        })
        .collect()
}

/// The load factor f_k of an entry at every step k (1…`steps`).
fn step_factors(f: &Option<Vec<f64>>, steps: usize) -> Vec<f64> {
    (1..=steps).map(|k| crate::scene::load_factor(f.as_deref(), k, steps)).collect()
}

/// The Dirichlet constraints at the last step (each entry's factors and values recorded in `path`);
/// a DOF held by two entries must have one value at every step.
fn dirichlet_constraints(scene: &Scene, mesh: &Mesh, faces: &FaceIndex, path: &mut LoadPath) -> Result<Vec<(usize, usize, f64)>> {
    let steps = path.steps;
    let mut constraints = Vec::new();
    // (node, component) → the first entry that holds it: a later entry must prescribe the same
    // value at every load step (identical duplicates are accepted; the last entry used to win)
    let mut holder: HashMap<(usize, usize), usize> = HashMap::new();
    let mut entry_face = Vec::with_capacity(scene.dirichlet.len());
    for (i, d) in scene.dirichlet.iter().enumerate() {
        path.dirichlet.push(step_factors(&d.factors, steps));
        let fi = face_index(mesh, faces, format!("dirichlet[{i}].face"), &d.face)?;
        entry_face.push(fi);
        let f = &mesh.faces[fi];
        for v in f.nodes() {
            for c in &d.components {
                let c = match c {
                    Component::X => 0,
                    Component::Y => 1,
                    Component::Z => 2,
                };
                if let Some(&j) = holder.get(&(v, c)) {
                    let (a, b) = (scene.dirichlet[j].value[c], d.value[c]);
                    let differ = |x: f64, y: f64| (x - y).abs() > 1e-12 * x.abs().max(y.abs());
                    if let Some(k) = (0..steps).find(|&k| differ(a * path.dirichlet[j][k], b * path.dirichlet[i][k])) {
                        let p = mesh.nodes[v];
                        let at = if steps > 1 { format!(" at load step {}", k + 1) } else { String::new() };
                        return Err(Error::scene(
                            format!("dirichlet[{i}]"),
                            format!(
                                "prescribes component {} of node {v} at ({:.6}, {:.6}, {:.6}) as {}{at}, but dirichlet[{j}] prescribes it as {} (faces {} and {} share the node); give each held component one value",
                                axis_name(c),
                                p[0],
                                p[1],
                                p[2],
                                b * path.dirichlet[i][k],
                                a * path.dirichlet[j][k],
                                mesh.faces[entry_face[j]].name,
                                f.name
                            ),
                        ));
                    }
                } else {
                    holder.insert((v, c), i);
                }
                constraints.push((v, c, d.value[c] * path.dirichlet[i][steps - 1]));
                path.constraint_entry.push((i, d.value[c]));
            }
        }
    }
    Ok(constraints)
}

/// The nodal loads of the tractions at the last step (each entry's factors and forces recorded in `path`).
fn traction_loads(scene: &Scene, mesh: &Mesh, faces: &FaceIndex, path: &mut LoadPath) -> Result<Vec<f64>> {
    let steps = path.steps;
    let mut loads = vec![0.0; 3 * mesh.nodes.len()];
    for (i, t) in scene.traction.iter().enumerate() {
        let f = &mesh.faces[face_index(mesh, faces, format!("traction[{i}].face"), &t.face)?];
        let mut unit = vec![0.0; loads.len()];
        match t.pressure {
            Some(p) => add_pressure(mesh, f, p, 0, &mut unit),
            None => add_traction(mesh, f, t.p.unwrap_or_default(), 0, &mut unit),
        }
        let fk = step_factors(&t.factors, steps);
        for (l, u) in loads.iter_mut().zip(&unit) {
            *l += fk[steps - 1] * u;
        }
        path.traction.push((fk, unit.into_iter().enumerate().filter(|x| x.1 != 0.0).collect()));
    }
    Ok(loads)
}

/// The (slave, master) faces of every contact pair, and why the slave of each is the one it is.
fn contact_faces(scene: &Scene, mesh: &Mesh, faces: &FaceIndex, lame: &[Lame]) -> Result<(Vec<(usize, usize)>, Vec<(usize, String)>)> {
    let mut contact = Vec::new();
    let mut slave_choice = Vec::new();
    let young: Vec<f64> = lame.iter().map(Lame::young).collect();
    for (i, p) in scene.contact.pair.iter().enumerate() {
        let (s, m) = match &p.faces {
            None => {
                let (s, m) = (
                    face_index(mesh, faces, format!("contact.pair[{i}].slave"), &p.slave)?,
                    face_index(mesh, faces, format!("contact.pair[{i}].master"), &p.master)?,
                );
                if let Some(w) = stiff_slave(mesh, &young, s, m, i) {
                    slave_choice.push((i, w));
                }
                (s, m)
            }
            Some(f) => {
                let a = face_index(mesh, faces, format!("contact.pair[{i}].faces"), &f[0])?;
                let b = face_index(mesh, faces, format!("contact.pair[{i}].faces"), &f[1])?;
                let (s, m, why) = choose_slave(mesh, &young, a, b, p);
                slave_choice.push((i, why));
                (s, m)
            }
        };
        if mesh.faces[s].body == mesh.faces[m].body {
            return Err(Error::scene(format!("contact.pair[{i}]"), "slave and master faces belong to the same body (self-contact is not supported)"));
        }
        contact.push((s, m));
    }
    Ok((contact, slave_choice))
}

/// The (slave, master) faces of every tie.
fn tie_faces(scene: &Scene, mesh: &Mesh, faces: &FaceIndex) -> Result<Vec<(usize, usize)>> {
    let mut tie_faces = Vec::new();
    for (i, t) in scene.ties.iter().enumerate() {
        let s = face_index(mesh, faces, format!("tie[{i}].slave"), &t.slave)?;
        let m = face_index(mesh, faces, format!("tie[{i}].master"), &t.master)?;
        if mesh.faces[s].body == mesh.faces[m].body {
            return Err(Error::scene(format!("tie[{i}]"), "slave and master faces belong to the same body"));
        }
        tie_faces.push((s, m));
    }
    Ok(tie_faces)
}

/// The contact rows when contact is active, the tangents of DOFs that Dirichlet holds voided.
fn contact_rows(
    scene: &Scene,
    mesh: &Mesh,
    contact: &[(usize, usize)],
    constraints: &[(usize, usize, f64)],
    path: &LoadPath,
    contact_active: bool,
) -> Result<Option<Contact>> {
    let mut pairs = if contact_active { Some(pairing::pair(mesh, &scene.contact.pair, contact)?) } else { None };
    if let Some(c) = pairs.as_mut() {
        let held: std::collections::HashSet<(usize, usize)> = constraints.iter().map(|&(v, k, _)| (v, k)).collect();
        // held at 0 at every step (a symmetry plane's rollers), not driven
        let still: std::collections::HashSet<(usize, usize)> =
            constraints.iter().zip(&path.constraint_entry).filter(|(_, e)| e.1 == 0.0).map(|(&(v, k, _), _)| (v, k)).collect();
        c.void_held_tangents(|v, k| held.contains(&(v, k)), |v, k| still.contains(&(v, k)));
    }
    Ok(pairs)
}

/// Each body's constraints and contact pairs, bucketed once (not a scan of all per body).
struct HoldBuckets {
    /// The (node, component) of each body's constraints.
    constraints: Vec<Vec<(usize, usize)>>,
    /// Whether contact touches each body.
    touches: Vec<bool>,
    /// The contact rows with a node in each body.
    pairs: Vec<Vec<usize>>,
}

impl HoldBuckets {
    /// Buckets `constraints`, the contact faces and the contact rows by body.
    fn new(mesh: &Mesh, constraints: &[(usize, usize, f64)], contact: &[(usize, usize)], pairs: Option<&Contact>, contact_active: bool) -> Self {
        let body_of = |v: usize| mesh.bodies.partition_point(|b| b.nodes.end <= v);
        let mut body_constraints: Vec<Vec<(usize, usize)>> = vec![Vec::new(); mesh.bodies.len()];
        for &(v, c, _) in constraints {
            body_constraints[body_of(v)].push((v, c));
        }
        // touched by contact
        let mut body_touches = vec![false; mesh.bodies.len()];
        if contact_active {
            for &(s, m) in contact {
                body_touches[mesh.faces[s].body] = true;
                body_touches[mesh.faces[m].body] = true;
            }
        }
        let mut body_pairs: Vec<Vec<usize>> = vec![Vec::new(); mesh.bodies.len()];
        if let Some(c) = pairs {
            for i in 0..c.len() {
                let mut bodies: Vec<usize> = c.row(i).iter().map(|&(v, _)| body_of(v)).collect();
                bodies.sort_unstable();
                bodies.dedup();
                for b in bodies {
                    body_pairs[b].push(i);
                }
            }
        }
        HoldBuckets { constraints: body_constraints, touches: body_touches, pairs: body_pairs }
    }
}

/// Refuses a decomposition into more subdomains per body than the body has elements.
fn check_parts(scene: &Scene, mesh: &Mesh) -> Result<()> {
    for body in &mesh.bodies {
        let ne = body.elems.len();
        let parts = scene.decomposition.parts(3 * body.nodes.len());
        if parts > ne {
            let key = if scene.decomposition.target_dofs.is_some() { "decomposition.target_dofs" } else { "decomposition.subdomains" };
            return Err(Error::scene(key, format!("{parts} subdomains per body exceed the {ne} elements of body \"{}\"", body.name)));
        }
    }
    Ok(())
}

/// The groups whose rigid motions Dirichlet leaves free and contact holds; refuses a group that
/// nothing holds.
fn floating_groups(mesh: &Mesh, groups: &[Vec<usize>], buckets: &HoldBuckets, pairs: Option<&Contact>, contact_active: bool) -> Result<Vec<Vec<usize>>> {
    let mut floating = Vec::new();
    for group in groups {
        let name = hold::group_name(mesh, group);
        let held = group.iter().any(|&b| !buckets.constraints[b].is_empty());
        let touches = group.iter().any(|&b| buckets.touches[b]);
        if !held && !touches {
            let what = if group.len() == 1 { "floats: it has no Dirichlet condition" } else { "float: none of them has a Dirichlet condition" };
            return Err(Error::scene("dirichlet", format!("{name} {what}{}", if contact_active { " and no contact" } else { " (contact is off)" })));
        }
        let axis = |c: usize| {
            let mut dir = [0.0; 3];
            dir[c] = 1.0;
            dir
        };
        let dirichlet = group.iter().flat_map(|&b| buckets.constraints[b].iter().map(|&(v, c)| (v, axis(c))));
        let free = free_motions(mesh, group, dirichlet.clone());
        if free.is_empty() {
            continue;
        }
        let its = if group.len() == 1 { "its" } else { "the group's" };
        let Some(c) = pairs.filter(|_| touches) else {
            return Err(Error::scene("dirichlet", format!("{name}: {its} rigid motions {} are held by no Dirichlet condition", free.join(", "))));
        };
        let (rows, zero_bound) = contact_hold_rows(mesh, group, &buckets.pairs, c);
        let unheld = free_motions(mesh, group, dirichlet.chain(rows));
        if !unheld.is_empty() {
            let hint = if zero_bound {
                " (a zero slip bound or friction coefficient does not hold a sliding motion)"
            } else if c.has_friction() {
                ""
            } else {
                " (frictionless contact does not hold a sliding motion)"
            };
            return Err(Error::scene(
                "dirichlet",
                format!("{name}: {its} rigid motions {} are held by neither Dirichlet conditions nor contact{hint}", unheld.join(", ")),
            ));
        }
        floating.push(group.clone());
    }
    Ok(floating)
}

/// The pairs' directions at the group's contact nodes: the normal, and each tangent along which
/// friction can carry a force (a slip bound g or coefficient μ > 0: a zero bound holds no sliding,
/// like no friction at all); and whether a zero bound or coefficient left a tangent out.
fn contact_hold_rows(mesh: &Mesh, group: &[usize], body_pairs: &[Vec<usize>], c: &Contact) -> (Vec<(usize, [f64; 3])>, bool) {
    let inside = |v: &usize| group.iter().any(|&b| mesh.bodies[b].nodes.contains(v));
    let mut rows = Vec::new();
    let mut zero_bound = false;
    let mut seen: Vec<usize> = group.iter().flat_map(|&b| body_pairs[b].iter().copied()).collect();
    seen.sort_unstable();
    seen.dedup();
    for i in seen {
        let holds = tangential_hold(c, i);
        zero_bound |= holds != [true, true] && (c.bound[i] != SlipBound::None || c.coulomb[i] != Coefficient::Fixed);
        for v in c.row(i).iter().map(|&(v, _)| v).filter(inside) {
            rows.push((v, c.normal[i]));
            for (t, hold) in [(c.t1[i], holds[0]), (c.t2[i], holds[1])] {
                if hold {
                    rows.push((v, t));
                }
            }
        }
    }
    (rows, zero_bound)
}

/// The slave rule in words, as `check` prints it and the docs state it ([`choose_slave`]).
pub const SLAVE_RULE: &str = "the smaller E·h (Young's modulus × mean facet size)";

/// Refuses ties and contact pairs whose rows would be the same constraint twice (B without full
/// row rank, found only by the FETI scaling or the coarse factorization otherwise): a slave
/// face in two ties, two ties or a tie and a contact pair between the same two faces, and a
/// tie's slave face that is also a contact pair's slave. `ties`, `contact`: (slave, master)
/// face indices in scene order.
fn overlapping_rows(mesh: &Mesh, ties: &[(usize, usize)], contact: &[(usize, usize)]) -> Result<()> {
    let name = |f: usize| &mesh.faces[f].name;
    let same_faces = |a: (usize, usize), b: (usize, usize)| a == b || a == (b.1, b.0);
    for (j, &(s, m)) in ties.iter().enumerate() {
        for (i, &(si, mi)) in ties[..j].iter().enumerate() {
            if same_faces((s, m), (si, mi)) {
                return Err(Error::scene(
                    format!("tie[{j}]"),
                    format!("ties {} and {} again, as tie[{i}] does: each pair of faces is tied once; remove one", name(s), name(m)),
                ));
            }
            if s == si {
                return Err(Error::scene(
                    format!("tie[{j}].slave"),
                    format!("{} is already the slave of tie[{i}]: a slave face is tied once (its nodes would carry two sets of tie rows)", name(s)),
                ));
            }
        }
        for (i, &(cs, cm)) in contact.iter().enumerate() {
            if same_faces((s, m), (cs, cm)) {
                return Err(Error::scene(
                    format!("tie[{j}]"),
                    format!(
                        "ties {} and {}, which contact.pair[{i}] puts in contact: faces are either tied or in contact; remove the tie or the pair",
                        name(s),
                        name(m)
                    ),
                ));
            }
            if s == cs {
                return Err(Error::scene(
                    format!("tie[{j}].slave"),
                    format!("{} is also the slave of contact.pair[{i}]: a slave face carries either tie rows or contact rows", name(s)),
                ));
            }
        }
    }
    Ok(())
}

/// E·h of a face: its body's Young's modulus times its mean facet size √(area/facets).
pub(crate) fn stiffness_size(mesh: &Mesh, e: &[f64], f: usize) -> (f64, f64) {
    let face = &mesh.faces[f];
    let h = (crate::fem::cell::face_area(face, &mesh.nodes) / face.facets.len().max(1) as f64).sqrt();
    (e[face.body] * h, h)
}

/// The ratio of the slave's E·h to the master's above which a slave is stiff ([`stiff_slave`]).
pub(crate) const STIFF_SLAVE: f64 = 2.0;

/// A warning where the named slave `s` has more than twice the master's E·h: a stiff slave over
/// a soft master makes the contact rows nearly dependent (measured on a flat punch over a block,
/// both meshes given: E·h 4.7× the master's left 20 of 123 nodes under it open in 261 products,
/// 470× left 91 open in 1 084; the block as slave: none open, 64–74 products).
fn stiff_slave(mesh: &Mesh, e: &[f64], s: usize, m: usize, i: usize) -> Option<String> {
    let ((ks, _), (km, _)) = (stiffness_size(mesh, e, s), stiffness_size(mesh, e, m));
    (ks > STIFF_SLAVE * km).then(|| {
        format!(
            "warning: contact pair {i}: the slave {} has {:.1}× the E·h (Young's modulus × facet size) of the master {}: a stiff slave over a soft master leaves nodes open and costs many products; swap them, or give `faces` and let the rule choose",
            mesh.faces[s].name,
            ks / km,
            mesh.faces[m].name
        )
    })
}

/// The slave of two faces `a`, `b` (indices into `mesh.faces`) where the pair leaves it open:
/// the face named by `slave` or `master` alone; else the one with the smaller E·h (Young's
/// modulus of its body times its mean facet size √(area/facets)) — the softer and the finer side.
/// A stiff slave over a soft, coarser master makes the dual rows nearly dependent (the master's
/// compliance reaches the slave rows only through the fewer master nodes): a stiff flat punch as
/// slave left 91 of 123 nodes under it open in 1 084 products, the soft block as slave none in 74.
/// Within 1 % the finer face, then `a`. Returns (slave, master, the reason in words).
fn choose_slave(mesh: &Mesh, e: &[f64], a: usize, b: usize, p: &crate::scene::ContactPair) -> (usize, usize, String) {
    let (fa, fb) = (&mesh.faces[a], &mesh.faces[b]);
    if !p.slave.is_empty() || !p.master.is_empty() {
        let a_is_slave = if p.slave.is_empty() { p.master == fb.name } else { p.slave == fa.name };
        let (s, m) = if a_is_slave { (a, b) } else { (b, a) };
        return (s, m, format!("slave {} as named", mesh.faces[s].name));
    }
    let ((ka, ha), (kb, hb)) = (stiffness_size(mesh, e, a), stiffness_size(mesh, e, b));
    let a_is_slave = if (ka - kb).abs() > 0.01 * ka.max(kb) { ka < kb } else { ha <= hb };
    let (s, m) = if a_is_slave { (a, b) } else { (b, a) };
    let (ks, km, hs, hm) = if a_is_slave { (ka, kb, ha, hb) } else { (kb, ka, hb, ha) };
    let (fs, fm) = (&mesh.faces[s], &mesh.faces[m]);
    let (softer, finer) = (e[fs.body] < e[fm.body], hs < hm);
    let side = match (softer, finer) {
        (true, true) => "the softer and finer side",
        (true, false) => "the softer side",
        (false, true) => "the finer side",
        (false, false) => "the first of `faces`",
    };
    (
        s,
        m,
        format!(
            "slave {} chosen by {SLAVE_RULE}: E·h {ks:.3e} (E {:.3e}, facets {hs:.3e}) against {km:.3e} (E {:.3e}, facets {hm:.3e}) of {}: {side}",
            fs.name, e[fs.body], e[fm.body], fm.name
        ),
    )
}

/// Whether pair `i`'s friction can carry a tangential force along t₁ and t₂: its slip bound
/// (Tresca g·w, orthotropic g₁·w and g₂·w) or, for Coulomb, its coefficient (μ, or μ₁ and μ₂)
/// is > 0.
fn tangential_hold(c: &Contact, i: usize) -> [bool; 2] {
    match (c.coulomb[i], c.bound[i]) {
        (Coefficient::Isotropic(mu), _) => [mu > 0.0; 2],
        (Coefficient::Orthotropic(a, b), _) => [a > 0.0, b > 0.0],
        (Coefficient::Fixed, SlipBound::None) => [false; 2],
        (Coefficient::Fixed, SlipBound::Disc(g)) => [g > 0.0; 2],
        (Coefficient::Fixed, SlipBound::Ellipse(a, b)) => [a > 0.0, b > 0.0],
    }
}

/// The bodies joined by ties (`links`: the bodies of each tie's two faces), as groups: each
/// ascending, the groups in the order of their first body; an untied body is a group of one.
fn tie_groups(bodies: usize, links: impl Iterator<Item = (usize, usize)>) -> Vec<Vec<usize>> {
    let mut root: Vec<usize> = (0..bodies).collect();
    fn find(root: &mut [usize], mut b: usize) -> usize {
        while root[b] != b {
            root[b] = root[root[b]];
            b = root[b];
        }
        b
    }
    for (a, b) in links {
        let (ra, rb) = (find(&mut root, a), find(&mut root, b));
        root[ra.max(rb)] = ra.min(rb);
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut at = vec![usize::MAX; bodies];
    for b in 0..bodies {
        let r = find(&mut root, b);
        if at[r] == usize::MAX {
            at[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[at[r]].push(b);
    }
    groups
}

/// The rigid motions of the bodies `group` (one body, or a tied group moving as one) that the
/// `rows` (node, direction) leave free, in words ([`rigid::free_modes`]).
fn free_motions(mesh: &Mesh, group: &[usize], rows: impl Iterator<Item = (usize, [f64; 3])>) -> Vec<String> {
    match rigid::free_modes(mesh, group, rows) {
        Some(modes) => modes.iter().map(rigid::describe).collect(),
        None => vec!["(eigen-decomposition failed)".into()],
    }
}

impl Model {
    /// What holds each tied group and each body held by contact alone, a line each for
    /// `check`: `bodies "w", "u" (tied): held by contact alone (pairs 0): translation along x, …`,
    /// or `… held by Dirichlet conditions on "lower"`.
    pub fn holding(&self) -> Vec<String> {
        let by_body = constraints_by_body(&self.mesh, &self.constraints);
        let mut groups: Vec<&Vec<usize>> = self.tied_groups.iter().chain(self.floating.iter().filter(|g| g.len() == 1)).collect();
        groups.sort();
        groups
            .into_iter()
            .map(|g| {
                let name = hold::group_name(&self.mesh, g);
                if self.floating.contains(g) {
                    let rows = g.iter().flat_map(|&b| by_body[b].iter()).map(|&(v, k, _)| {
                        let mut dir = [0.0; 3];
                        dir[k] = 1.0;
                        (v, dir)
                    });
                    let free = free_motions(&self.mesh, g, rows);
                    let pairs: Vec<String> = self
                        .contact
                        .iter()
                        .enumerate()
                        .filter(|(_, &(s, m))| g.contains(&self.mesh.faces[s].body) != g.contains(&self.mesh.faces[m].body))
                        .map(|(i, _)| i.to_string())
                        .collect();
                    let free = if free.len() == 6 { "all six rigid motions".to_string() } else { free.join(", ") };
                    format!("{name}: held by contact alone (pair {}) in {free}; solved by TFETI, Gλ = e kept by each Newton step (SMALSE-M where a step's pairs cannot hold it, or with decomposition.restricted = false)", pairs.join(", "))
                } else {
                    let held: Vec<String> = g.iter().filter(|&&b| !by_body[b].is_empty()).map(|&b| format!("\"{}\"", self.mesh.bodies[b].name)).collect();
                    format!("{name}: held by Dirichlet conditions on {}", held.join(", "))
                }
            })
            .collect()
    }
}

impl Model {
    /// Checks that contact and friction can hold the bodies held by contact alone
    /// ([`crate::contact::hold`]) at every load step, before anything is solved: a load they
    /// cannot hold at the first step is refused; at a later step k the path is cut to the steps
    /// before k ([`LoadPath::stopped`]: they are solved and written, and the run ends with the
    /// reason). The whole mesh and load vector must still be there (before TFETI releases them).
    pub fn check_held(&mut self) -> Result<()> {
        let Some(c) = self.pairs.as_ref().filter(|_| !self.floating.is_empty()) else { return Ok(()) };
        let by_body = constraints_by_body(&self.mesh, &self.constraints);
        let free: Vec<FreeBody> = self
            .floating
            .iter()
            .map(|group| {
                let rows = group.iter().flat_map(|&b| by_body[b].iter()).map(|&(v, k, _)| {
                    let mut dir = [0.0; 3];
                    dir[k] = 1.0;
                    (v, dir)
                });
                FreeBody { bodies: group.clone(), modes: rigid::free_modes(&self.mesh, group, rows).unwrap_or_default() }
            })
            .collect();
        for k in 1..=self.path.steps {
            let loads = if k == self.path.steps { std::borrow::Cow::Borrowed(&self.loads) } else { std::borrow::Cow::Owned(self.state(k).1) };
            if let Some(unheld) = hold::check(&self.mesh, c, &free, &loads)? {
                let e = unheld.error(&self.mesh, self.path.is_path().then_some((k, self.path.steps)));
                let Error::Numerical { what, reason } = &e else { return Err(e) };
                if k == 1 {
                    return Err(e);
                }
                let (constraints, loads) = self.state(k - 1);
                (self.constraints, self.loads) = (constraints, loads);
                self.path.stopped = Some(Stopped { at: k, of: self.path.steps, what: what.clone(), why: reason.clone() });
                self.path.steps = k - 1;
                return Ok(());
            }
        }
        Ok(())
    }
}
