//! Which paths a run may write. Owns the check, made before anything is computed, that no
//! result path — the HDF5 file, its XDMF and JSON sidecars, the exports (`output.export_dual`,
//! `output.export_fclib`) — is an input
//! of the run (the scene file, a mesh a body reads) or another result, and that each result
//! path is new or a regular file (not a directory, FIFO, device or socket).
//!
//! Two paths are the same file when their canonical forms are equal (for a path that does not
//! exist yet: its nearest existing folder canonicalized, the rest appended) or when both
//! exist with the same device and inode (hard links).

use std::os::unix::fs::{FileTypeExt, MetadataExt};
use std::path::{Component, Path, PathBuf};

use super::sibling;
use crate::error::{Error, Result};
use crate::scene::LoadedScene;

/// One path the run reads or writes, with the scene key that chose it and what it is.
#[derive(Clone, Debug)]
pub struct Named {
    /// The scene key (or option) naming the path, for the message.
    pub key: String,
    /// What the file is, e.g. "the XDMF sidecar".
    pub what: String,
    pub path: PathBuf,
}

impl Named {
    fn new(key: &str, what: &str, path: PathBuf) -> Self {
        Named { key: key.into(), what: what.into(), path }
    }
}

/// The result files of a solve of `ls`: the HDF5 file (chosen by `out_key`: `--out` or
/// `output.path`), its sidecars as the scene asks for them, and the exports.
pub fn results(ls: &LoadedScene, out_key: &str) -> Vec<Named> {
    let h5 = ls.output_path();
    let o = &ls.scene.output;
    let mut r = vec![Named::new(out_key, "the result file", h5.clone())];
    if o.xdmf {
        r.push(Named::new(out_key, "its XDMF sidecar", sibling(&h5, "xdmf")));
    }
    if o.report {
        r.push(Named::new(out_key, "its JSON report", sibling(&h5, "json")));
    }
    if let Some(p) = &o.export_dual {
        r.push(Named::new("output.export_dual", "the dual export", p.clone()));
    }
    if let Some(p) = &o.export_fclib {
        r.push(Named::new("output.export_fclib", "the FCLIB export", p.clone()));
    }
    r
}

/// The files a solve of `ls` reads: the scene and every body's mesh file (relative to the
/// scene's folder), with the files an Abaqus input includes.
pub fn inputs(ls: &LoadedScene) -> Vec<Named> {
    let mut r = vec![Named::new("scene", "the scene file", ls.path.clone())];
    for (i, b) in ls.scene.bodies.iter().enumerate() {
        if let Some((key, g)) = b.mesh_file() {
            let path = ls.dir().join(&g.file);
            r.push(Named::new(&format!("body[{i}].{key}.file"), &format!("the mesh of body[{i}]"), path.clone()));
            if g.resolved_format() == Some(crate::scene::MeshFormat::Abaqus) {
                for inc in crate::mesh::abaqus::files(&path).into_iter().skip(1) {
                    r.push(Named::new(&format!("body[{i}].{key}.file"), &format!("a file the mesh of body[{i}] includes"), inc));
                }
            }
        }
    }
    r
}

/// Refuses (naming both paths) a result that would overwrite an input or another result, and
/// a result path that exists and is not a regular file.
pub fn check(ls: &LoadedScene, out_key: &str) -> Result<()> {
    check_paths(&inputs(ls), &results(ls, out_key))
}

/// [`check`] on explicit lists.
pub fn check_paths(inputs: &[Named], results: &[Named]) -> Result<()> {
    for r in results {
        regular_or_new(r)?;
    }
    let ids: Vec<Identity> = results.iter().map(|r| Identity::of(&r.path)).collect();
    for input in inputs {
        let id = Identity::of(&input.path);
        if let Some(r) = results.iter().zip(&ids).find_map(|(r, rid)| id.same(rid).then_some(r)) {
            return Err(Error::scene(
                &r.key,
                format!("{} {} would overwrite {} {}; choose another path", r.what, r.path.display(), input.what, input.path.display()),
            ));
        }
    }
    // a result must not be another result
    for (j, b) in results.iter().enumerate() {
        if let Some(a) = (0..j).find(|&i| ids[i].same(&ids[j])).map(|i| &results[i]) {
            return Err(Error::scene(
                &b.key,
                format!("{} {} is also {} {} ({}); give each result its own path", b.what, b.path.display(), a.what, a.path.display(), a.key),
            ));
        }
    }
    Ok(())
}

/// A result path must be new or a regular file: renaming onto a directory fails late, and a
/// FIFO, device or socket would be replaced (as root, `/dev/null` by a regular file).
fn regular_or_new(r: &Named) -> Result<()> {
    let Ok(meta) = std::fs::metadata(&r.path) else { return Ok(()) };
    let t = meta.file_type();
    let kind = if t.is_file() {
        return Ok(());
    } else if t.is_dir() {
        "a directory"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    };
    Err(Error::scene(&r.key, format!("{} {} exists and is {kind}; give a new path or a regular file", r.what, r.path.display())))
}

/// What makes two paths the same file.
#[derive(Clone, Debug)]
struct Identity {
    canonical: PathBuf,
    /// Device and inode of an existing file.
    inode: Option<(u64, u64)>,
}

impl Identity {
    fn of(p: &Path) -> Self {
        let inode = std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()));
        Identity { canonical: canonical(p), inode }
    }

    fn same(&self, other: &Identity) -> bool {
        self.canonical == other.canonical || (self.inode.is_some() && self.inode == other.inode)
    }
}

/// The canonical form of `p`, which need not exist: its nearest existing ancestor
/// canonicalized, the components below it appended (`.` dropped, `..` taken lexically).
fn canonical(p: &Path) -> PathBuf {
    if let Ok(c) = std::fs::canonicalize(p) {
        return c;
    }
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut rest = Vec::new();
    let mut base = abs.as_path();
    let mut root = loop {
        match std::fs::canonicalize(base) {
            Ok(c) => break c,
            Err(_) => match (base.parent(), base.file_name()) {
                (Some(parent), Some(name)) => {
                    rest.push(name.to_os_string());
                    base = parent;
                }
                _ => break base.to_path_buf(),
            },
        }
    };
    for name in rest.iter().rev() {
        match Path::new(name).components().next() {
            Some(Component::ParentDir) => {
                root.pop();
            }
            Some(Component::CurDir) | None => {}
            _ => root.push(name),
        }
    }
    root
}
