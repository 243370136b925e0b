//! Exodus II importer (Cubit, SEACAS, MOOSE): reads one body (element blocks, or every volume
//! block of the file) into the same [`BodyGeometry`] as the Gmsh and Abaqus importers, checked
//! by the same steps (node references, elements listed twice, length scale, orientation).
//!
//! Containers: netCDF-4 (an HDF5 file, read with `hdf5`) and netCDF-3 classic or 64-bit offset
//! (the SEACAS default, read with the pure-Rust `netcdf3`), told apart by their first bytes;
//! netCDF-3 64-bit data (CDF-5) is refused with the conversion `nccopy -k nc4 in.exo out.exo`.
//!
//! Read: `coordx`/`coordy`/`coordz` (or the 2-D `coord`), the element blocks `connect1…N` with
//! their `elem_type` attribute, `eb_names` and `eb_prop1` (block ids), the side sets
//! `elem_ss1…`/`side_ss1…` with `ss_names`/`ss_prop1`, and the node sets `node_ns1…` with
//! `ns_names`/`ns_prop1`. Element numbers in side sets are the file's internal ones (blocks in
//! order, from 1), node numbers the positions in the coordinate arrays (from 1); the optional
//! `node_num_map`/`elem_num_map` are labels only and are not used.
//!
//! Volume elements: `HEX`/`HEX8`, `HEX20`, `HEX27` (`HEX` with 20 or 27 nodes),
//! `TETRA`/`TETRA4` (4 nodes), `TETRA10` (`TETRA` with 10 nodes), `WEDGE`/`WEDGE6` and
//! `WEDGE15` (`WEDGE` with 15 nodes), `PYRAMID`/`PYRAMID5`. Exodus's corner orders are the program's
//! ([`super::cell`]); the 10-node tetrahedron's last two edge nodes (Exodus: 9 on edge 2–4, 10
//! on edge 3–4) are swapped on reading, and the edge, face and centre nodes of HEX20, HEX27 and
//! WEDGE15 (Exodus II manual, SEACAS `ex_get_side_set_node_list` tables: bottom edges,
//! vertical edges, top edges; then the HEX27's centre and faces) are put in Gmsh's order
//! ([`HEX27_TO_OURS`], [`WEDGE15_TO_OURS`]). Another solid type (`PYRAMID13`, `HEX9`, …) in a
//! block of the body is refused, naming the block and the type; blocks of shells, bars or
//! spheres are not volumes and are skipped.
//!
//! The body is `volume = "name"`: the blocks of that `eb_names` entry (case-insensitive), or
//! `block_<id>` for the block of id `<id>` (the name an unnamed block gets); every volume block
//! when `volume` is left out. Faces, each named by its set's name (`sideset_<id>`,
//! `nodeset_<id>` when unnamed; the scene says `body.name`):
//! - a side set: its (element, side) pairs on the body's boundary (Exodus side numbering:
//!   HEX8 S1 1-2-6-5, S2 2-3-7-6, S3 3-4-8-7, S4 1-5-8-4, S5 1-4-3-2, S6 5-6-7-8; TETRA S1
//!   1-2-4, S2 2-3-4, S3 1-4-3, S4 1-3-2; WEDGE6 S1 1-2-5-4, S2 2-3-6-5, S3 1-4-6-3, S4 1-3-2,
//!   S5 4-5-6; the quadratic types' sides are the same, with their edge and face nodes);
//! - a node set: every boundary facet of the body all of whose nodes lie in the set (a node
//!   set that holds a whole face's nodes gives that face; one that holds the nodes of a line
//!   or of isolated points gives no facet and is left out).
//!
//! Sides of elements outside the body, interior sides and empty sets are skipped; a side set
//! and a node set of the same name are one face.

use std::cell::RefCell;
use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::gmsh::{check_listed_twice, check_scale, file_cell_nodes, orient, renumber, singular, used_nodes, FileCell};
use super::tags::TagIndex;
use super::topology::{boundary_faces, facets_on_nodes, find_boundary_facet, NamedFaces};
use super::{BodyGeometry, Cell, CellKind, Facet};
use crate::error::{Error, Result};

/// The element types read, for messages.
const EXODUS_SUPPORTED: &str = "HEX8, HEX20, HEX27, TETRA4, TETRA10, WEDGE6, WEDGE15, PYRAMID5";

/// The program's node `k` of a 20- or 27-node hexahedron is the Exodus HEX20/HEX27's node
/// `HEX27_TO_OURS[k]` (0-based; Exodus: edge nodes 9–12 on the bottom edges 1-2, 2-3, 3-4,
/// 4-1, 13–16 on the vertical edges 1-5, 2-6, 3-7, 4-8, 17–20 on the top edges 5-6, 6-7, 7-8,
/// 8-5; HEX27 then 21 the centre, 22 face 1-4-3-2, 23 face 5-6-7-8, 24 face 1-5-8-4, 25 face
/// 2-3-7-6, 26 face 1-2-6-5, 27 face 3-4-8-7).
const HEX27_TO_OURS: [usize; 27] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 12, 9, 13, 10, 14, 15, 16, 19, 17, 18, 21, 25, 23, 24, 26, 22, 20];

/// The program's node `k` of a 15-node wedge is the Exodus WEDGE15's node `WEDGE15_TO_OURS[k]`
/// (Exodus: edge nodes 7–9 on the bottom edges 1-2, 2-3, 3-1, 10–12 on the vertical edges 1-4,
/// 2-5, 3-6, 13–15 on the top edges 4-5, 5-6, 6-4).
const WEDGE15_TO_OURS: [usize; 15] = [0, 1, 2, 3, 4, 5, 6, 8, 9, 7, 10, 11, 12, 14, 13];

/// How to convert a file the reader cannot open.
const CONVERT: &str = "convert it with `nccopy -k nc4 in.exo out.exo`";

/// Reads the cells of element block(s) `volume` (every volume block of the file when `None`)
/// from the Exodus II file `path`, in a compact local numbering that keeps the file's node
/// order; its faces are the side sets and node sets that bound it.
pub fn read(path: &Path, volume: Option<&str>) -> Result<BodyGeometry> {
    read_many(path, &[volume])?.pop().expect("one volume asked, one body read")
}

/// The bodies of the Exodus II file `path` with the given element blocks (`None`: every volume
/// block), from one read of the file; the file's errors fail all, a body's own errors only it.
pub fn read_many(path: &Path, volumes: &[Option<&str>]) -> Result<Vec<Result<BodyGeometry>>> {
    let file = path.display().to_string();
    let nc = Nc::open(path).map_err(|e| match e {
        Opened::Io(e) => Error::io(&file, e),
        Opened::Msg(m) => Error::mesh(&file, m),
    })?;
    Ok(volumes.iter().map(|&v| build(&nc, v).map_err(|m| Error::mesh(&file, m))).collect())
}

/// The names the `volume` of a body may take in the Exodus II file `path` (its element blocks
/// of volume elements, read or not, each by its `eb_names` entry or else as `block_<id>`, in
/// file order, a name shared by several blocks once: they make one body) and the bodies
/// ([`super::Survey`]), from one read. The error is the file's, as [`read_many`] gives it.
pub fn survey(path: &Path) -> Result<super::Survey> {
    let file = path.display().to_string();
    let nc = Nc::open(path).map_err(|e| match e {
        Opened::Io(e) => Error::io(&file, e),
        Opened::Msg(m) => Error::mesh(&file, m),
    })?;
    let blocks = blocks(&nc).map_err(|m| Error::mesh(&file, m))?;
    let mut names: Vec<String> = Vec::new();
    // blocks of one name make one body
    for b in blocks.into_iter().filter(|b| b.ty != Ty::Ignored) {
        if !names.iter().any(|n| n.eq_ignore_ascii_case(&b.name)) {
            names.push(b.name);
        }
    }
    let bodies = std::iter::once(None).chain(names.iter().map(|n| Some(n.as_str()))).map(|v| build(&nc, v).map_err(|m| Error::mesh(&file, m))).collect();
    Ok((names, bodies))
}

/// Node and element counts and the file's size, from the variables' shapes (nothing of the
/// mesh is read); `None` when the file cannot be opened as Exodus. For the memory estimate.
pub fn counts(path: &Path) -> Option<(u64, u64, u64)> {
    let bytes = std::fs::metadata(path).ok()?.len();
    let nc = Nc::open(path).ok()?;
    let nodes = match nc.shape("coordx") {
        Some(s) => s.first().copied().unwrap_or(0),
        None => nc.shape("coord")?.get(1).copied().unwrap_or(0),
    };
    let elements: usize = (1..).map_while(|k| nc.shape(&format!("connect{k}"))).map(|s| s.first().copied().unwrap_or(0)).sum();
    Some((nodes as u64, elements as u64, bytes))
}

/// Why a file could not be opened.
enum Opened {
    Io(std::io::Error),
    Msg(String),
}

/// An open netCDF file of either container.
enum Nc {
    /// netCDF-4: an HDF5 file, one dataset per variable.
    Hdf5(hdf5::File),
    /// netCDF-3 classic or 64-bit offset.
    Classic(RefCell<netcdf3::FileReader>),
}

impl Nc {
    /// Opens `path` by its first bytes (`\x89HDF`, `CDF\x01`, `CDF\x02`; `CDF\x05` refused).
    fn open(path: &Path) -> std::result::Result<Nc, Opened> {
        use std::io::Read;
        let mut head = [0u8; 8];
        let mut f = std::fs::File::open(path).map_err(Opened::Io)?;
        let n = f.read(&mut head).map_err(Opened::Io)?;
        let head = &head[..n];
        if head.starts_with(b"\x89HDF\r\n\x1a\n") {
            let h = hdf5::File::open(path).map_err(|e| Opened::Msg(format!("not a readable netCDF-4 (HDF5) file: {e}")))?;
            return Ok(Nc::Hdf5(h));
        }
        match head.get(..4) {
            Some(b"CDF\x01") | Some(b"CDF\x02") => {
                let r = netcdf3::FileReader::open(path).map_err(|e| Opened::Msg(format!("not a readable netCDF-3 file: {e:?}")))?;
                Ok(Nc::Classic(RefCell::new(r)))
            }
            Some(b"CDF\x05") => Err(Opened::Msg(format!("a netCDF-3 64-bit data (CDF-5) file, which is not read; {CONVERT}"))),
            _ => Err(Opened::Msg("not an Exodus II file (neither netCDF-4/HDF5 nor netCDF-3: its first bytes are not \\x89HDF or CDF)".into())),
        }
    }

    /// The dimensions of variable `var`; `None` when there is no such variable.
    fn shape(&self, var: &str) -> Option<Vec<usize>> {
        match self {
            Nc::Hdf5(h) => h.link_exists(var).then(|| h.dataset(var).ok()).flatten().map(|d| d.shape()),
            Nc::Classic(r) => r.borrow().data_set().get_var(var).map(|v| v.get_dims().iter().map(|d| d.size()).collect()),
        }
    }

    /// The values of integer variable `var`.
    fn ints(&self, var: &str) -> std::result::Result<Vec<i64>, String> {
        match self {
            Nc::Hdf5(h) => h.dataset(var).and_then(|d| d.read_raw::<i64>()).map_err(|e| format!("variable {var}: {e}")),
            Nc::Classic(r) => match r.borrow_mut().read_var(var).map_err(|e| unreadable(var, e))? {
                netcdf3::DataVector::I8(v) => Ok(v.into_iter().map(i64::from).collect()),
                netcdf3::DataVector::I16(v) => Ok(v.into_iter().map(i64::from).collect()),
                netcdf3::DataVector::I32(v) => Ok(v.into_iter().map(i64::from).collect()),
                _ => Err(format!("variable {var} is not of an integer type")),
            },
        }
    }

    /// The values of floating-point variable `var`.
    fn floats(&self, var: &str) -> std::result::Result<Vec<f64>, String> {
        match self {
            Nc::Hdf5(h) => h.dataset(var).and_then(|d| d.read_raw::<f64>()).map_err(|e| format!("variable {var}: {e}")),
            Nc::Classic(r) => match r.borrow_mut().read_var(var).map_err(|e| unreadable(var, e))? {
                netcdf3::DataVector::F32(v) => Ok(v.into_iter().map(f64::from).collect()),
                netcdf3::DataVector::F64(v) => Ok(v),
                _ => Err(format!("variable {var} is not of a floating-point type")),
            },
        }
    }

    /// The rows of the 2-D character variable `var` (`eb_names`, …), each up to its first NUL,
    /// trailing blanks removed.
    fn names(&self, var: &str) -> std::result::Result<Vec<String>, String> {
        let shape = self.shape(var).unwrap_or_default();
        let bytes: Vec<u8> = match self {
            Nc::Hdf5(h) => {
                let d = h.dataset(var).map_err(|e| format!("variable {var}: {e}"))?;
                d.read_raw::<hdf5::types::FixedAscii<1>>()
                    .map(|v| v.iter().map(|c| c.as_bytes().first().copied().unwrap_or(0)).collect())
                    .or_else(|_| d.read_raw::<u8>())
                    .map_err(|e| format!("variable {var} is not a character array: {e}"))?
            }
            Nc::Classic(r) => match r.borrow_mut().read_var(var).map_err(|e| unreadable(var, e))? {
                netcdf3::DataVector::U8(v) => v,
                netcdf3::DataVector::I8(v) => v.into_iter().map(|b| b as u8).collect(),
                _ => return Err(format!("variable {var} is not a character array")),
            },
        };
        let width = match shape[..] {
            [_, w] if w > 0 => w,
            _ => return Err(format!("variable {var} is not a 2-D character array (dimensions {shape:?})")),
        };
        Ok(bytes.chunks(width).map(text).collect())
    }

    /// The text attribute `attr` of variable `var`.
    fn text_attr(&self, var: &str, attr: &str) -> Option<String> {
        match self {
            Nc::Hdf5(h) => {
                let a = h.dataset(var).ok()?.attr(attr).ok()?;
                if let Ok(v) = a.read_raw::<hdf5::types::FixedAscii<256>>() {
                    return v.first().map(|s| text(s.as_bytes()));
                }
                a.read_raw::<hdf5::types::VarLenUnicode>().ok()?.first().map(|s| text(s.as_bytes()))
            }
            Nc::Classic(r) => r.borrow().data_set().get_var_attr_as_string(var, attr).map(|s| text(s.as_bytes())),
        }
    }

    /// How many sets of a kind there are: the length of `prop` (`eb_prop1`, …), else the number
    /// of variables `var1`, `var2`, … in a row.
    fn count(&self, prop: &str, var: &str) -> usize {
        match self.shape(prop) {
            Some(s) => s.first().copied().unwrap_or(0),
            None => (1..).take_while(|k| self.shape(&format!("{var}{k}")).is_some()).count(),
        }
    }

    /// The ids (`prop`, else 1, 2, …) and names (`names_var`, else empty) of `n` sets.
    fn ids_and_names(&self, n: usize, prop: &str, names_var: &str) -> std::result::Result<(Vec<i64>, Vec<String>), String> {
        let ids = match self.shape(prop) {
            Some(_) => self.ints(prop)?,
            None => (1..=n as i64).collect(),
        };
        let names = match self.shape(names_var) {
            Some(_) => self.names(names_var)?,
            None => Vec::new(),
        };
        if ids.len() != n {
            return Err(format!("variable {prop} has {} ids for {n} sets", ids.len()));
        }
        Ok((ids, names))
    }
}

/// A netCDF-3 variable that cannot be read (a truncated file ends before its data).
fn unreadable(var: &str, e: netcdf3::ReadError) -> String {
    format!("cannot read variable {var} (is the file truncated?): {e:?}")
}

/// Bytes up to the first NUL, trailing blanks removed.
fn text(b: &[u8]) -> String {
    let end = b.iter().position(|&c| c == 0).unwrap_or(b.len());
    String::from_utf8_lossy(&b[..end]).trim_end().to_string()
}

/// What an element block is to this reader.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ty {
    /// Volume elements read as cells.
    Cell(CellKind),
    /// A solid type not read.
    Solid,
    /// Not part of the body's geometry (shells, bars, spheres, 2-D elements).
    Ignored,
}

/// The reader's view of `elem_type` (upper case) with `nodes` nodes per element.
fn classify(elem_type: &str, nodes: usize) -> Ty {
    let t = elem_type.trim().to_ascii_uppercase();
    match (t.as_str(), nodes) {
        ("HEX" | "HEX8" | "HEXAHEDRON", 8) => Ty::Cell(CellKind::Hex8),
        ("TETRA" | "TETRA4" | "TET" | "TET4", 4) => Ty::Cell(CellKind::Tet4),
        ("TETRA" | "TETRA10" | "TET" | "TET10", 10) => Ty::Cell(CellKind::Tet10),
        ("WEDGE" | "WEDGE6", 6) => Ty::Cell(CellKind::Wedge6),
        ("PYRAMID" | "PYRAMID5", 5) => Ty::Cell(CellKind::Pyr5),
        ("HEX" | "HEX20" | "HEXAHEDRON", 20) => Ty::Cell(CellKind::Hex20),
        ("HEX" | "HEX27" | "HEXAHEDRON", 27) => Ty::Cell(CellKind::Hex27),
        ("WEDGE" | "WEDGE15", 15) => Ty::Cell(CellKind::Wedge15),
        _ if ["SHELL", "QUAD", "TRI", "BAR", "BEAM", "TRUSS", "SPHERE", "CIRCLE", "NULL", "TSHELL", "EDGE", "FACE"].iter().any(|p| t.starts_with(p)) => {
            Ty::Ignored
        }
        _ => Ty::Solid,
    }
}

/// One element block of the file.
struct Block {
    /// 1-based position (`connect<k>`).
    k: usize,
    id: i64,
    /// `eb_names` entry, or `block_<id>`.
    name: String,
    elem_type: String,
    ty: Ty,
    /// Elements and nodes per element.
    count: usize,
    per: usize,
    /// Internal number of its first element minus one.
    first: usize,
}

impl Block {
    /// "element block "upper" (id 1)".
    fn describe(&self) -> String {
        format!("element block \"{}\" (id {})", self.name, self.id)
    }
}

/// The element blocks of the file, in order.
fn blocks(nc: &Nc) -> std::result::Result<Vec<Block>, String> {
    let n = nc.count("eb_prop1", "connect");
    let (ids, names) = nc.ids_and_names(n, "eb_prop1", "eb_names")?;
    let mut out = Vec::with_capacity(n);
    let mut first = 0;
    for k in 1..=n {
        let id = ids[k - 1];
        let name = names.get(k - 1).filter(|s| !s.is_empty()).cloned().unwrap_or_else(|| format!("block_{id}"));
        let var = format!("connect{k}");
        let (count, per, elem_type) = match nc.shape(&var) {
            Some(s) if s.len() == 2 => (s[0], s[1], nc.text_attr(&var, "elem_type").unwrap_or_default()),
            Some(s) if s.iter().product::<usize>() == 0 => (0, 0, String::new()),
            Some(s) => return Err(format!("{var} (block \"{name}\") has dimensions {s:?}, not (elements, nodes per element)")),
            None => (0, 0, String::new()), // an empty block has no connectivity
        };
        if count > 0 && elem_type.is_empty() {
            return Err(format!("{var} (block \"{name}\") has no elem_type attribute"));
        }
        let ty = if count == 0 { Ty::Ignored } else { classify(&elem_type, per) };
        out.push(Block { k, id, name, elem_type, ty, count, per, first });
        first += count;
    }
    Ok(out)
}

/// The node coordinates: `coordx`/`coordy`/`coordz`, or `coord` (3 × nodes); 3-D only.
fn coordinates(nc: &Nc) -> std::result::Result<Vec<[f64; 3]>, String> {
    let (x, y, z) = if nc.shape("coordx").is_some() {
        if nc.shape("coordz").is_none() {
            return Err("a 2-D mesh (no coordz); bodies are 3-D".into());
        }
        (nc.floats("coordx")?, nc.floats("coordy")?, nc.floats("coordz")?)
    } else if let Some(s) = nc.shape("coord") {
        if s.first() != Some(&3) {
            return Err(format!("coord has dimensions {s:?}: not a 3-D mesh (num_dim must be 3)"));
        }
        let all = nc.floats("coord")?;
        let n = s.get(1).copied().unwrap_or(0);
        if all.len() != 3 * n {
            return Err(format!("coord holds {} values for 3 × {n} coordinates", all.len()));
        }
        (all[..n].to_vec(), all[n..2 * n].to_vec(), all[2 * n..].to_vec())
    } else {
        return Err("no node coordinates (neither coordx/coordy/coordz nor coord): not an Exodus II mesh".into());
    };
    if x.len() != y.len() || x.len() != z.len() {
        return Err(format!("coordx, coordy and coordz have {}, {} and {} values", x.len(), y.len(), z.len()));
    }
    let p: Vec<[f64; 3]> = (0..x.len()).map(|i| [x[i], y[i], z[i]]).collect();
    if let Some((i, q)) = p.iter().enumerate().find(|(_, q)| q.iter().any(|v| !v.is_finite())) {
        return Err(format!("node {} has a non-finite coordinate ({}, {}, {})", i + 1, q[0], q[1], q[2]));
    }
    Ok(p)
}

/// The blocks that make up the body: those named `volume` (every volume block when `None`).
fn selected<'b>(all: &'b [Block], volume: Option<&str>) -> std::result::Result<Vec<&'b Block>, String> {
    let chosen: Vec<&Block> = match volume {
        None => all.iter().filter(|b| b.ty != Ty::Ignored).collect(),
        Some(name) => {
            let v: Vec<&Block> = all.iter().filter(|b| b.name.eq_ignore_ascii_case(name) || name == format!("block_{}", b.id)).collect();
            if v.is_empty() {
                let known: Vec<String> = all.iter().map(|b| format!("\"{}\" (id {})", b.name, b.id)).collect();
                let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
                return Err(format!("no element block named \"{name}\" (element blocks: {known})"));
            }
            v
        }
    };
    if let Some(b) = chosen.iter().find(|b| b.ty == Ty::Solid) {
        return Err(format!(
            "{} holds {} elements of type {} ({} nodes), which is not read; supported: {EXODUS_SUPPORTED}",
            b.describe(),
            b.count,
            b.elem_type,
            b.per
        ));
    }
    let cells: Vec<&Block> = chosen.into_iter().filter(|b| matches!(b.ty, Ty::Cell(_))).collect();
    if cells.is_empty() {
        let what = volume.map_or("the file".to_string(), |n| format!("element block \"{n}\""));
        return Err(format!("{what} holds no volume elements; supported: {EXODUS_SUPPORTED}"));
    }
    Ok(cells)
}

/// The body of the open file `nc`.
fn build(nc: &Nc, volume: Option<&str>) -> std::result::Result<BodyGeometry, String> {
    let coords = coordinates(nc)?;
    let all = blocks(nc)?;
    let body = selected(&all, volume)?;
    let n = coords.len() as u64;
    // connectivity as (internal element number, kind, 1-based node numbers in our order)
    let mut conn: Vec<(u64, CellKind, Vec<u64>)> = Vec::new();
    for b in &body {
        let Ty::Cell(kind) = b.ty else { continue };
        let var = format!("connect{}", b.k);
        let v = nc.ints(&var)?;
        if v.len() != b.count * b.per {
            return Err(format!("{var} holds {} values for {} elements of {} nodes", v.len(), b.count, b.per));
        }
        for (e, nodes) in v.chunks(b.per).enumerate() {
            let label = (b.first + e + 1) as u64;
            if let Some(t) = nodes.iter().find(|&&t| t < 1 || t as u64 > n) {
                return Err(format!("{}: element {label} refers to node {t}, outside the file's nodes 1 … {n}", b.describe()));
            }
            let mut nodes: Vec<u64> = nodes.iter().map(|&t| t as u64).collect();
            match kind {
                CellKind::Tet10 => nodes.swap(8, 9), // Exodus: 9 on edge 2-4, 10 on 3-4; ours 8 on (3,2), 9 on (3,1)
                CellKind::Hex20 | CellKind::Hex27 => nodes = HEX27_TO_OURS[..kind.len()].iter().map(|&k| nodes[k]).collect(),
                CellKind::Wedge15 => nodes = WEDGE15_TO_OURS.iter().map(|&k| nodes[k]).collect(),
                _ => {}
            }
            conn.push((label, kind, nodes));
        }
    }
    let file_cells: Vec<FileCell<'_>> = conn.iter().map(|(l, k, v)| (*l, *k, v.as_slice())).collect();
    let index = TagIndex::one_based(coords.len());
    let (file_nodes, used) = file_cell_nodes(&file_cells, &index, coords.len())?;
    check_listed_twice(&file_nodes, &file_cells)?;
    check_scale(&coords, &file_nodes, &file_cells)?;
    let (local, nodes) = used_nodes(&coords, &used);
    let mut cells: Vec<Cell> = Vec::with_capacity(file_nodes.len());
    for (h, &(label, kind, _)) in file_nodes.into_iter().zip(&file_cells) {
        let mut cell = h;
        renumber(&mut cell, &local);
        orient(&mut cell, &nodes).map_err(|why| format!("{} {label} {why}", singular(kind)))?;
        cells.push(cell);
    }
    let cell_of: HashMap<u64, usize> = file_cells.iter().enumerate().map(|(c, (label, _, _))| (*label, c)).collect();
    let total: usize = all.iter().map(|b| b.count).sum();
    let faces = faces(nc, &cells, &conn, &cell_of, &local, total)?;
    Ok(BodyGeometry { nodes, cells, faces })
}

/// The named faces: side sets, then node sets, merged by name (case-insensitive).
fn faces(
    nc: &Nc,
    cells: &[Cell],
    conn: &[(u64, CellKind, Vec<u64>)],
    cell_of: &HashMap<u64, usize>,
    local: &[usize],
    total: usize,
) -> std::result::Result<Vec<(String, Vec<Facet>)>, String> {
    let boundary = boundary_faces(cells);
    let to_local = |t: u64| local.get((t as usize).wrapping_sub(1)).copied().filter(|&l| l != usize::MAX);
    let mut named = NamedFaces::default();
    let mut add = |name: &str, list: Vec<Facet>| named.add(name, list);
    let n_ss = nc.count("ss_prop1", "elem_ss");
    let (ids, names) = nc.ids_and_names(n_ss, "ss_prop1", "ss_names")?;
    for k in 1..=n_ss {
        let name = names.get(k - 1).filter(|s| !s.is_empty()).cloned().unwrap_or_else(|| format!("sideset_{}", ids[k - 1]));
        let (ev, sv) = (format!("elem_ss{k}"), format!("side_ss{k}"));
        if nc.shape(&ev).is_none() {
            continue; // an empty side set has no variables
        }
        let (elems, sides) = (nc.ints(&ev)?, nc.ints(&sv)?);
        if elems.len() != sides.len() {
            return Err(format!("side set \"{name}\": {ev} has {} entries, {sv} {}", elems.len(), sides.len()));
        }
        let mut list = Vec::new();
        for (&e, &s) in elems.iter().zip(&sides) {
            if e < 1 || e as usize > total {
                return Err(format!("side set \"{name}\" names element {e}, outside the file's elements 1 … {total}"));
            }
            let Some(&c) = cell_of.get(&(e as u64)) else { continue };
            let (_, kind, nodes) = &conn[c];
            let table = exodus_sides(*kind);
            let corners = usize::try_from(s)
                .ok()
                .and_then(|s| table.get(s.wrapping_sub(1)))
                .ok_or_else(|| format!("side set \"{name}\": element {e} ({}) has sides 1 … {}, not {s}", singular(*kind), table.len()))?;
            // corners only: positions below 8, where Exodus's order and ours agree
            let loc: Option<Vec<usize>> = corners.iter().map(|&i| to_local(nodes[i])).collect();
            if let Some(q) = loc.and_then(|loc| find_boundary_facet(&boundary, &loc)) {
                list.push(*q);
            }
        }
        add(&name, list);
    }
    let n_ns = nc.count("ns_prop1", "node_ns");
    let (ids, names) = nc.ids_and_names(n_ns, "ns_prop1", "ns_names")?;
    for k in 1..=n_ns {
        let name = names.get(k - 1).filter(|s| !s.is_empty()).cloned().unwrap_or_else(|| format!("nodeset_{}", ids[k - 1]));
        let var = format!("node_ns{k}");
        if nc.shape(&var).is_none() {
            continue;
        }
        let set: HashSet<usize> = nc.ints(&var)?.into_iter().filter_map(|t| u64::try_from(t).ok().and_then(to_local)).collect();
        add(&name, facets_on_nodes(cells, &boundary, &set));
    }
    Ok(named.into_faces())
}

/// The corners (0-based Exodus positions) of Exodus sides 1, 2, … of a cell type.
fn exodus_sides(kind: CellKind) -> &'static [&'static [usize]] {
    const HEX: [&[usize]; 6] = [&[0, 1, 5, 4], &[1, 2, 6, 5], &[2, 3, 7, 6], &[0, 4, 7, 3], &[0, 3, 2, 1], &[4, 5, 6, 7]];
    const TET: [&[usize]; 4] = [&[0, 1, 3], &[1, 2, 3], &[0, 3, 2], &[0, 2, 1]];
    const WEDGE: [&[usize]; 5] = [&[0, 1, 4, 3], &[1, 2, 5, 4], &[0, 3, 5, 2], &[0, 2, 1], &[3, 4, 5]];
    const PYR: [&[usize]; 5] = [&[0, 1, 4], &[1, 2, 4], &[2, 3, 4], &[0, 4, 3], &[0, 3, 2, 1]];
    match kind {
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => &HEX,
        CellKind::Tet4 | CellKind::Tet10 => &TET,
        CellKind::Wedge6 | CellKind::Wedge15 => &WEDGE,
        CellKind::Pyr5 => &PYR,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each Exodus side's corners are the corners of one of our faces of the same cell type.
    #[test]
    fn every_exodus_side_is_one_of_our_faces() {
        for kind in CellKind::ALL {
            let ours: HashSet<Vec<usize>> = kind
                .faces()
                .iter()
                .map(|f| {
                    let mut c = f[..kind.facet_kind(f.len()).corners()].to_vec();
                    c.sort_unstable();
                    c
                })
                .collect();
            let sides = exodus_sides(kind);
            assert_eq!(sides.len(), ours.len(), "{kind:?}");
            for s in sides {
                let mut c = s.to_vec();
                c.sort_unstable();
                assert!(ours.contains(&c), "{kind:?} side {s:?}");
            }
        }
    }

    #[test]
    fn element_types() {
        assert_eq!(classify("HEX8", 8), Ty::Cell(CellKind::Hex8));
        assert_eq!(classify("tetra", 10), Ty::Cell(CellKind::Tet10));
        assert_eq!(classify("HEX20", 20), Ty::Cell(CellKind::Hex20));
        assert_eq!(classify("HEX", 27), Ty::Cell(CellKind::Hex27));
        assert_eq!(classify("WEDGE15", 15), Ty::Cell(CellKind::Wedge15));
        assert_eq!(classify("HEX9", 9), Ty::Solid);
        assert_eq!(classify("PYRAMID5", 5), Ty::Cell(CellKind::Pyr5));
        assert_eq!(classify("PYRAMID13", 13), Ty::Solid);
        assert_eq!(classify("SHELL4", 4), Ty::Ignored);
    }

    /// The HEX27 and WEDGE15 node positions of SEACAS's side tables
    /// (`ex_get_side_set_node_list`: each side's corners, then its edge nodes in turn, then a
    /// HEX27 side's centre), mapped by the permutations, are the program's edge and face nodes.
    #[test]
    fn quadratic_permutations_follow_the_side_tables() {
        use crate::mesh::cell::{HEX20_EDGES, HEX27_FACES, WEDGE15_EDGES};
        let hex: [[usize; 9]; 6] = [
            [1, 2, 6, 5, 9, 14, 17, 13, 26],
            [2, 3, 7, 6, 10, 15, 18, 14, 25],
            [3, 4, 8, 7, 11, 16, 19, 15, 27],
            [1, 5, 8, 4, 13, 20, 16, 12, 24],
            [1, 4, 3, 2, 12, 11, 10, 9, 22],
            [5, 6, 7, 8, 17, 18, 19, 20, 23],
        ];
        let wedge: [&[usize]; 5] =
            [&[1, 2, 5, 4, 7, 11, 13, 10], &[2, 3, 6, 5, 8, 12, 14, 11], &[1, 4, 6, 3, 10, 15, 12, 9], &[1, 3, 2, 9, 8, 7], &[4, 5, 6, 13, 14, 15]];
        // Exodus node (0-based) → its corners, from the tables
        let mut of: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
        for (kind, sides) in [(0, hex.iter().map(|s| &s[..]).collect::<Vec<_>>()), (1, wedge.to_vec())] {
            for s in sides {
                let n = if s.len() == 6 { 3 } else { 4 };
                for e in 0..n {
                    of.insert((kind, s[n + e] - 1), vec![s[e] - 1, s[(e + 1) % n] - 1]);
                }
                if s.len() == 9 {
                    of.insert((kind, s[8] - 1), s[..4].iter().map(|v| v - 1).collect());
                }
            }
        }
        let sorted = |mut v: Vec<usize>| {
            v.sort_unstable();
            v
        };
        assert_eq!(HEX27_TO_OURS[..8], [0, 1, 2, 3, 4, 5, 6, 7]);
        for (e, ours) in HEX20_EDGES.iter().enumerate() {
            assert_eq!(sorted(of[&(0, HEX27_TO_OURS[8 + e])].clone()), sorted(ours.to_vec()), "hex edge node {}", 8 + e);
        }
        for (f, ours) in HEX27_FACES.iter().enumerate() {
            assert_eq!(sorted(of[&(0, HEX27_TO_OURS[20 + f])].clone()), sorted(ours.to_vec()), "hex face node {}", 20 + f);
        }
        assert_eq!(HEX27_TO_OURS[26], 20, "the centre: the one node no side holds");
        assert!(!of.contains_key(&(0, 20)));
        assert_eq!(WEDGE15_TO_OURS[..6], [0, 1, 2, 3, 4, 5]);
        for (e, ours) in WEDGE15_EDGES.iter().enumerate() {
            assert_eq!(sorted(of[&(1, WEDGE15_TO_OURS[6 + e])].clone()), sorted(ours.to_vec()), "wedge edge node {}", 6 + e);
        }
    }
}
