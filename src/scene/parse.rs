//! Reading a scene: the file, TOML errors on one line, `--set key=value` overrides, the
//! `[solver]` table and the rest by serde, then [`Scene::resolve`] and [`Scene::validate`].

use std::path::{Path, PathBuf};

use super::{Scene, SolverSettings};
use crate::error::{Error, Result};

/// A scene as loaded: the values plus where it came from.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The scene's values ([`load`] resolves and validates them).
    pub scene: Scene,
    /// The scene file.
    pub path: PathBuf,
}

impl LoadedScene {
    /// Directory that relative paths in the scene are resolved against.
    pub fn dir(&self) -> PathBuf {
        self.path.parent().map(Path::to_path_buf).unwrap_or_default()
    }

    /// The resolved HDF5 output path.
    pub fn output_path(&self) -> PathBuf {
        self.scene.output.path.clone().unwrap_or_else(|| {
            let stem = self.path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or("result".into());
            PathBuf::from("out").join(format!("{stem}.h5"))
        })
    }
}

/// Reads, overrides (`key=value` pairs), resolves and validates a scene file.
pub fn load(path: &Path, overrides: &[String]) -> Result<LoadedScene> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display().to_string(), e))?;
    let scene = parse(&text, &path.display().to_string(), overrides)?;
    Ok(LoadedScene { scene, path: path.to_path_buf() })
}

/// Parses scene text (`file` is only used in messages).
pub fn parse(text: &str, file: &str, overrides: &[String]) -> Result<Scene> {
    let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| Error::Parse { file: file.into(), msg: one_line_toml_error(text, &e) })?;
    for o in overrides {
        apply_override(&mut table, o)?;
    }
    let solver = match table.remove("solver") {
        None => SolverSettings::default(),
        Some(toml::Value::Table(t)) => SolverSettings::from_table(t)?,
        Some(_) => return Err(Error::scene("solver", "must be a table")),
    };
    let mut scene: Scene = serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
        let path = e.path().to_string();
        let msg = e.inner().message().replace('\n', " ");
        Error::Scene { key: if path == "." { file.into() } else { path }, msg }
    })?;
    scene.solver = solver;
    scene.resolve();
    scene.validate()?;
    Ok(scene)
}

fn one_line_toml_error(text: &str, e: &toml::de::Error) -> String {
    let msg = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.len() - before.rfind('\n').map_or(0, |p| p + 1) + 1;
            format!("line {line}, column {col}: {msg}")
        }
        None => msg,
    }
}

/// `a.b.0.c=value`: sets a (possibly new) key; numeric parts index arrays. The value is parsed as
/// TOML (`16`, `1e-8`, `"gimssn"`, `[0, 0, -1]`, `false`), and taken as a plain string otherwise.
pub fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<()> {
    let bad = |msg: &str| Error::scene(format!("--set {assignment}"), msg);
    let (key, raw) = assignment.split_once('=').ok_or_else(|| bad("expected key=value"))?;
    let key = key.trim();
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(bad("empty key component"));
    }
    let value = match format!("v = {}", raw.trim()).parse::<toml::Table>() {
        Ok(mut t) => t.remove("v").unwrap_or(toml::Value::String(raw.into())),
        Err(_) => toml::Value::String(raw.trim().into()),
    };
    let mut root = toml::Value::Table(std::mem::take(table));
    let result = set_path(&mut root, &parts, value).map_err(|m| bad(&m));
    if let toml::Value::Table(t) = root {
        *table = t;
    }
    result
}

fn set_path(root: &mut toml::Value, parts: &[&str], value: toml::Value) -> std::result::Result<(), String> {
    let mut cur = root;
    for (i, part) in parts.iter().enumerate() {
        let last = i + 1 == parts.len();
        let here = parts[..i].join(".");
        cur = match cur {
            toml::Value::Table(t) => {
                if last {
                    t.insert(part.to_string(), value);
                    return Ok(());
                }
                t.entry(part.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            toml::Value::Array(a) => {
                let idx: usize = part.parse().map_err(|_| format!("`{part}` is not an index of the array `{here}`"))?;
                let len = a.len();
                let slot = a.get_mut(idx).ok_or_else(|| format!("index {idx} out of range: `{here}` has {len} entries"))?;
                if last {
                    *slot = value;
                    return Ok(());
                }
                slot
            }
            _ => return Err(format!("`{here}` is not a table")),
        };
    }
    Ok(())
}
