# Renders a tresca-feti result with ParaView (Debian: paraview python3-paraview xvfb):
#   xvfb-run -a -s "-screen 0 1280x1024x24" pvbatch run/render.py out/seed.xdmf out/seed.png [warp]
# Opens the XDMF with ParaView's Xdmf3 reader, prints what it read, warps by the displacement
# (factor `warp`, default 200) and colours by von Mises stress.
import sys
from paraview.simple import *

xdmf, png = sys.argv[1], sys.argv[2]
warp = float(sys.argv[3]) if len(sys.argv) > 3 else 200.0
r = Xdmf3ReaderS(FileName=[xdmf])
r.UpdatePipeline()
info = r.GetDataInformation()
print("points", info.GetNumberOfPoints(), "cells", info.GetNumberOfCells(),
      "point arrays", r.PointData.keys(), "cell arrays", r.CellData.keys())
w = WarpByVector(Input=r, Vectors=["POINTS", "displacement"], ScaleFactor=warp)
v = GetActiveViewOrCreate("RenderView")
v.ViewSize = [900, 600]
d = Show(w, v)
ColorBy(d, ("CELLS", "von_mises"))
d.RescaleTransferFunctionToDataRange(True)
d.SetScalarBarVisibility(v, True)
v.CameraPosition = [5, -4, 4]
v.CameraFocalPoint = [1, 0.5, 1]
v.CameraViewUp = [0, 0, 1]
ResetCamera(v)
SaveScreenshot(png, v)
print("wrote", png)
