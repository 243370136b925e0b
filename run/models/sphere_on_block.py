#!/usr/bin/env python3
"""A quarter Hertz sphere on a block, tet4, both bodies in one Gmsh 4.1 file (a stand-in for large users' models).

The upper body is the quarter (x ≥ 0, y ≥ 0) of the part of a ball of radius R = 4 centred at
(0, 0, R) below z = H (its curved lower surface touches the block at the origin); the block is
[0, W] × [0, W] × [-D, 0]. Physical volumes "ball" and "block"; physical surfaces "sphere" (the
ball's curved surface), "ball_top", "ball_x0", "ball_y0", "block_top", "block_bottom",
"block_x0", "block_y0".

    python3 run/models/sphere_on_block.py H_SIZE OUT.msh [--ascii]

h = 0.25 gives about 200 k DOFs; the mesh is finer (h/4) near the contact point.
"""
import sys

import gmsh

R, H, W, D = 4.0, 2.0, 4.0, 4.0


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) != 2:
        sys.exit(__doc__)
    h, out = float(args[0]), args[1]
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add("sphere_on_block")
    occ = gmsh.model.occ
    ball = occ.addSphere(0, 0, R, R)
    cut = occ.addBox(0, 0, 0, R, R, H)
    upper, _ = occ.intersect([(3, ball)], [(3, cut)])
    block = occ.addBox(0, 0, -D, W, W, D)
    occ.synchronize()
    up = upper[0][1]

    def surfaces(vol):
        return [s for _, s in gmsh.model.getBoundary([(3, vol)], oriented=False)]

    def at(vol, test):
        out = []
        for s in surfaces(vol):
            c = occ.getCenterOfMass(2, s)
            if test(*c):
                out.append(s)
        return out

    eps = 1e-6
    groups = {
        "ball_x0": at(up, lambda x, y, z: abs(x) < eps),
        "ball_y0": at(up, lambda x, y, z: abs(y) < eps),
        "ball_top": at(up, lambda x, y, z: abs(z - H) < eps),
        "block_top": at(block, lambda x, y, z: abs(z) < eps),
        "block_bottom": at(block, lambda x, y, z: abs(z + D) < eps),
        "block_x0": at(block, lambda x, y, z: abs(x) < eps),
        "block_y0": at(block, lambda x, y, z: abs(y) < eps),
    }
    named = {s for v in groups.values() for s in v}
    groups["sphere"] = [s for s in surfaces(up) if s not in named]
    for name, tags in groups.items():
        assert tags, name
        gmsh.model.setPhysicalName(2, gmsh.model.addPhysicalGroup(2, tags), name)
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [up]), "ball")
    gmsh.model.setPhysicalName(3, gmsh.model.addPhysicalGroup(3, [block]), "block")
    # finer near the contact point
    f = gmsh.model.mesh.field
    dist = f.add("MathEval")
    f.setString(dist, "F", f"{h / 4} + {h * 0.75} * Min(1, Sqrt(x*x + y*y + z*z) / 2)")
    f.setAsBackgroundMesh(dist)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.model.mesh.generate(3)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0 if "--ascii" in sys.argv else 1)
    gmsh.write(out)
    n = len(gmsh.model.mesh.getNodes()[0])
    print(f"{out}: {n} nodes, {3 * n} DOFs (h = {h})")
    gmsh.finalize()


if __name__ == "__main__":
    main()
