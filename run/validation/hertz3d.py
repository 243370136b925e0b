#!/usr/bin/python3
"""Hertz 3D check of run/validation/hertz3d.toml (quarter model, non-matching meshes, mortar).

Usage: run/validation/hertz3d.py [--cap hex8|tet4|tet10|hex20|hex27] [--flat hex8|hex20|hex27] [--friction none|coulomb] [--levels 17,25,33]
                                 [--bin target/release/tresca-feti] [--keep DIR] [RESULT.h5 …]
Solves the scene at each refinement (the cap with n×n×(n+1)/2 nodes, the flat block with a
different count, ≈ 0.85 n, so the contact faces never match; n counts the cells' corners: hex20
adds a node at every edge's middle, and h below is the slave face's node spacing, half the cell
size there), or reads the given results, and
prints per level: the measured quarter force F (×4 for the full sphere), Hertz's
a = (3·4F·R/(4E*))^{1/3} and p₀ = 3·4F/(2πa²) (identical materials: 1/E* = 2(1 − ν²)/E), the
pressure at the pole node, the peak (largest nodal) pressure and their relative errors, the
mean relative error (in p₀) of the nodes within a/2 of the pole off and on the symmetry planes
(a mesh that is not symmetric about them, Kuhn tetrahedra, reads lower there), the contact radius along the x axis (last
closed / first open node, their midpoint against a in element sizes h), the relative L2 error of
the nodal pressure against p₀√(1 − r²/a²) over the slave nodes, and the observed rates.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

E, NU, R = 50000.0, 0.3, 10.0
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def flat_nodes(n):
    """The flat block's nodes per edge for a cap with n: a different count (never n)."""
    m = round(0.85 * (n - 1)) + 1
    return m if m != n else m - 1


def level_sets(n, cap, flat, friction, mu):
    m = flat_nodes(n)
    sets = [f"body.0.box.nodes=[{n}, {n}, {(n + 1) // 2}]", f"body.1.box.nodes=[{m}, {m}, {(m + 1) // 2}]"]
    if cap != "hex8":
        sets.append(f'body.0.box.cells="{cap}"')
    if flat != "hex8":
        sets.append(f'body.1.box.cells="{flat}"')
    if friction == "coulomb":
        sets += [f'contact.pair.0.friction={{type="coulomb", mu={mu}}}']
    return sets


def solve(binary, scene, sets, out):
    cmd = [binary, "solve", scene, "--out", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"solve failed ({' '.join(cmd)}):\n{r.stdout}\n{r.stderr}")


def solve_levels(binary, scene, levels, sets_of, name, keep=None):
    """Solves `scene` at each level n of `levels` ("17,25") with the overrides sets_of(n) into
    KEEP (default: a temporary folder) as NAME-n.h5; returns the result paths."""
    d = keep or tempfile.mkdtemp(prefix=f"{name}-")
    os.makedirs(d, exist_ok=True)
    paths = []
    for n in map(int, levels.split(",")):
        out = os.path.join(d, f"{name}-{n}.h5")
        solve(binary, scene, sets_of(n), out)
        paths.append(out)
    return paths


def read(path):
    """(coordinates, status, pressure, traction, report) of the last step."""
    f = h5py.File(path, "r")
    x = np.array(f["/mesh/coordinates"])
    st = np.array(f["/fields/contact_status"])
    p = np.array(f["/fields/contact_pressure"])
    q = np.array(f["/fields/contact_traction"]) if "/fields/contact_traction" in f else None
    rep = json.loads(f.attrs["report"])
    return x, st, p, q, rep


def hertz(F):
    """(a, p₀) of the full sphere carrying F."""
    es = E / (2 * (1 - NU**2))
    a = (3 * F * R / (4 * es)) ** (1 / 3)
    return a, 3 * F / (2 * math.pi * a**2)


def axis_radius(x, st, sel, h):
    """Contact radius along the x axis: (last closed x, first open x) of the slave nodes at y = 0."""
    row = np.where(sel & (np.abs(x[:, 1]) < 1e-9 * h))[0]
    row = row[np.argsort(x[row, 0])]
    closed = x[row[st[row] > 1], 0]
    opened = x[row[(st[row] == 1) & (x[row, 0] > closed.max())], 0]
    return closed.max(), opened.min() if len(opened) else math.nan


def analyse(path):
    x, st, p, q, rep = read(path)
    sel = st > 0  # the slave nodes
    F = 4 * abs(rep["contact"]["total_force_on_slave"][2])
    a, p0 = hertz(F)
    xs = x[sel]
    zmin = xs[:, 2].min()
    # the slave face's grid spacing along x at y = 0
    row = np.sort(xs[np.abs(xs[:, 1]) < 1e-12, 0])
    h = np.diff(row).min()
    pole = np.where(sel & (np.hypot(x[:, 0], x[:, 1]) < 1e-9 * h))[0][0]
    r = np.hypot(x[sel, 0], x[sel, 1])
    ph = p0 * np.sqrt(np.clip(1 - r**2 / a**2, 0, None))
    l2 = np.linalg.norm(p[sel] - ph) / np.linalg.norm(ph)
    rc, ro = axis_radius(x, st, sel, h)
    # the nodes within a/2 of the pole, off and on the symmetry planes x = 0, y = 0
    ids = np.where(sel)[0]
    inner = np.hypot(x[ids, 0], x[ids, 1]) < 0.5 * a
    plane = (np.abs(x[ids, 0]) < 1e-9 * h) | (np.abs(x[ids, 1]) < 1e-9 * h)
    rel = (p[ids] - ph) / p0
    out = dict(F=F, a=a, p0=p0, h=h, ppole=p[pole], pmax=p[sel].max(), inner=rel[inner & ~plane].mean(), plane=rel[inner & plane].mean(), rc=rc, ro=ro, l2=l2, closed=int((st > 1).sum()), x=x, st=st, p=p, q=q, rep=rep, sel=sel)
    out["tang"] = None if q is None else np.linalg.norm(q[sel], axis=1).max()
    return out


def table(results, label):
    print(f"\n{label}")
    print(f"{'h':>8} {'a/h':>5} {'4F':>9} {'a':>7} {'p0':>9} {'p(pole)':>9} {'err':>7} {'max p':>9} {'err':>7} {'<a/2':>7} {'planes':>7} {'last closed':>11} {'first open':>10} {'(mid-a)/h':>9} {'L2 err':>7} {'rate':>5}")
    prev = None
    for r in results:
        mid = 0.5 * (r["rc"] + r["ro"])
        rate = "" if prev is None else f"{math.log(prev['l2'] / r['l2']) / math.log(prev['h'] / r['h']):5.2f}"
        print(f"{r['h']:8.5f} {r['a'] / r['h']:5.2f} {r['F']:9.3f} {r['a']:7.4f} {r['p0']:9.2f} {r['ppole']:9.2f} {(r['ppole'] - r['p0']) / r['p0']:+7.2%} "
              f"{r['pmax']:9.2f} {(r['pmax'] - r['p0']) / r['p0']:+7.2%} {r['inner']:+7.2%} {r['plane']:+7.2%} "
              f"{r['rc']:11.4f} {r['ro']:10.4f} {(mid - r['a']) / r['h']:+9.2f} {r['l2']:7.4f} {rate:>5}")
        prev = r


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", nargs="*")
    ap.add_argument("--cap", default="hex8", choices=["hex8", "tet4", "tet10", "hex20", "hex27"])
    ap.add_argument("--flat", default="hex8", choices=["hex8", "hex20", "hex27"])
    ap.add_argument("--friction", default="none", choices=["none", "coulomb"])
    ap.add_argument("--mu", type=float, default=0.3)
    ap.add_argument("--levels", default="17,25,33")
    ap.add_argument("--bin", default=os.path.join(ROOT, "target/release/tresca-feti"))
    ap.add_argument("--keep", help="directory for the result files (default: a temporary one)")
    args = ap.parse_args()
    scene = os.path.join(HERE, "hertz3d.toml")
    paths = args.results or solve_levels(args.bin, scene, args.levels, lambda n: level_sets(n, args.cap, args.flat, args.friction, args.mu), f"hertz3d-{args.cap}-{args.flat}-{args.friction}", args.keep)
    results = [analyse(p) for p in paths]
    table(results, f"Hertz 3D, cap {args.cap} on flat {args.flat} (non-matching, mortar), friction {args.friction}, R = {R}, E = {E}, ν = {NU}")
    if args.friction == "coulomb":
        print("closed slave nodes stick / slip:", ", ".join(f"{int((r['st'] == 2).sum())}/{int((r['st'] == 3).sum())}" for r in results))


if __name__ == "__main__":
    main()
