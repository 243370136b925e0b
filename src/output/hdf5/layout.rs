//! What goes where in the file: the names of its groups, datasets and attributes, how the
//! cells are stored under `/mesh` ([`CellLayout`], agreed over the ranks by [`cell_layout`]),
//! and the cells as the file's values (XDMF's node order and type ids).

use super::dataspace::gather_block;
use super::OutputData;
use crate::comm::Comm;
use crate::error::{Error, Result};
use crate::mesh::cell::MAX_CELL_NODES;
use crate::mesh::{Cell, CellKind};
use crate::output::Center;

pub(super) const MESH: &str = "mesh";
pub(super) const FIELDS: &str = "fields";
pub(super) const STEPS: &str = "steps";
pub(super) const TIME_ATTR: &str = "time";
pub(super) const COORDINATES: &str = "coordinates";
const HEXAHEDRA: &str = "hexahedra";
pub(super) const TETRAHEDRA: &str = "tetrahedra";
const TETRAHEDRA10: &str = "tetrahedra10";
const WEDGES: &str = "wedges";
const HEXAHEDRA20: &str = "hexahedra20";
const HEXAHEDRA27: &str = "hexahedra27";
const WEDGES15: &str = "wedges15";
const PYRAMIDS: &str = "pyramids";
pub(super) const MIXED: &str = "mixed";
pub(super) const CENTER_ATTR: &str = "center";

pub(super) fn center_str(c: Center) -> &'static str {
    match c {
        Center::Node => "node",
        Center::Cell => "cell",
    }
}

/// How the cells of a result file are stored under `/mesh` (see the module's table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellLayout {
    /// Every cell of one type (an empty mesh: hexahedra): `/mesh/hexahedra`, `/mesh/tetrahedra`,
    /// `/mesh/tetrahedra10` or `/mesh/wedges`, ncells × nodes per cell.
    Uniform(CellKind),
    /// Cells of several types: `/mesh/mixed`, `len` values, per cell its XDMF type id
    /// ([`CellKind::xdmf_id`]) and its nodes.
    Mixed {
        /// Length of `/mesh/mixed`: per cell, its type id and its nodes.
        len: usize,
    },
}

impl CellLayout {
    /// From the number of cells of each type ([`CellKind::ALL`] order).
    fn from_counts(n: [usize; CellKind::COUNT]) -> Self {
        let kinds: Vec<CellKind> = CellKind::ALL.iter().zip(n).filter(|(_, c)| *c > 0).map(|(&k, _)| k).collect();
        match kinds.as_slice() {
            [] => CellLayout::Uniform(CellKind::Hex8),
            [k] => CellLayout::Uniform(*k),
            _ => CellLayout::Mixed { len: CellKind::ALL.iter().zip(n).map(|(k, c)| c * (1 + k.len())).sum() },
        }
    }

    /// The layout of the whole mesh `cells`.
    pub fn of_cells(cells: &[Cell]) -> Self {
        let mut n = [0usize; CellKind::COUNT];
        for c in cells {
            n[c.kind.code()] += 1;
        }
        Self::from_counts(n)
    }

    /// The dataset under `/mesh` that holds the cells.
    pub fn dataset(self) -> &'static str {
        match self {
            CellLayout::Uniform(CellKind::Hex8) => HEXAHEDRA,
            CellLayout::Uniform(CellKind::Tet4) => TETRAHEDRA,
            CellLayout::Uniform(CellKind::Tet10) => TETRAHEDRA10,
            CellLayout::Uniform(CellKind::Wedge6) => WEDGES,
            CellLayout::Uniform(CellKind::Hex20) => HEXAHEDRA20,
            CellLayout::Uniform(CellKind::Hex27) => HEXAHEDRA27,
            CellLayout::Uniform(CellKind::Wedge15) => WEDGES15,
            CellLayout::Uniform(CellKind::Pyr5) => PYRAMIDS,
            CellLayout::Mixed { .. } => MIXED,
        }
    }
}

/// The cell datasets [`read`](fn@super::read) knows, one of which a file holds.
pub(super) const CELL_DATASETS: [&str; 9] = [HEXAHEDRA, TETRAHEDRA, TETRAHEDRA10, WEDGES, HEXAHEDRA20, HEXAHEDRA27, WEDGES15, PYRAMIDS, MIXED];

/// The layout of the cells of `data` over all ranks: that of `data.cells` where they are the
/// whole mesh; where the mesh is distributed, that of the rows the ranks hold (their cell types
/// sent to the ranks whose [`block`](super::dataspace::block)s hold the rows, one all-to-all exchange, then one sum).
/// Collective; the same result on every rank. A distributed mesh with a cell row that no rank
/// holds is an error.
pub fn cell_layout<C: Comm>(comm: &C, data: &OutputData) -> Result<CellLayout> {
    let Some(m) = &data.mesh_rows else { return Ok(CellLayout::of_cells(&data.cells)) };
    let ids: Vec<i64> = data.cells.iter().map(|c| c.kind.xdmf_id() as i64).collect();
    let mine = gather_block(comm, m.cells, 1, &m.cell_rows, &ids);
    // cells of each type in this rank's block, then the rows of it no rank holds (id 0)
    let mut n = [0u64; CellKind::COUNT + 1];
    for &id in &mine {
        match kind_of_id(id) {
            Some(k) => n[k.code()] += 1,
            None => n[CellKind::COUNT] += 1,
        }
    }
    comm.sum_u64(&mut n);
    if n[CellKind::COUNT] > 0 {
        return Err(Error::output(String::new(), format!("distributed mesh: {} of the {} cell rows are held by no rank", n[CellKind::COUNT], m.cells)));
    }
    Ok(CellLayout::from_counts(std::array::from_fn(|k| n[k] as usize)))
}

/// The cell type of an XDMF type id, if it is one of ours.
pub(super) fn kind_of_id(id: i64) -> Option<CellKind> {
    CellKind::ALL.into_iter().find(|k| k.xdmf_id() as i64 == id)
}

/// The position in our (Gmsh's) node order of each node in the file's (XDMF's = VTK's)
/// order: the same but for a 10-node tetrahedron, whose edge nodes (3,2) and (3,1) come the
/// other way round there ((1,3) before (2,3)); a 20/27-node hexahedron, whose edge nodes VTK
/// lists bottom ring, top ring, then the vertical edges (and a 27's face centres x−, x+, y−,
/// y+, z−, z+); a 15-node wedge, whose edge nodes VTK lists bottom ring, top ring, vertical.
pub(super) fn file_order(kind: CellKind) -> &'static [usize] {
    const TET10: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];
    const HEX27: [usize; 27] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 11, 13, 9, 16, 18, 19, 17, 10, 12, 14, 15, 22, 23, 21, 24, 20, 25, 26];
    const WEDGE15: [usize; 15] = [0, 1, 2, 3, 4, 5, 6, 9, 7, 12, 14, 13, 8, 10, 11];
    const IDENTITY: [usize; MAX_CELL_NODES] = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26];
    match kind {
        CellKind::Tet10 => &TET10,
        CellKind::Hex20 => &HEX27[..20],
        CellKind::Hex27 => &HEX27,
        CellKind::Wedge15 => &WEDGE15,
        k => &IDENTITY[..k.len()],
    }
}

/// The cells as i64 values in the file's node order: per cell its nodes (`mixed` false); its
/// XDMF type id and its nodes (`mixed`); and with `pad` each such record filled up with 0 to
/// 1 + [`MAX_CELL_NODES`] values (to be sent in fixed-size rows).
pub(super) fn cell_values(cells: &[Cell], mixed: bool, pad: bool) -> Result<Vec<i64>> {
    let mut out = Vec::with_capacity(cells.len() * (1 + MAX_CELL_NODES));
    let big = || Error::output(String::new(), "node index does not fit in i64");
    for c in cells {
        if mixed {
            out.push(c.kind.xdmf_id() as i64);
        }
        for &i in file_order(c.kind) {
            out.push(i64::try_from(c.nodes()[i]).map_err(|_| big())?);
        }
        if pad {
            out.extend(std::iter::repeat_n(0, MAX_CELL_NODES - c.kind.len()));
        }
    }
    Ok(out)
}
