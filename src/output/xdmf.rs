//! The XDMF 3 sidecar that lets ParaView (and VisIt) open the HDF5 result file.
//!
//! One uniform grid: its `Topology` from the cell dataset of `/mesh` ([`CellLayout`]), `XYZ`
//! geometry from `/mesh/coordinates`, and one `Attribute` per field from `/fields/<name>`:
//! `Scalar` for one component, `Vector` for 3, `Tensor6` for 6, `Tensor` for 9, `Matrix`
//! otherwise. The topology of a mesh of one cell type is `Hexahedron` (`/mesh/hexahedra`, n × 8),
//! `Tetrahedron` (`/mesh/tetrahedra`, n × 4), `Tetrahedron_10` (`/mesh/tetrahedra10`, n × 10)
//! or `Wedge` (`/mesh/wedges`, n × 6), with `NumberOfElements` n; that of a mesh of several types
//! is `Mixed` (`/mesh/mixed`, a flat list of per cell its XDMF type id and its nodes), with
//! `NumberOfElements` the cells and the list's length as its `Dimensions`. The node orders are
//! XDMF's (VTK's), which the HDF5 file stores.
//!
//! A load path ([`OutputData::steps`] non-empty) is instead one temporal collection,
//! `<Grid Name="load path" GridType="Collection" CollectionType="Temporal">`, that ParaView
//! plays as an animation: one uniform grid per step (`step 0001`, …) with its `<Time
//! Value="…"/>`, the same topology and geometry (repeated), and one `Attribute` per step field
//! from `/steps/<NNNN>/<name>`. The final state's `/fields` are not listed then (the last step
//! is that state).
//!
//! The heavy data stays in the HDF5 file, named relative to the XDMF file. Names are
//! XML-escaped, so the output is well-formed whatever the field names are.

use std::fmt::Write as _;
use std::path::Path;

use super::hdf5::CellLayout;
use super::{check_step_times, step_name, Center, Field, OutputData, Values};
use crate::error::{Error, Result};

/// Writes the XDMF description of `data` to `xdmf_path`; `h5_file_name` is the HDF5 file
/// written by [`super::hdf5::write`], relative to the directory of `xdmf_path` (normally its
/// bare file name); `cells` the layout of its cells over all ranks
/// ([`super::hdf5::cell_layout`]; for a whole mesh [`CellLayout::of_cells`]).
pub fn write(xdmf_path: &Path, h5_file_name: &str, data: &OutputData, cells: CellLayout) -> Result<()> {
    let shown = xdmf_path.display().to_string();
    let text = render(h5_file_name, data, cells).map_err(|m| Error::output(&shown, m))?;
    std::fs::write(xdmf_path, text.as_bytes()).map_err(|e| Error::io(&shown, e))
}

/// The XDMF document as a string.
fn render(h5: &str, data: &OutputData, cells: CellLayout) -> std::result::Result<String, String> {
    if h5.is_empty() || h5.contains(':') {
        // XDMF splits `file:/path` at the colon.
        return Err(format!("HDF5 file name {h5:?} must be non-empty and contain no ':'"));
    }
    let h5 = escape(h5)?;
    let mut s = String::new();
    // Writing into a String cannot fail: the fmt::Results below are ignored on purpose.
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="utf-8"?>"#);
    let _ = writeln!(s, r#"<Xdmf xmlns:xi="http://www.w3.org/2001/XInclude" Version="3.0">"#);
    let _ = writeln!(s, "  <Domain>");
    if data.steps.is_empty() {
        let _ = writeln!(s, r#"    <Grid Name="mesh" GridType="Uniform">"#);
        mesh(&mut s, 6, &h5, data, cells);
        attributes(&mut s, 6, &h5, "/fields", data, &data.fields, &data.rows)?;
        let _ = writeln!(s, "    </Grid>");
    } else {
        check_step_times(&data.steps)?;
        let _ = writeln!(s, r#"    <Grid Name="load path" GridType="Collection" CollectionType="Temporal">"#);
        for (i, step) in data.steps.iter().enumerate() {
            let name = step_name(i);
            let _ = writeln!(s, r#"      <Grid Name="step {name}" GridType="Uniform">"#);
            // Debug formatting: the shortest text that reads back as the same f64.
            let _ = writeln!(s, r#"        <Time Value="{:?}"/>"#, step.time);
            mesh(&mut s, 8, &h5, data, cells);
            attributes(&mut s, 8, &h5, &format!("/steps/{name}"), data, &step.fields, &step.rows).map_err(|m| format!("step {name}: {m}"))?;
            let _ = writeln!(s, "      </Grid>");
        }
        let _ = writeln!(s, "    </Grid>");
    }
    let _ = writeln!(s, "  </Domain>");
    let _ = writeln!(s, "</Xdmf>");
    Ok(s)
}

/// The `Topology` and `Geometry` of a grid, indented by `indent` spaces.
fn mesh(s: &mut String, indent: usize, h5: &str, data: &OutputData, cells: CellLayout) {
    let nnodes = data.nnodes();
    let nelems = data.ncells();
    let pad = " ".repeat(indent);
    let (topology, dims) = match cells {
        CellLayout::Uniform(kind) => (kind.xdmf_name(), format!("{nelems} {}", kind.len())),
        CellLayout::Mixed { len } => ("Mixed", len.to_string()),
    };
    let _ = writeln!(s, r#"{pad}<Topology TopologyType="{topology}" NumberOfElements="{nelems}">"#);
    data_item(s, indent + 2, &dims, "Int", 8, h5, &format!("/mesh/{}", cells.dataset()));
    let _ = writeln!(s, "{pad}</Topology>");
    let _ = writeln!(s, r#"{pad}<Geometry GeometryType="XYZ">"#);
    data_item(s, indent + 2, &format!("{nnodes} 3"), "Float", 8, h5, "/mesh/coordinates");
    let _ = writeln!(s, "{pad}</Geometry>");
}

/// One `Attribute` per field of `fields`, read from `<group>/<name>` (`group` needs no
/// escaping), indented by `indent` spaces; `rows` as [`OutputData::rows`] for these fields.
fn attributes(
    s: &mut String,
    indent: usize,
    h5: &str,
    group: &str,
    data: &OutputData,
    fields: &[Field],
    rows: &std::collections::BTreeMap<String, Vec<usize>>,
) -> std::result::Result<(), String> {
    let pad = " ".repeat(indent);
    for f in fields {
        let (number_type, precision, nvalues) = match &f.values {
            Values::F64(v) => ("Float", 8, v.len()),
            Values::I32(v) => ("Int", 4, v.len()),
        };
        if f.ncomp == 0 || nvalues % f.ncomp != 0 {
            return Err(format!("field {:?}: {nvalues} values do not split into {} components", f.name, f.ncomp));
        }
        let (center, expected) = match f.center {
            Center::Node => ("Node", data.nnodes()),
            Center::Cell => ("Cell", data.ncells()),
        };
        // a distributed field holds this rank's rows only; the file has them all
        let len = if rows.contains_key(&f.name) { expected } else { nvalues / f.ncomp };
        if len != expected {
            return Err(format!("field {:?}: {len} tuples on a mesh with {expected} {}s", f.name, center.to_lowercase()));
        }
        let attribute_type = match f.ncomp {
            1 => "Scalar",
            3 => "Vector",
            6 => "Tensor6",
            9 => "Tensor",
            _ => "Matrix",
        };
        let dims = if f.ncomp == 1 { format!("{len}") } else { format!("{len} {}", f.ncomp) };
        let name = escape(&f.name)?;
        let _ = writeln!(s, r#"{pad}<Attribute Name="{name}" AttributeType="{attribute_type}" Center="{center}">"#);
        data_item(s, indent + 2, &dims, number_type, precision, h5, &format!("{group}/{name}"));
        let _ = writeln!(s, "{pad}</Attribute>");
    }
    Ok(())
}

/// One `<DataItem>` referencing `h5:path`, indented by `indent` spaces; `h5` and `path` are
/// already escaped.
fn data_item(s: &mut String, indent: usize, dims: &str, number_type: &str, precision: u32, h5: &str, path: &str) {
    let pad = " ".repeat(indent);
    let _ = writeln!(s, r#"{pad}<DataItem Dimensions="{dims}" NumberType="{number_type}" Precision="{precision}" Format="HDF">{h5}:{path}</DataItem>"#);
}

/// Escapes `raw` for use in XML text or a double-quoted attribute value; characters XML 1.0
/// cannot carry at all (most control characters) are an error.
fn escape(raw: &str) -> std::result::Result<String, String> {
    let mut out = String::with_capacity(raw.len());
    for c in raw.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Kept literally they would be normalized to spaces inside attribute values.
            '\t' | '\n' | '\r' => {
                let _ = write!(out, "&#{};", c as u32);
            }
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => {
                return Err(format!("name {raw:?} contains a character XML cannot represent"));
            }
            c => out.push(c),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::Field;

    /// A minimal well-formedness check: balanced, properly nested tags, quoted attributes,
    /// valid entity references, no stray `<` or `&` in text. Returns the element names in
    /// document order.
    fn check_xml(doc: &str) -> std::result::Result<Vec<String>, String> {
        fn check_entities(t: &str) -> std::result::Result<(), String> {
            let mut rest = t;
            while let Some(i) = rest.find('&') {
                let after = &rest[i + 1..];
                let end = after.find(';').ok_or_else(|| format!("bare & in {t:?}"))?;
                let ent = &after[..end];
                let ok = matches!(ent, "amp" | "lt" | "gt" | "quot" | "apos")
                    || ent.strip_prefix('#').is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()));
                if !ok {
                    return Err(format!("bad entity &{ent};"));
                }
                rest = &after[end + 1..];
            }
            if t.contains('<') {
                return Err(format!("stray < in {t:?}"));
            }
            Ok(())
        }
        let mut stack: Vec<String> = Vec::new();
        let mut names = Vec::new();
        let mut rest = doc;
        let mut seen_root = false;
        loop {
            let Some(open) = rest.find('<') else {
                check_entities(rest)?;
                if !rest.trim().is_empty() && stack.is_empty() {
                    return Err("text after the root element".into());
                }
                break;
            };
            check_entities(&rest[..open])?;
            rest = &rest[open..];
            if let Some(r) = rest.strip_prefix("<?") {
                let end = r.find("?>").ok_or("unterminated <?")?;
                rest = &r[end + 2..];
                continue;
            }
            if let Some(r) = rest.strip_prefix("<!--") {
                let end = r.find("-->").ok_or("unterminated comment")?;
                rest = &r[end + 3..];
                continue;
            }
            // Find the closing '>' outside quoted attribute values.
            let mut quote = None;
            let mut close = None;
            for (i, b) in rest.bytes().enumerate().skip(1) {
                match (quote, b) {
                    (None, b'"' | b'\'') => quote = Some(b),
                    (Some(q), b) if b == q => quote = None,
                    (Some(_), b'<') => return Err("< inside attribute value".into()),
                    (None, b'>') => {
                        close = Some(i);
                        break;
                    }
                    _ => {}
                }
            }
            let close = close.ok_or("unterminated tag")?;
            let tag = &rest[1..close];
            rest = &rest[close + 1..];
            if let Some(name) = tag.strip_prefix('/') {
                let top = stack.pop().ok_or_else(|| format!("</{name}> without opening tag"))?;
                if top != name.trim() {
                    return Err(format!("</{name}> closes <{top}>"));
                }
                continue;
            }
            let self_closing = tag.ends_with('/');
            let tag = tag.trim_end_matches('/');
            let name_end = tag.find(char::is_whitespace).unwrap_or(tag.len());
            let name = &tag[..name_end];
            if name.is_empty() || !name.chars().all(|c| c.is_alphanumeric() || ":_-.".contains(c)) {
                return Err(format!("bad element name {name:?}"));
            }
            if stack.is_empty() {
                if seen_root {
                    return Err("two root elements".into());
                }
                seen_root = true;
            }
            // Attributes: name="value" pairs, each name once.
            let mut attrs = tag[name_end..].trim();
            let mut attr_names = std::collections::HashSet::new();
            while !attrs.is_empty() {
                let eq = attrs.find('=').ok_or_else(|| format!("attribute without value in <{name}>"))?;
                let an = attrs[..eq].trim();
                if an.is_empty() || an.contains(char::is_whitespace) || !attr_names.insert(an) {
                    return Err(format!("bad or repeated attribute {an:?} in <{name}>"));
                }
                let v = attrs[eq + 1..].trim_start();
                let q = v.chars().next().filter(|c| *c == '"' || *c == '\'').ok_or("unquoted attribute")?;
                let vend = v[1..].find(q).ok_or("unterminated attribute value")?;
                check_entities(&v[1..1 + vend])?;
                attrs = v[vend + 2..].trim_start();
            }
            names.push(name.to_owned());
            if !self_closing {
                stack.push(name.to_owned());
            }
        }
        if !stack.is_empty() {
            return Err(format!("unclosed elements {stack:?}"));
        }
        if !seen_root {
            return Err("no root element".into());
        }
        Ok(names)
    }

    fn sample() -> OutputData {
        // two hexahedra side by side along x: 12 nodes
        let g = crate::mesh::boxgen::generate([0.0; 3], [0.2, 1.0, 1.0], [3, 2, 2]);
        OutputData {
            coordinates: g.nodes,
            cells: g.cells,
            mesh_rows: None,
            fields: vec![
                Field { name: "displacement".into(), center: Center::Node, ncomp: 3, values: Values::F64(vec![0.0; 36]) },
                Field { name: "von <Mises> & \"co\"".into(), center: Center::Cell, ncomp: 1, values: Values::F64(vec![1.0, 2.0]) },
                Field { name: "subdomain".into(), center: Center::Cell, ncomp: 1, values: Values::I32(vec![0, 1]) },
                Field { name: "stress".into(), center: Center::Cell, ncomp: 6, values: Values::F64(vec![0.0; 12]) },
                Field { name: "grad".into(), center: Center::Cell, ncomp: 9, values: Values::F64(vec![0.0; 18]) },
                Field { name: "pair".into(), center: Center::Node, ncomp: 2, values: Values::I32(vec![0; 24]) },
            ],
            attributes: vec![("scene".into(), "x".repeat(100))],
            rows: Default::default(),
            steps: Vec::new(),
        }
    }

    fn tmp(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("tresca_feti_xdmf_{}_{name}", std::process::id()))
    }

    #[test]
    fn xdmf_is_well_formed_and_complete() {
        let data = sample();
        let path = tmp("ok.xdmf");
        write(&path, "r&d result.h5", &data, CellLayout::of_cells(&data.cells)).unwrap();
        let doc = std::fs::read_to_string(&path).unwrap();
        std::fs::remove_file(&path).unwrap();

        let names = check_xml(&doc).unwrap_or_else(|e| panic!("{e}\n{doc}"));
        assert_eq!(names.iter().filter(|n| *n == "Grid").count(), 1);
        assert_eq!(names.iter().filter(|n| *n == "Attribute").count(), data.fields.len());
        assert_eq!(names.iter().filter(|n| *n == "DataItem").count(), data.fields.len() + 2);

        assert!(doc.contains(r#"<Topology TopologyType="Hexahedron" NumberOfElements="2">"#));
        assert!(doc.contains(r#"Dimensions="2 8" NumberType="Int" Precision="8" Format="HDF">r&amp;d result.h5:/mesh/hexahedra<"#));
        assert!(doc.contains(r#"<Geometry GeometryType="XYZ">"#));
        assert!(doc.contains(r#"Dimensions="12 3" NumberType="Float" Precision="8" Format="HDF">r&amp;d result.h5:/mesh/coordinates<"#));
        assert!(doc.contains(r#"<Attribute Name="displacement" AttributeType="Vector" Center="Node">"#));
        assert!(doc.contains(r#"Dimensions="12 3" NumberType="Float" Precision="8" Format="HDF">r&amp;d result.h5:/fields/displacement<"#));
        assert!(doc.contains(r#"<Attribute Name="von &lt;Mises&gt; &amp; &quot;co&quot;" AttributeType="Scalar" Center="Cell">"#));
        assert!(doc.contains(r#"Dimensions="2" NumberType="Float" Precision="8""#));
        assert!(doc.contains(r#"<Attribute Name="subdomain" AttributeType="Scalar" Center="Cell">"#));
        assert!(doc.contains(r#"Dimensions="2" NumberType="Int" Precision="4" Format="HDF">r&amp;d result.h5:/fields/subdomain<"#));
        assert!(doc.contains(r#"<Attribute Name="stress" AttributeType="Tensor6" Center="Cell">"#));
        assert!(doc.contains(r#"Dimensions="2 6""#));
        assert!(doc.contains(r#"<Attribute Name="grad" AttributeType="Tensor" Center="Cell">"#));
        assert!(doc.contains(r#"<Attribute Name="pair" AttributeType="Matrix" Center="Node">"#));
        assert!(doc.contains(r#"Dimensions="12 2" NumberType="Int" Precision="4""#));
    }

    #[test]
    fn checker_rejects_malformed() {
        assert!(check_xml("<a><b></a></b>").is_err());
        assert!(check_xml("<a x=\"1\">&</a>").is_err());
        assert!(check_xml("<a x=\"<\"/>").is_err());
        assert!(check_xml("<a>").is_err());
        assert!(check_xml("<a/><b/>").is_err());
        assert!(check_xml("<?xml version=\"1.0\"?><a x='1' y=\"&amp;\"><b/>t&lt;</a>").is_ok());
    }

    #[test]
    fn bad_input_is_an_error_and_writes_nothing() {
        let mut data = sample();
        data.fields[1].values = Values::F64(vec![1.0; 3]);
        let path = tmp("bad.xdmf");
        let err = write(&path, "r.h5", &data, CellLayout::of_cells(&data.cells)).unwrap_err().to_string();
        assert!(err.contains("bad.xdmf") && err.contains("von"), "{err}");
        assert!(!path.exists());

        let err = write(&path, "c:r.h5", &sample(), CellLayout::Uniform(crate::mesh::CellKind::Hex8)).unwrap_err().to_string();
        assert!(err.contains("':'"), "{err}");
        let mut data = sample();
        data.fields[0].name = "a\u{1}b".into();
        assert!(write(&path, "r.h5", &data, CellLayout::of_cells(&data.cells)).is_err());
        assert!(!path.exists());
    }

    /// `sample()` on a load path of 3 steps, each with a node vector, an escaped-name cell
    /// scalar (distributed: this rank holds cell 1 only) and an integer cell field.
    fn with_steps() -> OutputData {
        let mut data = sample();
        data.steps = [0.1, 0.5, 1.0]
            .iter()
            .map(|&time| crate::output::Step {
                time,
                fields: vec![
                    Field { name: "displacement".into(), center: Center::Node, ncomp: 3, values: Values::F64(vec![time; 36]) },
                    Field { name: "von <Mises> & \"co\"".into(), center: Center::Cell, ncomp: 1, values: Values::F64(vec![time]) },
                    Field { name: "status".into(), center: Center::Cell, ncomp: 1, values: Values::I32(vec![0, 1]) },
                ],
                rows: [("von <Mises> & \"co\"".to_string(), vec![1])].into(),
            })
            .collect();
        data
    }

    #[test]
    fn load_path_is_a_temporal_collection() {
        let data = with_steps();
        let doc = render("r&d result.h5", &data, CellLayout::of_cells(&data.cells)).unwrap();
        let names = check_xml(&doc).unwrap_or_else(|e| panic!("{e}\n{doc}"));
        let count = |n: &str| names.iter().filter(|x| *x == n).count();
        // The collection and one uniform grid per step, each with its mesh and step fields.
        assert_eq!((count("Grid"), count("Time"), count("Topology"), count("Geometry")), (4, 3, 3, 3));
        assert_eq!((count("Attribute"), count("DataItem")), (9, 15));
        assert_eq!(names[..3], ["Xdmf", "Domain", "Grid"]);
        assert!(doc.contains(r#"<Grid Name="load path" GridType="Collection" CollectionType="Temporal">"#));

        // Steps in order, each with its time and its own datasets.
        let at = |needle: &str| doc.find(needle).unwrap_or_else(|| panic!("no {needle:?} in\n{doc}"));
        let mut last = 0;
        for (name, time) in [("0001", "0.1"), ("0002", "0.5"), ("0003", "1.0")] {
            let grid = at(&format!(r#"<Grid Name="step {name}" GridType="Uniform">"#));
            let t = at(&format!(r#"<Time Value="{time}"/>"#));
            let u = at(&format!(r#"Dimensions="12 3" NumberType="Float" Precision="8" Format="HDF">r&amp;d result.h5:/steps/{name}/displacement<"#));
            let vm = at(&format!(
                r#"Dimensions="2" NumberType="Float" Precision="8" Format="HDF">r&amp;d result.h5:/steps/{name}/von &lt;Mises&gt; &amp; &quot;co&quot;<"#
            ));
            let st = at(&format!(r#"Dimensions="2" NumberType="Int" Precision="4" Format="HDF">r&amp;d result.h5:/steps/{name}/status<"#));
            assert!(last < grid && grid < t && t < u && u < vm && vm < st, "step {name} out of order\n{doc}");
            last = st;
        }
        assert!(!doc.contains("/fields/"), "{doc}");
        assert_eq!(doc.matches(r#"r&amp;d result.h5:/mesh/hexahedra<"#).count(), 3);
        assert!(doc.contains(r#"<Attribute Name="von &lt;Mises&gt; &amp; &quot;co&quot;" AttributeType="Scalar" Center="Cell">"#));
    }

    #[test]
    fn bad_steps_are_an_error() {
        let mut data = with_steps();
        data.steps[1].fields[2].values = Values::I32(vec![0; 3]);
        let err = render("r.h5", &data, CellLayout::of_cells(&data.cells)).unwrap_err();
        assert!(err.contains("step 0002") && err.contains("status"), "{err}");
        let mut data = with_steps();
        data.steps[0].time = f64::INFINITY;
        assert!(render("r.h5", &data, CellLayout::of_cells(&data.cells)).unwrap_err().contains("not finite"));
        let mut data = with_steps();
        data.steps.swap(0, 2);
        assert!(render("r.h5", &data, CellLayout::of_cells(&data.cells)).unwrap_err().contains("not after"));
        let mut data = with_steps();
        data.steps[2].fields[0].name = "a\u{1}b".into();
        assert!(render("r.h5", &data, CellLayout::of_cells(&data.cells)).is_err());
    }

    /// Meshes of one other cell type get their own uniform topology, meshes of several types a
    /// `Mixed` one whose data item is the flat list (its length, not cells × nodes).
    #[test]
    fn other_cell_types_and_mixed_meshes_have_their_topology() {
        use crate::mesh::{Cell, CellKind};
        let mut data = sample();
        let tet = |k: CellKind| Cell::new(k, &(0..k.len()).collect::<Vec<_>>());
        for (kind, dims, dataset) in [
            (CellKind::Tet4, "2 4", "tetrahedra"),
            (CellKind::Tet10, "2 10", "tetrahedra10"),
            (CellKind::Wedge6, "2 6", "wedges"),
            (CellKind::Pyr5, "2 5", "pyramids"),
        ] {
            data.cells = vec![tet(kind); 2];
            let doc = render("r.h5", &data, CellLayout::of_cells(&data.cells)).unwrap();
            check_xml(&doc).unwrap_or_else(|e| panic!("{e}\n{doc}"));
            assert!(doc.contains(&format!(r#"<Topology TopologyType="{}" NumberOfElements="2">"#, kind.xdmf_name())), "{doc}");
            assert!(doc.contains(&format!(r#"Dimensions="{dims}" NumberType="Int" Precision="8" Format="HDF">r.h5:/mesh/{dataset}<"#)), "{doc}");
        }
        assert_eq!(CellKind::Tet10.xdmf_name(), "Tetrahedron_10");
        // a hexahedron and a 10-node tetrahedron: 1 + 8 + 1 + 10 values
        data.cells = vec![data.cells[0].clone(), tet(CellKind::Hex8)];
        data.cells[0] = tet(CellKind::Tet10);
        let layout = CellLayout::of_cells(&data.cells);
        assert_eq!(layout, CellLayout::Mixed { len: 20 });
        let doc = render("r.h5", &data, layout).unwrap();
        check_xml(&doc).unwrap_or_else(|e| panic!("{e}\n{doc}"));
        assert!(doc.contains(r#"<Topology TopologyType="Mixed" NumberOfElements="2">"#), "{doc}");
        assert!(doc.contains(r#"Dimensions="20" NumberType="Int" Precision="8" Format="HDF">r.h5:/mesh/mixed<"#), "{doc}");
        // in a load path every step's grid has it
        data.steps = vec![crate::output::Step { time: 1.0, fields: Vec::new(), rows: Default::default() }; 2];
        data.steps[1].time = 2.0;
        let doc = render("r.h5", &data, layout).unwrap();
        assert_eq!(doc.matches(r#"TopologyType="Mixed""#).count(), 2);
    }
}
