"""Writes a large hexahedral box model as an Abaqus input and a MED file (Gmsh's own exports,
as mesh/make_quadratic_conversions.py and mesh/make_med.py make the fixtures) for timing the
readers: N × N × N nodes (N = 100: 1 000 000 nodes, 970 299 C3D8 / HE8 cells) in one volume
"block" with its top and bottom faces "top" and "bottom", plus the scene that reads each.

    python3 run/bench/large_mesh/make_large_mesh.py [N] [DIR]    # pyenv python3 (gmsh module)

DIR (default /tmp/large_mesh) receives box.inp, box.med, box_inp.toml and box_med.toml; time
them with `tresca-feti check DIR/box_inp.toml` (its "mesh" line). Keep the files out of git.
"""
import os
import sys

import gmsh

n = int(sys.argv[1]) if len(sys.argv) > 1 else 100
out = sys.argv[2] if len(sys.argv) > 2 else "/tmp/large_mesh"
os.makedirs(out, exist_ok=True)
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("box")
v = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
gmsh.model.occ.synchronize()
for dim, tag in gmsh.model.getEntities(1):
    gmsh.model.mesh.setTransfiniteCurve(tag, n)
for dim, tag in gmsh.model.getEntities(2):
    gmsh.model.mesh.setTransfiniteSurface(tag)
    gmsh.model.mesh.setRecombine(2, tag)
gmsh.model.mesh.setTransfiniteVolume(v)
gmsh.model.mesh.setRecombine(3, v)
# the faces z = 0 and z = 1 by their centres
faces = {"bottom": [], "top": []}
for dim, tag in gmsh.model.getEntities(2):
    z = gmsh.model.occ.getCenterOfMass(dim, tag)[2]
    if abs(z) < 1e-9:
        faces["bottom"].append(tag)
    elif abs(z - 1) < 1e-9:
        faces["top"].append(tag)
gmsh.model.addPhysicalGroup(3, [v], name="block")
for name, tags in faces.items():
    gmsh.model.addPhysicalGroup(2, tags, name=name)
gmsh.model.mesh.generate(3)
gmsh.option.setNumber("Mesh.SaveGroupsOfElements", 1)
for ext in ["inp", "med"]:
    gmsh.write(os.path.join(out, f"box.{ext}"))
gmsh.finalize()

for ext in ["inp", "med"]:
    with open(os.path.join(out, f"box_{ext}.toml"), "w") as f:
        f.write(f"""title = "{n}^3-node box read from {ext}"
[[material]]
name = "m"
E = 1000.0
nu = 0.3
[[body]]
name = "b"
material = "m"
mesh = {{ file = "box.{ext}", volume = "block" }}
[[dirichlet]]
face = "b.bottom"
[[traction]]
face = "b.top"
p = [0.0, 0.0, -1.0]
""")
print(f"{out}: box.inp, box.med ({n ** 3} nodes, {(n - 1) ** 3} hexahedra) and their scenes")
