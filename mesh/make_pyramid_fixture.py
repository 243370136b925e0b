"""A hexahedral-dominant mesh with pyramids for the Gmsh reader's tests: the two-block
benchmark of two_blocks.geo (physical volumes "upper" (0,2)x(0,1)x(1,2) and "lower"
(0,2)x(0,1)x(0,1), no shared nodes on z = 1, its physical surfaces "upper_top", "upper_bottom",
"upper_left", "upper_right", "lower_top", "lower_left"), where each block is two volumes
glued at x = 1: x < 1 structured hexahedra (transfinite, recombined), x > 1 tetrahedra, which
Gmsh joins to the hexahedra's quadrangles at x = 1 with pyramids. So both bodies hold Hex8,
Pyr5 and Tet4 cells, and their faces quadrangles and triangles.

Run with the pyenv python3 (gmsh module): python3 mesh/make_pyramid_fixture.py"""
import gmsh

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.option.setNumber("Mesh.SaveAll", 0)
gmsh.option.setNumber("Mesh.RandomSeed", 1)
gmsh.model.add("hex_pyr_tet")
occ = gmsh.model.occ
model = gmsh.model
blocks = {}
for name, z0 in (("upper", 1), ("lower", 0)):
    a = occ.addBox(0, 0, z0, 1, 1, 1)
    b = occ.addBox(1, 0, z0, 1, 1, 1)
    out, _ = occ.fragment([(3, a)], [(3, b)])
    blocks[name] = (z0, [t for d, t in out])
occ.synchronize()
h = 0.25
for name, (z0, vols) in blocks.items():
    hexv = [v for v in vols if model.getBoundingBox(3, v)[3] < 1 + 1e-6][0]
    for d, t in model.getBoundary([(3, hexv)], oriented=False, combined=False):
        for _, c in model.getBoundary([(2, t)], oriented=False, combined=False):
            gmsh.model.mesh.setTransfiniteCurve(abs(c), 5)
        gmsh.model.mesh.setTransfiniteSurface(t)
        gmsh.model.mesh.setRecombine(2, t)
    gmsh.model.mesh.setTransfiniteVolume(hexv)
    model.addPhysicalGroup(3, vols, name=name)
gmsh.option.setNumber("Mesh.MeshSizeMin", h)
gmsh.option.setNumber("Mesh.MeshSizeMax", h)


def faces(pred):
    return [t for _, t in model.getEntities(2) if pred(model.getBoundingBox(2, t))]


eps = 1e-6
for name, z0 in (("upper", 1), ("lower", 0)):
    inside = lambda b, z0=z0: b[2] > z0 - eps and b[5] < z0 + 1 + eps
    model.addPhysicalGroup(2, faces(lambda b: inside(b) and abs(b[2] - b[5]) < eps and abs(b[2] - z0 - 1) < eps), name=f"{name}_top")
    if name == "upper":
        model.addPhysicalGroup(2, faces(lambda b: inside(b) and abs(b[2] - b[5]) < eps and abs(b[2] - z0) < eps), name="upper_bottom")
        model.addPhysicalGroup(2, faces(lambda b: inside(b) and abs(b[3]) < eps), name="upper_left")
        model.addPhysicalGroup(2, faces(lambda b: inside(b) and abs(b[0] - 2) < eps), name="upper_right")
    else:
        model.addPhysicalGroup(2, faces(lambda b: inside(b) and abs(b[3]) < eps), name="lower_left")
model.mesh.generate(3)
gmsh.write("mesh/hex_pyr_tet.msh")
gmsh.finalize()
