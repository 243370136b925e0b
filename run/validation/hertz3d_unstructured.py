#!/usr/bin/env python3
"""Hertz 3D on unstructured tet4 meshes (issue 55): the quarter model of run/validation/hertz3d.toml
(a cap of a sphere R = 10 pressed onto a flat of the same material, E = 50 000, ν = 0.3, the cap's
top moved down 0.0055) meshed by Gmsh with 4-node tetrahedra, size h within 0.45 of the pole and
4h further out, the two contact faces meshed independently.

    pip install gmsh h5py
    python3 run/validation/hertz3d_unstructured.py --h 0.045,0.03

Per mesh: a/h, the peak nodal pressure against p₀ = 3·4F/(2πa²) (a from the measured force), the
scatter of the nodes within a/2 of the pole off the symmetry planes (rms of p/p_Hertz(r) − 1), for
the nodal multipliers λ/D (`contact_pressure`) and for the area-weighted average over each slave
node's facets of their nodes' pressures (`contact_pressure_smooth`, when the result has it).
"""

import argparse, json, os, subprocess, sys, tempfile

import gmsh
import h5py
import numpy as np

E, NU, R, PRESS = 50000.0, 0.3, 10.0, 0.0055
HERE = os.path.dirname(os.path.abspath(__file__))


def mesh(path, h):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    occ = gmsh.model.occ
    z0 = 1.0 + R - (R * R - 2.0) ** 0.5  # as hertz3d.toml: the box's corners on the sphere
    ball = occ.addSphere(0, 0, 1.0 + R, R)
    cap, _ = occ.intersect([(3, occ.addBox(0, 0, 1.0, 1, 1, z0 + 1.0 - 1.0))], [(3, ball)])
    flat = occ.addBox(0, 0, 0, 1, 1, 1)
    occ.synchronize()
    m = gmsh.model
    capv = cap[0][1]
    m.addPhysicalGroup(3, [capv], name="cap")
    m.addPhysicalGroup(3, [flat], name="flat")
    def faces(vol, test):
        out = []
        for _, t in m.getBoundary([(3, vol)], oriented=False):
            bb = m.getBoundingBox(2, t)
            if test(bb):
                out.append(t)
        return out
    flatz = lambda z: (lambda bb: abs(bb[2] - z) < 1e-6 and abs(bb[5] - z) < 1e-6)
    m.addPhysicalGroup(2, faces(capv, lambda bb: bb[5] - bb[2] > 1e-6 and bb[5] < z0 + 1e-6 and bb[3] - bb[0] > 0.5 and bb[4] - bb[1] > 0.5), name="cap_sphere")
    m.addPhysicalGroup(2, faces(capv, lambda bb: abs(bb[2] - (z0 + 1.0)) < 1e-6 and abs(bb[5] - (z0 + 1.0)) < 1e-6), name="cap_top")
    m.addPhysicalGroup(2, faces(capv, lambda bb: bb[3] < 1e-6), name="cap_x0")
    m.addPhysicalGroup(2, faces(capv, lambda bb: bb[4] < 1e-6), name="cap_y0")
    m.addPhysicalGroup(2, faces(flat, flatz(1.0)), name="flat_top")
    m.addPhysicalGroup(2, faces(flat, flatz(0.0)), name="flat_bottom")
    m.addPhysicalGroup(2, faces(flat, lambda bb: bb[3] < 1e-6), name="flat_x0")
    m.addPhysicalGroup(2, faces(flat, lambda bb: bb[4] < 1e-6), name="flat_y0")
    f = m.mesh.field
    b = f.add("Ball")
    f.setNumber(b, "Radius", 0.45); f.setNumber(b, "VIn", h); f.setNumber(b, "VOut", 4 * h)
    f.setNumber(b, "Thickness", 0.3); f.setNumber(b, "ZCenter", 1.0)
    f.setAsBackgroundMesh(b)
    for k in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{k}", 0)
    m.mesh.generate(3)
    gmsh.write(path)
    gmsh.finalize()
    return z0


SCENE = """title = "Hertz 3D, unstructured tet4"
[[material]]
name = "m"
E = {E}
nu = {NU}
[[body]]
name = "cap"
material = "m"
gmsh = {{ file = "{msh}", volume = "cap" }}
[[body]]
name = "flat"
material = "m"
gmsh = {{ file = "{msh}", volume = "flat" }}
[[dirichlet]]
face = "flat.flat_bottom"
[[dirichlet]]
face = "cap.cap_top"
components = ["z"]
value = [0.0, 0.0, -{PRESS}]
[[dirichlet]]
face = "cap.cap_x0"
components = ["x"]
[[dirichlet]]
face = "cap.cap_y0"
components = ["y"]
[[dirichlet]]
face = "flat.flat_x0"
components = ["x"]
[[dirichlet]]
face = "flat.flat_y0"
components = ["y"]
[[contact.pair]]
slave = "cap.cap_sphere"
master = "flat.flat_top"
search_distance = 0.05
[output]
fields = {fields}
"""


def measure(out):
    with h5py.File(out) as f:
        x = f["mesh/coordinates"][:]
        st = f["fields/contact_status"][:]
        fields = {k: f["fields/" + k][:] for k in ("contact_pressure", "contact_pressure_smooth") if "fields/" + k in f}
        F = json.loads(f.attrs["report"])["contact"]["total_force_on_slave"][2]
    estar = E / (2 * (1 - NU * NU))
    a = (3 * 4 * abs(F) * R / (4 * estar)) ** (1 / 3)
    p0 = 3 * 4 * abs(F) / (2 * np.pi * a * a)
    r = np.hypot(x[:, 0], x[:, 1])
    off = (x[:, 0] > 1e-9) & (x[:, 1] > 1e-9)
    inner = (st > 1) & (r < 0.5 * a) & off
    out = {"a": a, "p0": p0}
    for k, p in fields.items():
        hz = p0 * np.sqrt(np.clip(1 - r * r / (a * a), 0, None))
        out[k] = (p[st > 0].max() / p0 - 1, float(np.sqrt(np.mean((p[inner] / hz[inner] - 1) ** 2))), int(inner.sum()))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--h", default="0.045,0.03")
    ap.add_argument("--bin", default=os.path.join(HERE, "../../target/release/tresca-feti"))
    ap.add_argument("--keep", default=None)
    a = ap.parse_args()
    work = a.keep or tempfile.mkdtemp(prefix="hertz-tet4-")
    os.makedirs(work, exist_ok=True)
    print("h        a/h    peak λ/D   scatter λ/D   peak smooth   scatter smooth   nodes")
    for h in (float(v) for v in a.h.split(",")):
        msh = os.path.join(work, f"hertz-{h}.msh")
        if not os.path.exists(msh):
            mesh(msh, h)
        scene = os.path.join(work, f"hertz-{h}.toml")
        fields = '["displacement", "contact_status", "contact_pressure", "contact_pressure_smooth"]'
        with open(scene, "w") as f:
            f.write(SCENE.format(E=E, NU=NU, msh=msh, PRESS=PRESS, fields=fields))
        out = os.path.join(work, f"hertz-{h}.h5")
        r = subprocess.run([a.bin, "solve", scene, "--out", out, "--quiet"], capture_output=True, text=True, timeout=1200)
        if r.returncode != 0:
            # a binary without the smoothed field
            with open(scene, "w") as f:
                f.write(SCENE.format(E=E, NU=NU, msh=msh, PRESS=PRESS, fields='["displacement", "contact_status", "contact_pressure"]'))
            r = subprocess.run([a.bin, "solve", scene, "--out", out, "--quiet"], capture_output=True, text=True, timeout=1200)
            if r.returncode != 0:
                sys.exit(r.stderr)
        m = measure(out)
        raw = m["contact_pressure"]
        sm = m.get("contact_pressure_smooth", (float("nan"), float("nan"), 0))
        print(f"{h:<8g} {m['a'] / h:5.1f}  {100 * raw[0]:+8.2f} %  {100 * raw[1]:9.2f} %   {100 * sm[0]:+9.2f} %   {100 * sm[1]:11.2f} %   {raw[2]}")


if __name__ == "__main__":
    main()
