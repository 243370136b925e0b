#!/usr/bin/env python3
"""Writes two_blocks.msh as an Exodus II file, the way Cubit or SEACAS lays one out:

    two_blocks.exo          netCDF-4 (HDF5)
    two_blocks_classic.exo  netCDF-3, 64-bit offset (the SEACAS default)

    /usr/bin/python3 -m pip install --user --break-system-packages netCDF4   # meshio 5 reads the .msh
    cd mesh && /usr/bin/python3 make_exodus.py

Content: every node of the .msh in its order (coordx/coordy/coordz), element blocks "upper"
(id 1) and "lower" (id 2) of HEX8 (connect1, connect2, in the .msh's element order), one side
set per physical surface (ids and names of the .msh's physical groups; each quadrangle given as
its hexahedron and that hexahedron's Exodus side number, found here from the Exodus side
table below) and one node set "upper_top_nodes" (the nodes of the physical surface upper_top).
meshio writes no side sets, so the netCDF variables are written here directly.
"""

import meshio
import netCDF4
import numpy as np

# Exodus II side numbering of HEX8 (1-based node positions; the Exodus II manual, SEACAS
# ex_get_side_set_node_list): side 1 = 1-2-6-5, 2 = 2-3-7-6, 3 = 3-4-8-7, 4 = 1-5-8-4,
# 5 = 1-4-3-2, 6 = 5-6-7-8.
HEX_SIDES = [(1, 2, 6, 5), (2, 3, 7, 6), (3, 4, 8, 7), (1, 5, 8, 4), (1, 4, 3, 2), (5, 6, 7, 8)]
LEN_NAME = 33


def names(ds, var, dim, values):
    v = ds.createVariable(var, "S1", (dim, "len_name"))
    v[:] = netCDF4.stringtochar(np.array(values, dtype=f"S{LEN_NAME}"))


def write(path, fmt):
    m = meshio.read("two_blocks.msh")
    groups = {name: tuple(v) for name, v in m.field_data.items()}  # name -> (tag, dim)
    phys = m.cell_data["gmsh:physical"]
    hexes = {}  # physical volume tag -> list of hexahedra (0-based nodes), in file order
    quads = {}  # physical surface tag -> list of quadrangles
    for block, tags in zip(m.cells, phys):
        into = hexes if block.type == "hexahedron" else quads
        for cell, t in zip(block.data, tags):
            into.setdefault(int(t), []).append([int(x) for x in cell])
    vol_names = sorted((tag, n) for n, (tag, d) in groups.items() if d == 3)
    surf_names = sorted((tag, n) for n, (tag, d) in groups.items() if d == 2)
    blocks = [(tag, n, hexes[tag]) for tag, n in vol_names]
    # global element numbers (1-based, blocks in order) and each hexahedron's node set
    elem_of = {}
    number = 0
    for _, _, cells in blocks:
        for c in cells:
            number += 1
            elem_of.setdefault(frozenset(c), []).append((number, c))
    sides = []
    for tag, n in surf_names:
        elems, sns = [], []
        for q in quads[tag]:
            found = [(e, s + 1) for key, hs in elem_of.items() if set(q) <= key for e, c in hs for s, side in enumerate(HEX_SIDES) if {c[k - 1] for k in side} == set(q)]
            assert len(found) == 1, (n, q, found)
            elems.append(found[0][0])
            sns.append(found[0][1])
        sides.append((tag, n, elems, sns))
    top_tag = groups["upper_top"][0]
    ns_nodes = sorted({v + 1 for q in quads[top_tag] for v in q})

    ds = netCDF4.Dataset(path, "w", format=fmt)
    ds.api_version = np.float32(8.03)
    ds.version = np.float32(8.03)
    ds.floating_point_word_size = np.int32(8)
    ds.file_size = np.int32(1)
    ds.maximum_name_length = np.int32(32)
    ds.int64_status = np.int32(0)
    ds.title = "two_blocks.msh (tresca-feti fixture)"
    ds.createDimension("len_string", 33)
    ds.createDimension("len_line", 81)
    ds.createDimension("four", 4)
    ds.createDimension("len_name", LEN_NAME)
    ds.createDimension("time_step", None)
    ds.createDimension("num_dim", 3)
    ds.createDimension("num_nodes", len(m.points))
    ds.createDimension("num_elem", number)
    ds.createDimension("num_el_blk", len(blocks))
    ds.createDimension("num_side_sets", len(sides))
    ds.createDimension("num_node_sets", 1)
    ds.createVariable("time_whole", "f8", ("time_step",))
    for d, name in enumerate("xyz"):
        ds.createVariable(f"coord{name}", "f8", ("num_nodes",))[:] = m.points[:, d]
    names(ds, "coor_names", "num_dim", ["x", "y", "z"])
    names(ds, "eb_names", "num_el_blk", [n for _, n, _ in blocks])
    ds.createVariable("eb_status", "i4", ("num_el_blk",))[:] = 1
    prop = ds.createVariable("eb_prop1", "i4", ("num_el_blk",))
    prop.setncattr("name", "ID")
    prop[:] = [tag for tag, _, _ in blocks]
    for k, (_, _, cells) in enumerate(blocks, start=1):
        ds.createDimension(f"num_el_in_blk{k}", len(cells))
        ds.createDimension(f"num_nod_per_el{k}", 8)
        c = ds.createVariable(f"connect{k}", "i4", (f"num_el_in_blk{k}", f"num_nod_per_el{k}"))
        c.elem_type = "HEX8"
        c[:] = np.array(cells) + 1
    names(ds, "ss_names", "num_side_sets", [n for _, n, _, _ in sides])
    ds.createVariable("ss_status", "i4", ("num_side_sets",))[:] = 1
    prop = ds.createVariable("ss_prop1", "i4", ("num_side_sets",))
    prop.setncattr("name", "ID")
    prop[:] = [tag for tag, _, _, _ in sides]
    for k, (_, _, elems, sns) in enumerate(sides, start=1):
        ds.createDimension(f"num_side_ss{k}", len(elems))
        ds.createVariable(f"elem_ss{k}", "i4", (f"num_side_ss{k}",))[:] = elems
        ds.createVariable(f"side_ss{k}", "i4", (f"num_side_ss{k}",))[:] = sns
    names(ds, "ns_names", "num_node_sets", ["upper_top_nodes"])
    ds.createVariable("ns_status", "i4", ("num_node_sets",))[:] = 1
    prop = ds.createVariable("ns_prop1", "i4", ("num_node_sets",))
    prop.setncattr("name", "ID")
    prop[:] = [1]
    ds.createDimension("num_nod_ns1", len(ns_nodes))
    ds.createVariable("node_ns1", "i4", ("num_nod_ns1",))[:] = ns_nodes
    ds.close()


write("two_blocks.exo", "NETCDF4")
write("two_blocks_classic.exo", "NETCDF3_64BIT_OFFSET")
