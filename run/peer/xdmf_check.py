#!/usr/bin/env python3
"""Opens a tresca-feti result's XDMF with a reader of its own (meshio, Debian python3-meshio)
and checks it against the HDF5 file read with h5py: the points, the cells (type and count),
and every field of every step equal to the arrays the file holds.
   run/peer/xdmf_check.py OUT.xdmf
Prints one line per grid and exits 1 at the first mismatch."""
import sys

import h5py
import meshio
import numpy as np

xdmf = sys.argv[1]
h5 = h5py.File(xdmf[: -len(".xdmf")] + ".h5", "r")
coords = h5["mesh/coordinates"][()]


def check_grid(name, points, cells, point_data, cell_data, fields):
    if not np.array_equal(points, coords):
        sys.exit(f"{name}: the points differ from /mesh/coordinates")
    ncells = sum(len(b.data) for b in cells)
    for key, values in list(point_data.items()) + list(cell_data.items()):
        values = values[0] if isinstance(values, list) else values
        stored = fields[key][()]
        if values.shape[0] != stored.shape[0] or not np.array_equal(values.reshape(stored.shape), stored):
            sys.exit(f"{name}: field {key} differs from the HDF5 file's")
    for key in point_data:
        if len(point_data[key]) != len(points):
            sys.exit(f"{name}: node field {key} has {len(point_data[key])} rows for {len(points)} points")
    print(f"{name}: {len(points)} points, {ncells} cells ({', '.join(b.type for b in cells)}), "
          f"{len(point_data)} node and {len(cell_data)} cell fields equal to the HDF5 file's")


if "steps" in h5:
    with meshio.xdmf.TimeSeriesReader(xdmf) as r:
        points, cells = r.read_points_cells()
        if r.num_steps != len(h5["steps"]):
            sys.exit(f"{r.num_steps} steps in the XDMF, {len(h5['steps'])} in the HDF5 file")
        for k in range(r.num_steps):
            t, pd, cd = r.read_data(k)
            check_grid(f"step {k + 1} (t = {t})", points, cells, pd, cd, h5["steps"][f"{k + 1:04d}"])
else:
    m = meshio.read(xdmf)
    check_grid("mesh", m.points, m.cells, m.point_data, m.cell_data, h5["fields"])
