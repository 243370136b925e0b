#!/usr/bin/python3
"""Cattaneo–Mindlin 3D check of run/validation/cattaneo_mindlin3d.toml (half model about y = 0).

Usage: run/validation/cattaneo_mindlin3d.py [--levels 17,25] [--cap hex8|tet4] [--bin …] [--keep DIR] [RESULT.h5 …]
Solves the scene at each refinement (n nodes per unit length on the cap, ≈ 0.85 n on the flat
block: never matching) or reads the given results, and prints from the last load step, for the
full sphere's P = 2|F_z| and Q = 2|F_x| (either body as slave) (identical materials, 1/E* = 2(1 − ν²)/E): Hertz's a and p₀,
Mindlin's stick radius c = a(1 − Q/(μP))^{1/3}; the stick zone along the x axis (its ends halfway
between the outermost sticking node and the next one) and along the y axis, against c in element
sizes h; the relative 2-norm errors over the slave nodes of the pressure against Hertz and of the
shear traction's x component against q(r) = μp₀(√(1 − r²/a²) − (c/a)√(1 − r²/c²)); how much
the shear changed the pressure (β = 0: not at all in theory); and the share of the closed nodes
that slip while pressing alone (step 1: none in theory).
"""
import argparse
import json
import math
import os
import sys

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from hertz3d import E, NU, R, ROOT, HERE, flat_nodes, solve_levels  # noqa: E402

MU = 0.3


def level_sets(n, cap):
    m = flat_nodes(n)
    sets = [f"body.0.box.nodes=[{2 * n - 1}, {n}, {(n + 1) // 2}]", f"body.1.box.nodes=[{2 * m - 1}, {m}, {(m + 1) // 2}]"]
    if cap != "hex8":
        sets.append(f'body.0.box.cells="{cap}"')
    return sets


def stick_extent(coord, st, h):
    """(lo, hi) of the stick zone along one axis: the outermost sticking nodes ± h/2."""
    s = np.sort(coord[st == 2])
    return s[0] - h / 2, s[-1] + h / 2


def analyse(path):
    f = h5py.File(path, "r")
    x = np.array(f["/mesh/coordinates"])
    st = np.array(f["/fields/contact_status"])
    p = np.array(f["/fields/contact_pressure"])
    q = np.array(f["/fields/contact_traction"])
    # the pressure after step 1 (before the shear)
    p1 = np.array(f["/steps/0001/contact_pressure"]) if "/steps/0001/contact_pressure" in f else None
    rep = json.loads(f.attrs["report"])
    force = rep["contact"]["total_force_on_slave"]
    P, Q = 2 * abs(force[2]), 2 * abs(force[0])  # either body as slave
    es = E / (2 * (1 - NU**2))
    a = (3 * P * R / (4 * es)) ** (1 / 3)
    p0 = 3 * P / (2 * math.pi * a**2)
    c = a * (1 - Q / (MU * P)) ** (1 / 3)
    sel = st > 0
    xs = x[sel]
    tol = 1e-9
    h = np.diff(np.unique(np.round(xs[np.abs(xs[:, 1]) < tol, 0], 12))).min()
    r = np.hypot(x[sel, 0], x[sel, 1])
    hertz = p0 * np.sqrt(np.clip(1 - r**2 / a**2, 0, None))
    cm = MU * hertz - np.where(r < c, MU * p0 * (c / a) * np.sqrt(np.clip(1 - r**2 / c**2, 0, None)), 0)
    ep = np.linalg.norm(p[sel] - hertz) / np.linalg.norm(hertz)
    eq = np.linalg.norm(np.abs(q[sel, 0]) - cm) / np.linalg.norm(cm)
    xa = sel & (np.abs(x[:, 1]) < tol)
    ya = sel & (np.abs(x[:, 0]) < tol)
    lo, hi = stick_extent(x[xa, 0], st[xa], h)
    _, yhi = stick_extent(x[ya, 1], st[ya], h)
    dp = None if p1 is None else np.abs(p[sel] - p1[sel]).max() / p0
    # spurious slip while pressing (step 1; none in theory for equal materials): slip / closed
    st1 = np.array(f["/steps/0001/contact_status"]) if "/steps/0001/contact_status" in f else None
    slip1 = None if st1 is None else (st1 == 3).sum() / max(1, (st1 > 1).sum())
    return dict(h=h, P=P, Q=Q, a=a, p0=p0, c=c, lo=lo, hi=hi, yhi=yhi, ep=ep, eq=eq, dp=dp, slip1=slip1,
                nstick=int((st == 2).sum()), nslip=int((st == 3).sum()), nopen=int((st == 1).sum()))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", nargs="*")
    ap.add_argument("--cap", default="hex8")
    ap.add_argument("--levels", default="17,25")
    ap.add_argument("--bin", default=os.path.join(ROOT, "target/release/tresca-feti"))
    ap.add_argument("--keep")
    ap.add_argument("--set", action="append", default=[], help="extra scene overrides")
    args = ap.parse_args()
    scene = os.path.join(HERE, "cattaneo_mindlin3d.toml")
    paths = args.results or solve_levels(args.bin, scene, args.levels, lambda n: level_sets(n, args.cap) + args.set, f"cm3d-{args.cap}", args.keep)
    print(f"Cattaneo–Mindlin 3D, cap {args.cap} on flat hex8 (non-matching, mortar), μ = {MU}, R = {R}, E = {E}, ν = {NU}")
    print(f"{'h':>8} {'P':>8} {'Q/μP':>6} {'a':>7} {'c':>7} {'c/h':>5} {'stick x':>17} {'(half-c)/h':>10} {'centre/h':>8} {'stick y':>8} {'(y-c)/h':>7} "
          f"{'p err':>6} {'q err':>6} {'Δp/p0':>6} {'stick/slip/open':>15} {'slip@1':>6}")
    for path in paths:
        r = analyse(path)
        half = (r["hi"] - r["lo"]) / 2
        dp = "" if r["dp"] is None else f"{r['dp']:6.3f}"
        s1 = "" if r["slip1"] is None else f"{100 * r['slip1']:5.1f}%"
        print(f"{r['h']:8.5f} {r['P']:8.3f} {r['Q'] / (MU * r['P']):6.3f} {r['a']:7.4f} {r['c']:7.4f} {r['c'] / r['h']:5.2f} [{r['lo']:+7.4f},{r['hi']:+7.4f}] "
              f"{(half - r['c']) / r['h']:+10.2f} {(r['hi'] + r['lo']) / 2 / r['h']:+8.2f} {r['yhi']:8.4f} {(r['yhi'] - r['c']) / r['h']:+7.2f} "
              f"{r['ep']:6.3f} {r['eq']:6.3f} {dp:>6} {r['nstick']:>5}/{r['nslip']}/{r['nopen']} {s1:>6}")


if __name__ == "__main__":
    main()
