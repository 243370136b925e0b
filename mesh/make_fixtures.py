#!/usr/bin/env python3
"""Writes the tetrahedral, quadratic and mixed Gmsh 4.1 test meshes of this folder, each in
ASCII (`<name>.msh`) and binary (`<name>_binary.msh`) encoding.

    pip install gmsh      # the Python API (the files were made with Gmsh 4.15.2)
    cd mesh && python3 make_fixtures.py

two_tet_blocks     the two-block benchmark of two_blocks.geo meshed with 4-node tetrahedra:
                   physical volumes "upper" (0,2)x(0,1)x(1,2) and "lower" (0,2)x(0,1)x(0,1),
                   no shared nodes on z = 1, the physical surfaces of two_blocks.geo
two_tet10_blocks   the same at order 2 (10-node tetrahedra, 6-node triangles)
sphere_on_block    a ball of radius 1 centred at (0, 0, 2), physical volume "ball" with its whole
                   surface "sphere", resting at its pole on the block (-1.5,1.5)x(-1.5,1.5)x(0,1),
                   physical volume "block" with "block_top" and "block_bottom"; 4-node
                   tetrahedra, ASCII only
sphere_on_block_tet10  the same at size 0.5 in 10-node tetrahedra
press_fit_rings    a shrink fit, quarter model in plane strain: the ring "shaft" (radii 0.5 to
                   1.001) inside the ring "hub" (1.0 to 2.0), 0.1 thick in z, both structured
                   hexahedra on the same 24 angular divisions (16 radial in the shaft, 24 in the
                   hub); surfaces "shaft_outer", "hub_inner", "<ring>_x0", "<ring>_y0" (the
                   symmetry planes) and "<ring>_z" (both z faces); ASCII only
pipe / pipe_tet10  a thick-walled pipe under internal pressure, quarter model in plane strain:
                   the ring "pipe" (radii 1 to 2, 0.1 thick in z), structured hexahedra on 8
                   radial and 16 angular divisions, or the same divisions split into 10-node
                   tetrahedra with curved (quadratic) arcs; surfaces "inner", "outer", "x0",
                   "y0" and "z" (both z faces); ASCII only
hollow_sphere_tet10  an octant of a hollow sphere, radii 1 to 2 (x, y, z > 0), in 10-node
                   tetrahedra of size 0.3 with curved faces: body "shell", surfaces "inner",
                   "outer", "x0", "y0", "z0"; ASCII only
wedge_layer        the unit cube as one body "body": a boundary layer of wedges (triangles of
                   z = 0 extruded to z = 0.2 in 2 layers) under 4-node tetrahedra; its
                   sub-volumes are also "layer" and "core"; physical surfaces "bottom" (z = 0,
                   triangles), "top" (z = 1, triangles), "xmin" (x = 0: quadrangles of the
                   layer and triangles of the core)

Only elements of physical groups are saved (Mesh.SaveAll = 0).
"""

import gmsh


def save(name):
    for binary, suffix in ((0, ""), (1, "_binary")):
        gmsh.option.setNumber("Mesh.Binary", binary)
        gmsh.write(f"{name}{suffix}.msh")


def common_options():
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)


def two_blocks(name, order, size):
    gmsh.clear()
    gmsh.model.add(name)
    occ = gmsh.model.occ
    occ.addBox(0, 0, 1, 2, 1, 1, 1)  # upper
    occ.addBox(0, 0, 0, 2, 1, 1, 2)  # lower
    occ.synchronize()
    # OpenCASCADE numbers the faces of a box x=min, x=max, y=min, y=max, z=min, z=max.
    model = gmsh.model
    model.addPhysicalGroup(3, [1], name="upper")
    model.addPhysicalGroup(3, [2], name="lower")
    for tag, face in (
        (6, "upper_top"),
        (5, "upper_bottom"),
        (1, "upper_left"),
        (2, "upper_right"),
        (12, "lower_top"),
        (7, "lower_left"),
    ):
        model.addPhysicalGroup(2, [tag], name=face)
    gmsh.option.setNumber("Mesh.MeshSizeMin", size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    model.mesh.generate(3)
    if order > 1:
        model.mesh.setOrder(order)
    save(name)


def wedge_layer(name, size):
    gmsh.clear()
    gmsh.model.add(name)
    geo = gmsh.model.geo
    p = [geo.addPoint(x, y, 0, size) for x, y in ((0, 0), (1, 0), (1, 1), (0, 1))]
    lines = [geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    base = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    # boundary layer: 2 layers of wedges up to z = 0.2
    layer = geo.extrude([(2, base)], 0, 0, 0.2, numElements=[2], recombine=True)
    top_of_layer = layer[0][1]
    layer_volume = layer[1][1]
    # the core above it, meshed with tetrahedra
    core = geo.extrude([(2, top_of_layer)], 0, 0, 0.8)
    top = core[0][1]
    core_volume = core[1][1]
    geo.synchronize()
    model = gmsh.model
    model.addPhysicalGroup(3, [layer_volume, core_volume], name="body")
    model.addPhysicalGroup(3, [layer_volume], name="layer")
    model.addPhysicalGroup(3, [core_volume], name="core")
    model.addPhysicalGroup(2, [base], name="bottom")
    model.addPhysicalGroup(2, [top], name="top")
    # x = 0: the side surfaces of both extrusions with a bounding box at x = 0
    xmin = []
    for dim, tag in model.getEntities(2):
        x0, _, _, x1, _, _ = model.getBoundingBox(dim, tag)
        if abs(x0) < 1e-6 and abs(x1) < 1e-6:
            xmin.append(tag)
    model.addPhysicalGroup(2, xmin, name="xmin")
    model.mesh.generate(3)
    save(name)


def sphere_on_block(name, size, order=1):
    gmsh.clear()
    gmsh.model.add(name)
    occ = gmsh.model.occ
    ball = occ.addSphere(0, 0, 2, 1)
    block = occ.addBox(-1.5, -1.5, 0, 3, 3, 1)
    occ.synchronize()
    model = gmsh.model
    model.addPhysicalGroup(3, [ball], name="ball")
    model.addPhysicalGroup(3, [block], name="block")
    model.addPhysicalGroup(2, [b[1] for b in model.getBoundary([(3, ball)])], name="sphere")
    at_z = lambda z: [abs(t) for _, t in model.getBoundary([(3, block)]) if abs(model.getBoundingBox(2, abs(t))[2] - z) < 1e-6 and abs(model.getBoundingBox(2, abs(t))[5] - z) < 1e-6]
    model.addPhysicalGroup(2, at_z(1.0), name="block_top")
    model.addPhysicalGroup(2, at_z(0.0), name="block_bottom")
    gmsh.option.setNumber("Mesh.MeshSizeMin", size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    model.mesh.generate(3)
    if order > 1:
        model.mesh.setOrder(order)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(f"{name}.msh")


def ring(geo, r0, r1, nr, nth, t):
    """A quarter ring r0 < r < r1 in x, y > 0, extruded to z = t in one layer of hexahedra:
    (volume, lateral surfaces y = 0, outer arc, x = 0, inner arc, the two z faces)."""
    c = geo.addPoint(0, 0, 0)
    p = [geo.addPoint(r0, 0, 0), geo.addPoint(r1, 0, 0), geo.addPoint(0, r1, 0), geo.addPoint(0, r0, 0)]
    lines = [geo.addLine(p[0], p[1]), geo.addCircleArc(p[1], c, p[2]), geo.addLine(p[2], p[3]), geo.addCircleArc(p[3], c, p[0])]
    base = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    for line, n in zip(lines, (nr, nth, nr, nth)):
        geo.mesh.setTransfiniteCurve(line, n + 1)
    geo.mesh.setTransfiniteSurface(base)
    geo.mesh.setRecombine(2, base)
    ext = geo.extrude([(2, base)], 0, 0, t, numElements=[1], recombine=True)
    return ext[1][1], [e[1] for e in ext[2:6]], [base, ext[0][1]]


def press_fit_rings(name):
    gmsh.clear()
    gmsh.model.add(name)
    geo = gmsh.model.geo
    shaft = ring(geo, 0.5, 1.001, 16, 24, 0.1)
    hub = ring(geo, 1.0, 2.0, 24, 24, 0.1)
    geo.synchronize()
    model = gmsh.model
    for label, (vol, (y0, outer, x0, inner), zs) in (("shaft", shaft), ("hub", hub)):
        model.addPhysicalGroup(3, [vol], name=label)
        model.addPhysicalGroup(2, [y0], name=f"{label}_y0")
        model.addPhysicalGroup(2, [x0], name=f"{label}_x0")
        model.addPhysicalGroup(2, zs, name=f"{label}_z")
        model.addPhysicalGroup(2, [outer if label == "shaft" else inner], name="shaft_outer" if label == "shaft" else "hub_inner")
    model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(f"{name}.msh")


def pipe(name, order):
    gmsh.clear()
    gmsh.model.add(name)
    geo = gmsh.model.geo
    c = geo.addPoint(0, 0, 0)
    p = [geo.addPoint(1, 0, 0), geo.addPoint(2, 0, 0), geo.addPoint(0, 2, 0), geo.addPoint(0, 1, 0)]
    lines = [geo.addLine(p[0], p[1]), geo.addCircleArc(p[1], c, p[2]), geo.addLine(p[2], p[3]), geo.addCircleArc(p[3], c, p[0])]
    base = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    for line, n in zip(lines, (8, 16, 8, 16)):
        geo.mesh.setTransfiniteCurve(line, n + 1)
    geo.mesh.setTransfiniteSurface(base)
    hex_ = order == 1
    if hex_:
        geo.mesh.setRecombine(2, base)
    ext = geo.extrude([(2, base)], 0, 0, 0.1, numElements=[1], recombine=hex_)
    geo.synchronize()
    model = gmsh.model
    y0, outer, x0, inner = [e[1] for e in ext[2:6]]
    model.addPhysicalGroup(3, [ext[1][1]], name="pipe")
    for tag, label in ((inner, "inner"), (outer, "outer"), (x0, "x0"), (y0, "y0")):
        model.addPhysicalGroup(2, [tag], name=label)
    model.addPhysicalGroup(2, [base, ext[0][1]], name="z")
    model.mesh.generate(3)
    if order > 1:
        model.mesh.setOrder(order)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(f"{name}.msh")


def hollow_sphere(name, size):
    gmsh.clear()
    gmsh.model.add(name)
    occ = gmsh.model.occ
    shell, _ = occ.cut([(3, occ.addSphere(0, 0, 0, 2))], [(3, occ.addSphere(0, 0, 0, 1))])
    octant, _ = occ.intersect(shell, [(3, occ.addBox(0, 0, 0, 3, 3, 3))])
    occ.synchronize()
    model = gmsh.model
    vol = octant[0][1]
    model.addPhysicalGroup(3, [vol], name="shell")
    faces = {"inner": [], "outer": [], "x0": [], "y0": [], "z0": []}
    for _, t in model.getBoundary([(3, vol)], oriented=False):
        x0, y0, z0, x1, y1, z1 = model.getBoundingBox(2, t)
        if max(x1, y1, z1) > 1.5:
            key = "outer" if min(x1 - x0, y1 - y0, z1 - z0) > 1e-6 else ("x0" if x1 < 1e-6 else "y0" if y1 < 1e-6 else "z0")
        else:
            key = "inner"
        faces[key].append(t)
    for key, tags in faces.items():
        model.addPhysicalGroup(2, tags, name=key)
    gmsh.option.setNumber("Mesh.MeshSizeMin", size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    model.mesh.generate(3)
    model.mesh.setOrder(2)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(f"{name}.msh")


gmsh.initialize()
common_options()
two_blocks("two_tet_blocks", 1, 0.4)
two_blocks("two_tet10_blocks", 2, 0.5)
wedge_layer("wedge_layer", 0.3)
sphere_on_block("sphere_on_block", 0.3)
sphere_on_block("sphere_on_block_tet10", 0.5, 2)
press_fit_rings("press_fit_rings")
pipe("pipe", 1)
pipe("pipe_tet10", 2)
hollow_sphere("hollow_sphere_tet10", 0.3)
gmsh.finalize()
