//! The documentation's examples run: every ```toml block of the README, the scene reference and
//! the tutorial goes through `check` (the model built, the plan priced), and the tutorial's
//! printed figures are what `check` and a 2-rank `solve` print.

mod common;

use std::path::Path;

use common::{mpirun, root, run, tmpdir};

/// The ```toml blocks of a document (repository-relative path), but those whose first line is
/// `# fragment`.
fn toml_blocks(doc: &str) -> Vec<String> {
    let text = std::fs::read_to_string(root().join(doc)).unwrap();
    text.split("```toml\n").skip(1).map(|b| b.split("```").next().unwrap_or_default().to_string()).filter(|b| !b.starts_with("# fragment")).collect()
}

/// The untyped ``` blocks (printed output) of `doc` after the heading that starts with
/// `heading`, up to the next heading.
fn printed_blocks(doc: &str, heading: &str) -> Vec<String> {
    let text = std::fs::read_to_string(root().join(doc)).unwrap();
    let start = text.find(heading).unwrap_or_else(|| panic!("{doc}: no heading {heading}"));
    let mut blocks = Vec::new();
    let mut open: Option<(bool, String)> = None;
    for line in text[start..].lines().skip(1) {
        if open.is_none() && line.starts_with("## ") {
            break;
        }
        match (open.take(), line.strip_prefix("```")) {
            (None, Some(lang)) => open = Some((lang.trim().is_empty(), String::new())),
            (None, None) => {}
            (Some((untyped, body)), Some(_)) => {
                if untyped {
                    blocks.push(body);
                }
            }
            (Some((untyped, body)), None) => open = Some((untyped, body + line + "\n")),
        }
    }
    blocks
}

/// A folder laid out like the repository (`run/` for the scene, `mesh/` beside it), as the
/// docs' mesh paths, relative to the scene file, expect.
fn scene_dir(name: &str) -> std::path::PathBuf {
    let dir = tmpdir(name);
    std::fs::create_dir_all(dir.join("run")).unwrap();
    let mesh = dir.join("mesh");
    if !mesh.exists() {
        std::os::unix::fs::symlink(root().join("mesh"), &mesh).unwrap();
    }
    dir
}

#[test]
fn every_toml_example_of_the_docs_passes_check() {
    let dir = scene_dir("docs-examples");
    let mut checked = 0;
    for doc in ["README.md", "docs/scene-reference.md", "docs/tutorial.md"] {
        let blocks = toml_blocks(doc);
        assert!(!blocks.is_empty(), "{doc}: no ```toml example");
        for (k, b) in blocks.iter().enumerate() {
            let scene = dir.join("run").join(format!("{}_{k}.toml", Path::new(doc).file_stem().unwrap().to_string_lossy()));
            std::fs::write(&scene, b).unwrap();
            let o = run(&["check", scene.to_str().unwrap()]);
            assert!(o.status.success(), "{doc}, ```toml block {k}: check refuses it: {}\n{b}", String::from_utf8_lossy(&o.stderr));
            checked += 1;
        }
    }
    assert!(checked >= 5, "only {checked} examples");
    // the tutorial's scene is the one in run/
    let tutorial = toml_blocks("docs/tutorial.md");
    let value = |t: &str| t.parse::<toml::Table>().unwrap();
    assert_eq!(
        value(&tutorial[0]),
        value(&std::fs::read_to_string(root().join("run/tutorial.toml")).unwrap()),
        "docs/tutorial.md and run/tutorial.toml differ"
    );
}

/// Each printed line of `doc` (but a lone `…`) is a line of `out`: whole, or up to its `…`; a
/// live line (`[  t s] …`) without its time stamp and the step's trailing time.
fn assert_printed(doc: &str, printed: &str, out: &str) {
    let strip = |l: &str| -> String {
        let l = l.trim_end();
        let l = if l.starts_with('[') { l.split_once("] ").map_or(l, |x| x.1) } else { l };
        match (l.starts_with("load step"), l.rfind(", ")) {
            (true, Some(i)) if l.ends_with(" s") => l[..i].to_string(),
            _ => l.to_string(),
        }
    };
    let lines: Vec<String> = out.lines().map(strip).collect();
    let mut n = 0;
    for want in printed.lines().map(strip).filter(|l| !l.trim().is_empty() && l.trim() != "…") {
        let found = match want.split_once('…') {
            Some((head, _)) => lines.iter().any(|l| l.starts_with(head.trim_end())),
            None => lines.contains(&want),
        };
        assert!(found, "{doc} prints\n  {want}\nbut the program prints:\n{out}");
        n += 1;
    }
    assert!(n > 3, "{doc}: only {n} printed lines compared");
}

#[test]
fn the_tutorials_printed_figures_are_what_the_program_prints() {
    let scene = root().join("run/tutorial.toml");
    let o = run(&["check", scene.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let check = printed_blocks("docs/tutorial.md", "## 4. Check the scene");
    assert_eq!(check.len(), 1, "one printed block under step 4");
    assert_printed("docs/tutorial.md, step 4", &check[0], &String::from_utf8_lossy(&o.stdout));
    // step 5: the live lines and the summary of `mpirun -n 2 … solve` (the times excepted)
    let out = tmpdir("docs-tutorial").join("tutorial.h5");
    let o = mpirun(2, &["solve", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let solve = printed_blocks("docs/tutorial.md", "## 5. Solve under MPI");
    assert_eq!(solve.len(), 2, "the live lines and the summary under step 5");
    assert_printed("docs/tutorial.md, step 5", &solve[0], &stdout);
    let summary: String = solve[1].lines().filter(|l| !l.starts_with("time [s]") && !l.starts_with("wrote ")).map(|l| format!("{l}\n")).collect();
    assert_printed("docs/tutorial.md, step 5 (summary)", &summary, &stdout);
}
