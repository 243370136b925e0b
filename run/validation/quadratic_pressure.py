#!/usr/bin/python3
"""Candidate nodal contact pressures on quadratic slave faces (Quad8 of hex20, Tri6 of tet10), computed
from a result file's `contact_pressure` (z = λ/w, the dual multipliers' coefficients) and mesh:

  raw     z = λ/w as written;  smooth: the written `contact_pressure_smooth`
  proj    L2 projection on the standard quadratic basis, M p = f (f = T⁻¹λ the forces on the
          standard slave DOFs, λ = z w, w = ∫φ̃ of the modified basis φ̃ = Tφ, α = 1/5)
  proj+   the same clipped at 0
  vlump   forces lumped on the corners through the linear basis, p_c = ∫N¹_c p / ∫N¹_c, edges the mean of their corners
  vcons   the linear (corner) L2 projection M¹p¹ = f¹, edges the mean of their corners
  patch   per node, a quadratic polynomial fitted (least squares) to the moments λ_k = ∫φ̃_k p of the
          nodes whose support lies in the node's facets and their neighbours, evaluated at the node

Geometry is taken in the (x, y) projection (the slave faces here are flat or nearly: R = 10 cap).
Usage: quadratic_pressure.py FILE.h5 [--hertz] [--row Y]"""
import argparse
import json
import math
import sys

import h5py
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

ALPHA = 0.2
E, NU, R = 50000.0, 0.3, 10.0
HEX_FACES = [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
TET_FACES = [(0, 1, 2), (0, 1, 3), (1, 2, 3), (0, 2, 3)]


def gauss(n):
    g, w = np.polynomial.legendre.leggauss(n)
    return g, w


def quad8(xi, eta):
    c = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    N, dN = np.zeros(8), np.zeros((8, 2))
    for i, (a, b) in enumerate(c):
        N[i] = 0.25 * (1 + a * xi) * (1 + b * eta) * (a * xi + b * eta - 1)
        dN[i] = [0.25 * a * (1 + b * eta) * (2 * a * xi + b * eta), 0.25 * b * (1 + a * xi) * (a * xi + 2 * b * eta)]
    m = [(0, -1), (1, 0), (0, 1), (-1, 0)]
    for i, (a, b) in enumerate(m):
        if a == 0:
            N[4 + i] = 0.5 * (1 - xi**2) * (1 + b * eta)
            dN[4 + i] = [-xi * (1 + b * eta), 0.5 * b * (1 - xi**2)]
        else:
            N[4 + i] = 0.5 * (1 + a * xi) * (1 - eta**2)
            dN[4 + i] = [0.5 * a * (1 - eta**2), -eta * (1 + a * xi)]
    return N, dN


def tri6(r, s):
    t = 1 - r - s
    N = np.array([t * (2 * t - 1), r * (2 * r - 1), s * (2 * s - 1), 4 * r * t, 4 * r * s, 4 * s * t])
    dN = np.array([[1 - 4 * t, 1 - 4 * t], [4 * r - 1, 0], [0, 4 * s - 1], [4 * (t - r), -4 * r], [4 * s, 4 * r], [-4 * s, 4 * (t - s)]])
    return N, dN


def rule(n):
    if n == 8:
        g, w = gauss(4)
        return [((a, b), wa * wb, quad8) for a, wa in zip(g, w) for b, wb in zip(g, w)]
    # tri: collapsed Gauss (Duffy), exact enough
    g, w = gauss(5)
    pts = []
    for a, wa in zip(g, w):
        for b, wb in zip(g, w):
            u, v = 0.5 * (a + 1), 0.5 * (b + 1)
            pts.append(((u * (1 - v), v), 0.25 * wa * wb * (1 - u), tri6))
    return pts


def facets(f, slave):
    """Slave facets: (corners in cycle, mids per edge) as global node ids."""
    out = []
    x = np.array(f["mesh/coordinates"])
    for name, faces, nc in (("hexahedra20", HEX_FACES, 8), ("tetrahedra10", TET_FACES, 4)):
        if f"mesh/{name}" not in f:
            continue
        for cell in np.array(f[f"mesh/{name}"]):
            cor, mid = cell[:nc], cell[nc:]
            for fc in faces:
                ids = [cor[i] for i in fc]
                if not all(slave[i] for i in ids):
                    continue
                mids = []
                for k in range(len(ids)):
                    a, b = ids[k], ids[(k + 1) % len(ids)]
                    mp = 0.5 * (x[a] + x[b])
                    mids.append(mid[np.argmin(np.linalg.norm(x[mid] - mp, axis=1))])
                if all(slave[i] for i in mids):
                    out.append(ids + mids)
    # unique facets
    seen, uniq = set(), []
    for q in out:
        k = tuple(sorted(q))
        if k not in seen:
            seen.add(k)
            uniq.append(q)
    return uniq


def analyse(path, hertz, rowy):
    f = h5py.File(path, "r")
    x = np.array(f["mesh/coordinates"])
    st = np.array(f["fields/contact_status"])
    z = np.array(f["fields/contact_pressure"])
    sm = np.array(f["fields/contact_pressure_smooth"])
    rep = json.loads(f.attrs["report"])
    slave = st > 0
    fs = facets(f, slave)
    nodes = np.array(sorted({i for q in fs for i in q}))
    loc = {g: i for i, g in enumerate(nodes)}
    n = len(nodes)
    nc = len(fs[0]) // 2
    corner = np.zeros(n, bool)
    edges = set()  # (edge node, corner)
    for q in fs:
        for k in range(nc):
            corner[loc[q[k]]] = True
            edges.add((loc[q[nc + k]], loc[q[k]]))
            edges.add((loc[q[nc + k]], loc[q[(k + 1) % nc]]))
    Mrows, Mcols, Mv = [], [], []
    M1r, M1c, M1v = [], [], []
    w = np.zeros(n)
    w1 = np.zeros(n)
    # per facet data for the patch fit
    fgeo = []
    for q in fs:
        xy = x[q][:, :2]
        L = [loc[g] for g in q]
        Me = np.zeros((2 * nc, 2 * nc))
        M1e = np.zeros((nc, nc))
        pts = []
        for pt, wt, fn in rule(2 * nc):
            N, dN = fn(*pt)
            J = xy.T @ dN
            dA = wt * abs(np.linalg.det(J))
            Nt = N.copy()  # modified basis φ̃ = T φ
            for k in range(nc):
                Nt[k] += ALPHA * (N[nc + k] + N[nc + (k - 1) % nc])
            Nt[nc:] *= 1 - 2 * ALPHA
            N1 = N[:nc].copy()
            for k in range(nc):
                N1[k] += 0.5 * (N[nc + k] + N[nc + (k - 1) % nc])
            Me += dA * np.outer(N, N)
            M1e += dA * np.outer(N1, N1)
            w[L] += dA * Nt
            w1[L[:nc]] += dA * N1
            pts.append((N @ xy, dA, Nt))
        fgeo.append((L, pts))
        for a in range(2 * nc):
            for b in range(2 * nc):
                Mrows.append(L[a]); Mcols.append(L[b]); Mv.append(Me[a, b])
        for a in range(nc):
            for b in range(nc):
                M1r.append(L[a]); M1c.append(L[b]); M1v.append(M1e[a, b])
    M = sp.csr_matrix((Mv, (Mrows, Mcols)), shape=(n, n))
    M1 = sp.csr_matrix((M1v, (M1r, M1c)), shape=(n, n))
    zz = z[nodes]
    lam = zz * w
    fstd = np.where(corner, lam, lam / (1 - 2 * ALPHA))
    for e, c in edges:
        fstd[c] -= ALPHA * fstd[e]
    out = {"raw": zz, "smooth": sm[nodes]}
    p = spl.spsolve(M, fstd)
    out["proj"] = p
    out["proj+"] = np.maximum(p, 0)
    f1 = np.where(corner, fstd, 0.0)
    for e, c in edges:
        f1[c] += 0.5 * fstd[e]
    def edges_mean(pc):
        s, k = np.where(corner, pc, 0.0), np.where(corner, 1.0, 0.0)
        for e, c in edges:
            s[e] += 0.5 * pc[c]
        return s
    out["vlump"] = edges_mean(np.where(corner, f1 / np.where(w1 > 0, w1, 1), 0))
    ci = np.where(corner)[0]
    pc = np.zeros(n)
    pc[ci] = spl.spsolve(M1[ci][:, ci].tocsc(), f1[ci])
    out["vcons"] = edges_mean(pc)
    # patch fit to moments
    node_f = [[] for _ in range(n)]
    for fi, (L, _) in enumerate(fgeo):
        for l in L:
            node_f[l].append(fi)
    xy = x[nodes][:, :2]
    pp = np.zeros(n)
    for i in range(n):
        patch = set(node_f[i])
        ext = set(patch)
        for fi in patch:
            for l in fgeo[fi][0]:
                ext.update(node_f[l])
        ks = [k for k in {l for fi in ext for l in fgeo[fi][0]} if set(node_f[k]) <= ext]
        h = math.sqrt(sum(fgeo[fi][1][0][1] for fi in patch) + 1e-300) or 1.0
        h = max(np.ptp(xy[[l for fi in patch for l in fgeo[fi][0]]], axis=0))
        A = np.zeros((len(ks), 6))
        kpos = {k: r for r, k in enumerate(ks)}
        for fi in ext:
            L, pts = fgeo[fi]
            for X, dA, Nt in pts:
                u, v = (X - xy[i]) / h
                mono = np.array([1, u, v, u * u, u * v, v * v])
                for a, l in enumerate(L):
                    if l in kpos:
                        A[kpos[l]] += dA * Nt[a] * mono
        c, *_ = np.linalg.lstsq(A, lam[ks], rcond=None)
        pp[i] = c[0]
    out["patch"] = pp
    res = {"path": path, "n": n, "out": out, "x": x[nodes]}
    if hertz:
        F = 4 * abs(rep["contact"]["total_force_on_slave"][2])
        es = E / (2 * (1 - NU**2))
        a = (3 * F * R / (4 * es)) ** (1 / 3)
        p0 = 3 * F / (2 * math.pi * a**2)
        r = np.hypot(xy[:, 0], xy[:, 1])
        ph = p0 * np.sqrt(np.clip(1 - r**2 / a**2, 0, None))
        pole = np.argmin(r)
        hc = np.ptp(x[fs[0]][:, 0])
        print(f"{path}: a = {a:.4f}, p0 = {p0:.2f}, a/h_cell = {a / hc:.2f}, {n} slave nodes")
        print(f"  {'field':8} {'pole':>8} {'peak':>8} {'L2':>7} {'min/p0':>8} {'<a/2 corner':>11} {'<a/2 edge':>10}")
        inner = r < 0.5 * a
        for k, v in out.items():
            print(f"  {k:8} {(v[pole] - p0) / p0:+8.2%} {(v.max() - p0) / p0:+8.2%} {np.linalg.norm(v - ph) / np.linalg.norm(ph):7.4f} {v.min() / p0:+8.3f} "
                  f"{np.mean((v - ph)[inner & corner]) / p0:+11.2%} {np.mean((v - ph)[inner & ~corner]) / p0:+10.2%}")
    if rowy is not None:
        row = np.where(np.abs(xy[:, 1] - rowy) < 1e-9)[0]
        row = row[np.argsort(xy[row, 0])]
        print(f"{path}: the slave nodes at y = {rowy}")
        print("  " + f"{'x':>7}" + "".join(f"{k:>9}" for k in out))
        for j in row:
            print("  " + f"{xy[j, 0]:7.3f}" + "".join(f"{v[j]:9.3f}" for v in out.values()))
        print("  " + f"{'min':>7}" + "".join(f"{v.min():9.3f}" for v in out.values()))
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="+")
    ap.add_argument("--hertz", action="store_true", help="compare with Hertz (run/validation/hertz3d.toml, quarter model)")
    ap.add_argument("--row", type=float, help="print the slave nodes at this y")
    args = ap.parse_args()
    for p in args.files:
        analyse(p, args.hertz, args.row)


if __name__ == "__main__":
    sys.exit(main())
