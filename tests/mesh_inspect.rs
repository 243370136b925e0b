//! `tresca-feti mesh FILE`: the volumes and faces it lists are those a scene gets. For every
//! listed volume a scene of one body made of it goes through `tresca-feti check`, whose face
//! list (names and facets) must be the listing's, in both directions; the starter scene parses
//! as TOML and holds the listed volumes; a file without volumes, a missing and a malformed file;
//! the tutorial pastes the real listing.

mod common;

use std::path::Path;

use common::{root, run, tmpdir};

/// One listed volume (`None`: the file has none): its body name and faces, `(full name, facets)`.
struct Listed {
    volume: Option<String>,
    body: String,
    faces: Vec<(String, String)>,
    same_as_earlier: bool,
}

/// The listing of `tresca-feti mesh FILE`, its volumes and the starter scene's text.
fn listing(file: &Path, extra: &[&str]) -> (String, Vec<Listed>, String) {
    let mut args = vec!["mesh", file.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = run(&args);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    let (head, starter) = text.split_once("\nstarter scene").unwrap_or_else(|| panic!("no starter scene in\n{text}"));
    let starter = starter.split_once('\n').unwrap().1.to_string();
    let mut out: Vec<Listed> = Vec::new();
    if head.contains("no named volumes: a body takes every volume cell (omit `volume`)") {
        out.push(Listed { volume: None, body: String::new(), faces: Vec::new(), same_as_earlier: false });
    }
    for line in head.lines() {
        if let Some(rest) = line.strip_prefix("  volume ") {
            let (quoted, note) = rest.split_once(" (").map_or((rest, ""), |(q, n)| (q, n));
            let v: toml::Value = toml::from_str(&format!("v = {quoted}")).unwrap();
            let volume = v["v"].as_str().unwrap().to_string();
            out.push(Listed { volume: Some(volume), body: String::new(), faces: Vec::new(), same_as_earlier: note.starts_with("the same cells") });
        } else if let Some(rest) = line.strip_prefix("    face ") {
            let (name, facets) = rest.split_once(": ").unwrap();
            let last = out.last_mut().unwrap_or_else(|| panic!("a face before any volume in\n{text}"));
            last.body = name.split_once('.').unwrap().0.to_string();
            last.faces.push((name.to_string(), facets.to_string()));
        }
    }
    assert!(!out.is_empty(), "no volume listed in\n{text}");
    (text, out, starter)
}

/// `check`'s faces (name, facets) for a scene of one body `body` read from `file` (`volume`), held by its face `fixed`.
fn checked_faces(dir: &Path, k: usize, file: &Path, extra: &str, l: &Listed) -> Vec<(String, String)> {
    let q = |s: &str| toml::Value::String(s.into()).to_string();
    let volume = l.volume.as_deref().map_or(String::new(), |v| format!(", volume = {}", q(v)));
    let scene = format!(
        "[[material]]\nname = \"m\"\nE = 1000.0\nnu = 0.3\n\n[[body]]\nname = {}\nmaterial = \"m\"\nmesh = {{ file = {}{volume}{extra} }}\n\n[[dirichlet]]\nface = {}\n",
        q(&l.body),
        q(file.to_str().unwrap()),
        q(&l.faces[0].0)
    );
    let path = dir.join(format!("scene{k}.toml"));
    std::fs::write(&path, scene).unwrap();
    let o = run(&["check", path.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(o.status.success(), "check of volume {:?} of {}: {text}{}", l.volume, file.display(), String::from_utf8_lossy(&o.stderr));
    let section = text.split_once("\nfaces:\n").unwrap().1;
    section
        .lines()
        .take_while(|l| l.starts_with("  "))
        .map(|l| {
            let (name, rest) = l.trim().split_once(": ").unwrap();
            // "18 quadrilaterals, 28 nodes, area …": the facets part
            (name.to_string(), rest.split(", ").next().unwrap().to_string())
        })
        .collect()
}

/// The listing of `file` against `check`, volume by volume, and its starter scene.
fn agrees_with_check(name: &str, file: &Path, extra_args: &[&str], extra_key: &str) -> Vec<Listed> {
    let dir = tmpdir(name);
    let (text, listed, starter) = listing(file, extra_args);
    for (k, l) in listed.iter().enumerate() {
        assert!(!l.faces.is_empty(), "volume {:?} of {} lists no faces:\n{text}", l.volume, file.display());
        let checked = checked_faces(&dir, k, file, extra_key, l);
        assert_eq!(l.faces, checked, "volume {:?} of {}: the listing's faces against check's", l.volume, file.display());
    }
    // the starter scene: TOML, one body per listed volume not the same cells as an earlier one
    let scene: toml::Value = toml::from_str(&starter).unwrap_or_else(|e| panic!("starter scene of {}: {e}\n{starter}", file.display()));
    let bodies = scene["body"].as_array().unwrap();
    let wanted: Vec<Option<&str>> = listed.iter().filter(|l| !l.same_as_earlier).map(|l| l.volume.as_deref()).collect();
    let got: Vec<Option<&str>> = bodies.iter().map(|b| b["mesh"].get("volume").and_then(|v| v.as_str())).collect();
    assert_eq!(got, wanted, "{starter}");
    for b in bodies {
        assert_eq!(b["mesh"]["file"].as_str(), file.to_str(), "{starter}");
    }
    listed
}

#[test]
fn listed_volumes_and_faces_are_what_check_builds() {
    let volumes = |l: &[Listed]| l.iter().map(|l| l.volume.clone().unwrap()).collect::<Vec<_>>();
    for (f, expect) in [
        ("two_blocks.msh", vec!["upper", "lower"]),
        ("two_blocks.inp", vec!["Volume1", "Volume2", "upper", "lower"]),
        ("two_blocks.med", vec!["lower", "upper"]),
        ("two_blocks.exo", vec!["upper", "lower"]),
        ("two_blocks_classic.exo", vec!["upper", "lower"]),
        ("hex_pyr_tet.msh", vec!["upper", "lower"]),
    ] {
        let listed = agrees_with_check(f, &root().join("mesh").join(f), &[], "");
        assert_eq!(volumes(&listed), expect, "{f}");
    }
    // an assembly: instances and `instance.set`
    let listed = agrees_with_check("assembly", &root().join("mesh/two_blocks_assembly.inp"), &[], "");
    for v in ["upper", "lower", "upper.upper_all", "lower.lower_all"] {
        assert!(volumes(&listed).iter().any(|l| l == v), "{v} not listed");
    }
    // the Gmsh-written Abaqus file: "upper" is "Volume1"'s cells again
    let (text, listed, _) = listing(&root().join("mesh/two_blocks.inp"), &[]);
    assert!(listed[2].same_as_earlier && listed[3].same_as_earlier && !listed[0].same_as_earlier, "{text}");
}

#[test]
fn format_flag_skipped_keywords_and_a_file_without_volumes() {
    // a copy without an extension that names the format needs --format, as the scene needs `format`
    let dir = tmpdir("format");
    let copy = dir.join("blocks.txt");
    std::fs::copy(root().join("mesh/two_blocks_assembly.inp"), &copy).unwrap();
    let (text, ..) = listing(&copy, &["--format", "abaqus"]);
    assert!(text.contains("format: abaqus (--format)"), "{text}");
    assert!(text.lines().any(|l| l.starts_with("abaqus: skipped keywords in") && l.contains("*MATERIAL (2)")), "{text}");
    agrees_with_check("format-check", &copy, &["--format", "abaqus"], ", format = \"abaqus\"");
    let o = run(&["mesh", copy.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));

    // one C3D8 and no element set of volume elements; a set of S4R elements is its bottom face
    let cube = dir.join("cube.inp");
    let nodes: String = (0..8).map(|i| format!("{}, {}, {}, {}\n", i + 1, i & 1, (i >> 1) & 1, (i >> 2) & 1)).collect();
    std::fs::write(&cube, format!("*NODE\n{nodes}*ELEMENT, TYPE=C3D8\n1, 1, 2, 4, 3, 5, 6, 8, 7\n*ELEMENT, TYPE=S4R, ELSET=bottom\n2, 1, 3, 4, 2\n")).unwrap();
    let listed = agrees_with_check("no-volumes", &cube, &[], "");
    assert_eq!(listed.len(), 1);
    assert_eq!(listed[0].faces, vec![("cube.bottom".to_string(), "1 quadrilaterals".to_string())]);
}

#[test]
fn missing_and_malformed_files_are_one_line_errors() {
    let dir = tmpdir("errors");
    let bad = dir.join("bad.msh");
    std::fs::write(&bad, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2\n").unwrap();
    let missing = dir.join("missing.exo");
    for f in [&bad, &missing] {
        let o = run(&["mesh", f.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.starts_with("error: ") && stderr.contains(f.to_str().unwrap()), "{stderr}");
        assert!(o.stdout.is_empty());
    }
}

#[test]
fn the_tutorials_listing_is_what_the_program_prints() {
    let doc = std::fs::read_to_string(root().join("docs/tutorial.md")).unwrap();
    let command = "```sh\ntresca-feti mesh mesh/two_blocks.inp\n```\n\n```\n";
    let at = doc.find(command).expect("docs/tutorial.md shows `tresca-feti mesh mesh/two_blocks.inp`") + command.len();
    let printed = doc[at..].split("\n```").next().unwrap();
    let o = std::process::Command::new(common::BIN).args(["mesh", "mesh/two_blocks.inp"]).current_dir(root()).output().unwrap();
    assert!(o.status.success());
    assert_eq!(printed.trim_end(), String::from_utf8_lossy(&o.stdout).trim_end(), "docs/tutorial.md's listing is not what the program prints");
}
