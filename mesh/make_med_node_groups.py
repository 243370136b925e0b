#!/usr/bin/env python3
"""Writes mesh/two_blocks_node_groups.med: mesh/two_blocks.med (Gmsh's MED export) read and
written again by meshio (a second MED writer, MED 3.0 layout), with two groups of nodes added as
code_aster's GROUP_NO are stored (`NOE/FAM` and `/FAS/<mesh>/NOEUD`): "clamp", the nodes of the
face group lower_left, and "press_nodes", those of upper_top. The element groups are kept.

    cd mesh && /usr/bin/python3 make_med_node_groups.py      # Debian python3-meshio
"""
import meshio
import numpy as np

m = meshio.read("two_blocks.med")
quads = m.cells_dict["quad"]
tags = m.cell_data_dict["cell_tags"]["quad"]
name_of = {num: names[0] for num, names in m.cell_tags.items()}
family = {name: num for num, name in name_of.items()}
points = np.zeros(len(m.points), dtype=int)
points[np.unique(quads[tags == family["lower_left"]])] = 1
points[np.unique(quads[tags == family["upper_top"]])] = 2
m.point_data["point_tags"] = points
m.point_tags = {1: ["clamp"], 2: ["press_nodes"]}
meshio.write("two_blocks_node_groups.med", m)
print("two_blocks_node_groups.med:", (points == 1).sum(), "clamp nodes,", (points == 2).sum(), "press_nodes nodes")
