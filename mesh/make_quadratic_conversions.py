"""Gmsh's own Abaqus and MED exports of the quadratic fixtures (cube_hex20.msh, cube_hex27.msh,
prism_wedge15.msh) and of the hexahedral-dominant hex_pyr_tet.msh: cube_hex20.inp,
prism_wedge15.inp (C3D20, C3D15: Gmsh converts the node order to Abaqus's on writing),
hex_pyr_tet.inp (C3D8, C3D5, C3D4; no .med of it), cube_hex20.med, cube_hex27.med, prism_wedge15.med (H20, H27,
P15 with QU8, QU9, TR6 faces, MED's node orders). Gmsh writes the 27-node hexahedron to
Abaqus with its own node order, not read here, so no cube_hex27.inp. Gmsh prints the .inp's
coordinates to 14 significant digits; they are rewritten here at full precision (the
.msh's values), so that the same mesh solves bit for bit.

    cd mesh && python3 make_quadratic_conversions.py      # pyenv python3 (gmsh module)
"""
import gmsh

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
for name, inp in [("cube_hex20", True), ("cube_hex27", False), ("prism_wedge15", True), ("hex_pyr_tet", True)]:
    gmsh.open(f"{name}.msh")
    if name != "hex_pyr_tet":
        gmsh.write(f"{name}.med")
    if inp:
        gmsh.option.setNumber("Mesh.SaveGroupsOfElements", 1)
        gmsh.write(f"{name}.inp")
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        at = {int(t): xyz[3 * i : 3 * i + 3] for i, t in enumerate(tags)}
        lines = open(f"{name}.inp").read().split("\n")
        block = False
        for i, line in enumerate(lines):
            if line.startswith("*"):
                block = line.upper().startswith("*NODE")
            elif block and line.strip():
                t = int(line.split(",")[0])
                lines[i] = f"{t}, " + ", ".join(repr(float(v)) for v in at[t])
        open(f"{name}.inp", "w").write("\n".join(lines))
    gmsh.clear()
gmsh.finalize()
