//! docs/scene-reference.md against the scene parser: the reference's key column holds exactly the
//! keys the parser accepts (`tresca_feti::scene::keys::keys`, read from the parser's own serde
//! definitions), and every row of an enumerated key names each of its values.

use std::collections::BTreeSet;

use tresca_feti::scene::keys::{keys, Key};

/// The reference's rows: (key, the whole row), from table rows whose first cell is `` `a.b` ``.
fn rows(text: &str) -> Vec<(String, String)> {
    text.lines()
        .filter_map(|l| {
            let cell = l.strip_prefix("| `")?;
            let (key, _) = cell.split_once('`')?;
            Some((key.to_string(), l.to_string()))
        })
        .collect()
}

fn reference() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scene-reference.md");
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn listing(keys: &[Key]) -> String {
    keys.iter()
        .map(|k| {
            let v = if k.values.is_empty() { String::new() } else { format!("  values: {}", k.values.join(", ")) };
            let m = if k.methods.is_empty() { String::new() } else { format!("  methods: {}", k.methods.join(", ")) };
            format!("{}{v}{m}", k.path)
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn every_key_of_the_parser_is_documented_and_no_other() {
    let keys = keys();
    if std::env::var_os("TRESCA_PRINT_KEYS").is_some() {
        println!("{}", listing(&keys));
    }
    let text = reference();
    let doc_rows = rows(&text);
    let documented: BTreeSet<&str> = doc_rows.iter().map(|(k, _)| k.as_str()).collect();
    assert_eq!(documented.len(), doc_rows.len(), "a key has two rows in docs/scene-reference.md");
    let parsed: BTreeSet<&str> = keys.iter().map(|k| k.path.as_str()).collect();
    let undocumented: Vec<&str> = parsed.difference(&documented).copied().collect();
    let unknown: Vec<&str> = documented.difference(&parsed).copied().collect();
    assert!(
        undocumented.is_empty() && unknown.is_empty(),
        "docs/scene-reference.md and the scene parser disagree:\n  accepted by the parser, not documented: {undocumented:?}\n  documented, not accepted by the parser: {unknown:?}\n(TRESCA_PRINT_KEYS=1 cargo test --release --test scene_reference -- --nocapture lists the parser's keys)"
    );
    // an enumerated key's row names every value the parser takes, each in backticks
    for k in &keys {
        let (_, row) = doc_rows.iter().find(|(p, _)| *p == k.path).expect("checked above");
        for v in &k.values {
            assert!(row.contains(&format!("`{v}`")), "docs/scene-reference.md, `{}`: the value `{v}` is not named", k.path);
        }
        for m in &k.methods {
            assert!(row.contains(m.as_str()), "docs/scene-reference.md, `{}`: read by method {m}, which the row does not name", k.path);
        }
    }
}

#[test]
fn the_reference_examples_parse() {
    // every ```toml block of the reference is a whole scene or a fragment appended to a minimal one
    let minimal =
        "[[material]]\nname = \"m\"\nE = 1.0\nnu = 0.3\n[[body]]\nname = \"b\"\nmaterial = \"m\"\nbox = { min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }\n";
    let text = reference();
    let mut blocks = text.split("```toml\n").skip(1).map(|b| b.split("```").next().unwrap_or_default()).peekable();
    assert!(blocks.peek().is_some(), "no ```toml example in docs/scene-reference.md");
    for b in blocks {
        let scene = if b.contains("[[body]]") { b.to_string() } else { format!("{minimal}{b}") };
        if let Err(e) = tresca_feti::scene::parse(&scene, "docs/scene-reference.md", &[]) {
            panic!("an example of docs/scene-reference.md does not parse: {e}\n{b}");
        }
    }
}

/// One piece of slave advice everywhere: the rule's own words (`model::SLAVE_RULE`, which
/// `check` prints with its choice) in the tutorial and at both keys of the reference, and no
/// other advice beside it.
#[test]
fn the_docs_give_the_slave_rule() {
    let rule = tresca_feti::model::SLAVE_RULE;
    let flat = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    let tutorial = flat(&std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/tutorial.md")).unwrap());
    assert!(tutorial.contains(rule), "docs/tutorial.md does not state the slave rule \"{rule}\"");
    let reference = reference();
    for key in ["contact.pair.slave", "contact.pair.faces"] {
        let (_, row) = rows(&reference).into_iter().find(|(k, _)| k == key).unwrap_or_else(|| panic!("no row for {key}"));
        assert!(row.contains(rule), "{key}: {row}");
    }
    for doc in [&tutorial, &flat(&reference)] {
        for other in ["take the finer side", "take the softer side", "take the stiffer side", "take the coarser side"] {
            assert!(!doc.to_lowercase().contains(other), "advice beside the rule: {other}");
        }
    }
}

/// Every `docs/troubleshooting.md#…` anchor an error names (each kind's section) or a doc
/// links to is a heading of that page (GitHub's slug: lower case, spaces to hyphens, other
/// punctuation dropped).
#[test]
fn the_troubleshooting_anchors_errors_name_exist() {
    use tresca_feti::Error;
    let root = env!("CARGO_MANIFEST_DIR");
    let page = std::fs::read_to_string(format!("{root}/docs/troubleshooting.md")).unwrap();
    let slug = |h: &str| h.trim().to_lowercase().chars().filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-').collect::<String>().replace(' ', "-");
    let headings: BTreeSet<String> = page.lines().filter_map(|l| l.strip_prefix('#')).map(|h| slug(h.trim_start_matches('#'))).collect();
    let errors = [
        Error::scene("k", "m"),
        Error::mesh("f", "m"),
        Error::io("p", std::io::Error::other("x")),
        Error::numerical("w", "r"),
        Error::output("p", "m"),
        Error::memory("w", "m"),
    ];
    let mut anchors: BTreeSet<String> = errors.iter().filter_map(|e| e.docs_section()).map(str::to_string).collect();
    for dir in ["src", "docs"] {
        let mut stack = vec![std::path::PathBuf::from(format!("{root}/{dir}"))];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap().flatten() {
                let p = e.path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|x| x == "rs" || x == "md") {
                    let text = std::fs::read_to_string(&p).unwrap();
                    for part in text.split("troubleshooting.md#").skip(1) {
                        // `#{s}` in a format string is the section of docs_section, checked above
                        let a: String = part.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '-').collect();
                        if !a.is_empty() {
                            anchors.insert(a);
                        }
                    }
                }
            }
        }
    }
    assert!(anchors.len() >= 6, "{anchors:?}");
    for a in &anchors {
        assert!(headings.contains(a), "docs/troubleshooting.md has no heading for #{a} (headings: {headings:?})");
    }
}
