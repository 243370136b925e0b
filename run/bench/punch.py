#!/usr/bin/env python3
"""A quarter flat cylindrical punch on a block, tet4, the two bodies meshed independently (non-matching).

The punch is the quarter (x ≥ 0, y ≥ 0) of a cylinder of radius A = 1 and height 2 standing on
z = 0; the block is the quarter [0, 6] × [0, 6] × [-6, 0] of a 12 mm cube. Physical volumes "punch"
and "block"; physical surfaces "punch_bottom", "punch_top", "punch_x0", "punch_y0", "block_top",
"block_bottom", "block_x0", "block_y0". The two volumes are not fragmented, so their meshes do not
match on z = 0.

    python3 run/bench/punch.py H_BLOCK H_PUNCH OUT.msh

Sizes: H_BLOCK within 1.5 A of the axis on the block's top, growing to 1.0 away from it; H_PUNCH on
the punch's bottom, growing to 4 H_PUNCH at its top.
"""
import sys

import gmsh

A, HP, W, D = 1.0, 2.0, 6.0, 6.0


def main():
    args = sys.argv[1:]
    if len(args) != 3:
        sys.exit(__doc__)
    hb, hp, out = float(args[0]), float(args[1]), args[2]
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("punch")
    occ = gmsh.model.occ
    cyl = occ.addCylinder(0, 0, 0, 0, 0, HP, A, angle=1.5707963267948966)
    block = occ.addBox(0, 0, -D, W, W, D)
    occ.synchronize()

    def at(vol, test):
        tags = []
        for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False):
            if test(*occ.getCenterOfMass(2, s)):
                tags.append(s)
        return tags

    eps = 1e-6
    groups = {
        "punch_bottom": at(cyl, lambda x, y, z: abs(z) < eps),
        "punch_top": at(cyl, lambda x, y, z: abs(z - HP) < eps),
        "punch_x0": at(cyl, lambda x, y, z: abs(x) < eps),
        "punch_y0": at(cyl, lambda x, y, z: abs(y) < eps),
        "block_top": at(block, lambda x, y, z: abs(z) < eps),
        "block_bottom": at(block, lambda x, y, z: abs(z + D) < eps),
        "block_x0": at(block, lambda x, y, z: abs(x) < eps),
        "block_y0": at(block, lambda x, y, z: abs(y) < eps),
    }
    for name, tags in groups.items():
        assert tags, name
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, tags), name)
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [cyl]), "punch")
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [block]), "block")
    f = gmsh.model.mesh.field
    fb = f.add("MathEval")
    f.setString(fb, "F", f"{hb} + Min(1, Max(0, Sqrt(x*x + y*y + z*z) - {1.5 * A}) / 4) * {1.0 - hb}")
    fp = f.add("MathEval")
    f.setString(fp, "F", f"{hp} * (1 + 3 * Max(0, z) / {HP})")
    rb = f.add("Restrict")
    f.setNumber(rb, "InField", fb)
    f.setNumbers(rb, "VolumesList", [block])
    rp = f.add("Restrict")
    f.setNumber(rp, "InField", fp)
    f.setNumbers(rp, "VolumesList", [cyl])
    mn = f.add("Min")
    f.setNumbers(mn, "FieldsList", [rb, rp])
    f.setAsBackgroundMesh(mn)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 1)
    gmsh.write(out)
    n = len(gmsh.model.mesh.getNodes()[0])
    print(f"{out}: {n} nodes, {3 * n} DOFs (h block {hb}, punch {hp})")
    gmsh.finalize()


if __name__ == "__main__":
    main()
