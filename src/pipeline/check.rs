//! What `solve` and `check` share before solving ([`prepare`]: the scene read and its output
//! guarded, the model built, the decomposition planned, the dual and the method resolved, and
//! every refusal), so that `check` refuses what `solve` refuses; and `check`'s text
//! ([`run_check`]).

use std::fmt::Write;
use std::path::{Path, PathBuf};

use super::forecast::Network;
use super::memory::{self, MeshCount};
use super::{body_dofs, monitor, pair_notes, plan, preconditioner, report, resolve_method, DualKind, Timings};
use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::fem::assembly::DofMap;
use crate::model::{self, Model};
use crate::output;
use crate::scene::LoadedScene;

/// A scene ready to solve: read and checked, its model built, its decomposition planned.
pub struct Prepared {
    /// The scene with the plan's decomposition and the resolved method.
    pub ls: LoadedScene,
    /// The model built from the scene.
    pub model: Model,
    /// The plan's priced candidates (`None`: the scene set the decomposition).
    pub plan: Option<Vec<plan::Candidate>>,
    /// Solved on the TFETI dual (else the monolithic one).
    pub tfeti: bool,
}

/// Phases `scene`, `mesh` and `plan` of `solve` and all of `check` but its text: reads the
/// scene (with the output path `out` of `--out`), refuses a result that would overwrite an input
/// or another result and a mesh that does not fit in memory, builds the model, plans the
/// decomposition for `ranks` ranks, resolves the method, and refuses what no solve of this
/// dual can do (a preconditioner the method cannot use, an export of another dual, a load path
/// without contact). The memory estimate with the plan's factors is the caller's
/// ([`memory::check_after_plan`] in `solve`; `check` prints it for `--ranks`).
pub fn prepare<C: Comm>(comm: &C, scene_path: &Path, overrides: &[String], out: Option<PathBuf>, ranks: usize, t: &mut Timings) -> Result<Prepared> {
    let out_key = if out.is_some() { "--out" } else { "output.path" };
    let ls = t.phase(comm, "scene", || {
        let mut ls = crate::scene::load(scene_path, overrides)?;
        if let Some(o) = out {
            ls.scene.output.path = Some(o);
        }
        // no result may overwrite an input or another result: refused before any work
        output::guard::check(&ls, out_key)?;
        Ok(ls)
    })?;
    let mut parts = Vec::new();
    let model = t.phase_with(comm, "mesh", Some(monitor::Unit::Bytes), |p| {
        memory::check_before_mesh(comm, &ls).and_then(|()| model::build_timed(&ls, &mut parts, &|done, total| p.set(done, total))).and_then(|mut m| {
            let clock = std::time::Instant::now();
            let held = m.check_held();
            parts.push(("hold check", clock.elapsed().as_secs_f64()));
            held.map(|()| m)
        })
    })?;
    t.split(comm, "mesh", &parts);
    let mut ls = ls;
    held_by_contact(&mut ls.scene.decomposition, &model);
    let common = ls.scene.solver.params.common.clone();
    let mut split = Vec::new();
    let plan = t
        .phase(comm, "plan", || plan::resolve_timed(comm, &model, &mut ls.scene.decomposition, &common, ranks, &mut split))
        .map_err(|e| memory::name_the_mesh(&ls, e))?;
    t.split(comm, "plan", &split);
    let kind = DualKind::of(&ls, &model);
    resolve_method(&mut ls.scene.solver, kind);
    let tfeti = ls.scene.decomposition.is_tfeti(&body_dofs(&model));
    preconditioner(ls.scene.solver.params.method(), ls.scene.solver.preconditioner, DualKind::of(&ls, &model))?;
    refusals_after_plan(&ls, &model, tfeti)?;
    Ok(Prepared { ls, model, plan, tfeti })
}

/// What `solve` refuses once the plan has chosen the dual (`tfeti`), and `check` with it: an
/// export of the monolithic dual on a TFETI scene, an FCLIB export without a Coulomb pair, a
/// load path without contact.
fn refusals_after_plan(ls: &LoadedScene, model: &Model, tfeti: bool) -> Result<()> {
    for (key, set) in [("output.export_dual", ls.scene.output.export_dual.is_some()), ("output.export_fclib", ls.scene.output.export_fclib.is_some())] {
        if !set {
            continue;
        }
        let why = if tfeti {
            Some("exports the monolithic dual; this scene is solved by TFETI (set decomposition.subdomains = 1)")
        } else if !model.pairs.as_ref().is_some_and(|c| c.is_coulomb()) {
            Some("exports a Coulomb problem; the scene has no Coulomb pair")
        } else {
            None
        };
        if let Some(why) = why {
            return Err(Error::scene(key, why));
        }
    }
    if model.pairs.is_none() && model.path.is_path() {
        return Err(Error::scene("load.steps", "a load path needs contact (without it the response is linear in the load: solve the last state)"));
    }
    Ok(())
}

/// A scene with a body held by contact alone ([`Model::floating`]) is solved by TFETI with the
/// orthogonal projector (SMALSE-M: Gλ = e over every row; C = G_E G_Eᵀ is singular there),
/// whatever `[decomposition]` says about the dual and the projector.
pub fn held_by_contact(dec: &mut crate::scene::DecompositionSettings, model: &Model) {
    if !model.floating.is_empty() {
        dec.tfeti = true;
        dec.projector = crate::scene::Projector::Orthogonal;
    }
}

/// `tresca-feti check`: everything `solve` does before solving ([`prepare`], for `ranks` ranks),
/// and the text to print: the resolved scene, the bodies, faces, loads and contact pairs, the
/// subdomains, the plan's table and the memory estimate; with `forecast` (hosts, the network
/// model and its file) the scaling forecast of the chosen decomposition after the plan's table.
pub fn run_check<C: Comm>(comm: &C, scene_path: &Path, overrides: &[String], ranks: usize, forecast: Option<(usize, &Network, &str)>) -> Result<String> {
    let Prepared { ls, model, plan, tfeti } = prepare(comm, scene_path, overrides, None, ranks, &mut Timings::live(false))?;
    let chosen = plan.as_deref().and_then(plan::cheapest);
    let needs = memory::after_plan(&MeshCount::of_model(&ls, &model), &model, &ls.scene.decomposition, chosen, ranks, ls.scene.solver.precision);
    let units = report::UnitsReport::of(&ls.scene.units);
    let unit = |which| report::UnitsReport::suffix(units.as_ref(), which);
    let u = Units { length: unit(0), force: unit(1), stress: unit(2), area: unit(3) };
    let mut s = String::new();
    let _ = writeln!(s, "# resolved scene {}\n{}", ls.path.display(), ls.scene.to_toml());
    skipped_keywords(&mut s, &ls);
    let free = bodies(&mut s, &model);
    faces(&mut s, &model, &u);
    tractions(&mut s, &ls, &model, &u);
    let load: [f64; 3] = std::array::from_fn(|c| model.loads.iter().skip(c).step_by(3).sum());
    if let Some(stop) = &model.path.stopped {
        let _ = writeln!(s, "warning: load path {}; solve writes steps 1–{} and exits with this reason", stop.describe(), stop.at - 1);
    }
    let _ = writeln!(s, "total applied load: ({:.6e}, {:.6e}, {:.6e}){}", load[0], load[1], load[2], u.force);
    let _ = writeln!(s, "DOFs: n = {} ({} free after Dirichlet elimination)", model.ndof(), free);
    contact(&mut s, &ls, &model, &u);
    if !model.ties.is_empty() {
        let _ = writeln!(s, "ties: {} mortar rows × 3 directions (equality multipliers of the TFETI dual)", model.ties.len());
    }
    for line in model.holding() {
        let _ = writeln!(s, "{line}");
    }
    if tfeti {
        subdomains(&mut s, &ls, &model)?;
    }
    if plan.is_some() || forecast.is_some() {
        let _ = writeln!(s, "{}", super::rates::current().line);
    }
    if let Some(p) = &plan {
        let _ = write!(s, "{}", plan::table(p, ranks));
    }
    if let Some((hosts, net, file)) = forecast {
        // the plan's choice, or the priced candidate of the subdomains the scene sets
        let priced;
        let c = match chosen {
            Some(c) => c,
            None => {
                let dec = &ls.scene.decomposition;
                let open = crate::scene::DecompositionSettings { subdomains: None, target_dofs: None, ..dec.clone() };
                priced = plan::price(comm, &model, &open, &ls.scene.solver.params.common, ranks)?;
                let parts: Vec<usize> = model.mesh.bodies.iter().map(|_| dec.subdomains.unwrap_or(0)).collect();
                priced.iter().find(|c| c.parts == parts && c.tfeti == tfeti).ok_or_else(|| {
                    Error::scene(
                        "--hosts",
                        "the forecast prices the plan's candidates; this scene's [decomposition] is not one of them (leave subdomains and target_dofs unset)",
                    )
                })?
            }
        };
        let _ = write!(s, "{}", super::forecast::table(c, ranks, model.ndof(), ranks, hosts, net, file));
    }
    let _ = write!(s, "{}", memory::summary(&needs, ranks)?);
    let _ = write!(s, "dual: {}", if tfeti { "TFETI" } else { "monolithic" });
    Ok(s)
}

/// One line per Abaqus input file of the scene: the keywords its reader skipped (they do not
/// describe the mesh), with their counts.
fn skipped_keywords(s: &mut String, ls: &LoadedScene) {
    let mut seen = Vec::new();
    for b in &ls.scene.bodies {
        let Some((_, g)) = b.mesh_file().filter(|(_, g)| g.resolved_format() == Some(crate::scene::MeshFormat::Abaqus)) else { continue };
        let path = ls.dir().join(&g.file);
        if seen.contains(&path) {
            continue;
        }
        let skipped = crate::mesh::abaqus::skipped(&path);
        if !skipped.is_empty() {
            let list: Vec<String> = skipped.iter().map(|(k, n)| format!("*{k} ({n})")).collect();
            let _ = writeln!(s, "abaqus: skipped keywords in {}: {}", g.file.display(), list.join(", "));
        }
        seen.push(path);
    }
}

/// The unit suffixes of the scene's `[units]` (empty without).
struct Units {
    length: String,
    force: String,
    stress: String,
    area: String,
}

/// One line per body (nodes, elements, DOFs free and held); returns the free DOFs of all.
fn bodies(s: &mut String, model: &Model) -> usize {
    let mesh = &model.mesh;
    let _ = writeln!(s, "mesh: {} bodies, {} nodes, {}", mesh.bodies.len(), mesh.nodes.len(), crate::mesh::describe_cells(&mesh.cells));
    let mut free_total = 0;
    let by_body = model::constraints_by_body(mesh, &model.constraints);
    for (body, cons) in mesh.bodies.iter().zip(&by_body) {
        let dofs = DofMap::new(body.nodes.clone(), cons);
        free_total += dofs.nfree;
        let _ = writeln!(
            s,
            "  body {}: {} nodes, {} elements, {} DOFs ({} free, {} Dirichlet)",
            body.name,
            body.nodes.len(),
            body.elems.len(),
            3 * body.nodes.len(),
            dofs.nfree,
            3 * body.nodes.len() - dofs.nfree
        );
    }
    free_total
}

/// One line per face: its facets, nodes and area, and the region it was cut from.
fn faces(s: &mut String, model: &Model, u: &Units) {
    let (mesh, area) = (&model.mesh, &u.area);
    let _ = writeln!(s, "faces:");
    for (k, f) in mesh.faces.iter().enumerate() {
        let a = crate::fem::cell::face_area(f, &mesh.nodes);
        let cut = model.cut_faces.iter().find(|c| c.face == k).map_or(String::new(), |c| {
            format!(
                " (cut from {} by {}: the facets whose centres lie in it; the region covers {:.6e}{area} of {}, {:+.1} %)",
                mesh.faces[c.from].name,
                c.region,
                c.region_area,
                mesh.faces[c.from].name,
                100.0 * (a / c.region_area - 1.0)
            )
        });
        let _ = writeln!(s, "  {}: {}, {} nodes, area {a:.6e}{area}{cut}", f.name, crate::mesh::describe_facets(&f.facets), f.nodes().len());
    }
}

/// One line per traction: its load, area and resultant, and the warning where the face's
/// facets do not cover the region it was cut by.
fn tractions(s: &mut String, ls: &LoadedScene, model: &Model, u: &Units) {
    let (mesh, area, force, stress) = (&model.mesh, &u.area, &u.force, &u.stress);
    for (i, t) in ls.scene.traction.iter().enumerate() {
        let r = model.path.traction_resultant(i);
        let a = mesh.face(&t.face).map_or(f64::NAN, |f| crate::fem::cell::face_area(f, &mesh.nodes));
        let load = match (t.p, t.pressure) {
            (_, Some(p)) => format!("pressure {p}{stress}"),
            (p, None) => {
                let p = p.unwrap_or_default();
                format!("p = ({}, {}, {}){stress}", p[0], p[1], p[2])
            }
        };
        let _ =
            writeln!(s, "traction[{i}] on {}: {load} over area {a:.6e}{area}, resultant ({:.6e}, {:.6e}, {:.6e}){force} at factor 1", t.face, r[0], r[1], r[2]);
        if let Some(c) = mesh.faces.iter().position(|f| f.name == t.face).and_then(|k| model.cut_faces.iter().find(|c| c.face == k)) {
            if (a / c.region_area - 1.0).abs() > crate::model::CUT_AREA_TOLERANCE {
                let _ = writeln!(
                    s,
                    "warning: traction[{i}] on {}: the face's facets cover {a:.6e}{area}, its region {:.6e}{area} of {} ({:+.1} %); the load is the traction over the facets: refine the mesh where the region's edge cuts the face, or make the face a surface of the mesh",
                    t.face,
                    c.region_area,
                    mesh.faces[c.from].name,
                    100.0 * (a / c.region_area - 1.0)
                );
            }
        }
    }
}

/// One line per contact pair (its faces, the slave choice, the notes), and the contact summary.
fn contact(s: &mut String, ls: &LoadedScene, model: &Model, u: &Units) {
    let (mesh, area, length) = (&model.mesh, &u.area, &u.length);
    for (i, &(sl, ma)) in model.contact.iter().enumerate() {
        let _ = writeln!(
            s,
            "contact pair {i}: slave {} ({} nodes) against master {} ({} nodes){}",
            mesh.faces[sl].name,
            mesh.faces[sl].nodes().len(),
            mesh.faces[ma].name,
            mesh.faces[ma].nodes().len(),
            if ls.scene.contact.enabled { "" } else { " — disabled" }
        );
        if let Some((_, why)) = model.slave_choice.iter().find(|c| c.0 == i) {
            let _ = writeln!(s, "{}{why}", if why.starts_with("warning") { "" } else { "  " });
        }
        for line in model.pairs.as_ref().map_or_else(Vec::new, |c| pair_notes(c, i, length)) {
            let _ = writeln!(s, "{line}");
        }
    }
    if let Some(c) = &model.pairs {
        let (gmin, gmax) = c.gap.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &g| (a.min(g), b.max(g)));
        let tangential = if c.has_friction() { 2 * c.len() } else { 0 };
        let _ = writeln!(
            s,
            "contact: m = {} pairs ({}), Σw = {:.6e}{area}, gaps in [{gmin:.3e}, {gmax:.3e}]{length}, multipliers: {} normal + {} tangential ({} void: held by Dirichlet conditions)",
            c.len(),
            c.discretization.iter().map(|d| format!("{d:?}").to_lowercase().replace("nodetonode", "node-to-node")).collect::<Vec<_>>().join(", "),
            c.area.iter().sum::<f64>(),
            c.len(),
            tangential,
            c.void.iter().flatten().filter(|&&v| v).count()
        );
    }
}

/// The TFETI decomposition: subdomains per body, and one line per subdomain.
fn subdomains(s: &mut String, ls: &LoadedScene, model: &Model) -> Result<()> {
    let (mesh, dec) = (&model.mesh, &ls.scene.decomposition);
    let parts: Vec<usize> = mesh.bodies.iter().map(|b| dec.parts(3 * b.nodes.len())).collect();
    let fresh;
    let d = match model.partition.get() {
        Some((p, d)) if *p == parts => d,
        _ => {
            fresh = crate::feti::decomposition::decompose_each(mesh, &parts)?;
            &fresh
        }
    };
    let _ = writeln!(
        s,
        "TFETI: {} subdomains ({} per body), {} interface nodes",
        d.subdomains.len(),
        parts.iter().map(|p| p.to_string()).collect::<Vec<_>>().join(", "),
        d.interface_nodes()
    );
    for (i, sd) in d.subdomains.iter().enumerate() {
        let iface = sd.nodes.iter().filter(|&&v| d.copies[v].len() > 1).count();
        let _ = writeln!(
            s,
            "  subdomain {i} (body {}): {} elements, {} nodes, {} DOFs, {iface} interface nodes",
            mesh.bodies[sd.body].name,
            sd.elems.len(),
            sd.nodes.len(),
            3 * sd.nodes.len()
        );
    }
    Ok(())
}
