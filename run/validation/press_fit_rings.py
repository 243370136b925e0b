#!/usr/bin/env python3
"""Press fits of two rings meshed independently (issue 55): a shaft a < r < b inside a hub
b < r < c, a = 10, b = 20, c = 40 mm, 2 mm thick, quarter model in plane strain (z held on both
z faces, rollers on x = 0 and y = 0), steel E = 210 GPa, ν = 0.3, radial interference δ = 0.02.
Lamé: p = E'δ/b / ((c² + b²)/(c² − b²) + (b² + a²)/(b² − a²)) = 69.23 MPa, E' = E/(1 − ν²);
the force on the slave's quarter along x is −p·b·t.

Meshes (Gmsh Python API, `pip install gmsh`): tet4 or tet10 of size h, or hexahedra with
`--hex NS,NH` angular divisions on the shaft and the hub. Two ways to state the fit:
  meshed   the shaft's outer radius is b + δ (`interference = true`)
  stated   both at the nominal radius b, `interference = δ`

    python3 run/validation/press_fit_rings.py --mesh tet4 --h 1.5 --fit stated
    python3 run/validation/press_fit_rings.py --mesh hex --hex 24,16 --fit meshed

Prints the slave nodes closed, the worst interior node (not on a symmetry plane or a z face)
and every node against Lamé, the mean, and the resultant.
"""

import argparse, json, os, subprocess, sys, tempfile

import gmsh
import h5py
import numpy as np

A, B, C, T, DELTA, E, NU = 10.0, 20.0, 40.0, 2.0, 0.02, 210000.0, 0.3


def lame():
    e1 = E / (1 - NU * NU)
    return e1 * DELTA / B / ((C * C + B * B) / (C * C - B * B) + (B * B + A * A) / (B * B - A * A))


def ring_geo(geo, r0, r1, nr, nth):
    c = geo.addPoint(0, 0, 0)
    p = [geo.addPoint(r0, 0, 0), geo.addPoint(r1, 0, 0), geo.addPoint(0, r1, 0), geo.addPoint(0, r0, 0)]
    lines = [geo.addLine(p[0], p[1]), geo.addCircleArc(p[1], c, p[2]), geo.addLine(p[2], p[3]), geo.addCircleArc(p[3], c, p[0])]
    base = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    for line, n in zip(lines, (nr, nth, nr, nth)):
        geo.mesh.setTransfiniteCurve(line, n + 1)
    geo.mesh.setTransfiniteSurface(base)
    geo.mesh.setRecombine(2, base)
    ext = geo.extrude([(2, base)], 0, 0, T, numElements=[2], recombine=True)
    y0, outer, x0, inner = [e[1] for e in ext[2:6]]
    return ext[1][1], {"y0": [y0], "x0": [x0], "outer": [outer], "inner": [inner], "z": [base, ext[0][1]]}


def ring_occ(occ, r0, r1):
    outer = occ.addCylinder(0, 0, 0, 0, 0, T, r1)
    inner = occ.addCylinder(0, 0, 0, 0, 0, T, r0)
    ring, _ = occ.cut([(3, outer)], [(3, inner)])
    quad, _ = occ.intersect(ring, [(3, occ.addBox(0, 0, 0, 2 * r1, 2 * r1, T))])
    return quad[0][1]


def classify(model, vol, r0, r1):
    faces = {"y0": [], "x0": [], "outer": [], "inner": [], "z": []}
    for _, t in model.getBoundary([(3, vol)], oriented=False):
        x0, y0, z0, x1, y1, z1 = model.getBoundingBox(2, t)
        if z1 - z0 < 1e-6:
            faces["z"].append(t)
        elif x1 - x0 < 1e-6 and x1 < 1e-6:
            faces["x0"].append(t)
        elif y1 - y0 < 1e-6 and y1 < 1e-6:
            faces["y0"].append(t)
        elif max(x1, y1) > 0.5 * (r0 + r1):
            faces["outer"].append(t)
        else:
            faces["inner"].append(t)
    return faces


def mesh(path, kind, h, hexdiv, outer_shaft):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.model.add("rings")
    model = gmsh.model
    if kind == "hex":
        geo = model.geo
        ns, nh = hexdiv
        shaft, fs = ring_geo(geo, A, outer_shaft, max(2, round((outer_shaft - A) / (B * np.pi / 2 / ns))), ns)
        hub, fh = ring_geo(geo, B, C, max(2, round((C - B) / (B * np.pi / 2 / nh))), nh)
        geo.synchronize()
    else:
        occ = model.occ
        shaft = ring_occ(occ, A, outer_shaft)
        hub = ring_occ(occ, B, C)
        occ.synchronize()
        fs, fh = classify(model, shaft, A, outer_shaft), classify(model, hub, B, C)
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    for name, vol, faces in (("shaft", shaft, fs), ("hub", hub, fh)):
        model.addPhysicalGroup(3, [vol], name=name)
        for k, tags in faces.items():
            model.addPhysicalGroup(2, tags, name=f"{name}_{k}")
    model.mesh.generate(3)
    if kind == "tet10":
        model.mesh.setOrder(2)
    gmsh.write(path)
    gmsh.finalize()


SCENE = """title = "press fit of independently meshed rings"
units = {{ length = "mm", force = "N" }}
[[material]]
name = "steel"
E = {E}
nu = {NU}
[[body]]
name = "shaft"
material = "steel"
gmsh = {{ file = "{msh}", volume = "shaft" }}
[[body]]
name = "hub"
material = "steel"
gmsh = {{ file = "{msh}", volume = "hub" }}
[[dirichlet]]
face = "shaft.shaft_z"
components = ["z"]
[[dirichlet]]
face = "hub.hub_z"
components = ["z"]
[[dirichlet]]
face = "shaft.shaft_x0"
components = ["x"]
[[dirichlet]]
face = "shaft.shaft_y0"
components = ["y"]
[[dirichlet]]
face = "hub.hub_x0"
components = ["x"]
[[dirichlet]]
face = "hub.hub_y0"
components = ["y"]
[[contact.pair]]
slave = "shaft.shaft_outer"
master = "hub.hub_inner"
interference = {fit}
[output]
fields = ["displacement", "contact_status", "contact_pressure", "gap"]
"""


def run(binary, kind, h, hexdiv, fit, work, extra=()):
    msh = os.path.join(work, "rings.msh")
    mesh(msh, kind, h, hexdiv, B + DELTA if fit == "meshed" else B)
    scene = os.path.join(work, "rings.toml")
    with open(scene, "w") as f:
        f.write(SCENE.format(E=E, NU=NU, msh=msh, fit="true" if fit == "meshed" else DELTA))
    out = os.path.join(work, "rings.h5")
    cmd = [binary, "solve", scene, "--out", out, "--quiet", *extra]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    if r.returncode != 0:
        return None, r.stderr.strip()
    with h5py.File(out) as f:
        x, st, p = f["mesh/coordinates"][:], f["fields/contact_status"][:], f["fields/contact_pressure"][:]
        rep = json.loads(f.attrs["report"])
    slave = st > 0
    closed = st > 1
    edge = (np.abs(x[:, 0]) < 1e-9) | (np.abs(x[:, 1]) < 1e-9) | (np.abs(x[:, 2]) < 1e-9) | (np.abs(x[:, 2] - T) < 1e-9)
    pl = lame()
    err = (p - pl) / pl
    fx = rep["contact"]["total_force_on_slave"][0]
    return {
        "slave": int(slave.sum()), "closed": int(closed.sum()),
        "interior_worst": float(np.abs(err[slave & ~edge]).max()), "all_worst": float(np.abs(err[slave]).max()),
        "mean": float(err[closed].mean()), "resultant": fx / (-pl * B * T) - 1, "nA": rep["solver"]["nA"],
    }, ""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh", choices=["tet4", "tet10", "hex"], default="tet4")
    ap.add_argument("--h", type=float, default=1.5)
    ap.add_argument("--hex", default="24,24", help="angular divisions of the shaft and the hub")
    ap.add_argument("--fit", choices=["meshed", "stated"], default="stated")
    ap.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "../../target/release/tresca-feti"))
    ap.add_argument("--set", action="append", default=[])
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as work:
        extra = [x for s in a.set for x in ("--set", s)]
        r, err = run(a.bin, a.mesh, a.h, tuple(int(v) for v in a.hex.split(",")), a.fit, work, extra)
    label = f"{a.mesh} {'h = %g' % a.h if a.mesh != 'hex' else 'divisions ' + a.hex} {a.fit}"
    if r is None:
        print(f"{label}: failed: {err}")
        sys.exit(1)
    print(f"{label}: Lamé {lame():.3f} MPa; {r['closed']} of {r['slave']} slave nodes closed; interior worst {100 * r['interior_worst']:.1f} %, "
          f"all worst {100 * r['all_worst']:.1f} %, mean {100 * r['mean']:+.2f} %, resultant {100 * r['resultant']:+.2f} %, nA {r['nA']}")


if __name__ == "__main__":
    main()
