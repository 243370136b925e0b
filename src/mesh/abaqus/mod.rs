//! Abaqus input (`.inp`) importer: reads one body (an element set, or every volume element of
//! the file) into the same [`BodyGeometry`] as the Gmsh importer ([`super::gmsh`]), checked by
//! the same steps (node references, elements listed twice, length scale, orientation).
//!
//! Read: `*NODE` (rectangular coordinates; `NSET=`), `*ELEMENT, TYPE=…` (`ELSET=`), `*ELSET`
//! and `*NSET` (labels, set names, `GENERATE`, `INSTANCE=`), `*SURFACE, TYPE=ELEMENT` (lines
//! `elset or element, S1…S6`; no face identifier: every boundary facet of those elements),
//! `*SURFACE, TYPE=NODE` (lines `nset or node[, weight]`), `*INCLUDE, INPUT=` and `INPUT=` on
//! `*NODE`/`*ELEMENT`/`*ELSET`/`*NSET` (paths relative to the file that names them), and
//! `*PART`/`*END PART`, `*ASSEMBLY`/`*END ASSEMBLY`, `*INSTANCE`/`*END INSTANCE` as Abaqus/CAE
//! writes them ([`assembly`]: each instance a moved copy of its part; its elements are the
//! element set `instance`, its part's sets and surfaces `instance.name`). Keywords and set
//! names are case-insensitive, `**` lines are comments, a keyword line or an element's data
//! line that ends with a comma goes on on the next line. Every other keyword (`*MATERIAL`,
//! `*STEP`, `*BOUNDARY`, …) is skipped with its data, and [`skipped`] lists them (`check`
//! prints the list).
//!
//! Volume elements: `C3D8`, `C3D8R`, `C3D8I`, `C3D8H`, `C3D8RH`, `C3D8IH` (read as 8-node
//! hexahedra: the program's own integration, not Abaqus's reduced or incompatible-mode one),
//! `C3D4`/`C3D4H`, `C3D10`/`C3D10H`/`C3D10M`/`C3D10MH`, `C3D6`/`C3D6H` (wedges),
//! `C3D20`/`C3D20R`/`C3D20H`/`C3D20RH` (20-node hexahedra), `C3D15`/`C3D15H` (15-node
//! wedges) and `C3D5`/`C3D5H` (pyramids). Abaqus's corner orders are the program's ([`super::cell`]); the 10-node
//! tetrahedron's last two edge nodes (Abaqus: 9 on edge 2–4, 10 on edge 3–4) are swapped on
//! reading, and the edge nodes of C3D20 and C3D15 (bottom edges, top edges, then vertical
//! edges) are put in Gmsh's order ([`C3D20_TO_OURS`], [`C3D15_TO_OURS`]). Other solid types
//! (`C3D27`, whose face-node order is not checked here, `C3D13`, …) in the body are an error
//! naming them. Faces S1–S6 of C3D20 and S1–S5 of C3D15 are 8-node quadrilaterals and 6-node
//! triangles with their edge nodes.
//!
//! Faces, each named by its set or surface name (the scene says `body.name`):
//! - every `*SURFACE, TYPE=ELEMENT` whose facets bound the body's elements (Abaqus face
//!   numbering, Abaqus Analysis User's Guide, "Three-dimensional solid element library", face
//!   tables; the same in Bower's `abq_facenodes_3D` of his Abaqus UEL code: C3D8 S1 1-2-3-4,
//!   S2 5-8-7-6, S3 1-5-6-2, S4 2-6-7-3, S5 3-7-8-4, S6 4-8-5-1; C3D4/C3D10 S1 1-2-3, S2 1-4-2,
//!   S3 2-4-3, S4 3-4-1; C3D6 S1 1-2-3, S2 4-6-5, S3 1-2-5-4, S4 2-3-6-5, S5 3-1-4-6);
//! - every element set holding surface elements (`CPS3`, `CPS4`, `S4R`, `M3D4`, `SFM3D4`,
//!   `R3D4`, … — Gmsh writes a physical surface this way): the body's boundary facets with the
//!   same corners, as the Gmsh importer reads a physical surface.
//!
//! - every `*SURFACE, TYPE=NODE`: the body's boundary facets whose nodes all lie in the
//!   surface's nodes (weights ignored);
//! - every `*NSET` (Abaqus/CAE writes one for each set a boundary condition names): the body's
//!   boundary facets whose nodes all lie in the set, merged with a surface of the same name.

mod assembly;

use std::collections::{HashMap, HashSet};

use rustc_hash::{FxHashMap, FxHashSet};
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use super::gmsh::{check_listed_twice, check_scale, file_cell_nodes, orient, renumber, singular, used_nodes, FileCell, SUPPORTED};
use super::tags::TagIndex;
use super::topology::{boundary_faces, find_boundary_facet, NamedFaces};
use super::{BodyGeometry, Cell, CellKind, Facet};
use crate::error::{Error, Result};

/// Deepest nesting of `*INCLUDE` (deeper: an include loop).
const MAX_DEPTH: usize = 16;

/// Most labels one `GENERATE` line may produce.
const MAX_GENERATE: u64 = 100_000_000;

/// The volume element types read, in Abaqus's names, for messages.
const ABAQUS_SUPPORTED: &str = "C3D8 (C3D8R, C3D8I, C3D8H), C3D4, C3D10 (C3D10M), C3D6, C3D20 (C3D20R, C3D20H), C3D15, C3D5";

/// The program's node `k` of a 20-node hexahedron is the C3D20's node `C3D20_TO_OURS[k]`
/// (0-based; Abaqus: edge nodes 9–12 on the bottom edges 1-2, 2-3, 3-4, 4-1, 13–16 on the top
/// edges 5-6, 6-7, 7-8, 8-5, 17–20 on the vertical edges 1-5, 2-6, 3-7, 4-8).
const C3D20_TO_OURS: [usize; 20] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 16, 9, 17, 10, 18, 19, 12, 15, 13, 14];

/// The program's node `k` of a 15-node wedge is the C3D15's node `C3D15_TO_OURS[k]` (Abaqus:
/// edge nodes 7–9 on the bottom edges 1-2, 2-3, 3-1, 10–12 on the top edges 4-5, 5-6, 6-4,
/// 13–15 on the vertical edges 1-4, 2-5, 3-6).
const C3D15_TO_OURS: [usize; 15] = [0, 1, 2, 3, 4, 5, 6, 8, 12, 7, 13, 14, 9, 11, 10];

/// Reads the cells of element set `volume` (every volume element of the file when `None`) from
/// the Abaqus input file `path`, in a compact local numbering that keeps the file's node order;
/// its faces are the element-based surfaces and the sets of surface elements that bound it.
pub fn read(path: &Path, volume: Option<&str>) -> Result<BodyGeometry> {
    read_many(path, &[volume])?.pop().expect("one volume asked, one body read")
}

/// [`read`] for several bodies of one input file: its lines are loaded and parsed once, then
/// each element set of `volumes` is built from the parsed deck. The outer error is the file's;
/// the inner ones are each body's.
pub fn read_many(path: &Path, volumes: &[Option<&str>]) -> Result<Vec<Result<BodyGeometry>>> {
    read_many_with(path, volumes, &|_, _| ())
}

/// [`read_many`], telling `progress(done, total)` the bytes of the file being loaded (the input
/// file or one it includes) read so far.
pub fn read_many_with(path: &Path, volumes: &[Option<&str>], progress: &dyn Fn(u64, u64)) -> Result<Vec<Result<BodyGeometry>>> {
    let mut lines = Vec::new();
    load(path, 0, &mut lines, None, progress)?;
    let deck = Deck::parse(&lines)?;
    Ok(volumes.iter().map(|&v| deck.build(v).map_err(|f| f.into_error(path, &lines))).collect())
}

/// The names the `volume` of a body may take in the input file `path` (its element sets that
/// hold volume elements; with `*PART`/`*INSTANCE`, each instance and its parts' sets as
/// `instance.set`; in order of definition) and the bodies ([`super::Survey`]), from one parse.
/// The error is the file's, as [`read_many`] gives it.
pub fn survey(path: &Path) -> Result<super::Survey> {
    let mut lines = Vec::new();
    load(path, 0, &mut lines, None, &|_, _| ())?;
    let deck = Deck::parse(&lines)?;
    let names: Vec<String> = deck.volume_sets().into_iter().map(str::to_string).collect();
    let bodies = std::iter::once(None).chain(names.iter().map(|n| Some(n.as_str()))).map(|v| deck.build(v).map_err(|f| f.into_error(path, &lines))).collect();
    Ok((names, bodies))
}

/// Node, element and byte counts of an input file and the files it includes, from one cheap
/// pass over their lines (data lines under `*NODE` and `*ELEMENT`); `None` when the file
/// cannot be read. For the memory estimate before the mesh is read.
pub fn counts(path: &Path) -> Option<(u64, u64, u64)> {
    let mut s = Scan::default();
    s.scan(path, 0).then_some((s.nodes, s.elements, s.bytes))
}

/// The input file and every file it includes (`*INCLUDE, INPUT=`, `INPUT=` on data keywords),
/// as far as they can be read.
pub fn files(path: &Path) -> Vec<PathBuf> {
    let mut s = Scan::default();
    s.scan(path, 0);
    s.files
}

/// The keywords that describe the mesh, read; every other one is skipped with its data lines.
const READ: [&str; 13] =
    ["NODE", "ELEMENT", "ELSET", "NSET", "SURFACE", "INCLUDE", "HEADING", "PART", "END PART", "ASSEMBLY", "END ASSEMBLY", "INSTANCE", "END INSTANCE"];

/// Keywords that make or move mesh data: skipped, the mesh would be read wrong, so a file with
/// one is refused naming it (the others not read describe no mesh).
const CHANGES_THE_MESH: [(&str, &str); 7] = [
    ("NGEN", "generates nodes"),
    ("NFILL", "generates nodes"),
    ("NCOPY", "copies nodes"),
    ("NMAP", "maps node coordinates"),
    ("ELGEN", "generates elements"),
    ("ELCOPY", "copies elements"),
    ("SYSTEM", "puts the following nodes in a local coordinate system"),
];

/// The keywords skipped in an input file and the files it includes (not describing the mesh:
/// `*MATERIAL`, `*STEP`, `*BOUNDARY`, …), each with how often it occurs, in order of first
/// occurrence; `*SURFACE` of a type not read counts as `SURFACE, TYPE=…`.
pub fn skipped(path: &Path) -> Vec<(String, usize)> {
    let mut s = Scan::default();
    s.scan(path, 0);
    s.skipped
}

/// The cheap pass of [`counts`], [`files`] and [`skipped`].
#[derive(Default)]
struct Scan {
    nodes: u64,
    elements: u64,
    bytes: u64,
    files: Vec<PathBuf>,
    skipped: Vec<(String, usize)>,
}

impl Scan {
    /// Scans `path` (and its includes); false when `path` itself cannot be read.
    fn scan(&mut self, path: &Path, depth: usize) -> bool {
        let Ok(f) = std::fs::File::open(path) else { return false };
        self.files.push(path.to_path_buf());
        self.bytes += f.metadata().map_or(0, |m| m.len());
        let mut block = 0u8; // 1 nodes, 2 elements
        for line in std::io::BufReader::new(f).split(b'\n') {
            let Ok(line) = line else { break };
            let t = String::from_utf8_lossy(&line);
            let t = t.trim();
            if t.starts_with("**") || t.is_empty() {
                continue;
            }
            if t.starts_with('*') {
                let (name, params) = keyword(t);
                let surface_type = param(&params, "TYPE").map(str::to_ascii_uppercase).filter(|t| name == "SURFACE" && t != "ELEMENT" && t != "NODE");
                if let Some(skip) = surface_type.map(|t| format!("SURFACE, TYPE={t}")).or_else(|| (!READ.contains(&name.as_str())).then(|| name.clone())) {
                    match self.skipped.iter_mut().find(|(n, _)| *n == skip) {
                        Some((_, c)) => *c += 1,
                        None => self.skipped.push((skip, 1)),
                    }
                }
                block = match name.as_str() {
                    "NODE" => 1,
                    "ELEMENT" => 2,
                    _ => 0,
                };
                if let Some(inc) = param(&params, "INPUT") {
                    if depth < MAX_DEPTH {
                        self.scan(&relative(path, inc), depth + 1);
                    }
                }
            } else if block == 1 {
                self.nodes += 1;
            } else if block == 2 && !t.ends_with(',') {
                self.elements += 1;
            }
        }
        true
    }
}

/// One line of the input after includes are expanded: its file, its number there (from 1) and
/// its text (a keyword line with its continuation lines joined).
struct Line {
    file: Rc<Path>,
    no: usize,
    text: String,
}

/// An error at line `at` of the expanded input (`None`: about the whole file).
struct Fail {
    at: Option<usize>,
    msg: String,
}

impl Fail {
    fn at(i: usize, msg: impl Into<String>) -> Self {
        Fail { at: Some(i), msg: msg.into() }
    }

    fn file(msg: impl Into<String>) -> Self {
        Fail { at: None, msg: msg.into() }
    }

    /// The error naming the file and line.
    fn into_error(self, path: &Path, lines: &[Line]) -> Error {
        match self.at.and_then(|i| lines.get(i)) {
            Some(l) => Error::mesh(l.file.display().to_string(), format!("line {}: {}", l.no, self.msg)),
            None => Error::mesh(path.display().to_string(), self.msg),
        }
    }
}

/// The directory of `file` joined with `name`.
fn relative(file: &Path, name: &str) -> PathBuf {
    file.parent().unwrap_or(Path::new("")).join(name)
}

/// Reads `path` into `out`, expanding `*INCLUDE` and `INPUT=` in place; `from` is the line that
/// names it (for the error when it cannot be read); `progress` hears the bytes of it read.
fn load(path: &Path, depth: usize, out: &mut Vec<Line>, from: Option<usize>, progress: &dyn Fn(u64, u64)) -> Result<()> {
    let here = |out: &Vec<Line>, msg: String| match from {
        Some(i) => Fail::at(i, msg).into_error(path, out),
        None => Error::mesh(path.display().to_string(), msg),
    };
    if depth > MAX_DEPTH {
        return Err(here(out, format!("includes nested deeper than {MAX_DEPTH} (does a file include itself?)")));
    }
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if from.is_some() => return Err(here(out, format!("cannot read included file {}: {e}", path.display()))),
        Err(e) => return Err(Error::io(path.display().to_string(), e)),
    };
    let text = String::from_utf8_lossy(&bytes);
    let file: Rc<Path> = Rc::from(path);
    let raw: Vec<&str> = text.lines().collect();
    let mut k = 0;
    while k < raw.len() {
        if k % 65_536 == 0 {
            progress((raw[k].as_ptr() as usize - text.as_ptr() as usize) as u64, text.len() as u64);
        }
        let no = k + 1;
        let mut t = raw[k].trim().to_string();
        k += 1;
        let is_keyword = t.starts_with('*') && !t.starts_with("**");
        if is_keyword {
            while t.ends_with(',') && k < raw.len() {
                t.push_str(raw[k].trim());
                k += 1;
            }
        }
        out.push(Line { file: file.clone(), no, text: t });
        if !is_keyword {
            continue;
        }
        let (name, params) = keyword(&out[out.len() - 1].text);
        if let Some(inc) = param(&params, "INPUT") {
            let at = out.len() - 1;
            if name == "INCLUDE" {
                out.pop();
                out.push(Line { file: file.clone(), no, text: "**".into() });
            }
            load(&relative(path, inc), depth + 1, out, Some(at), progress)?;
        }
    }
    progress(text.len() as u64, text.len() as u64);
    Ok(())
}

/// A keyword line's name (upper case, no `*`) and its parameters (upper-case keys, values with
/// quotes removed).
fn keyword(text: &str) -> (String, Vec<(String, String)>) {
    let mut parts = text.trim_start_matches('*').split(',');
    let name = parts.next().unwrap_or("").trim().to_ascii_uppercase();
    let params = parts
        .filter(|p| !p.trim().is_empty())
        .map(|p| match p.split_once('=') {
            Some((k, v)) => (k.trim().to_ascii_uppercase(), v.trim().trim_matches('"').to_string()),
            None => (p.trim().to_ascii_uppercase(), String::new()),
        })
        .collect();
    (name, params)
}

/// The value of parameter `key` (upper case).
fn param<'a>(params: &'a [(String, String)], key: &str) -> Option<&'a str> {
    params.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

/// What an element type is to this reader.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Ty {
    /// A volume element read as a cell.
    Cell(CellKind),
    /// A surface element (its corners name a face).
    Facet,
    /// A solid element of a type not read.
    Solid,
    /// Not part of the body's geometry (beams, springs, masses, 2-D elements, …).
    Ignored,
}

/// The reader's view of Abaqus element type `name` (upper case); `None` when unknown.
fn classify(name: &str) -> Option<Ty> {
    Some(match name {
        "C3D8" | "C3D8R" | "C3D8I" | "C3D8H" | "C3D8RH" | "C3D8IH" => Ty::Cell(CellKind::Hex8),
        "C3D4" | "C3D4H" => Ty::Cell(CellKind::Tet4),
        "C3D10" | "C3D10H" | "C3D10M" | "C3D10MH" => Ty::Cell(CellKind::Tet10),
        "C3D6" | "C3D6H" => Ty::Cell(CellKind::Wedge6),
        "C3D5" | "C3D5H" => Ty::Cell(CellKind::Pyr5),
        "C3D20" | "C3D20R" | "C3D20H" | "C3D20RH" => Ty::Cell(CellKind::Hex20),
        "C3D15" | "C3D15H" => Ty::Cell(CellKind::Wedge15),
        _ if ["C3D", "DC3D", "AC3D", "SC6", "SC8", "COH3D", "CCL"].iter().any(|p| name.starts_with(p)) => Ty::Solid,
        _ if ["CPS", "CPE", "S3", "S4", "S8", "S9", "STRI", "M3D", "SFM3D", "R3D", "DS3", "DS4", "DS6", "DS8"].iter().any(|p| name.starts_with(p)) => Ty::Facet,
        _ if [
            "T2D", "T3D", "B2", "B3", "PIPE", "ELBOW", "SPRING", "DASHPOT", "MASS", "ROTARYI", "CONN", "GAP", "JOINT", "FRAME", "CAX", "CGAX", "SAX", "R2D",
            "RAX", "DC1D", "DC2D", "DCAX", "ITS", "ITT", "CPEG",
        ]
        .iter()
        .any(|p| name.starts_with(p)) =>
        {
            Ty::Ignored
        }
        _ => return None,
    })
}

/// One element of the file: label, type, node labels (in the program's order), its data line.
struct Elem {
    label: u64,
    ty: Ty,
    type_name: Rc<str>,
    nodes: Vec<u64>,
    line: usize,
}

/// A named set of labels (first spelling of the name kept).
struct Set {
    name: String,
    labels: Vec<u64>,
}

/// Sets by upper-case name, in order of definition.
#[derive(Default)]
struct Sets {
    list: Vec<Set>,
    by_name: HashMap<String, usize>,
}

impl Sets {
    fn entry(&mut self, name: &str) -> &mut Vec<u64> {
        let key = name.to_ascii_uppercase();
        let i = *self.by_name.entry(key).or_insert_with(|| {
            self.list.push(Set { name: name.to_string(), labels: Vec::new() });
            self.list.len() - 1
        });
        &mut self.list[i].labels
    }

    fn get(&self, name: &str) -> Option<&Set> {
        self.by_name.get(&name.to_ascii_uppercase()).map(|&i| &self.list[i])
    }
}

/// One data line of an element-based surface: an element label or set name, the face (1-based;
/// `None`: every boundary facet), the line.
struct SurfaceItem {
    what: String,
    face: Option<usize>,
    line: usize,
}

/// An element-based surface (`node`: a node-based one, `*SURFACE, TYPE=NODE`).
struct Surface {
    name: String,
    node: bool,
    items: Vec<SurfaceItem>,
}

/// The block the data lines at hand belong to.
enum Block {
    Skip,
    Node(Option<String>),
    Element {
        ty: Ty,
        type_name: Rc<str>,
        elset: Option<String>,
        count: Option<usize>,
    },
    Elset {
        name: String,
        generate: bool,
        instance: Option<usize>,
    },
    Nset {
        name: String,
        generate: bool,
        instance: Option<usize>,
    },
    Surface(usize),
    /// The translation and rotation lines of an `*INSTANCE`.
    Instance,
}

/// The mesh part of an input file.
#[derive(Default)]
struct Deck {
    /// (label, coordinates) in file order.
    nodes: Vec<(u64, [f64; 3])>,
    node_line: FxHashMap<u64, usize>,
    elems: Vec<Elem>,
    elem_index: FxHashMap<u64, usize>,
    elsets: Sets,
    nsets: Sets,
    surfaces: Vec<Surface>,
    /// Parts by upper-case name (`*PART` … `*END PART`), each read as a deck of its own.
    parts: HashMap<String, (String, Deck)>,
    /// Instance names in order: instance `k` (from 1) holds its part's label `L` as
    /// [`assembly::shifted`]`(k, L)`.
    instances: Vec<String>,
}

/// The comma-separated fields of a data line (empty ones, as after a trailing comma, dropped).
fn fields(text: &str) -> impl Iterator<Item = &str> {
    text.split(',').map(str::trim).filter(|f| !f.is_empty())
}

fn int(f: &str, what: &str, i: usize) -> std::result::Result<u64, Fail> {
    f.parse::<u64>().map_err(|_| Fail::at(i, format!("{what} \"{f}\" is not a positive integer")))
}

fn float(f: &str, i: usize) -> std::result::Result<f64, Fail> {
    f.replace(['D', 'd'], "e").parse::<f64>().map_err(|_| Fail::at(i, format!("coordinate \"{f}\" is not a number")))
}

impl Deck {
    /// The nodes, elements, sets and surfaces of the expanded input `lines`.
    fn parse(lines: &[Line]) -> Result<Deck> {
        let mut deck = Deck::default();
        let path = lines.first().map(|l| l.file.to_path_buf()).unwrap_or_default();
        deck.read_lines(lines).map_err(|f| f.into_error(&path, lines))?;
        Ok(deck)
    }

    fn read_lines(&mut self, lines: &[Line]) -> std::result::Result<(), Fail> {
        let mut block = Block::Skip;
        let mut pending: Option<(String, usize)> = None; // an element line going on
        let mut seen_node = false;
        let mut nest = assembly::Nest::default();
        for (i, l) in lines.iter().enumerate() {
            let t = l.text.as_str();
            if t.is_empty() || t.starts_with("**") {
                continue;
            }
            if t.starts_with('*') {
                if let Some((p, at)) = pending.take() {
                    return Err(Fail::at(at, format!("element line \"{p}\" ends with a comma but no line goes on")));
                }
                let (name, params) = keyword(t);
                if self.structure(&name, &params, i, &mut nest)? {
                    block = if name == "INSTANCE" { Block::Instance } else { Block::Skip };
                    continue;
                }
                let next = self.keyword_block(&name, &params, i)?;
                if name == "NODE" {
                    seen_node = true;
                }
                block = next;
                continue;
            }
            match &block {
                Block::Skip => {}
                Block::Node(nset) => self.node_line(t, nset.as_deref(), i)?,
                Block::Element { ty, type_name, elset, count } => {
                    let (text, at) = match pending.take() {
                        Some((mut p, at)) => {
                            p.push(',');
                            p.push_str(t);
                            (p, at)
                        }
                        None => (t.to_string(), i),
                    };
                    let have = fields(&text).count();
                    if text.ends_with(',') && count.is_none_or(|c| have < c + 1) {
                        pending = Some((text, at));
                        continue;
                    }
                    self.element_line(&text, *ty, type_name, elset.as_deref(), *count, at)?;
                }
                Block::Elset { name, generate, instance } => {
                    let labels = set_line(t, *generate, &self.elsets, *instance, &self.instances, i)?;
                    self.elsets.entry(name).extend(labels);
                }
                Block::Nset { name, generate, instance } => {
                    let labels = set_line(t, *generate, &self.nsets, *instance, &self.instances, i)?;
                    self.nsets.entry(name).extend(labels);
                }
                Block::Instance => nest.data_line(t, i)?,
                Block::Surface(s) => {
                    let mut f = fields(t);
                    let what = f.next().unwrap_or("").to_string();
                    let face = match f.next() {
                        None => None,
                        Some(_) if self.surfaces[*s].node => None, // a node surface's weight
                        Some(id) => {
                            let n = id.to_ascii_uppercase().strip_prefix('S').and_then(|d| d.parse::<usize>().ok()).filter(|n| (1..=6).contains(n));
                            Some(
                                n.ok_or_else(|| Fail::at(i, format!("face identifier \"{id}\" of *SURFACE {} is not one of S1 … S6", self.surfaces[*s].name)))?,
                            )
                        }
                    };
                    self.surfaces[*s].items.push(SurfaceItem { what, face, line: i });
                }
            }
        }
        if let Some((p, at)) = pending {
            return Err(Fail::at(at, format!("element line \"{p}\" ends with a comma but no line goes on")));
        }
        nest.finish()?;
        if !seen_node {
            return Err(Fail::file("no *NODE keyword: not an Abaqus input with a mesh"));
        }
        Ok(())
    }

    /// The block a keyword line opens.
    fn keyword_block(&mut self, name: &str, params: &[(String, String)], i: usize) -> std::result::Result<Block, Fail> {
        let generate = params.iter().any(|(k, _)| k == "GENERATE");
        Ok(match name {
            "NODE" => {
                if let Some(sys) = param(params, "SYSTEM").filter(|s| !s.eq_ignore_ascii_case("R")) {
                    return Err(Fail::at(i, format!("*NODE, SYSTEM={sys}: only rectangular coordinates (SYSTEM=R) are read")));
                }
                Block::Node(param(params, "NSET").map(str::to_string))
            }
            "ELEMENT" => {
                let type_name: Rc<str> = param(params, "TYPE").ok_or_else(|| Fail::at(i, "*ELEMENT without TYPE="))?.to_ascii_uppercase().into();
                let ty = classify(&type_name).ok_or_else(|| {
                    Fail::at(i, format!("element type \"{type_name}\" is not known; volume elements read: {ABAQUS_SUPPORTED}; surface elements (CPS3, CPS4, S4R, M3D4, …) name faces"))
                })?;
                let count = match ty {
                    Ty::Cell(k) => Some(k.len()),
                    _ => None,
                };
                let elset = param(params, "ELSET").map(str::to_string);
                if let Some(e) = &elset {
                    self.elsets.entry(e);
                }
                Block::Element { ty, type_name, elset, count }
            }
            "ELSET" => {
                let name = param(params, "ELSET").ok_or_else(|| Fail::at(i, "*ELSET without ELSET="))?.to_string();
                Block::Elset { name, generate, instance: self.instance_param(params, i)? }
            }
            "NSET" => {
                let name = param(params, "NSET").ok_or_else(|| Fail::at(i, "*NSET without NSET="))?.to_string();
                Block::Nset { name, generate, instance: self.instance_param(params, i)? }
            }
            "SURFACE" => {
                let sname = param(params, "NAME").ok_or_else(|| Fail::at(i, "*SURFACE without NAME="))?.to_string();
                let ty = param(params, "TYPE").map(str::to_ascii_uppercase);
                match ty.as_deref() {
                    None | Some("ELEMENT") | Some("NODE") => {
                        self.surfaces.push(Surface { name: sname, node: ty.as_deref() == Some("NODE"), items: Vec::new() });
                        Block::Surface(self.surfaces.len() - 1)
                    }
                    _ => Block::Skip,
                }
            }
            _ => {
                if let Some((_, why)) = CHANGES_THE_MESH.iter().find(|(k, _)| *k == name) {
                    return Err(Fail::at(i, format!("*{name} {why}, which the reader does not do: skipping it would misread the mesh (write the mesh out in full, e.g. from Abaqus/CAE)")));
                }
                Block::Skip
            }
        })
    }

    fn node_line(&mut self, t: &str, nset: Option<&str>, i: usize) -> std::result::Result<(), Fail> {
        let mut f = fields(t);
        let label = int(f.next().unwrap_or(""), "node number", i)?;
        let mut p = [0.0; 3];
        for (d, x) in f.enumerate() {
            if d >= 3 {
                return Err(Fail::at(i, format!("node {label} has more than three coordinates")));
            }
            p[d] = float(x, i)?;
        }
        if p.iter().any(|x| !x.is_finite()) {
            return Err(Fail::at(i, format!("node {label} has a non-finite coordinate ({}, {}, {})", p[0], p[1], p[2])));
        }
        if let Some(&first) = self.node_line.get(&label) {
            return Err(Fail::at(i, format!("node {label} is defined twice (first on the line {} of the input)", first + 1)));
        }
        self.node_line.insert(label, i);
        self.nodes.push((label, p));
        if let Some(s) = nset {
            self.nsets.entry(s).push(label);
        }
        Ok(())
    }

    fn element_line(&mut self, text: &str, ty: Ty, type_name: &Rc<str>, elset: Option<&str>, count: Option<usize>, i: usize) -> std::result::Result<(), Fail> {
        let mut f = fields(text);
        let label = int(f.next().unwrap_or(""), "element number", i)?;
        let mut nodes = f.map(|x| int(x, "node number", i)).collect::<std::result::Result<Vec<u64>, Fail>>()?;
        if let Some(c) = count {
            if nodes.len() != c {
                return Err(Fail::at(i, format!("element {label} has {} nodes, {type_name} takes {c}", nodes.len())));
            }
        }
        if ty == Ty::Ignored || (ty == Ty::Facet && ![3, 4, 6, 8, 9].contains(&nodes.len())) {
            return Ok(());
        }
        match ty {
            Ty::Cell(CellKind::Tet10) => nodes.swap(8, 9), // Abaqus: 9 on edge 2-4, 10 on 3-4; ours 8 on (3,2), 9 on (3,1)
            Ty::Cell(CellKind::Hex20) => nodes = C3D20_TO_OURS.iter().map(|&k| nodes[k]).collect(),
            Ty::Cell(CellKind::Wedge15) => nodes = C3D15_TO_OURS.iter().map(|&k| nodes[k]).collect(),
            _ => {}
        }
        if self.elem_index.insert(label, self.elems.len()).is_some() {
            return Err(Fail::at(i, format!("element {label} is defined twice")));
        }
        self.elems.push(Elem { label, ty, type_name: type_name.clone(), nodes, line: i });
        if let Some(s) = elset {
            self.elsets.entry(s).push(label);
        }
        Ok(())
    }

    /// The body of element set `volume` (every volume element when `None`).
    fn build(&self, volume: Option<&str>) -> std::result::Result<BodyGeometry, Fail> {
        let in_set: Option<FxHashSet<u64>> = match volume {
            None => None,
            Some(name) => Some(self.elsets.get(name).ok_or_else(|| Fail::file(self.unknown_set(name)))?.labels.iter().copied().collect()),
        };
        let body: Vec<usize> = (0..self.elems.len()).filter(|&e| in_set.as_ref().is_none_or(|s| s.contains(&self.elems[e].label))).collect();
        let what = match volume {
            Some(name) => format!("element set \"{name}\""),
            None => "the file".into(),
        };
        if let Some(&e) = body.iter().find(|&&e| self.elems[e].ty == Ty::Solid) {
            let el = &self.elems[e];
            let n = body.iter().filter(|&&e| self.elems[e].ty == Ty::Solid).count();
            return Err(Fail::at(
                el.line,
                format!(
                    "{what} holds {n} solid elements of a type not read (element {}: {}); supported: {ABAQUS_SUPPORTED}",
                    self.show(el.label),
                    el.type_name
                ),
            ));
        }
        let cells_at: Vec<usize> = body.into_iter().filter(|&e| matches!(self.elems[e].ty, Ty::Cell(_))).collect();
        if cells_at.is_empty() {
            return Err(Fail::file(format!("{what} holds no volume elements; supported: {ABAQUS_SUPPORTED} (as {SUPPORTED})")));
        }
        let tags: Vec<u64> = self.nodes.iter().map(|(t, _)| *t).collect();
        let index = TagIndex::new(&tags).map_err(|i| Fail::file(format!("node {} is defined twice", self.show(tags[i]))))?;
        for &e in &cells_at {
            let el = &self.elems[e];
            if let Some(t) = el.nodes.iter().find(|&&t| !index.contains(t)) {
                return Err(Fail::at(el.line, format!("element {} refers to node {}, which no *NODE defines", self.show(el.label), self.show(*t))));
            }
        }
        let coords: Vec<[f64; 3]> = self.nodes.iter().map(|(_, p)| *p).collect();
        let file_cells: Vec<FileCell<'_>> = cells_at
            .iter()
            .map(|&e| {
                let el = &self.elems[e];
                let Ty::Cell(kind) = el.ty else { unreachable!("filtered to cells") };
                (el.label, kind, el.nodes.as_slice())
            })
            .collect();
        let (file_nodes, used) = file_cell_nodes(&file_cells, &index, coords.len()).map_err(Fail::file)?;
        check_listed_twice(&file_nodes, &file_cells).map_err(Fail::file)?;
        check_scale(&coords, &file_nodes, &file_cells).map_err(Fail::file)?;
        let (local, nodes) = used_nodes(&coords, &used);
        let mut cells: Vec<Cell> = Vec::with_capacity(file_nodes.len());
        for ((h, &(label, kind, _)), &e) in file_nodes.into_iter().zip(&file_cells).zip(&cells_at) {
            let mut cell = h;
            renumber(&mut cell, &local);
            orient(&mut cell, &nodes).map_err(|why| Fail::at(self.elems[e].line, format!("{} {} {why}", singular(kind), self.show(label))))?;
            cells.push(cell);
        }
        let cell_of: FxHashMap<u64, usize> = file_cells.iter().enumerate().map(|(c, (label, _, _))| (*label, c)).collect();
        let to_local = |t: &u64| index.get(*t).map(|i| local[i]).filter(|&l| l != usize::MAX);
        let faces = self.faces(&cells, &cell_of, &to_local)?;
        Ok(BodyGeometry { nodes, cells, faces })
    }

    /// "no element set named …" with the sets of volume elements.
    fn unknown_set(&self, name: &str) -> String {
        let known: Vec<String> = self.volume_sets().iter().map(|s| format!("\"{s}\"")).collect();
        let known = if known.is_empty() { "none".to_string() } else { known.join(", ") };
        format!("no element set named \"{name}\" (element sets of volume elements: {known})")
    }

    /// The element sets holding volume elements (read or not), in order of definition.
    fn volume_sets(&self) -> Vec<&str> {
        let vol: HashSet<u64> = self.elems.iter().filter(|e| matches!(e.ty, Ty::Cell(_) | Ty::Solid)).map(|e| e.label).collect();
        self.elsets.list.iter().filter(|s| s.labels.iter().any(|l| vol.contains(l))).map(|s| s.name.as_str()).collect()
    }

    /// The named faces: element-based surfaces, then sets of surface elements, merged by name.
    fn faces(
        &self,
        cells: &[Cell],
        cell_of: &FxHashMap<u64, usize>,
        to_local: &dyn Fn(&u64) -> Option<usize>,
    ) -> std::result::Result<Vec<(String, Vec<Facet>)>, Fail> {
        let boundary = boundary_faces(cells);
        let mut named = NamedFaces::default();
        let mut add = |name: &str, list: Vec<Facet>| named.add(name, list);
        for s in &self.surfaces {
            if s.node {
                add(&s.name, self.node_surface(s, cells, &boundary, to_local)?);
                continue;
            }
            let mut list = Vec::new();
            for item in &s.items {
                let labels: Vec<u64> = match assembly::resolve(&item.what, None, &self.instances) {
                    Some(l) => vec![l],
                    None => self
                        .elsets
                        .get(&item.what)
                        .ok_or_else(|| Fail::at(item.line, format!("*SURFACE {} names element set \"{}\", which is not defined", s.name, item.what)))?
                        .labels
                        .clone(),
                };
                for l in labels {
                    let e = *self
                        .elem_index
                        .get(&l)
                        .ok_or_else(|| Fail::at(item.line, format!("*SURFACE {} names element {}, which no *ELEMENT defines", s.name, self.show(l))))?;
                    let Some(&c) = cell_of.get(&l) else { continue };
                    let el = &self.elems[e];
                    let Ty::Cell(kind) = el.ty else { continue };
                    match item.face {
                        Some(f) => {
                            let table = abaqus_faces(kind);
                            let corners = table.get(f - 1).ok_or_else(|| {
                                Fail::at(
                                    item.line,
                                    format!("*SURFACE {}: element {} ({}) has faces S1 … S{}, not S{f}", s.name, self.show(l), singular(kind), table.len()),
                                )
                            })?;
                            let loc: Option<Vec<usize>> = corners.iter().map(|&k| to_local(&el.nodes[k])).collect();
                            if let Some(q) = loc.and_then(|loc| find_boundary_facet(&boundary, &loc)) {
                                list.push(*q);
                            }
                        }
                        None => {
                            for f in 0..cells[c].kind.faces().len() {
                                let q = cells[c].facet(c, f);
                                if boundary.contains_key(&q.key()) {
                                    list.push(q);
                                }
                            }
                        }
                    }
                }
            }
            add(&s.name, list);
        }
        for set in &self.elsets.list {
            let mut list = Vec::new();
            for l in &set.labels {
                let Some(el) = self.elem_index.get(l).map(|&e| &self.elems[e]) else { continue };
                if el.ty != Ty::Facet {
                    continue;
                }
                let n = if el.nodes.len() == 3 || el.nodes.len() == 6 { 3 } else { 4 };
                let loc: Option<Vec<usize>> = el.nodes[..n].iter().map(to_local).collect();
                if let Some(q) = loc.and_then(|loc| find_boundary_facet(&boundary, &loc)) {
                    list.push(*q);
                }
            }
            add(&set.name, list);
        }
        // every node set (what Abaqus/CAE writes for a picked face that a boundary condition
        // holds): the boundary facets all of whose nodes lie in it, merged with a surface of the
        // same name, as an Exodus node set
        if !self.nsets.list.is_empty() {
            let ordered = super::topology::boundary_in_cell_order(cells, &boundary);
            for set in &self.nsets.list {
                let nodes: HashSet<usize> = set.labels.iter().filter_map(to_local).collect();
                if !nodes.is_empty() {
                    add(&set.name, super::topology::on_nodes(&ordered, &nodes));
                }
            }
        }
        Ok(named.into_faces())
    }
}

/// The corners (0-based positions in the element's node list) of Abaqus faces S1, S2, … of a
/// cell type.
fn abaqus_faces(kind: CellKind) -> &'static [&'static [usize]] {
    const HEX: [&[usize]; 6] = [&[0, 1, 2, 3], &[4, 7, 6, 5], &[0, 4, 5, 1], &[1, 5, 6, 2], &[2, 6, 7, 3], &[3, 7, 4, 0]];
    const TET: [&[usize]; 4] = [&[0, 1, 2], &[0, 3, 1], &[1, 3, 2], &[2, 3, 0]];
    const WEDGE: [&[usize]; 5] = [&[0, 1, 2], &[3, 5, 4], &[0, 3, 4, 1], &[1, 4, 5, 2], &[2, 5, 3, 0]];
    const PYR: [&[usize]; 5] = [&[0, 1, 2, 3], &[0, 4, 1], &[1, 4, 2], &[2, 4, 3], &[3, 4, 0]];
    match kind {
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => &HEX,
        CellKind::Tet4 | CellKind::Tet10 => &TET,
        CellKind::Wedge6 | CellKind::Wedge15 => &WEDGE,
        CellKind::Pyr5 => &PYR,
    }
}

/// The labels of one `*ELSET`/`*NSET` data line: labels and set names, or `first, last, step`
/// under `GENERATE`.
fn set_line(t: &str, generate: bool, sets: &Sets, instance: Option<usize>, names: &[String], i: usize) -> std::result::Result<Vec<u64>, Fail> {
    let shift = |l: u64| instance.map_or(l, |k| assembly::shifted(k, l));
    if generate {
        let v: Vec<u64> = fields(t).map(|f| int(f, "GENERATE bound", i)).collect::<std::result::Result<_, _>>()?;
        let (a, b, s) = match v[..] {
            [a, b] => (a, b, 1),
            [a, b, s] => (a, b, s),
            _ => return Err(Fail::at(i, "GENERATE takes first, last[, step]")),
        };
        if s == 0 || b < a || (b - a) / s >= MAX_GENERATE {
            return Err(Fail::at(i, format!("GENERATE {a}, {b}, {s}: needs first ≤ last, a positive step and at most {MAX_GENERATE} labels")));
        }
        return Ok((a..=b).step_by(s as usize).map(shift).collect());
    }
    let mut out = Vec::new();
    for f in fields(t) {
        match assembly::resolve(f, instance, names) {
            Some(l) => out.push(l),
            None => {
                let name = instance.map_or_else(|| f.to_string(), |k| format!("{}.{f}", names[k - 1]));
                let set = sets.get(&name).ok_or_else(|| Fail::at(i, format!("set item \"{f}\" is neither a number nor a set defined before")))?;
                out.extend(&set.labels);
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    /// A scratch folder of its own, removed when dropped.
    struct Tmp(PathBuf);

    impl std::ops::Deref for Tmp {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for Tmp {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn tmp(tag: &str) -> Tmp {
        let d = std::env::temp_dir().join(format!("abaqus-unit-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        Tmp(d)
    }

    /// Two hexahedra stacked in z (unit cubes), nodes 1…12, with a surface on the top.
    const TWO_HEX: &str = "*Heading\n two hexes\n** comment\n*Node, nset=all\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n9, 0., 0., 2.\n10, 1., 0., 2.\n11, 1.0, 1.0, 2.0\n12, 0, 1, 2\n*element, type=C3D8R, elset=block\n1, 1, 2, 3, 4,\n 5, 6, 7, 8\n2, 5, 6, 7, 8, 9, 10, 11, 12\n*Elset, elset=upper\n2,\n*ELSET, ELSET=both, GENERATE\n1, 2, 1\n*Surface, type=ELEMENT, name=top\nupper, S2\n*SURFACE, NAME=bottom\n1, S1\n*SURFACE, NAME=skin\nboth\n*MATERIAL, NAME=steel\n*ELASTIC\n210000., 0.3\n";

    /// The reader tells its progress in bytes of the file, rising, ending at its size; the
    /// bodies read are the same as without it.
    #[test]
    fn progress_counts_the_bytes_read() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("mesh/two_blocks.inp");
        let calls = std::cell::RefCell::new(Vec::new());
        let with = read_many_with(&path, &[None], &|d, n| calls.borrow_mut().push((d, n))).unwrap();
        let size = std::fs::metadata(&path).unwrap().len();
        let calls = calls.into_inner();
        assert!(calls.windows(2).all(|w| w[0].0 <= w[1].0) && calls.iter().all(|c| c.0 <= c.1), "{calls:?}");
        assert_eq!(calls.last(), Some(&(size, size)));
        let plain = read_many(&path, &[None]).unwrap();
        assert_eq!(format!("{:?}", with[0].as_ref().unwrap().nodes), format!("{:?}", plain[0].as_ref().unwrap().nodes));
    }

    #[test]
    fn reads_two_hexes_with_surfaces() {
        let d = tmp("two");
        let g = read(&write(&d, "a.inp", TWO_HEX), None).unwrap();
        assert_eq!((g.nodes.len(), g.cells.len()), (12, 2));
        let face = |n: &str| g.faces.iter().find(|(f, _)| f == n).map(|(_, q)| q.clone()).unwrap_or_else(|| panic!("no face {n}"));
        assert_eq!(face("top").len(), 1);
        assert!(face("top")[0].nodes().iter().all(|&v| g.nodes[v][2] == 2.0));
        assert!(face("bottom")[0].nodes().iter().all(|&v| g.nodes[v][2] == 0.0));
        assert_eq!(face("skin").len(), 10);
        let upper = read(&d.join("a.inp"), Some("UPPER")).unwrap();
        assert_eq!((upper.nodes.len(), upper.cells.len()), (8, 1));
        // `*Node, nset=all`: the node set of every node is the whole skin
        assert_eq!(upper.faces.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>(), ["top", "skin", "all"]);
        assert_eq!(face("all").len(), 10);
        assert_eq!(counts(&d.join("a.inp")).map(|c| (c.0, c.1)), Some((12, 2)));
    }

    #[test]
    fn includes_are_read_relative_to_the_file() {
        let d = tmp("inc");
        let (head, rest) = TWO_HEX.split_at(TWO_HEX.find("*element").unwrap());
        std::fs::create_dir_all(d.join("sub")).unwrap();
        write(&d.join("sub"), "elems.inp", rest);
        let main = write(&d, "main.inp", &format!("{head}*INCLUDE, INPUT=sub/elems.inp\n"));
        assert_eq!(read(&main, None).unwrap().cells.len(), 2);
        assert_eq!(files(&main).len(), 2);
    }

    #[test]
    fn node_surfaces_are_the_boundary_facets_on_their_nodes() {
        let d = tmp("nodesurf");
        let text = format!("{TWO_HEX}*NSET, NSET=topn\n9, 10, 11, 12\n*SURFACE, TYPE=NODE, NAME=ntop\ntopn, 1.0\n*SURFACE, TYPE=NODE, NAME=upper_nodes\n5\n6\n7\n8, 2.5\ntopn\n");
        let g = read(&write(&d, "n.inp", &text), None).unwrap();
        let face = |n: &str| g.faces.iter().find(|(f, _)| f == n).map(|(_, q)| q.clone()).unwrap_or_else(|| panic!("no face {n}"));
        assert_eq!(face("ntop").iter().map(|q| q.key()).collect::<Vec<_>>(), face("top").iter().map(|q| q.key()).collect::<Vec<_>>());
        // nodes 5…12: the top and the four sides of the upper hexahedron (z = 1 is inside)
        let upper = face("upper_nodes");
        assert_eq!(upper.len(), 5);
        assert!(upper.iter().all(|q| q.nodes().iter().all(|&v| g.nodes[v][2] >= 1.0)));
        let e = err(&text.replace("topn, 1.0", "nowhere, 1.0"));
        assert!(e.contains("nowhere") && e.contains("line 37"), "{e}");
    }

    /// Every `*NSET` is a face: the boundary facets on its nodes (a set of the top's nodes gives
    /// the top, merged with a surface of its name; a set of the upper cell's nodes its five
    /// boundary facets; a set of nodes that bound no facet, nothing); in an instance, `inst.set`.
    #[test]
    fn node_sets_are_the_boundary_facets_on_their_nodes() {
        let d = tmp("nsets");
        let text = format!(
            "{TWO_HEX}*NSET, NSET=topn\n9, 10, 11, 12\n*NSET, NSET=upper_cell, GENERATE\n5, 12, 1\n*NSET, NSET=corners\n1, 12\n*NSET, NSET=top\n9, 10, 11\n"
        );
        let g = read(&write(&d, "n.inp", &text), None).unwrap();
        let keys = |n: &str| -> Vec<[usize; 4]> {
            let mut k: Vec<[usize; 4]> = g.faces.iter().find(|(f, _)| f == n).unwrap_or_else(|| panic!("no face {n}")).1.iter().map(|q| q.key()).collect();
            k.sort_unstable();
            k
        };
        assert_eq!(keys("topn").len(), 1);
        assert_eq!(keys("topn"), keys("top"), "the surface top and the node set topn are one facet");
        // `top` as a node set of three of the four nodes adds no facet to the surface `top`
        assert_eq!(g.faces.iter().filter(|(f, _)| f == "top").count(), 1);
        let upper = keys("upper_cell");
        assert_eq!(upper.len(), 5);
        assert!(g.faces.iter().all(|(f, _)| f != "corners"), "two nodes bound no facet");
        let p = read(&write(&d, "p.inp", CUBE_PARTS), Some("c")).unwrap();
        let face = |n: &str| p.faces.iter().find(|(f, _)| f == n).map(|(_, q)| q.iter().map(|q| q.key()).collect::<Vec<_>>());
        assert_eq!(face("c.base"), face("c.bottom"), "the part's node set, placed with its instance");
    }

    /// A unit cube as a part, placed twice: translated by (1, 0, 0) then turned 90° about z,
    /// and translated by (0, 0, 5).
    const CUBE_PARTS: &str = "*Part, name=cube\n*Node\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n5, 0, 0, 1\n6, 1, 0, 1\n7, 1, 1, 1\n8, 0, 1, 1\n*Element, type=C3D8, elset=e\n1, 1, 2, 3, 4, 5, 6, 7, 8\n*Nset, nset=base\n1, 2, 3, 4\n*Surface, type=NODE, name=bottom\nbase\n*End Part\n*Assembly, name=A\n*Instance, name=c, part=cube\n1., 0., 0.\n0., 0., 0., 0., 0., 1., 90.\n*End Instance\n*Instance, name=d, part=cube\n0., 0., 5.\n*End Instance\n*Elset, elset=_t, internal, instance=d\n1\n*Surface, type=ELEMENT, name=top\nc.e, S2\n_t, S2\n*End Assembly\n";

    #[test]
    fn instances_place_moved_copies_of_their_part() {
        let d = tmp("parts");
        let path = write(&d, "p.inp", CUBE_PARTS);
        let c = read(&path, Some("c")).unwrap();
        // node 2 (1, 0, 0): translated to (2, 0, 0), turned to (0, 2, 0); node 7 (1, 1, 1) → (2, 1, 1) → (-1, 2, 1)
        for (v, want) in [(1, [0.0, 2.0, 0.0]), (6, [-1.0, 2.0, 1.0])] {
            assert!((0..3).all(|k| (c.nodes[v][k] - want[k]).abs() < 1e-14), "{:?}", c.nodes[v]);
        }
        let face = |g: &BodyGeometry, n: &str| g.faces.iter().find(|(f, _)| f == n).map(|(_, q)| q.clone()).unwrap_or_else(|| panic!("no face {n}"));
        assert!(face(&c, "c.bottom")[0].nodes().iter().all(|&v| c.nodes[v][2].abs() < 1e-14));
        assert!(face(&c, "top")[0].nodes().iter().all(|&v| (c.nodes[v][2] - 1.0).abs() < 1e-14));
        let dd = read(&path, Some("d.e")).unwrap();
        assert_eq!(face(&dd, "top").len(), 1);
        assert!(face(&dd, "top")[0].nodes().iter().all(|&v| dd.nodes[v][2] == 6.0));
        let all = read(&path, None).unwrap();
        assert_eq!((all.nodes.len(), all.cells.len()), (16, 2));
        let e = err(&CUBE_PARTS.replace("_t, S2", "d.9, S2"));
        assert!(e.contains("element d.9") && e.contains("line 30"), "{e}");
        let e = err(&CUBE_PARTS.replace("0., 0., 0., 0., 0., 1., 90.", "1., 1., 1., 1., 1., 1., 90."));
        assert!(e.contains("line 21") && e.contains("axis"), "{e}");
    }

    fn err(text: &str) -> String {
        // a directory of its own per call: the tests run in parallel threads
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let d = tmp(&format!("err{}", CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed)));
        read(&write(&d, "bad.inp", text), None).unwrap_err().to_string()
    }

    #[test]
    fn malformed_inputs_name_the_line() {
        let e = err(&TWO_HEX.replace("2, 5, 6, 7, 8, 9, 10, 11, 12", "2, 5, 6, 7, 8, 9, 10, 11, 99"));
        assert!(e.contains("line 20") && e.contains("node 99"), "{e}");
        let e = err(&TWO_HEX.replace("C3D8R", "XYZ9"));
        assert!(e.contains("line 17") && e.contains("XYZ9"), "{e}");
        let e = err(&TWO_HEX.replace("upper, S2", "nowhere, S2"));
        assert!(e.contains("line 26") && e.contains("nowhere"), "{e}");
        let e = err(&TWO_HEX.replace("upper, S2", "upper, S9"));
        assert!(e.contains("line 26") && e.contains("S9"), "{e}");
        let e = err("*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n");
        assert!(e.contains("*NODE"), "{e}");
        let e = err(&TWO_HEX.replace("C3D8R", "C3D20"));
        assert!(e.contains("C3D20") && e.contains("line 18"), "{e}");
        let e = err(&TWO_HEX.replace("C3D8R", "C3D27"));
        assert!(e.contains("C3D27") && e.contains("line 18"), "{e}");
        let e = err("*PART, NAME=p\n*NODE\n1, 0, 0, 0\n");
        assert!(e.contains("line 1") && e.contains("*END PART"), "{e}");
        assert!(!e.contains('\n'));
        // keywords that make or move mesh data are refused, not skipped
        for (kw, what) in [("*NGEN, NSET=row", "generates nodes"), ("*Elgen, elset=more", "generates elements"), ("*SYSTEM", "local coordinate system")] {
            let e = err(&TWO_HEX.replace("*Elset, elset=upper", &format!("{kw}\n1, 2\n*Elset, elset=upper")));
            assert!(e.contains(what) && e.contains("line 21") && !e.contains('\n'), "{kw}: {e}");
        }
    }

    /// The edge nodes' corner pairs (0-based) as Abaqus numbers them (Abaqus Analysis User's
    /// Guide, "Three-dimensional solid element library", the 20-node brick and 15-node wedge
    /// figures), mapped by the permutations, are the program's edges.
    #[test]
    fn quadratic_permutations_follow_the_element_library() {
        use crate::mesh::cell::{HEX20_EDGES, WEDGE15_EDGES};
        let c3d20: [[usize; 2]; 12] = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4], [0, 4], [1, 5], [2, 6], [3, 7]];
        let c3d15: [[usize; 2]; 9] = [[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3], [0, 3], [1, 4], [2, 5]];
        let same = |a: [usize; 2], b: [usize; 2]| a == b || a == [b[1], b[0]];
        assert_eq!(C3D20_TO_OURS[..8], [0, 1, 2, 3, 4, 5, 6, 7]);
        for (e, &ours) in HEX20_EDGES.iter().enumerate() {
            assert!(same(c3d20[C3D20_TO_OURS[8 + e] - 8], ours), "hex20 edge node {}", 8 + e);
        }
        assert_eq!(C3D15_TO_OURS[..6], [0, 1, 2, 3, 4, 5]);
        for (e, &ours) in WEDGE15_EDGES.iter().enumerate() {
            assert!(same(c3d15[C3D15_TO_OURS[6 + e] - 6], ours), "wedge15 edge node {}", 6 + e);
        }
    }
}
