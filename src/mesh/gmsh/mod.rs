//! Gmsh 4.1 importer: reads one body (a physical volume, or every volume element of the file)
//! of an ASCII or binary `.msh` file into a [`BodyGeometry`], with one named face per named
//! physical surface.
//!
//! Volume elements read: 8-node hexahedra (Gmsh type 5), 4- and 10-node tetrahedra (types 4
//! and 11) and 6-node prisms (type 6, our wedges), mixed in any combination; the node orders
//! are Gmsh's, which are ours ([`super::cell`]). Any other volume element in the body (Hex20,
//! Hex27, pyramids, Pri15/18, tetrahedra of order 3, …) is an error naming its type and count.
//! Every cell is checked corner by corner: consistently inverted ones (mirrored) are
//! reordered, degenerate or twisted ones are an error naming the element tag; a 10-node
//! tetrahedron must also have a positive Jacobian throughout. A cell listed twice (the same
//! node set under two tags) is an error, and so are edges or coordinates outside the length
//! scale double precision carries.
//!
//! Faces: the triangles and quadrangles (3, 4, 6 and 8 nodes: Gmsh types 2, 3, 9, 16) of each
//! physical surface are looked up, by their corners, among the boundary facets of the kept
//! cells; the cell's own outward facet is stored (so a face's facets are always outward and of
//! the cell's kind: a 3-node triangle on a 10-node tetrahedron gives its 6-node facet).
//! Surface elements that bound no kept cell are skipped, surfaces left with none dropped.
//!
//! `mshio` parses the `$Entities`, `$Nodes` and `$Elements` sections. Two small pieces are read
//! here directly, because `mshio` drops them: the `$PhysicalNames` section, and the node tags
//! (which `mshio` discards whenever they are contiguous, although their order still matters).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::Path;

use mshio::{ElementType, MshFile, MshParserError};

use super::cell::MAX_CELL_NODES;
use super::tags::TagIndex;
use super::topology::{boundary_faces, find_boundary_facet};
use super::{BodyGeometry, Cell, CellKind, Facet};
use crate::error::{Error, Result};

/// Prefix of every message about a file that cannot be parsed at all.
const UNREADABLE: &str = "not a readable Gmsh 4.1 mesh";

/// Reads the cells (hex8, tet4, tet10, wedge6) of physical volume `volume` (every volume element
/// of the file when `None`) from the Gmsh 4.1 file `path`, in a compact local numbering that
/// keeps the file's node order.
///
/// Every physical surface (named by its number when it has no name) becomes a face made of the
/// outward boundary facets of the kept cells that its triangles and quadrangles name; surfaces
/// with no such facet are left out.
pub fn read(path: &Path, volume: Option<&str>) -> Result<BodyGeometry> {
    read_many(path, &[volume])?.pop().expect("one volume asked, one body read")
}

/// [`read`] for several bodies of one file: the file is read and parsed once, then each body of
/// `volumes` is built from the parsed file. The outer error is the file's (unreadable,
/// malformed); the inner ones are each body's (a volume not in the file, a bad cell).
pub fn read_many(path: &Path, volumes: &[Option<&str>]) -> Result<Vec<Result<BodyGeometry>>> {
    read_many_with(path, volumes, &|_, _| ())
}

/// [`read_many`], telling `progress(done, total)` the bytes of the file read so far (a pipe:
/// its total is what has arrived).
pub fn read_many_with(path: &Path, volumes: &[Option<&str>], progress: &dyn Fn(u64, u64)) -> Result<Vec<Result<BodyGeometry>>> {
    let file = path.display().to_string();
    let parsed = Parsed::read(path, progress)?;
    Ok(volumes.iter().map(|&v| parsed.build(v).map_err(|msg| Error::mesh(&file, msg))).collect())
}

/// The names the `volume` of a body may take in the Gmsh file `path` (its physical volumes, a
/// nameless one by its number, in order of their numbers, each name once) and the bodies
/// ([`super::Survey`]), from one parse. The error is the file's, as [`read_many`] gives it.
pub fn survey(path: &Path) -> Result<super::Survey> {
    let file = path.display().to_string();
    let parsed = Parsed::read(path, &|_, _| ())?;
    let mut names: Vec<String> = Vec::new();
    for n in known_volumes(&parsed.msh, &parsed.names).into_values() {
        if !names.contains(&n) {
            names.push(n);
        }
    }
    let bodies = std::iter::once(None).chain(names.iter().map(|n| Some(n.as_str()))).map(|v| parsed.build(v).map_err(|msg| Error::mesh(&file, msg))).collect();
    Ok((names, bodies))
}

/// The whole file, its buffer reserved first: a file larger than the memory left is an error,
/// not an abort. A pipe (`/dev/stdin`) is read once, as it arrives, each chunk's memory
/// reserved before it is read.
fn read_bytes(path: &Path, progress: &dyn Fn(u64, u64)) -> Result<Vec<u8>> {
    use std::io::Read;
    const CHUNK: usize = 1 << 22;
    let file = path.display().to_string();
    let mut f = std::fs::File::open(path).map_err(|e| Error::io(&file, e))?;
    let meta = f.metadata().map_err(|e| Error::io(&file, e))?;
    if meta.is_file() {
        let mut bytes = super::try_vec::<u8>("the file's bytes", (meta.len() as usize).saturating_add(1))?;
        // in chunks into the reserved buffer, for the monitor
        while f.by_ref().take(CHUNK as u64).read_to_end(&mut bytes).map_err(|e| Error::io(&file, e))? > 0 {
            progress(bytes.len() as u64, meta.len().max(bytes.len() as u64));
        }
        return Ok(bytes);
    }
    let mut bytes: Vec<u8> = Vec::new();
    loop {
        bytes
            .try_reserve(CHUNK)
            .map_err(|_| Error::memory(&file, format!("the piped mesh does not fit in memory after {} read", crate::error::human_bytes(bytes.len() as f64))))?;
        let n = f.by_ref().take(CHUNK as u64).read_to_end(&mut bytes).map_err(|e| Error::io(&file, e))?;
        if n == 0 {
            return Ok(bytes);
        }
        progress(bytes.len() as u64, bytes.len() as u64);
    }
}

/// Nodes and elements as the `$Nodes` and `$Elements` section headers give them (each at
/// most the file's size in bytes), found by streaming the file — nothing of its size is
/// allocated; `None` where the file cannot be opened or a header is not found (the reader then
/// says what is wrong with it).
pub fn header_counts(path: &Path) -> Option<(u64, u64, u64)> {
    use std::io::{Seek, SeekFrom};
    let mut f = std::fs::File::open(path).ok()?;
    // a pipe can be read once only: the reader takes it, its estimate is what arrives
    let meta = f.metadata().ok().filter(std::fs::Metadata::is_file)?;
    let size = meta.len();
    let mut head = vec![0u8; 512];
    let n = read_up_to(&mut f, &mut head);
    let encoding = check_header(&head[..n]).ok()?;
    // the offsets just past the lines `$Nodes` and `$Elements`, in one pass over the file
    let tags: [&[u8]; 2] = [b"\n$Nodes", b"\n$Elements"];
    let mut found = [None::<u64>; 2];
    f.seek(SeekFrom::Start(0)).ok()?;
    let mut buf = vec![0u8; 1 << 20];
    let mut carry: Vec<u8> = Vec::new();
    let mut base = 0u64; // file offset of carry[0]
    loop {
        let n = read_up_to(&mut f, &mut buf);
        if n == 0 {
            break;
        }
        carry.extend_from_slice(&buf[..n]);
        for (k, tag) in tags.iter().enumerate() {
            if found[k].is_some() {
                continue;
            }
            let mut from = 0;
            while let Some(p) = carry[from..].windows(tag.len()).position(|w| w == *tag) {
                let end = from + p + tag.len();
                match carry.get(end) {
                    Some(b'\n') => {
                        found[k] = Some(base + end as u64 + 1);
                        break;
                    }
                    Some(b'\r') if carry.get(end + 1) == Some(&b'\n') => {
                        found[k] = Some(base + end as u64 + 2);
                        break;
                    }
                    _ => from += p + 1,
                }
            }
        }
        if found.iter().all(Option::is_some) {
            break;
        }
        let keep = carry.len().min(16);
        base += (carry.len() - keep) as u64;
        carry.drain(..carry.len() - keep);
    }
    let mut second = |at: u64| -> Option<u64> {
        f.seek(SeekFrom::Start(at)).ok()?;
        let mut b = [0u8; 128];
        let n = read_up_to(&mut f, &mut b);
        match encoding {
            Encoding::Ascii => std::str::from_utf8(&b[..n]).ok()?.split_whitespace().nth(1)?.parse().ok(),
            Encoding::Binary { size_t, big_endian } if (1..=8).contains(&size_t) && n >= 2 * size_t => {
                let w = &b[size_t..2 * size_t];
                let mut x = [0u8; 8];
                if big_endian {
                    x[8 - size_t..].copy_from_slice(w);
                    Some(u64::from_be_bytes(x))
                } else {
                    x[..size_t].copy_from_slice(w);
                    Some(u64::from_le_bytes(x))
                }
            }
            _ => None,
        }
    };
    let nodes = second(found[0]?)?.min(size);
    let elements = second(found[1]?)?.min(size);
    Some((nodes, elements, size))
}

fn read_up_to(f: &mut std::fs::File, buf: &mut [u8]) -> usize {
    use std::io::Read;
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..]) {
            Ok(0) | Err(_) => break,
            Ok(k) => n += k,
        }
    }
    n
}

/// A file parsed once: mshio's sections, the physical names and the node tags, from which
/// [`Parsed::build`] makes any of its bodies.
struct Parsed {
    msh: Msh,
    names: HashMap<(i32, i32), String>,
    tags: Vec<u64>,
}

impl Parsed {
    /// Reads and parses the file `path`; errors name it.
    fn read(path: &Path, progress: &dyn Fn(u64, u64)) -> Result<Self> {
        let file = path.display().to_string();
        let bytes = read_bytes(path, progress).map_err(|e| match e {
            Error::Memory { msg, .. } => Error::memory(&file, msg),
            e => e,
        })?;
        Parsed::new(&bytes).map_err(|msg| Error::mesh(&file, msg))
    }

    /// Parses the bytes of a whole file.
    fn new(bytes: &[u8]) -> Result<Self, String> {
        let encoding = check_header(bytes)?;
        // mshio still has a few `unimplemented!`/overflow paths on malformed input: never let them
        // escape as a panic.
        let msh = std::panic::catch_unwind(|| mshio::parse_msh_bytes(bytes).map_err(|e| describe(bytes, encoding, &e)))
            .map_err(|_| format!("{UNREADABLE}: the parser gave up on malformed content"))??;
        for (present, section) in [(msh.data.nodes.is_some(), "$Nodes"), (msh.data.elements.is_some(), "$Elements")] {
            if !present {
                return Err(format!("{UNREADABLE}: it has no {section} section"));
            }
        }
        let names = physical_names(bytes)?;
        let tags = node_tags(bytes, encoding, &msh)?;
        Ok(Parsed { msh, names, tags })
    }

    /// Body `volume` (every volume element when `None`) of the parsed file.
    fn build(&self, volume: Option<&str>) -> Result<BodyGeometry, String> {
        build(&self.msh, &self.names, &self.tags, volume)
    }
}

/// Body `volume` of the file whose bytes are `bytes`.
#[cfg(test)]
fn parse(bytes: &[u8], volume: Option<&str>) -> Result<BodyGeometry, String> {
    Parsed::new(bytes)?.build(volume)
}

// ---------------------------------------------------------------------------------------------
// Header, physical names and node tags (read here, not by mshio)

/// How the file stores numbers, from its `$MeshFormat` header.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    Binary { size_t: usize, big_endian: bool },
}

/// Checks the `$MeshFormat` header before mshio sees the file, for a clear message on other
/// versions and for binary word sizes that mshio would panic on.
fn check_header(bytes: &[u8]) -> Result<Encoding, String> {
    let mut lines = bytes.split(|&b| b == b'\n');
    let first = lines.next().unwrap_or_default();
    if first.strip_suffix(b"\r").unwrap_or(first) != b"$MeshFormat" {
        return Err(format!("{UNREADABLE}: it does not start with $MeshFormat"));
    }
    let line = lines.next().unwrap_or_default();
    let fields: Vec<&str> = std::str::from_utf8(line).unwrap_or("").split_whitespace().collect();
    match fields.as_slice() {
        ["4.1", "0", _] => Ok(Encoding::Ascii),
        ["4.1", "1", size @ ("1" | "2" | "4" | "8" | "16")] => {
            // The header line is followed by the binary int 1, which tells the byte order.
            let at = first.len() + 1 + line.len() + 1;
            let one = bytes.get(at..at + 4).ok_or_else(|| format!("{UNREADABLE}: truncated $MeshFormat header"))?;
            if one != [1, 0, 0, 0] && one != [0, 0, 0, 1] {
                return Err(format!("{UNREADABLE}: the header says binary (file-type 1) but no binary integer 1 follows it (line 3)"));
            }
            Ok(Encoding::Binary { size_t: size.parse().unwrap_or(8), big_endian: one == [0, 0, 0, 1] })
        }
        [version, ..] if *version != "4.1" => {
            Err(format!("{UNREADABLE}: format version {}, re-export it with `-format msh41`", version.chars().take(10).collect::<String>()))
        }
        _ => Err(format!("{UNREADABLE}: malformed $MeshFormat header")),
    }
}

/// One line from a mshio error: what failed, inside which sections and blocks, and where.
fn describe(bytes: &[u8], encoding: Encoding, err: &MshParserError<&[u8]>) -> String {
    use mshio::error::MshParserErrorKind as K;
    let trace = err.filtered_backtrace();
    let what = trace.iter().find_map(|(_, kind)| match kind {
        K::UnsupportedMshVersion => Some("unsupported format version".to_string()),
        K::UnsupportedTypeSize(ty, n) => Some(format!("unsupported size {n} of binary {ty} values")),
        K::InvalidFileHeader => Some("invalid $MeshFormat header".to_string()),
        K::InvalidSectionHeader => Some("expected the start of a section".to_string()),
        K::UnknownElement => Some("unknown element type".to_string()),
        K::TooManyEntities => Some("too many entities".to_string()),
        K::ValueOutOfRange(ty) => Some(format!("{ty} value out of range")),
        K::InvalidTag => Some("invalid tag".to_string()),
        K::InvalidParameter => Some("invalid parameter".to_string()),
        K::InvalidElementDefinition => Some("invalid element definition".to_string()),
        K::InvalidNodeDefinition => Some("invalid node definition".to_string()),
        K::Unimplemented => Some("unsupported feature".to_string()),
        K::Context(_) | K::NomError(_) => None,
    });
    // Outermost first: section, block, item (mshio's "Expected N ..." notes only repeat counts).
    let contexts: Vec<&str> = trace.iter().rev().filter_map(|(_, k)| k.context()).filter(|c| !c.starts_with("Expected ")).collect();
    let rest = trace.first().or(err.backtrace.first()).map_or(&[][..], |(rest, _)| *rest);
    let place = if rest.is_empty() {
        "at the end of the file".to_string()
    } else {
        let offset = bytes.len().saturating_sub(rest.len());
        match encoding {
            Encoding::Ascii => format!("line {}", bytes[..offset].iter().filter(|&&b| b == b'\n').count() + 1),
            Encoding::Binary { .. } => format!("byte {offset}"),
        }
    };
    if let (None, true, Encoding::Ascii) = (&what, contexts.is_empty(), encoding) {
        let offset = bytes.len().saturating_sub(rest.len());
        if let Some(name) = open_section(&bytes[..offset]) {
            return format!("{UNREADABLE}: expected $End{name} to close the ${name} section ({place})");
        }
    }
    let what = what.unwrap_or_else(|| if rest.is_empty() { "unexpected end of file".to_string() } else { "unexpected content".to_string() });
    if contexts.is_empty() {
        format!("{UNREADABLE}: {what} ({place})")
    } else {
        format!("{UNREADABLE}: {what} in {} ({place})", contexts.join(" > "))
    }
}

/// The section still open at the end of `head` (a `$Name` line with no `$EndName` after it).
fn open_section(head: &[u8]) -> Option<String> {
    let mut open: Option<&[u8]> = None;
    for line in head.split(|&b| b == b'\n') {
        let Some(name) = line.trim_ascii().strip_prefix(b"$") else {
            continue;
        };
        match name.strip_prefix(b"End") {
            Some(end) if open == Some(end) => open = None,
            Some(_) => {}
            None => open = Some(name),
        }
    }
    open.map(|n| String::from_utf8_lossy(n).into_owned())
}

/// Offset just past the line `$name` (a section start), if the file has that section.
fn section_start(bytes: &[u8], name: &str) -> Option<usize> {
    let tag = format!("${name}");
    let tag = tag.as_bytes();
    let mut from = 0;
    while let Some(pos) = bytes[from..].windows(tag.len()).position(|w| w == tag) {
        let at = from + pos;
        let end = at + tag.len();
        let line_start = at == 0 || bytes[at - 1] == b'\n';
        let rest = &bytes[end..];
        let eol = if rest.starts_with(b"\r\n") {
            Some(2)
        } else if rest.starts_with(b"\n") {
            Some(1)
        } else {
            None
        };
        if let (true, Some(eol)) = (line_start, eol) {
            return Some(end + eol);
        }
        from = at + 1;
    }
    None
}

/// `(dim, tag) -> name` from the `$PhysicalNames` section; empty when the section is absent.
fn physical_names(bytes: &[u8]) -> Result<HashMap<(i32, i32), String>, String> {
    let mut names = HashMap::new();
    let Some(start) = section_start(bytes, "PhysicalNames") else {
        return Ok(names);
    };
    let bad = |what: &str| format!("{UNREADABLE}: malformed $PhysicalNames section ({what})");
    let mut lines = bytes[start..].split(|&b| b == b'\n').map(|l| String::from_utf8_lossy(l).trim().to_string());
    let count: usize = lines.next().and_then(|l| l.parse().ok()).ok_or_else(|| bad("no count"))?;
    for i in 0..count {
        let line = lines.next().unwrap_or_default();
        let parsed = (|| {
            let mut it = line.splitn(3, char::is_whitespace);
            let dim: i32 = it.next()?.parse().ok()?;
            let tag: i32 = it.next()?.trim().parse().ok()?;
            let name = it.next()?.trim().strip_prefix('"')?.strip_suffix('"')?;
            Some(((dim, tag), name.to_string()))
        })();
        let (key, name) = parsed.ok_or_else(|| bad(&format!("entry {} of {count}", i + 1)))?;
        names.insert(key, name);
    }
    if lines.next().as_deref() != Some("$EndPhysicalNames") {
        return Err(bad("missing $EndPhysicalNames"));
    }
    Ok(names)
}

/// The node tags of the `$Nodes` section in file order (one per node of mshio's node blocks).
fn node_tags(bytes: &[u8], encoding: Encoding, msh: &MshFile<u64, i32, f64>) -> Result<Vec<u64>, String> {
    let Some(nodes) = &msh.data.nodes else {
        return Ok(Vec::new());
    };
    let bad = || format!("{UNREADABLE}: malformed $Nodes section");
    let start = section_start(bytes, "Nodes").ok_or_else(bad)?;
    let sizes: Vec<usize> = nodes.node_blocks.iter().map(|b| b.nodes.len()).collect();
    let tags = match encoding {
        Encoding::Ascii => ascii_node_tags(&bytes[start..], &sizes),
        Encoding::Binary { size_t, big_endian } => binary_node_tags(&bytes[start..], &sizes, size_t, big_endian),
    };
    tags.ok_or_else(bad)
}

fn ascii_node_tags(text: &[u8], sizes: &[usize]) -> Option<Vec<u64>> {
    let mut tokens = text.split(|b| b.is_ascii_whitespace()).filter(|t| !t.is_empty());
    let num = |t: &[u8]| -> Option<u64> { std::str::from_utf8(t).ok()?.parse().ok() };
    if num(tokens.next()?)? != sizes.len() as u64 {
        return None;
    }
    for _ in 0..3 {
        tokens.next()?; // total nodes, min and max tag
    }
    let mut tags = Vec::with_capacity(sizes.iter().sum());
    for &n in sizes {
        for _ in 0..3 {
            tokens.next()?; // entity dim, entity tag, parametric (0: mshio rejects parametric nodes)
        }
        if num(tokens.next()?)? != n as u64 {
            return None;
        }
        for _ in 0..n {
            tags.push(num(tokens.next()?)?);
        }
        for _ in 0..3 * n {
            tokens.next()?;
        }
    }
    Some(tags)
}

fn binary_node_tags(data: &[u8], sizes: &[usize], size_t: usize, big_endian: bool) -> Option<Vec<u64>> {
    let mut pos = 0usize;
    let mut take = |len: usize| -> Option<&[u8]> {
        let s = data.get(pos..pos.checked_add(len)?)?;
        pos += len;
        Some(s)
    };
    let word = |b: &[u8]| -> Option<u64> {
        let mut buf = [0u8; 16];
        let n = b.len();
        if big_endian {
            buf[16 - n..].copy_from_slice(b);
            u64::try_from(u128::from_be_bytes(buf)).ok()
        } else {
            buf[..n].copy_from_slice(b);
            u64::try_from(u128::from_le_bytes(buf)).ok()
        }
    };
    if size_t > 16 || word(take(size_t)?)? != sizes.len() as u64 {
        return None;
    }
    take(3 * size_t)?;
    let mut tags = Vec::with_capacity(sizes.iter().sum());
    for &n in sizes {
        take(12)?; // entity dim, entity tag, parametric: 3 ints
        if word(take(size_t)?)? != n as u64 {
            return None;
        }
        for _ in 0..n {
            tags.push(word(take(size_t)?)?);
        }
        take(n.checked_mul(24)?)?;
    }
    Some(tags)
}

// ---------------------------------------------------------------------------------------------
// Assembling the body

/// A physical group's display name: its `$PhysicalNames` entry, or its number.
fn group_name(names: &HashMap<(i32, i32), String>, dim: i32, tag: i32) -> String {
    names.get(&(dim, tag)).cloned().unwrap_or_else(|| tag.to_string())
}

/// `"Hex8: 54, Qua4: 18"`, by element type number.
fn type_counts(counts: &HashMap<ElementType, usize>) -> String {
    let mut v: Vec<(ElementType, usize)> = counts.iter().map(|(&t, &c)| (t, c)).collect();
    v.sort_by_key(|(t, _)| *t as i32);
    if v.is_empty() {
        return "no elements".to_string();
    }
    v.iter().map(|(t, c)| format!("{t:?}: {c}")).collect::<Vec<_>>().join(", ")
}

/// A parsed Gmsh file.
type Msh = MshFile<u64, i32, f64>;

/// A volume element of the body as the file gives it: its tag, cell type and node tags.
pub(super) type FileCell<'m> = (u64, CellKind, &'m [u64]);

/// The body of a parsed file: its cells in a compact local numbering, and its named faces.
fn build(msh: &Msh, names: &HashMap<(i32, i32), String>, tags: &[u64], volume: Option<&str>) -> Result<BodyGeometry, String> {
    let entities = msh.data.entities.as_ref();
    let surfaces = entities.map_or(&[][..], |e| e.surfaces.as_slice());
    let surf_groups: HashMap<i32, &[i32]> = surfaces.iter().map(|s| (s.tag, s.physical_tags.as_slice())).collect();
    let selected = selected_volumes(msh, names, volume)?;
    let in_body = |entity: i32| selected.as_ref().is_none_or(|s| s.contains(&entity));
    let elements = Elements::scan(msh, in_body);
    elements.check_cells(volume)?;
    let file_cells = &elements.file_cells;
    let (coords, index) = node_index(msh, tags)?;
    check_surface_nodes(msh, &index)?;
    let (file_nodes, used) = file_cell_nodes(file_cells, &index, coords.len())?;
    check_listed_twice(&file_nodes, file_cells)?;
    check_scale(&coords, &file_nodes, file_cells)?;
    let (local, nodes) = used_nodes(&coords, &used);

    // Cells in local numbering, each oriented (consistently inverted ones reordered).
    let mut cells: Vec<Cell> = Vec::with_capacity(file_nodes.len());
    for (mut cell, &(etag, kind, _)) in file_nodes.into_iter().zip(file_cells) {
        renumber(&mut cell, &local);
        orient(&mut cell, &nodes).map_err(|why| format!("{} {etag} {why}", singular(kind)))?;
        cells.push(cell);
    }
    let faces = named_faces(names, &surf_groups, &elements.surface_elems, &index, &local, &cells);
    Ok(BodyGeometry { nodes, cells, faces })
}

/// Which volume entities make up the body: those of physical volume `volume` (None: every one).
fn selected_volumes(msh: &Msh, names: &HashMap<(i32, i32), String>, volume: Option<&str>) -> Result<Option<HashSet<i32>>, String> {
    let Some(name) = volume else {
        return Ok(None);
    };
    let volumes = msh.data.entities.as_ref().map_or(&[][..], |e| e.volumes.as_slice());
    let vol_groups: HashMap<i32, &[i32]> = volumes.iter().map(|v| (v.tag, v.physical_tags.as_slice())).collect();
    let known = known_volumes(msh, names);
    let wanted: HashSet<i32> = known.iter().filter(|(_, n)| n.as_str() == name).map(|(t, _)| *t).collect();
    if wanted.is_empty() {
        let list: Vec<String> = known.values().map(|n| format!("\"{n}\"")).collect();
        let list = if list.is_empty() { "none".to_string() } else { list.join(", ") };
        return Err(format!("no physical volume named \"{name}\" (known: {list})"));
    }
    Ok(Some(vol_groups.iter().filter(|(_, g)| g.iter().any(|t| wanted.contains(t))).map(|(&e, _)| e).collect()))
}

/// The physical volumes of the file by number: those `$PhysicalNames` names, and those the
/// volume entities carry (a nameless one named by its number).
fn known_volumes(msh: &Msh, names: &HashMap<(i32, i32), String>) -> BTreeMap<i32, String> {
    let volumes = msh.data.entities.as_ref().map_or(&[][..], |e| e.volumes.as_slice());
    let mut known: BTreeMap<i32, String> = names.iter().filter(|((d, _), _)| *d == 3).map(|((_, t), n)| (*t, n.clone())).collect();
    for v in volumes {
        for &t in &v.physical_tags {
            known.entry(t).or_insert_with(|| group_name(names, 3, t));
        }
    }
    known
}

/// The elements of the file: the cells of the body (other 3D types for the diagnostics) and
/// the surface elements of every surface entity.
struct Elements<'m> {
    /// Elements of each type in the file, and of each 3D type in the body.
    all_counts: HashMap<ElementType, usize>,
    body_3d: HashMap<ElementType, usize>,
    /// The body's volume elements of a type not read.
    unsupported: HashMap<ElementType, usize>,
    file_cells: Vec<FileCell<'m>>,
    /// Surface entity → the node tags of its triangles and quadrangles.
    surface_elems: HashMap<i32, Vec<&'m [u64]>>,
}

impl<'m> Elements<'m> {
    /// Sorts the file's element blocks: volume ones of the entities `in_body`, surface ones.
    fn scan(msh: &'m Msh, in_body: impl Fn(i32) -> bool) -> Self {
        let mut all_counts: HashMap<ElementType, usize> = HashMap::new();
        let mut body_3d: HashMap<ElementType, usize> = HashMap::new();
        let mut unsupported: HashMap<ElementType, usize> = HashMap::new();
        let mut file_cells: Vec<FileCell<'m>> = Vec::new();
        let mut surface_elems: HashMap<i32, Vec<&[u64]>> = HashMap::new();
        for block in msh.data.elements.iter().flat_map(|e| &e.element_blocks) {
            *all_counts.entry(block.element_type).or_default() += block.elements.len();
            if block.entity_dim == 3 && in_body(block.entity_tag) {
                *body_3d.entry(block.element_type).or_default() += block.elements.len();
                match cell_kind(block.element_type) {
                    Some(kind) => file_cells.extend(block.elements.iter().map(|e| (e.element_tag, kind, e.nodes.as_slice()))),
                    None => *unsupported.entry(block.element_type).or_default() += block.elements.len(),
                }
            } else if block.entity_dim == 2 && surface_kind(block.element_type).is_some() {
                surface_elems.entry(block.entity_tag).or_default().extend(block.elements.iter().map(|e| e.nodes.as_slice()));
            }
        }
        Elements { all_counts, body_3d, unsupported, file_cells, surface_elems }
    }

    /// Refuses a body with volume elements of a type not read, or with none.
    fn check_cells(&self, volume: Option<&str>) -> Result<(), String> {
        let body = match volume {
            Some(name) => format!("physical volume \"{name}\""),
            None => "the file".to_string(),
        };
        if !self.unsupported.is_empty() {
            return Err(format!("{body} contains volume elements of a type not supported ({}); supported: {SUPPORTED}", type_counts(&self.unsupported)));
        }
        if self.file_cells.is_empty() {
            let (what, found) = match volume {
                Some(_) => (format!("{body} contains"), type_counts(&self.body_3d)),
                None => ("contains".to_string(), type_counts(&self.all_counts)),
            };
            return Err(format!("{what} no volume elements (found: {found}); supported: {SUPPORTED}"));
        }
        Ok(())
    }
}

/// The coordinates of every node in file order, and the file index of every tag (each tag
/// once, every coordinate finite).
fn node_index(msh: &Msh, tags: &[u64]) -> Result<(Vec<[f64; 3]>, TagIndex), String> {
    let coords: Vec<[f64; 3]> = msh.data.nodes.iter().flat_map(|n| &n.node_blocks).flat_map(|b| b.nodes.iter().map(|p| [p.x, p.y, p.z])).collect();
    if coords.len() != tags.len() {
        return Err(format!("{UNREADABLE}: malformed $Nodes section"));
    }
    // the first fault in file order: a tag defined twice, or a non-finite coordinate before it
    let index = TagIndex::new(tags);
    let twice = *index.as_ref().err().unwrap_or(&tags.len());
    if let Some((t, p)) = tags[..twice].iter().zip(&coords).find(|(_, p)| p.iter().any(|x| !x.is_finite())) {
        return Err(format!("node {t} has a non-finite coordinate ({}, {}, {})", p[0], p[1], p[2]));
    }
    let index = index.map_err(|i| format!("node {} is defined twice in $Nodes", tags[i]))?;
    Ok((coords, index))
}

/// Refuses surface elements that name nodes the file does not define (those of other volumes
/// are fine: such facets are skipped in [`named_faces`]).
fn check_surface_nodes(msh: &Msh, index: &TagIndex) -> Result<(), String> {
    let blocks = msh.data.elements.iter().flat_map(|e| &e.element_blocks);
    for block in blocks.filter(|b| b.entity_dim == 2) {
        let Some((_, name)) = surface_kind(block.element_type) else { continue };
        for e in &block.elements {
            if let Some(t) = e.nodes.iter().find(|&&t| !index.contains(t)) {
                return Err(format!("{name} {} refers to node {t}, which is not in $Nodes", e.element_tag));
            }
        }
    }
    Ok(())
}

/// The nodes the cells use, in file order: each file node's local index (`usize::MAX` where
/// unused) and the coordinates of the used ones.
pub(super) fn used_nodes(coords: &[[f64; 3]], used: &[bool]) -> (Vec<usize>, Vec<[f64; 3]>) {
    let mut local = vec![usize::MAX; coords.len()];
    let mut nodes = Vec::new();
    for (i, p) in coords.iter().enumerate().filter(|(i, _)| used[*i]) {
        local[i] = nodes.len();
        nodes.push(*p);
    }
    (local, nodes)
}

/// The cells in file indices, and which of the `n` file nodes they use.
pub(super) fn file_cell_nodes(file_cells: &[FileCell<'_>], index: &TagIndex, n: usize) -> Result<(Vec<Cell>, Vec<bool>), String> {
    let mut file_nodes: Vec<Cell> = Vec::with_capacity(file_cells.len());
    let mut used = vec![false; n];
    let mut h = [0usize; MAX_CELL_NODES];
    for &(etag, kind, nodes) in file_cells {
        if nodes.len() != kind.len() {
            return Err(format!("{} {etag} has {} nodes, expected {}", singular(kind), nodes.len(), kind.len()));
        }
        for (slot, &t) in h.iter_mut().zip(nodes) {
            let i = index.get(t).ok_or_else(|| format!("{} {etag} refers to node {t}, which is not in $Nodes", singular(kind)))?;
            used[i] = true;
            *slot = i;
        }
        file_nodes.push(Cell::new(kind, &h[..nodes.len()]));
    }
    Ok((file_nodes, used))
}

/// A cell of file indices renumbered to the local ones `local`.
pub(super) fn renumber(cell: &mut Cell, local: &[usize]) {
    for v in cell.nodes_mut() {
        *v = local[*v];
    }
}

/// Refuses a cell listed twice (the same nodes, in any order, under another tag): it would be
/// counted twice, and its faces would stop being boundary faces (a clamped face loses them).
pub(super) fn check_listed_twice(file_nodes: &[Cell], file_cells: &[FileCell<'_>]) -> Result<(), String> {
    // sorted by (type, four smallest nodes, file order): a repeat lies in a run of equal
    // prefixes, where the whole sorted node lists are compared; the first in file order wins
    let sorted = |c: usize| {
        let mut k = file_nodes[c].nodes().to_vec();
        k.sort_unstable();
        k
    };
    let mut low = [0usize; MAX_CELL_NODES];
    let mut order: Vec<([usize; 5], usize)> = file_nodes
        .iter()
        .enumerate()
        .map(|(c, h)| {
            let mut k = [usize::MAX; 5];
            k[0] = file_cells[c].1.code();
            let low = &mut low[..h.nodes().len()];
            low.copy_from_slice(h.nodes());
            low.sort_unstable();
            for (slot, &v) in k[1..].iter_mut().zip(low.iter()) {
                *slot = v;
            }
            (k, c)
        })
        .collect();
    order.sort_unstable();
    let mut repeat: Option<(usize, usize)> = None; // (second, first) in file order
    for run in order.chunk_by(|a, b| a.0 == b.0).filter(|r| r.len() > 1) {
        let full: Vec<Vec<usize>> = run.iter().map(|&(_, c)| sorted(c)).collect();
        for j in 1..run.len() {
            if let Some(i) = (0..j).find(|&i| full[i] == full[j]) {
                if repeat.is_none_or(|(second, _)| run[j].1 < second) {
                    repeat = Some((run[j].1, run[i].1));
                }
                break;
            }
        }
    }
    if let Some((second, first)) = repeat {
        let (first, (etag, kind, _)) = (file_cells[first].0, file_cells[second]);
        return Err(format!("{} {first} and {etag} have the same {} nodes (an element listed twice); remove one", plural(kind), kind.len()));
    }
    Ok(())
}

/// The faces: named physical surfaces, in tag order, merged by name, each the outward boundary
/// facets of `cells` that its surface elements name.
fn named_faces(
    names: &HashMap<(i32, i32), String>,
    surf_groups: &HashMap<i32, &[i32]>,
    surface_elems: &HashMap<i32, Vec<&[u64]>>,
    index: &TagIndex,
    local: &[usize],
    cells: &[Cell],
) -> Vec<(String, Vec<Facet>)> {
    let boundary = boundary_faces(cells);
    let mut groups: BTreeMap<i32, Vec<i32>> = BTreeMap::new(); // group -> surface entities
    for ((d, t), _) in names.iter() {
        if *d == 2 {
            groups.entry(*t).or_default();
        }
    }
    let mut entities: Vec<(&i32, &&[i32])> = surf_groups.iter().collect();
    entities.sort_unstable();
    for (&s, g) in entities {
        for &t in g.iter() {
            groups.entry(t).or_default().push(s);
        }
    }
    let mut faces: Vec<(String, Vec<Facet>)> = Vec::new();
    // name → index into `faces`, and the facets each face holds (groups of one name merge)
    let mut face_of: HashMap<String, usize> = HashMap::new();
    let mut face_seen: Vec<HashSet<(usize, [usize; 4])>> = Vec::new();
    for (tag, ents) in groups {
        let name = group_name(names, 2, tag);
        let mut seen: HashSet<(usize, [usize; 4])> = HashSet::new();
        let mut list: Vec<Facet> = Vec::new();
        for q in ents.iter().filter_map(|s| surface_elems.get(s)).flatten() {
            let Some(loc) = corners_local(q, index, local) else {
                continue;
            };
            if let Some(fq) = find_boundary_facet(&boundary, &loc) {
                if seen.insert((fq.elem, fq.key())) {
                    list.push(*fq);
                }
            }
        }
        if list.is_empty() {
            continue;
        }
        match face_of.get(&name) {
            Some(&f) => {
                for fq in list {
                    if face_seen[f].insert((fq.elem, fq.key())) {
                        faces[f].1.push(fq);
                    }
                }
            }
            None => {
                face_of.insert(name.clone(), faces.len());
                face_seen.push(seen);
                faces.push((name, list));
            }
        }
    }
    faces
}

/// The volume element types read, for messages.
pub(super) const SUPPORTED: &str = "Hex8, Hex20, Hex27, Tet4, Tet10, Pri6 (wedge), Pri15, Pyr5";

/// The cell type of a Gmsh volume element type, if it is one this reader takes.
fn cell_kind(t: ElementType) -> Option<CellKind> {
    match t {
        ElementType::Hex8 => Some(CellKind::Hex8),
        ElementType::Tet4 => Some(CellKind::Tet4),
        ElementType::Tet10 => Some(CellKind::Tet10),
        ElementType::Pri6 => Some(CellKind::Wedge6),
        ElementType::Hex20 => Some(CellKind::Hex20),
        ElementType::Hex27 => Some(CellKind::Hex27),
        ElementType::Pri15 => Some(CellKind::Wedge15),
        ElementType::Pyr5 => Some(CellKind::Pyr5),
        _ => None,
    }
}

/// The corners and the name (in messages) of a Gmsh surface element type that can name a
/// face: 3-, 4-, 6-, 8- and 9-node triangles and quadrangles.
fn surface_kind(t: ElementType) -> Option<(usize, &'static str)> {
    match t {
        ElementType::Tri3 => Some((3, "triangle")),
        ElementType::Qua4 => Some((4, "quadrangle")),
        ElementType::Tri6 => Some((3, "6-node triangle")),
        ElementType::Qua8 => Some((4, "8-node quadrangle")),
        ElementType::Qua9 => Some((4, "9-node quadrangle")),
        _ => None,
    }
}

/// One cell of a type, in messages.
pub(super) fn singular(kind: CellKind) -> &'static str {
    match kind {
        CellKind::Hex8 => "hexahedron",
        CellKind::Tet4 => "tetrahedron",
        CellKind::Tet10 => "10-node tetrahedron",
        CellKind::Wedge6 => "wedge",
        CellKind::Hex20 => "20-node hexahedron",
        CellKind::Hex27 => "27-node hexahedron",
        CellKind::Wedge15 => "15-node wedge",
        CellKind::Pyr5 => "pyramid",
    }
}

/// Several cells of a type, in messages.
fn plural(kind: CellKind) -> &'static str {
    match kind {
        CellKind::Hex8 => "hexahedra",
        CellKind::Tet4 => "tetrahedra",
        CellKind::Tet10 => "10-node tetrahedra",
        CellKind::Wedge6 => "wedges",
        CellKind::Hex20 => "20-node hexahedra",
        CellKind::Hex27 => "27-node hexahedra",
        CellKind::Wedge15 => "15-node wedges",
        CellKind::Pyr5 => "pyramids",
    }
}

/// The corner edges of a cell type (local node pairs).
fn edges(kind: CellKind) -> &'static [[usize; 2]] {
    const HEX: [[usize; 2]; 12] = [[0, 1], [1, 2], [2, 3], [3, 0], [4, 5], [5, 6], [6, 7], [7, 4], [0, 4], [1, 5], [2, 6], [3, 7]];
    const TET: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];
    const WEDGE: [[usize; 2]; 9] = [[0, 1], [1, 2], [2, 0], [3, 4], [4, 5], [5, 3], [0, 3], [1, 4], [2, 5]];
    const PYR: [[usize; 2]; 8] = [[0, 1], [1, 2], [2, 3], [3, 0], [0, 4], [1, 4], [2, 4], [3, 4]];
    match kind {
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => &HEX,
        CellKind::Tet4 | CellKind::Tet10 => &TET,
        CellKind::Wedge6 | CellKind::Wedge15 => &WEDGE,
        CellKind::Pyr5 => &PYR,
    }
}

/// The length scale of the body: every element's longest edge and every coordinate must lie
/// within what double precision carries through element volumes (∝ h³) and the stiffness
/// (∝ E·h): [`crate::scene::range`]. (An element collapsed to a point is left to the
/// orientation check, which calls it degenerate.)
pub(super) fn check_scale(coords: &[[f64; 3]], cells: &[Cell], tags: &[(u64, CellKind, &[u64])]) -> Result<(), String> {
    use crate::scene::range::{MAX, MIN};
    // (edge, element tag, type) of the shortest and the longest longest-edge
    let mut lo: Option<(f64, u64, CellKind)> = None;
    let mut hi: Option<(f64, u64, CellKind)> = None;
    for (h, &(etag, kind, _)) in cells.iter().zip(tags) {
        let h = h.nodes();
        let len = |[a, b]: [usize; 2]| {
            let (p, q) = (coords[h[a]], coords[h[b]]);
            // scaled first: the squares of 1e-200 or 1e200 do not survive
            let d = [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
            let m = d.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            if m == 0.0 || !m.is_finite() {
                m
            } else {
                m * d.iter().map(|v| (v / m) * (v / m)).sum::<f64>().sqrt()
            }
        };
        let (short, e) = edges(kind).iter().map(|&ab| len(ab)).fold((f64::INFINITY, 0.0f64), |(a, b), l| (a.min(l), b.max(l)));
        if short > 0.0 && e / short > crate::scene::range::MAX_ASPECT {
            return Err(format!(
                "{} {etag} has edges of {short:.3e} against {e:.3e} m (ratio {:.1e}): thinner than the element can represent (ratio at most {:e}: the stiffness's condition number grows with its square); remesh the thin part",
                singular(kind),
                e / short,
                crate::scene::range::MAX_ASPECT
            ));
        }
        if e > 0.0 && lo.is_none_or(|l| e < l.0) {
            lo = Some((e, etag, kind));
        }
        if hi.is_none_or(|l| e > l.0) {
            hi = Some((e, etag, kind));
        }
    }
    for (found, bad) in [(lo, lo.is_some_and(|l| l.0 < MIN)), (hi, hi.is_some_and(|l| l.0 > MAX))] {
        if let (Some((e, etag, kind)), true) = (found, bad) {
            return Err(format!(
                "element edges of {e:.3e} m ({} {etag}) lie outside {MIN:e} … {MAX:e} m, the length scale double precision carries through element volumes (∝ h³) and stiffness (∝ E·h); scale the mesh",
                singular(kind)
            ));
        }
    }
    let mut used = vec![false; coords.len()];
    for &v in cells.iter().flat_map(Cell::nodes) {
        used[v] = true;
    }
    let far = coords.iter().zip(&used).filter(|(_, &u)| u).flat_map(|(p, _)| *p).fold(0.0f64, |a, v| a.max(v.abs()));
    if far > MAX {
        return Err(format!("coordinates up to {far:.3e} m lie outside ±{MAX:e} m; move the mesh nearer the origin or scale it"));
    }
    Ok(())
}

/// Local nodes of the corners of a file surface element (its first three or four nodes), or
/// `None` if one of them is not a node of the body.
fn corners_local(q: &[u64], index: &TagIndex, local: &[usize]) -> Option<Vec<usize>> {
    let n = if q.len() == 3 || q.len() == 6 { 3 } else { 4 };
    q.get(..n)?.iter().map(|&t| local.get(index.get(t)?).copied().filter(|&l| l != usize::MAX)).collect()
}

/// Orients `cell` (coordinates `x`): a cell whose corner Jacobians are all positive is kept,
/// one whose corner Jacobians are all negative (mirrored) is reordered, anything else is the
/// error (the reason, to follow the cell's name). (A 10-node tetrahedron whose edge nodes are
/// out of place, inverted between its corners, is refused by the assembly's Jacobian check.)
pub(super) fn orient(cell: &mut Cell, x: &[[f64; 3]]) -> Result<(), String> {
    // no allocation for hexahedra and tetrahedra (a million cells)
    let mut buf = [[0.0; 3]; MAX_CELL_NODES];
    let p = cell.coords_in(x, &mut buf);
    let (hex, tet, other): ([f64; 8], [f64; 1], Vec<f64>);
    let j: &[f64] = match cell.kind {
        CellKind::Hex8 | CellKind::Hex20 | CellKind::Hex27 => {
            hex = corner_jacobians(p.get(..8).and_then(|c| c.try_into().ok()).ok_or("has a wrong node count")?);
            &hex
        }
        CellKind::Tet4 | CellKind::Tet10 => {
            tet = [scaled_triple(p[0], p[1], p[2], p[3])];
            &tet
        }
        CellKind::Wedge6 | CellKind::Wedge15 => {
            other = wedge_corner_jacobians(p);
            &other
        }
        CellKind::Pyr5 => {
            other = pyramid_corner_jacobians(p);
            &other
        }
    };
    if j.iter().any(|&d| d <= 0.0) {
        if !j.iter().all(|&d| d < 0.0) {
            return Err(match cell.kind {
                CellKind::Tet4 | CellKind::Tet10 => "is degenerate (its four corners lie in one plane)".into(),
                _ => "is degenerate or twisted (its corner Jacobians do not share one sign)".into(),
            });
        }
        // the mirror ξ ↔ η: corners 1 ↔ 3 (hexahedra) or 1 ↔ 2 (wedges), with their edge and
        // face nodes
        let swaps: &[(usize, usize)] = match cell.kind {
            CellKind::Hex8 => &[(1, 3), (5, 7)],
            CellKind::Tet4 => &[(1, 2)],
            CellKind::Tet10 => &[(1, 2), (4, 6), (8, 9)],
            CellKind::Wedge6 => &[(1, 2), (4, 5)],
            CellKind::Hex20 => &[(1, 3), (5, 7), (8, 9), (11, 13), (12, 15), (16, 17), (18, 19)],
            CellKind::Hex27 => &[(1, 3), (5, 7), (8, 9), (11, 13), (12, 15), (16, 17), (18, 19), (21, 22), (23, 24)],
            CellKind::Wedge15 => &[(1, 2), (4, 5), (6, 7), (10, 11), (12, 13)],
            CellKind::Pyr5 => &[(1, 3)],
        };
        let v = cell.nodes_mut();
        for &(a, b) in swaps {
            v.swap(a, b);
        }
    }
    Ok(())
}

/// det(b − a, c − a, d − a) divided by the product of the three edge lengths; values within
/// 1e-12 of zero (or not finite) are 0.
fn scaled_triple(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> f64 {
    let sub = |p: [f64; 3], q: [f64; 3]| [p[0] - q[0], p[1] - q[1], p[2] - q[2]];
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let (u, v, w) = (sub(b, a), sub(c, a), sub(d, a));
    let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
    let scale = norm(u) * norm(v) * norm(w);
    let s = if scale > 0.0 { det / scale } else { 0.0 };
    if s.abs() <= 1e-12 || !s.is_finite() {
        0.0
    } else {
        s
    }
}

/// Scaled Jacobian at the six corners of a wedge: at a bottom corner the triple product of
/// the edges to the next and the previous corner of its triangle and the edge up; at a top
/// corner the same with the edge down, sign flipped.
fn wedge_corner_jacobians(p: &[[f64; 3]]) -> Vec<f64> {
    (0..6)
        .map(|c| {
            let (t, base) = (c % 3, c - c % 3);
            let (next, prev, other) = (base + (t + 1) % 3, base + (t + 2) % 3, if c < 3 { c + 3 } else { c - 3 });
            let s = scaled_triple(p[c], p[next], p[prev], p[other]);
            if c < 3 {
                s
            } else {
                -s
            }
        })
        .collect()
}

/// Scaled Jacobian at the four base corners of a pyramid: the triple product of the edges to
/// the next and the previous base corner and the edge up to the apex.
fn pyramid_corner_jacobians(p: &[[f64; 3]]) -> Vec<f64> {
    (0..4).map(|c| scaled_triple(p[c], p[(c + 1) % 4], p[(c + 3) % 4], p[4])).collect()
}

/// Scaled Jacobian at the eight corners of a hex8 (VTK order): the triple product of the three
/// edges leaving the corner along +ξ, +η, +ζ, divided by the product of their lengths; values
/// within 1e-12 of zero count as zero.
fn corner_jacobians(p: &[[f64; 3]; 8]) -> [f64; 8] {
    // For each corner: its neighbours along ξ, η, ζ and whether the corner sits at the + end of
    // that direction (then the edge points backwards and its sign flips).
    const NEIGHBOURS: [[usize; 3]; 8] = [[1, 3, 4], [0, 2, 5], [3, 1, 6], [2, 0, 7], [5, 7, 0], [4, 6, 1], [7, 5, 2], [6, 4, 3]];
    const FLIPS: [usize; 8] = [0, 1, 2, 1, 1, 2, 3, 2];
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let norm = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
    let mut out = [0.0; 8];
    for (c, o) in out.iter_mut().enumerate() {
        let [a, b, d] = NEIGHBOURS[c].map(|n| sub(p[n], p[c]));
        let det = a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) + a[2] * (b[0] * d[1] - b[1] * d[0]);
        let scale = norm(a) * norm(b) * norm(d);
        let s = if scale > 0.0 { det / scale } else { 0.0 };
        let s = if FLIPS[c] % 2 == 1 { -s } else { s };
        *o = if s.abs() <= 1e-12 || !s.is_finite() { 0.0 } else { s };
    }
    out
}

#[cfg(test)]
mod tests;
