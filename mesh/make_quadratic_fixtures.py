"""Quadratic hexahedra and wedges for the Gmsh reader's tests: a 1 x 1 x 1 box as hex20
(second order, incomplete), as hex27 (second order, complete), and a 1 x 1 x 1 extruded
triangle as wedge15, each with a physical volume "body" and the physical surface "top"
(z = 1). Run with the pyenv python3 (gmsh module): python3 mesh/make_quadratic_fixtures.py"""
import gmsh


def box(name, incomplete, wedge):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.add(name)
    if wedge:
        p = [gmsh.model.geo.addPoint(x, y, 0) for x, y in [(0, 0), (1, 0), (0, 1)]]
        lines = [gmsh.model.geo.addLine(p[i], p[(i + 1) % 3]) for i in range(3)]
        s = gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(lines)])
        gmsh.model.geo.mesh.setTransfiniteSurface(s)
        for c in lines:
            gmsh.model.geo.mesh.setTransfiniteCurve(c, 3)
        ext = gmsh.model.geo.extrude([(2, s)], 0, 0, 1, numElements=[2], recombine=True)
    else:
        p = [gmsh.model.geo.addPoint(x, y, 0) for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)]]
        lines = [gmsh.model.geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
        s = gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(lines)])
        for c in lines:
            gmsh.model.geo.mesh.setTransfiniteCurve(c, 3)
        gmsh.model.geo.mesh.setTransfiniteSurface(s)
        gmsh.model.geo.mesh.setRecombine(2, s)
        ext = gmsh.model.geo.extrude([(2, s)], 0, 0, 1, numElements=[2], recombine=True)
    gmsh.model.geo.synchronize()
    top = ext[0][1]
    vol = ext[1][1]
    gmsh.model.addPhysicalGroup(3, [vol], name="body")
    gmsh.model.addPhysicalGroup(2, [top], name="top")
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", 1 if incomplete else 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(3)
    gmsh.write(f"mesh/{name}.msh")
    gmsh.finalize()


box("cube_hex20", True, False)
box("cube_hex27", False, False)
box("prism_wedge15", True, True)
