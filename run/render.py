# Renders a tresca-feti result with ParaView (Debian: paraview python3-paraview xvfb):
#   xvfb-run -a -s "-screen 0 1280x1024x24" pvbatch run/render.py RESULT.xdmf OUT.png [WARP] [--animation]
# Opens the XDMF with ParaView's Xdmf3 reader, prints what it read, warps by the displacement
# (factor WARP, default 200) and colours by von Mises stress. A load path (an XDMF time series)
# is drawn at its last step; with --animation also one picture per step, OUT.0000.png,
# OUT.0001.png, … (the frames of the animation ParaView's Play button shows).
import sys
from paraview.simple import *

args = [a for a in sys.argv[1:] if a != "--animation"]
animation = "--animation" in sys.argv[1:]
xdmf, png = args[0], args[1]
warp = float(args[2]) if len(args) > 2 else 200.0
r = Xdmf3ReaderS(FileName=[xdmf])
times = list(r.TimestepValues or [])
r.UpdatePipeline(time=times[-1]) if times else r.UpdatePipeline()
info = r.GetDataInformation()
print("points", info.GetNumberOfPoints(), "cells", info.GetNumberOfCells(),
      "point arrays", r.PointData.keys(), "cell arrays", r.CellData.keys(),
      "steps", len(times) if times else 1)
w = WarpByVector(Input=r, Vectors=["POINTS", "displacement"], ScaleFactor=warp)
v = GetActiveViewOrCreate("RenderView")
v.ViewSize = [900, 600]
d = Show(w, v)
ColorBy(d, ("CELLS", "von_mises"))
v.CameraPosition = [5, -4, 4]
v.CameraFocalPoint = [1, 0.5, 1]
v.CameraViewUp = [0, 0, 1]
ResetCamera(v)
scene = GetAnimationScene()
if times:
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = times[-1]
    label = Show(AnnotateTimeFilter(Input=r, Format="load step {time:.0f}"), v)
    label.FontSize = 14
d.RescaleTransferFunctionToDataRange(False, True)
bar = GetScalarBar(GetColorTransferFunction("von_mises"), v)
bar.Title = "von Mises [MPa]"
bar.ComponentTitle = ""
d.SetScalarBarVisibility(v, True)
SaveScreenshot(png, v)
print("wrote", png)
if animation and times:
    stem = png[:-4] if png.endswith(".png") else png
    SaveAnimation(stem + ".png", v, FrameWindow=[0, len(times) - 1])
    print("wrote", ", ".join("%s.%04d.png" % (stem, i) for i in range(len(times))))
