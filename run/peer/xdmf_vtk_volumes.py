#!/usr/bin/env python3
"""Opens tresca-feti results' XDMF files with VTK's own reader (vtkXdmfReader, the one ParaView
uses) and prints, per VTK cell type, the count and the smallest, largest and summed cell volume
of vtkCellSizeFilter (ParaView's "Cell Size"); exits 1 if any volume is not positive (a node
order VTK reads as an inverted cell).

    python3 -m venv /tmp/vtkenv && /tmp/vtkenv/bin/pip install vtk
    /tmp/vtkenv/bin/python run/peer/xdmf_vtk_volumes.py OUT.xdmf [MORE.xdmf …]
"""
import collections
import sys

import vtk
from vtkmodules.vtkIOXdmf2 import vtkXdmfReader

bad = False
for path in sys.argv[1:]:
    reader = vtkXdmfReader()
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutputDataObject(0)
    if grid.IsA("vtkMultiBlockDataSet"):
        it = grid.NewIterator()
        it.InitTraversal()
        grid = it.GetCurrentDataObject()
    size = vtk.vtkCellSizeFilter()
    size.SetInputData(grid)
    size.ComputeVolumeOn()
    size.Update()
    out = size.GetOutput()
    volume = out.GetCellData().GetArray("Volume")
    by_type = collections.defaultdict(list)
    for i in range(out.GetNumberOfCells()):
        by_type[out.GetCellType(i)].append(volume.GetValue(i))
    for t, v in sorted(by_type.items()):
        name = vtk.vtkCellTypeUtilities.GetClassNameFromTypeId(t)
        print(f"{path}: {name} {len(v)} cells, volume min {min(v):.4g} max {max(v):.4g} sum {sum(v):.6g}")
        bad |= min(v) <= 0.0
print(f"VTK {vtk.vtkVersion.GetVTKVersion()}: {'an inverted cell' if bad else 'every volume positive'}")
sys.exit(1 if bad else 0)
