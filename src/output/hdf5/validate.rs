//! The checks of the data to write, before anything is created: whatever would otherwise fail
//! half-way through writing.

use super::layout::center_str;
use super::{mesh_len, values_len, Rows};
use crate::output::{check_step_times, step_name, Field, OutputData};

/// Checks everything that would otherwise fail half-way through writing.
pub(super) fn validate(data: &OutputData) -> std::result::Result<(), String> {
    let nnodes = data.nnodes();
    if let Some(m) = &data.mesh_rows {
        if m.node_rows.len() != data.coordinates.len() || m.cell_rows.len() != data.cells.len() {
            return Err(format!(
                "distributed mesh: {} node rows for {} coordinates, {} cell rows for {} cells",
                m.node_rows.len(),
                data.coordinates.len(),
                m.cell_rows.len(),
                data.cells.len()
            ));
        }
        if let Some(r) = m.node_rows.iter().find(|&&r| r >= m.nodes) {
            return Err(format!("distributed mesh: node row {r} beyond the {} nodes", m.nodes));
        }
        if let Some(r) = m.cell_rows.iter().find(|&&r| r >= m.cells) {
            return Err(format!("distributed mesh: cell row {r} beyond the {} cells", m.cells));
        }
    }
    if let Some((e, cell)) = data.cells.iter().enumerate().find(|(_, h)| h.nodes().iter().any(|&n| n >= nnodes)) {
        return Err(format!("cell {e} references node {:?} beyond the {nnodes} nodes", cell.nodes()));
    }
    validate_fields(data, &data.fields, &data.rows)?;
    check_step_times(&data.steps)?;
    for (i, step) in data.steps.iter().enumerate() {
        validate_fields(data, &step.fields, &step.rows).map_err(|m| format!("step {}: {m}", step_name(i)))?;
    }
    let mut names = std::collections::HashSet::new();
    for (name, value) in &data.attributes {
        if name.is_empty() {
            return Err("empty attribute name".into());
        }
        if name.contains('\0') || value.contains('\0') {
            return Err(format!("attribute {name:?}: name or value contains a NUL character"));
        }
        if !names.insert(name.as_str()) {
            return Err(format!("attribute {name:?} appears twice"));
        }
    }
    Ok(())
}

/// Checks one group's fields against the mesh of `data`: usable unique names, ncomp > 0, rows
/// on the mesh, and as many values as rows × ncomp.
fn validate_fields(data: &OutputData, fields: &[Field], rows: &Rows) -> std::result::Result<(), String> {
    let mut names = std::collections::HashSet::new();
    for f in fields {
        check_link_name(&f.name).map_err(|m| format!("field {:?}: {m}", f.name))?;
        if !names.insert(f.name.as_str()) {
            return Err(format!("field {:?} appears twice", f.name));
        }
        if f.ncomp == 0 {
            return Err(format!("field {:?}: ncomp is 0", f.name));
        }
        let len = mesh_len(data, f.center);
        let expected = match rows.get(&f.name) {
            Some(rows) => {
                if let Some(r) = rows.iter().find(|&&r| r >= len) {
                    return Err(format!("field {:?}: row {r} beyond the {len} {}s", f.name, center_str(f.center)));
                }
                rows.len()
            }
            None => len,
        };
        let got = values_len(&f.values);
        if got != expected * f.ncomp {
            return Err(format!("field {:?}: {got} values, expected {expected} {}s × {} components", f.name, center_str(f.center), f.ncomp));
        }
    }
    Ok(())
}

/// A dataset name must be one link: non-empty, no `/`, not `.`, no NUL.
fn check_link_name(name: &str) -> std::result::Result<(), &'static str> {
    if name.is_empty() || name == "." || name.contains('/') || name.contains('\0') {
        Err("a field name must be non-empty, not \".\", and contain no '/' or NUL")
    } else {
        Ok(())
    }
}
