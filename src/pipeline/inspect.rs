//! `tresca-feti mesh FILE`: what a mesh file offers a scene. Owns the listing of a file's
//! format, its volume cells, the volumes a body's `mesh.volume` accepts with the faces each such
//! body gets (`body.FACE`), and a starter scene. The names and the bodies come from the
//! readers' own `survey` (one parse, their `read_many`'s build), so the listing is what a scene gets.

use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::mesh::{abaqus, describe_cells, describe_facets, exodus, gmsh, med, BodyGeometry};
use crate::scene::{MeshDef, MeshFormat};

/// `--format`: `gmsh`, `abaqus`, `med` or `exodus` (the scene's `mesh.format` values).
pub fn parse_format(s: &str) -> std::result::Result<MeshFormat, String> {
    MeshFormat::deserialize(serde::de::value::StrDeserializer::<serde::de::value::Error>::new(s))
        .map_err(|_| format!("unknown mesh format \"{s}\" (known: abaqus, gmsh, med, exodus)"))
}

/// The scene's name of a format (`mesh.format`).
fn format_name(f: MeshFormat) -> &'static str {
    match f {
        MeshFormat::Abaqus => "abaqus",
        MeshFormat::Gmsh => "gmsh",
        MeshFormat::Med => "med",
        MeshFormat::Exodus => "exodus",
    }
}

/// The listing `tresca-feti mesh` prints for the mesh file `path` (`format`: `--format`, else
/// the one its extension names, as the scene's `mesh` key resolves it). A file that cannot be
/// read or parsed is the reader's error; a volume that cannot be a body is a line of the listing.
pub fn report(path: &Path, format: Option<MeshFormat>) -> Result<String> {
    let def = MeshDef { file: path.to_path_buf(), volume: None, format, translate: None };
    let file = path.display().to_string();
    let Some(fmt) = def.resolved_format() else {
        return Err(Error::mesh(
            &file,
            "unknown mesh format: the extension is none of .msh, .inp, .med, .exo, .e, .ex2; give --format (abaqus, gmsh, med, exodus)",
        ));
    };
    // the names and the bodies (every volume cell first, then each volume) from one parse
    let (volumes, bodies) = match fmt {
        MeshFormat::Abaqus => abaqus::survey(path)?,
        MeshFormat::Gmsh => gmsh::survey(path)?,
        MeshFormat::Med => med::survey(path)?,
        MeshFormat::Exodus => exodus::survey(path)?,
    };
    let mut bodies = bodies.into_iter();
    let whole = bodies.next().expect("the whole file asked for, read");

    let mut s = String::new();
    let how =
        if format.is_some() { "--format".to_string() } else { format!("from the extension .{}", path.extension().and_then(|e| e.to_str()).unwrap_or("")) };
    let _ = writeln!(s, "file: {file}");
    let _ = writeln!(s, "format: {} ({how})", format_name(fmt));
    match &whole {
        Ok(g) => {
            let _ = writeln!(s, "nodes: {} (of the volume cells)", g.nodes.len());
            let _ = writeln!(s, "cells: {}", describe_cells(&g.cells));
        }
        Err(e) => {
            let _ = writeln!(s, "cells: every volume cell together cannot be one body: {e}");
        }
    }
    if fmt == MeshFormat::Abaqus {
        let skipped = abaqus::skipped(path);
        if !skipped.is_empty() {
            let list: Vec<String> = skipped.iter().map(|(k, n)| format!("*{k} ({n})")).collect();
            let _ = writeln!(s, "abaqus: skipped keywords in {file}: {}", list.join(", "));
        }
    }
    let bodies: Vec<Result<BodyGeometry>> = bodies.collect();
    // (body name, volume, the earlier volume of the same cells) of the starter scene
    let mut starter: Vec<(String, Option<&str>, Option<&str>)> = Vec::new();
    if volumes.is_empty() {
        let _ = writeln!(s, "no named volumes: a body takes every volume cell (omit `volume`)");
        let name = body_name(path.file_stem().and_then(|n| n.to_str()).unwrap_or("body"), &starter);
        body_lines(&mut s, &name, &whole);
        starter.push((name, None, None));
    } else {
        let _ = writeln!(s, "volumes ({}; `mesh = {{ file, volume }}`), each with the faces a body of it gets (`BODY.FACE`):", volumes.len());
        for (k, (v, body)) in volumes.iter().zip(&bodies).enumerate() {
            let name = body_name(v, &starter);
            let same = bodies[..k].iter().position(|b| matches!((b, body), (Ok(a), Ok(b)) if a.cells == b.cells && a.nodes == b.nodes));
            let same = same.map(|j| volumes[j].as_str());
            let note = same.map_or(String::new(), |w| format!(" (the same cells as volume {})", toml::Value::String(w.into())));
            let _ = writeln!(s, "  volume {}{note}", toml::Value::String(v.clone()));
            body_lines(&mut s, &name, body);
            starter.push((name, Some(v), same));
        }
    }
    let _ = writeln!(s, "\nstarter scene (TOML; the file's path is relative to the scene file):");
    s += &starter_scene(&file, format.map(format_name), &starter);
    Ok(s)
}

/// The cells of body `name` and its faces by full name, or why it cannot be a body.
fn body_lines(s: &mut String, name: &str, body: &Result<BodyGeometry>) {
    match body {
        Ok(g) => {
            let _ = writeln!(s, "    cells: {}, {} nodes", describe_cells(&g.cells), g.nodes.len());
            if g.faces.is_empty() {
                let _ = writeln!(s, "    faces: none");
            }
            for (face, facets) in &g.faces {
                let _ = writeln!(s, "    face {name}.{face}: {}", describe_facets(facets));
            }
        }
        Err(e) => {
            let _ = writeln!(s, "    cannot be a body: {e}");
        }
    }
}

/// A body name for volume `v`: its name with each '.' (not allowed in body names) as '_', made
/// unique among the names `taken` by a numbered suffix.
fn body_name(v: &str, taken: &[(String, Option<&str>, Option<&str>)]) -> String {
    let base: String = if v.is_empty() { "body".into() } else { v.replace('.', "_") };
    let free = |n: &str| !taken.iter().any(|(t, _, _)| t == n);
    if free(&base) {
        return base;
    }
    (2..).map(|k| format!("{base}_{k}")).find(|n| free(n)).expect("some suffix is free")
}

/// One `[[body]]` per (name, volume), all of one placeholder material; a volume of the same
/// cells as an earlier one is commented out (two bodies would overlap).
fn starter_scene(file: &str, format: Option<&str>, bodies: &[(String, Option<&str>, Option<&str>)]) -> String {
    let q = |v: &str| toml::Value::String(v.into()).to_string();
    let mut s = format!("title = {}\n", q(&format!("from {file}")));
    s += "\n[[material]]\nname = \"material\"\nE = 210000.0  # Young's modulus, in the scene's units\nnu = 0.3\n";
    for (name, volume, same) in bodies {
        let mut mesh = format!("file = {}", q(file));
        if let Some(v) = volume {
            mesh += &format!(", volume = {}", q(v));
        }
        if let Some(f) = format {
            mesh += &format!(", format = {}", q(f));
        }
        let body = format!("[[body]]\nname = {}\nmaterial = \"material\"\nmesh = {{ {mesh} }}\n", q(name));
        match same {
            None => s += &format!("\n{body}"),
            Some(w) => {
                let _ = writeln!(s, "\n# the same cells as volume {}:", q(w));
                body.lines().for_each(|l| s += &format!("# {l}\n"));
            }
        }
    }
    s += "\n# then supports ([[dirichlet]] face = \"BODY.FACE\"), loads ([[traction]]) and [[contact.pair]]:\n# docs/scene-reference.md\n";
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn body_names_drop_dots_and_stay_unique() {
        let taken = vec![("upper_all".to_string(), None, None)];
        assert_eq!(body_name("upper.all", &taken), "upper_all_2");
        assert_eq!(body_name("lower", &taken), "lower");
        assert_eq!(body_name("", &[]), "body");
    }

    #[test]
    fn formats_parse_as_the_scene_names_them() {
        for f in [MeshFormat::Abaqus, MeshFormat::Gmsh, MeshFormat::Med, MeshFormat::Exodus] {
            assert_eq!(parse_format(format_name(f)), Ok(f));
        }
        assert!(parse_format("stl").unwrap_err().contains("stl"));
    }
}
