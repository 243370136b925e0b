"""Writes the MED fixtures with Gmsh's own MED export (Gmsh built with the MED library writes
MED 4.1 through it: node order converted to MED's, physical groups as MED groups):
two_blocks.med, two_tet_blocks.med, two_tet10_blocks.med, wedge_layer.med.

    cd mesh && python3 make_med.py      # needs `pip install gmsh` (4.15.2 made the files)
"""
import gmsh

gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
for name in ["two_blocks", "two_tet_blocks", "two_tet10_blocks", "wedge_layer"]:
    gmsh.open(f"{name}.msh")
    gmsh.write(f"{name}.med")
    gmsh.clear()
gmsh.finalize()
