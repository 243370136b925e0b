//! Salome / code_aster MED importer (`.med`, MED 3.x and 4.x, which are HDF5 files): reads one
//! body (a group of volume cells, or every volume cell of the file) into the same
//! [`BodyGeometry`] as the Gmsh importer ([`super::gmsh`]), checked by the same steps (node
//! references, cells listed twice, length scale, orientation).
//!
//! Read, for the file's only mesh `<m>` at its only time step `<s>`:
//! - `/ENS_MAA/<m>/<s>/NOE/COO`: the coordinates, all x, then all y, then all z (`NBR` nodes);
//! - `/ENS_MAA/<m>/<s>/MAI/<type>/NOD`: each type's connectivity, 1-based positions in `COO`,
//!   column-major (every cell's first node, then every cell's second node, …; `NBR` cells), and
//!   `FAM` beside it: each cell's family number (0, or negative for an element family);
//! - `/FAS/<m>/ELEME/<family>`: attribute `NUM` (the family number) and `GRO/NOM`, the names of
//!   the groups the family belongs to (80 bytes each, padded with spaces or NULs).
//!
//! Cell types: `TE4`, `T10`, `HE8`, `H20`, `H27`, `PE6`, `P15`, `PY5` (volumes), `TR3`, `QU4`,
//! `TR6`, `QU8`, `QU9` (faces); points and edges (`PO1`, `SE2`, `SE3`, `SE4`) are skipped; any
//! other type in the file (`P13`, `P18`, …) is refused naming it. MED numbers a cell's corners the
//! other way round from Gmsh (its reference cells have a negative Jacobian in the program's
//! convention, [`super::cell`]); the node orders are converted as Gmsh's own MED reader does
//! (`med2mshNodeIndex` of its `GModelIO_MED.cpp`: the program's node k is MED's node
//! `perm[k]`): TE4 0 2 1 3, T10 0 2 1 3 6 5 4 7 8 9, HE8 0 3 2 1 4 7 6 5, H20 0 3 2 1 4 7 6 5
//! 11 8 16 10 19 9 18 17 15 12 14 13, H27 the H20's then 20 24 21 23 22 25 26, PE6 0 2 1 3 5 4,
//! P15 0 2 1 3 5 4 8 6 12 7 14 13 11 9 10; face types keep their order.
//!
//! Faces: every group holding face cells that bound the body is the face `body.<group>`; a
//! family in several groups puts its cells in each. Every group of nodes (`NOE/FAM` with
//! `/FAS/<m>/NOEUD`, code_aster's `GROUP_NO`) is a face too: the body's boundary facets all of
//! whose nodes lie in it, merged with a group of faces of the same name.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use ::hdf5::{File, Group};

use super::gmsh::{check_listed_twice, check_scale, file_cell_nodes, orient, renumber, singular, used_nodes, FileCell};
use super::tags::TagIndex;
use super::topology::{boundary_faces, find_boundary_facet};
use super::{BodyGeometry, Cell, CellKind, Facet};
use crate::error::{Error, Result};

/// The volume cell types read, in MED's names, for messages.
const MED_SUPPORTED: &str = "TE4, T10, HE8, H20, H27, PE6, P15, PY5 (volumes), TR3, QU4, TR6, QU8, QU9 (faces)";

/// What a MED cell type is to this reader.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ty {
    /// A volume cell, and the program's node `k` is MED's node `perm[k]`.
    Cell(CellKind, &'static [usize]),
    /// A face cell with this many corners (its first nodes).
    Facet(usize),
    /// Points and edges: not part of a body.
    Ignored,
}

/// The reader's view of MED type `name`; `None` when not read.
fn classify(name: &str) -> Option<Ty> {
    Some(match name {
        "TE4" => Ty::Cell(CellKind::Tet4, &[0, 2, 1, 3]),
        "T10" => Ty::Cell(CellKind::Tet10, &[0, 2, 1, 3, 6, 5, 4, 7, 8, 9]),
        "HE8" => Ty::Cell(CellKind::Hex8, &[0, 3, 2, 1, 4, 7, 6, 5]),
        "PE6" => Ty::Cell(CellKind::Wedge6, &[0, 2, 1, 3, 5, 4]),
        "PY5" => Ty::Cell(CellKind::Pyr5, &[0, 3, 2, 1, 4]),
        "H20" => Ty::Cell(CellKind::Hex20, &[0, 3, 2, 1, 4, 7, 6, 5, 11, 8, 16, 10, 19, 9, 18, 17, 15, 12, 14, 13]),
        "H27" => Ty::Cell(CellKind::Hex27, &[0, 3, 2, 1, 4, 7, 6, 5, 11, 8, 16, 10, 19, 9, 18, 17, 15, 12, 14, 13, 20, 24, 21, 23, 22, 25, 26]),
        "P15" => Ty::Cell(CellKind::Wedge15, &[0, 2, 1, 3, 5, 4, 8, 6, 12, 7, 14, 13, 11, 9, 10]),
        "TR3" | "TR6" => Ty::Facet(3),
        "QU4" | "QU8" | "QU9" => Ty::Facet(4),
        "PO1" | "SE2" | "SE3" | "SE4" => Ty::Ignored,
        _ => return None,
    })
}

/// Nodes per cell of the MED types read.
fn nodes_of(name: &str) -> usize {
    match name {
        "PO1" => 1,
        "SE2" => 2,
        "SE3" | "TR3" => 3,
        "SE4" | "QU4" | "TE4" => 4,
        "TR6" | "PE6" => 6,
        "QU8" | "HE8" => 8,
        "QU9" => 9,
        "P15" => 15,
        "H20" => 20,
        "H27" => 27,
        _ => 10, // T10
    }
}

/// One block of cells of one type.
struct Block {
    name: String,
    ty: Ty,
    /// Node positions (0-based), cell after cell, in MED's order.
    nodes: Vec<u64>,
    fam: Vec<i64>,
}

impl Block {
    fn len(&self) -> usize {
        self.fam.len()
    }

    fn cell(&self, c: usize) -> &[u64] {
        let n = nodes_of(&self.name);
        &self.nodes[c * n..(c + 1) * n]
    }
}

/// The mesh of a MED file.
struct Med {
    coords: Vec<[f64; 3]>,
    blocks: Vec<Block>,
    /// Element family number → its groups.
    groups: HashMap<i64, Vec<String>>,
    /// Each node's family number (`NOE/FAM`; empty when the file has none) and node family
    /// number → its groups (`/FAS/<mesh>/NOEUD`).
    node_fam: Vec<i64>,
    node_groups: HashMap<i64, Vec<String>>,
}

/// Reads the cells of group `volume` (every volume cell of the file when `None`) from the MED
/// file `path`, in a compact local numbering that keeps the file's node order; its faces are the
/// groups of face cells that bound it.
pub fn read(path: &Path, volume: Option<&str>) -> Result<BodyGeometry> {
    read_many(path, &[volume])?.pop().expect("one body asked for")
}

/// The bodies of the MED file `path` with the given volume groups (`None`: every volume cell),
/// from one read of the file; the file's errors fail all, a body's own errors only that body.
pub fn read_many(path: &Path, volumes: &[Option<&str>]) -> Result<Vec<Result<BodyGeometry>>> {
    let med = Med::open(path)?;
    Ok(volumes.iter().map(|&v| med.build(v).map_err(|msg| Error::mesh(path.display().to_string(), msg))).collect())
}

/// The names the `volume` of a body may take in the MED file `path` (its groups of volume
/// cells, sorted) and the bodies ([`super::Survey`]), from one read. The error is the file's,
/// as [`read_many`] gives it.
pub fn survey(path: &Path) -> Result<super::Survey> {
    let med = Med::open(path)?;
    let names = med.group_names(true);
    let bodies = std::iter::once(None)
        .chain(names.iter().map(|n| Some(n.as_str())))
        .map(|v| med.build(v).map_err(|msg| Error::mesh(path.display().to_string(), msg)))
        .collect();
    Ok((names, bodies))
}

/// Node, cell and byte counts of a MED file from its `NBR` attributes; `None` when it cannot be
/// read. For the memory estimate before the mesh is read.
pub fn counts(path: &Path) -> Option<(u64, u64, u64)> {
    let bytes = std::fs::metadata(path).ok()?.len();
    let file = File::open(path).ok()?;
    let step = mesh_step(&file).ok()?.1;
    let nodes = nbr(&step.dataset("NOE/COO").ok()?.attr("NBR").ok()?).ok()?;
    let mut cells = 0;
    for t in step.group("MAI").ok()?.member_names().ok()? {
        cells += step.dataset(&format!("MAI/{t}/NOD")).ok().and_then(|d| d.attr("NBR").ok()).and_then(|a| nbr(&a).ok()).unwrap_or(0);
    }
    Some((nodes, cells, bytes))
}

/// The HDF5 library's message on one line.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A non-negative count attribute.
fn nbr(a: &::hdf5::Attribute) -> std::result::Result<u64, String> {
    let v = a.read_scalar::<i64>().map_err(|e| one_line(&e.to_string()))?;
    u64::try_from(v).map_err(|_| format!("negative count {v}"))
}

/// The name of the file's only mesh and the group of its only time step.
fn mesh_step(file: &File) -> std::result::Result<(String, Group), String> {
    let ens = file.group("ENS_MAA").map_err(|_| "not a MED file (no /ENS_MAA group of meshes)".to_string())?;
    let meshes = ens.member_names().map_err(|e| one_line(&e.to_string()))?;
    let [name] = meshes.as_slice() else {
        return Err(format!("holds {} meshes ({}); the reader takes a file of one mesh", meshes.len(), meshes.join(", ")));
    };
    let mesh = ens.group(name).map_err(|e| one_line(&e.to_string()))?;
    if mesh.link_exists("NOE") {
        return Ok((name.clone(), mesh));
    }
    let steps = mesh.member_names().map_err(|e| one_line(&e.to_string()))?;
    let [step] = steps.as_slice() else {
        return Err(format!("mesh \"{name}\" has {} time steps; the reader takes a mesh of one", steps.len()));
    };
    Ok((name.clone(), mesh.group(step).map_err(|e| one_line(&e.to_string()))?))
}

impl Med {
    /// Opens and loads the MED file `path`; errors name it.
    fn open(path: &Path) -> Result<Med> {
        let err = |msg: String| Error::mesh(path.display().to_string(), msg);
        if let Err(e) = std::fs::metadata(path) {
            return Err(Error::io(path.display().to_string(), e));
        }
        let file = File::open(path).map_err(|e| err(format!("not a readable MED file (HDF5): {}", one_line(&e.to_string()))))?;
        Med::load(&file).map_err(err)
    }

    /// Coordinates, cell blocks and element families of `file`.
    fn load(file: &File) -> std::result::Result<Med, String> {
        fn h5(what: &str) -> impl Fn(::hdf5::Error) -> String + '_ {
            move |e| format!("cannot read {what}: {}", one_line(&e.to_string()))
        }
        let (name, step) = mesh_step(file)?;
        let coo = step.dataset("NOE/COO").map_err(|_| format!("mesh \"{name}\" has no node coordinates (NOE/COO)"))?;
        let n = nbr(&coo.attr("NBR").map_err(h5("NOE/COO NBR"))?)? as usize;
        let x: Vec<f64> = coo.read_raw().map_err(h5("the node coordinates NOE/COO"))?;
        if x.len() != 3 * n {
            return Err(format!("NOE/COO holds {} numbers for {n} nodes; the reader takes 3-D meshes (x, y, z per node)", x.len()));
        }
        let coords: Vec<[f64; 3]> = (0..n).map(|i| [x[i], x[n + i], x[2 * n + i]]).collect();
        if let Some(i) = coords.iter().position(|p| p.iter().any(|v| !v.is_finite())) {
            return Err(format!("node {} has a non-finite coordinate", i + 1));
        }
        let mai = step.group("MAI").map_err(|_| format!("mesh \"{name}\" has no cells (MAI)"))?;
        let mut blocks = Vec::new();
        for t in mai.member_names().map_err(h5("MAI"))? {
            let ty = classify(&t).ok_or_else(|| format!("holds cells of MED type {t}, which the reader does not take (it reads {MED_SUPPORTED})"))?;
            let nod = mai.dataset(&format!("{t}/NOD")).map_err(|_| format!("MAI/{t} has no nodal connectivity (NOD)"))?;
            let cells = nbr(&nod.attr("NBR").map_err(h5(&format!("MAI/{t}/NOD NBR")))?)? as usize;
            let raw: Vec<i64> = nod.read_raw().map_err(h5(&format!("MAI/{t}/NOD")))?;
            let k = nodes_of(&t);
            if raw.len() != k * cells {
                return Err(format!("MAI/{t}/NOD holds {} numbers for {cells} cells of {k} nodes", raw.len()));
            }
            let mut nodes = vec![0u64; raw.len()];
            for (j, &v) in raw.iter().enumerate() {
                let (slot, c) = (j / cells, j % cells);
                if v < 1 || v as usize > n {
                    return Err(format!("{t} cell {} refers to node {v}, which is not in NOE/COO (nodes 1 … {n})", c + 1));
                }
                nodes[c * k + slot] = (v - 1) as u64;
            }
            let fam: Vec<i64> = match mai.dataset(&format!("{t}/FAM")) {
                Ok(d) => d.read_raw().map_err(h5(&format!("MAI/{t}/FAM")))?,
                Err(_) => vec![0; cells],
            };
            if fam.len() != cells {
                return Err(format!("MAI/{t}/FAM holds {} family numbers for {cells} cells", fam.len()));
            }
            blocks.push(Block { name: t, ty, nodes, fam });
        }
        let groups = families(file, &name, "ELEME")?;
        let node_groups = families(file, &name, "NOEUD")?;
        let node_fam: Vec<i64> = match step.dataset("NOE/FAM") {
            Ok(d) if !node_groups.is_empty() => d.read_raw().map_err(h5("NOE/FAM"))?,
            _ => Vec::new(),
        };
        if !node_fam.is_empty() && node_fam.len() != n {
            return Err(format!("NOE/FAM holds {} family numbers for {n} nodes", node_fam.len()));
        }
        Ok(Med { coords, blocks, groups, node_fam, node_groups })
    }

    /// The volume cells of group `name` (every one when `None`): (block, cell) pairs.
    fn select(&self, volume: Option<&str>) -> std::result::Result<Vec<(usize, usize)>, String> {
        let in_group = |f: i64| volume.is_none_or(|g| self.groups.get(&f).is_some_and(|v| v.iter().any(|n| n == g)));
        let mut out = Vec::new();
        for (b, block) in self.blocks.iter().enumerate() {
            if matches!(block.ty, Ty::Cell(..)) {
                out.extend((0..block.len()).filter(|&c| in_group(block.fam[c])).map(|c| (b, c)));
            }
        }
        if out.is_empty() {
            return Err(match volume {
                None => format!("holds no volume cells; supported: {MED_SUPPORTED}"),
                Some(g) => {
                    let known: Vec<String> = self.group_names(true).iter().map(|g| format!("\"{g}\"")).collect();
                    let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                    format!("no group of volume cells named \"{g}\" (groups of volume cells: {known})")
                }
            });
        }
        Ok(out)
    }

    /// The names (sorted) of the groups holding volume cells (`volume`) or face cells.
    fn group_names(&self, volume: bool) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        for block in self.blocks.iter().filter(|b| matches!(b.ty, Ty::Cell(..)) == volume) {
            for f in &block.fam {
                for g in self.groups.get(f).into_iter().flatten() {
                    if !names.contains(g) {
                        names.push(g.clone());
                    }
                }
            }
        }
        names.sort();
        names
    }

    /// The body of group `volume` (every volume cell when `None`).
    fn build(&self, volume: Option<&str>) -> std::result::Result<BodyGeometry, String> {
        let chosen = self.select(volume)?;
        // the program's node order, MED position + 1 as the node "tag"
        // every cell's list in one vector (a million cells: no vector each), cell i's ending at ends[i]
        let (mut flat, mut ends): (Vec<u64>, Vec<usize>) = (Vec::new(), Vec::with_capacity(chosen.len()));
        for &(b, c) in &chosen {
            let Ty::Cell(_, perm) = self.blocks[b].ty else { unreachable!("selected volume cells") };
            let cell = self.blocks[b].cell(c);
            flat.extend(perm.iter().map(|&k| cell[k] + 1));
            ends.push(flat.len());
        }
        let file_cells: Vec<FileCell<'_>> = chosen
            .iter()
            .enumerate()
            .map(|(i, &(b, c))| {
                let Ty::Cell(kind, _) = self.blocks[b].ty else { unreachable!("selected volume cells") };
                let start = if i == 0 { 0 } else { ends[i - 1] };
                (c as u64 + 1, kind, &flat[start..ends[i]])
            })
            .collect();
        let index = TagIndex::one_based(self.coords.len());
        let (file_nodes, used) = file_cell_nodes(&file_cells, &index, self.coords.len())?;
        check_listed_twice(&file_nodes, &file_cells)?;
        check_scale(&self.coords, &file_nodes, &file_cells)?;
        let (local, nodes) = used_nodes(&self.coords, &used);
        let mut cells: Vec<Cell> = Vec::with_capacity(file_nodes.len());
        for ((h, &(label, kind, _)), &(b, _)) in file_nodes.into_iter().zip(&file_cells).zip(&chosen) {
            let mut cell = h;
            renumber(&mut cell, &local);
            orient(&mut cell, &nodes).map_err(|why| format!("{} {label} of MAI/{} {why}", singular(kind), self.blocks[b].name))?;
            cells.push(cell);
        }
        let faces = self.faces(&cells, &local);
        Ok(BodyGeometry { nodes, cells, faces })
    }

    /// The groups of face cells that bound `cells`, in order of name.
    fn faces(&self, cells: &[Cell], local: &[usize]) -> Vec<(String, Vec<Facet>)> {
        let boundary = boundary_faces(cells);
        let mut faces: BTreeMap<&str, (Vec<Facet>, std::collections::HashSet<(usize, [usize; 4])>)> = BTreeMap::new();
        for block in &self.blocks {
            let Ty::Facet(corners) = block.ty else { continue };
            for c in 0..block.len() {
                let Some(names) = self.groups.get(&block.fam[c]) else { continue };
                let loc: Vec<usize> = block.cell(c)[..corners].iter().map(|&i| local[i as usize]).collect();
                if loc.contains(&usize::MAX) {
                    continue;
                }
                let Some(q) = find_boundary_facet(&boundary, &loc) else { continue };
                for g in names {
                    let (list, seen) = faces.entry(g.as_str()).or_default();
                    if seen.insert((q.elem, q.key())) {
                        list.push(*q);
                    }
                }
            }
        }
        // every group of nodes (code_aster's GROUP_NO): the boundary facets all of whose nodes
        // lie in it, merged with a group of faces of the same name
        if !self.node_fam.is_empty() {
            let mut members: BTreeMap<&str, std::collections::HashSet<usize>> = BTreeMap::new();
            for (i, f) in self.node_fam.iter().enumerate() {
                for g in self.node_groups.get(f).into_iter().flatten() {
                    if local[i] != usize::MAX {
                        members.entry(g.as_str()).or_default().insert(local[i]);
                    }
                }
            }
            if !members.is_empty() {
                let ordered = super::topology::boundary_in_cell_order(cells, &boundary);
                for (g, set) in members {
                    let on = super::topology::on_nodes(&ordered, &set);
                    if on.is_empty() {
                        continue;
                    }
                    let (list, seen) = faces.entry(g).or_default();
                    for q in on {
                        if seen.insert((q.elem, q.key())) {
                            list.push(q);
                        }
                    }
                }
            }
        }
        faces.into_iter().map(|(n, (list, _))| (n.to_string(), list)).collect()
    }
}

/// Family number → group names, from `/FAS/<mesh>/<kind>` (`ELEME`: cell families, `NOEUD`:
/// node families).
fn families(file: &File, mesh: &str, kind: &str) -> std::result::Result<HashMap<i64, Vec<String>>, String> {
    let mut out = HashMap::new();
    let Ok(eleme) = file.group(&format!("FAS/{mesh}/{kind}")) else { return Ok(out) };
    let h5 = |what: String| move |e: ::hdf5::Error| format!("cannot read {what}: {}", one_line(&e.to_string()));
    for fam in eleme.member_names().map_err(h5(format!("FAS/{mesh}/{kind}")))? {
        let g = eleme.group(&fam).map_err(h5(format!("family {fam}")))?;
        let num: i64 = g.attr("NUM").and_then(|a| a.read_scalar()).map_err(h5(format!("family {fam} NUM")))?;
        let Ok(nom) = g.dataset("GRO/NOM") else { continue };
        let bytes: Vec<u8> = match nom.read_raw::<[i8; 80]>() {
            Ok(v) => v.iter().flatten().map(|&b| b as u8).collect(),
            Err(_) => nom.read_raw::<i8>().map_err(h5(format!("family {fam} GRO/NOM")))?.into_iter().map(|b| b as u8).collect(),
        };
        let names: Vec<String> =
            bytes.chunks(80).map(|c| String::from_utf8_lossy(c).trim_end_matches(['\0', ' ']).trim().to_string()).filter(|s| !s.is_empty()).collect();
        out.insert(num, names);
    }
    Ok(out)
}
