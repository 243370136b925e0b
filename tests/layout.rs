//! The crate's shape (docs/method.md, "Code layout"): the graph of its top-level modules, read from the `crate::…`
//! paths in the sources (comments and test modules left out), has no cycle, and the solver layer
//! `qp` is the floor: it uses nothing of the crate but `error` and `comm`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Every `.rs` file below `dir`.
fn sources(dir: &Path) -> Vec<std::path::PathBuf> {
    let (mut stack, mut files) = (vec![dir.to_path_buf()], Vec::new());
    while let Some(d) = stack.pop() {
        for p in std::fs::read_dir(&d).unwrap().flatten().map(|e| e.path()) {
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    files
}

/// Top-level module → the top-level modules its code names.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let modules: BTreeSet<String> = std::fs::read_dir(&src)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter_map(|p| {
            let stem = p.file_stem()?.to_string_lossy().into_owned();
            (p.is_dir() || p.extension().is_some_and(|x| x == "rs")).then_some(stem)
        })
        .filter(|m| m != "lib" && m != "main")
        .collect();
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    // a test module in a file of its own (`tests.rs`) is left out like one inline
    for p in sources(&src).into_iter().filter(|p| p.file_stem().is_some_and(|s| s != "tests")) {
        let rel = p.strip_prefix(&src).unwrap();
        let top = rel.components().next().unwrap().as_os_str().to_string_lossy().trim_end_matches(".rs").to_string();
        if !modules.contains(&top) {
            continue;
        }
        let text = std::fs::read_to_string(&p).unwrap();
        let code = text.split("#[cfg(test)]").next().unwrap();
        for line in code.lines().map(str::trim_start).filter(|l| !l.starts_with("//")) {
            for (i, _) in line.match_indices("crate::") {
                let name: String = line[i + 7..].chars().take_while(|c| c.is_ascii_lowercase() || *c == '_').collect();
                if modules.contains(&name) && name != top {
                    g.entry(top.clone()).or_default().insert(name);
                }
            }
        }
        g.entry(top).or_default();
    }
    g
}

#[test]
fn the_module_graph_has_no_cycle() {
    let g = graph();
    assert!(g.len() > 10, "found the modules: {g:?}");
    assert_acyclic(&g, "crate");
}

/// Panics naming the first import cycle of `g` (depth-first search with colours: 1 on the
/// stack, 2 done).
fn assert_acyclic(g: &BTreeMap<String, BTreeSet<String>>, what: &str) {
    fn visit(u: &str, g: &BTreeMap<String, BTreeSet<String>>, colour: &mut BTreeMap<String, u8>, path: &mut Vec<String>, what: &str) {
        colour.insert(u.to_string(), 1);
        path.push(u.to_string());
        for v in g.get(u).into_iter().flatten() {
            match colour.get(v) {
                Some(1) => panic!("import cycle in {what}: {} → {v}", path.join(" → ")),
                Some(_) => {}
                None => visit(v, g, colour, path, what),
            }
        }
        path.pop();
        colour.insert(u.to_string(), 2);
    }
    let mut colour = BTreeMap::new();
    for u in g.keys() {
        if !colour.contains_key(u) {
            visit(u, g, &mut colour, &mut vec![], what);
        }
    }
}

#[test]
fn the_solver_layer_is_the_floor() {
    let g = graph();
    let qp = &g["qp"];
    let allowed: BTreeSet<String> = ["error", "comm"].map(String::from).into();
    assert!(qp.is_subset(&allowed), "qp uses {qp:?}");
    // and the layers above it do use it
    for m in ["dual", "feti", "pipeline", "contact"] {
        assert!(g[m].contains("qp"), "{m} does not use qp: {:?}", g[m]);
    }
}

/// Inside the solver layer too: the graph of `qp`'s submodules, read from their `super::…` and
/// `crate::qp::…` paths (comments and test modules left out), has no cycle — shared code (the
/// Coulomb cone's coefficients and bounds, `qp::cone`) sits below the methods that use it.
#[test]
fn the_solver_layers_modules_have_no_cycle() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/qp");
    // a submodule is a file `qp/<name>.rs` or a folder `qp/<name>/` (its `mod.rs` and the files
    // beside it, all one node)
    let entries: Vec<_> =
        std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.path()).filter(|p| p.is_dir() || p.extension().is_some_and(|x| x == "rs")).collect();
    let names: BTreeSet<String> = entries.iter().map(|p| p.file_stem().unwrap().to_string_lossy().into_owned()).filter(|n| n != "mod").collect();
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for p in &entries {
        let me = p.file_stem().unwrap().to_string_lossy().into_owned();
        if me == "mod" {
            continue;
        }
        // (file, whether its `super::` is `qp`): a folder's `mod.rs` is, the files beside it not
        let files: Vec<(std::path::PathBuf, bool)> = match p.is_dir() {
            false => vec![(p.clone(), true)],
            true => sources(p)
                .into_iter()
                .filter(|f| f.file_stem().is_some_and(|s| s != "tests"))
                .map(|f| (f.clone(), f.file_stem().is_some_and(|s| s == "mod")))
                .collect(),
        };
        let uses = g.entry(me.clone()).or_default();
        for (f, super_is_qp) in files {
            let text = std::fs::read_to_string(&f).unwrap();
            let code = text.split("#[cfg(test)]").next().unwrap();
            for line in code.lines().map(str::trim_start).filter(|l| !l.starts_with("//")) {
                for pat in ["super::", "crate::qp::", "super::super::"] {
                    if (pat == "super::") != super_is_qp && pat != "crate::qp::" {
                        continue;
                    }
                    for (i, _) in line.match_indices(pat) {
                        let name: String = line[i + pat.len()..].chars().take_while(|c| c.is_ascii_lowercase() || *c == '_').collect();
                        if names.contains(&name) && name != me {
                            uses.insert(name);
                        }
                    }
                }
            }
        }
    }
    assert!(g.len() > 8 && g["ssn"].contains("cone") && g.contains_key("sets"), "read the graph: {g:?}");
    assert_acyclic(&g, "qp");
}

/// No source file over 1 200 lines (tests included).
#[test]
fn no_source_file_grows_past_1200_lines() {
    const LIMIT: usize = 1200;
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut over = Vec::new();
    for p in sources(&src) {
        let name = p.strip_prefix(&src).unwrap().to_string_lossy().replace('\\', "/");
        let lines = std::fs::read_to_string(&p).unwrap().lines().count();
        if lines > LIMIT {
            over.push(format!("{name}: {lines} lines (at most {LIMIT})"));
        }
    }
    assert!(over.is_empty(), "split these files: {over:?}");
}
