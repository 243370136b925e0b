#!/usr/bin/env python3
"""Writes the quadratic fixtures cube_hex20.msh, cube_hex27.msh, prism_wedge15.msh as Exodus II
files (netCDF-4) cube_hex20.exo, cube_hex27.exo, prism_wedge15.exo: one element block "body"
(HEX20, HEX27, WEDGE15), the side set "top" (each facet of the physical surface top as its
element and Exodus side number) and the node set "top_nodes".

Each element's nodes are laid out from the Exodus II documentation alone, by geometry: the
corners in the .msh's order (the same as Exodus's), then each Exodus edge, face or centre
node found as the cell node at the midpoint of the corners the documentation names for it
(SEACAS ex_get_side_set_node_list tables: HEX edges 9-12 bottom, 13-16 vertical, 17-20 top,
HEX27 21 centre, 22-27 faces; WEDGE15 edges 7-9 bottom, 10-12 vertical, 13-15 top).

    cd mesh && /usr/bin/python3 make_quadratic_exodus.py    # meshio 5 reads the .msh, netCDF4 writes
"""

import meshio
import netCDF4
import numpy as np

HEX_EDGES = [(1, 2), (2, 3), (3, 4), (4, 1), (1, 5), (2, 6), (3, 7), (4, 8), (5, 6), (6, 7), (7, 8), (8, 5)]
HEX_FACES = [(1, 2, 3, 4, 5, 6, 7, 8), (1, 4, 3, 2), (5, 6, 7, 8), (1, 5, 8, 4), (2, 3, 7, 6), (1, 2, 6, 5), (3, 4, 8, 7)]  # 21 centre, 22-27
WEDGE_EDGES = [(1, 2), (2, 3), (3, 1), (1, 4), (2, 5), (3, 6), (4, 5), (5, 6), (6, 4)]
HEX_SIDES = [(1, 2, 6, 5), (2, 3, 7, 6), (3, 4, 8, 7), (1, 5, 8, 4), (1, 4, 3, 2), (5, 6, 7, 8)]
WEDGE_SIDES = [(1, 2, 5, 4), (2, 3, 6, 5), (1, 4, 6, 3), (1, 3, 2), (4, 5, 6)]
TYPES = {"hexahedron20": ("HEX20", 8, HEX_EDGES, [], HEX_SIDES), "hexahedron27": ("HEX27", 8, HEX_EDGES, HEX_FACES, HEX_SIDES), "wedge15": ("WEDGE15", 6, WEDGE_EDGES, [], WEDGE_SIDES)}
LEN_NAME = 33
meshio._mesh.topological_dimension.setdefault("wedge15", 3)  # meshio 5 reads the type but lacks its dimension


def names(ds, var, dim, values):
    v = ds.createVariable(var, "S1", (dim, "len_name"))
    v[:] = netCDF4.stringtochar(np.array(values, dtype=f"S{LEN_NAME}"))


def exodus_cell(x, cell, nc, edges, faces):
    """The cell's nodes in Exodus order: corners, then the node at each documented midpoint."""
    out = list(cell[:nc])
    for group in (edges, faces):
        for corners in group:
            p = np.mean([x[cell[c - 1]] for c in corners], axis=0)
            at = [v for v in cell if np.allclose(x[v], p, atol=1e-12)]
            assert len(at) == 1, (corners, at)
            out.append(at[0])
    assert sorted(out) == sorted(cell)
    return out


def write(name):
    m = meshio.read(f"{name}.msh")
    x = m.points
    vol = [b for b in m.cells if b.type in TYPES]
    assert len(vol) == 1
    etype, nc, edges, faces, sides = TYPES[vol[0].type]
    cells = [exodus_cell(x, [int(v) for v in c], nc, edges, faces) for c in vol[0].data]
    tag_top = m.field_data["top"][0]
    tops = [c for b, t in zip(m.cells, m.cell_data["gmsh:physical"]) if b.type not in TYPES for c, tt in zip(b.data, t) if tt == tag_top]
    elems, sns = [], []
    for q in tops:
        corners = {int(v) for v in q[: 3 if len(q) == 6 else 4]}
        found = [(e + 1, s + 1) for e, c in enumerate(cells) for s, side in enumerate(sides) if {c[k - 1] for k in side} == corners]
        assert len(found) == 1, found
        elems.append(found[0][0])
        sns.append(found[0][1])
    ns_nodes = sorted({int(v) + 1 for q in tops for v in q})

    ds = netCDF4.Dataset(f"{name}.exo", "w", format="NETCDF4")
    ds.api_version = np.float32(8.03)
    ds.version = np.float32(8.03)
    ds.floating_point_word_size = np.int32(8)
    ds.file_size = np.int32(1)
    ds.maximum_name_length = np.int32(32)
    ds.int64_status = np.int32(0)
    ds.title = f"{name}.msh (tresca-feti fixture)"
    ds.createDimension("len_string", 33)
    ds.createDimension("len_line", 81)
    ds.createDimension("four", 4)
    ds.createDimension("len_name", LEN_NAME)
    ds.createDimension("time_step", None)
    ds.createDimension("num_dim", 3)
    ds.createDimension("num_nodes", len(x))
    ds.createDimension("num_elem", len(cells))
    ds.createDimension("num_el_blk", 1)
    ds.createDimension("num_side_sets", 1)
    ds.createDimension("num_node_sets", 1)
    ds.createVariable("time_whole", "f8", ("time_step",))
    for d, c in enumerate("xyz"):
        ds.createVariable(f"coord{c}", "f8", ("num_nodes",))[:] = x[:, d]
    names(ds, "coor_names", "num_dim", ["x", "y", "z"])
    names(ds, "eb_names", "num_el_blk", ["body"])
    ds.createVariable("eb_status", "i4", ("num_el_blk",))[:] = 1
    prop = ds.createVariable("eb_prop1", "i4", ("num_el_blk",))
    prop.setncattr("name", "ID")
    prop[:] = [1]
    ds.createDimension("num_el_in_blk1", len(cells))
    ds.createDimension("num_nod_per_el1", len(cells[0]))
    c = ds.createVariable("connect1", "i4", ("num_el_in_blk1", "num_nod_per_el1"))
    c.elem_type = etype
    c[:] = np.array(cells) + 1
    names(ds, "ss_names", "num_side_sets", ["top"])
    ds.createVariable("ss_status", "i4", ("num_side_sets",))[:] = 1
    prop = ds.createVariable("ss_prop1", "i4", ("num_side_sets",))
    prop.setncattr("name", "ID")
    prop[:] = [1]
    ds.createDimension("num_side_ss1", len(elems))
    ds.createVariable("elem_ss1", "i4", ("num_side_ss1",))[:] = elems
    ds.createVariable("side_ss1", "i4", ("num_side_ss1",))[:] = sns
    names(ds, "ns_names", "num_node_sets", ["top_nodes"])
    ds.createVariable("ns_status", "i4", ("num_node_sets",))[:] = 1
    prop = ds.createVariable("ns_prop1", "i4", ("num_node_sets",))
    prop.setncattr("name", "ID")
    prop[:] = [1]
    ds.createDimension("num_nod_ns1", len(ns_nodes))
    ds.createVariable("node_ns1", "i4", ("num_nod_ns1",))[:] = ns_nodes
    ds.close()


for n in ["cube_hex20", "cube_hex27", "prism_wedge15"]:
    write(n)
