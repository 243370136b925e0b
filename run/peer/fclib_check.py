#!/usr/bin/python3
"""Peer check of an FCLIB global problem written by tresca-feti, solved again by Siconos.

Usage: run/peer/fclib_check.py FILE.h5 [TOL]

FILE.h5 holds /fclib_global (FCLIB's global form M v = H r + f, u = Hᵀv + w, per contact
(normal, t1, t2), Coulomb cones with μ) and /guesses/1 (tresca-feti's v, u, r), as written by
`tresca_feti::dual::fclib::write_global`. Debian's python3-siconos is built without FCLIB (no
`globalFrictionContact_fclib_read`), so the file is read here with h5py, following fclib.h's
layout (matrices as triplets with CSparse's meaning — i rows, p columns — or compressed columns
or rows). Siconos' global solver gfc3d (NSGS_WR: the Gauss–Seidel solver of the local
reformulation; NSN_AC, the global Alart–Curnier Newton, if it fails) solves it from zero. The
script prints the relative differences max|v_siconos − v_ours|/max|v_ours| and the same for r,
the FCLIB residual of our guess and Siconos' error measure at it, and exits 0 when both
differences are ≤ TOL (default 1e-6), else 1.
"""
import sys

import h5py
import numpy as np
import siconos.numerics as sn


def triplets(g):
    """(m, n, rows, cols, values) of an FCLIB matrix group."""
    nzmax, m, n, nz = (int(np.asarray(g[k]).ravel()[0]) for k in ("nzmax", "m", "n", "nz"))
    p, i, x = (np.asarray(g[k]) for k in ("p", "i", "x"))
    if nz >= 0:  # triplet (CSparse: i rows, p columns)
        return m, n, i[:nz], p[:nz], x[:nz]
    if nz == -1:  # compressed columns
        return m, n, i[: p[n]], np.repeat(np.arange(n), np.diff(p[: n + 1])), x[: p[n]]
    if nz == -2:  # compressed rows
        return m, n, np.repeat(np.arange(m), np.diff(p[: m + 1])), i[: p[m]], x[: p[m]]
    raise ValueError(f"{g.name}: unknown sparse storage nz = {nz}")


def numerics(m, n, rows, cols, vals):
    """A Siconos sparse NumericsMatrix (triplet) from triplets."""
    a = sn.NM_create(sn.NM_SPARSE, m, n)
    sn.NM_triplet_alloc(a, len(vals))
    for r, c, v in zip(rows.tolist(), cols.tolist(), vals.tolist()):
        sn.NM_zentry(a, r, c, v, 0.0)
    return a


def product(m, n, rows, cols, vals, x, transpose=False):
    y = np.zeros(n if transpose else m)
    if transpose:
        np.add.at(y, cols, vals * x[rows])
    else:
        np.add.at(y, rows, vals * x[cols])
    return y


def solve(problem, n, nr, solver):
    options = sn.SolverOptions(solver)
    options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 100000
    options.dparam[sn.SICONOS_DPARAM_TOL] = 1e-14
    r, u, v = np.zeros(nr), np.zeros(nr), np.zeros(n)
    info = sn.gfc3d_driver(problem, r, u, v, options)
    return info, options.dparam[sn.SICONOS_DPARAM_RESIDU], v, u, r


def main():
    path = sys.argv[1]
    tol = float(sys.argv[2]) if len(sys.argv) > 2 else 1e-6
    with h5py.File(path, "r") as f:
        g = f["fclib_global"]
        dim = int(np.asarray(g["spacedim"]).ravel()[0])
        mm, hh = triplets(g["M"]), triplets(g["H"])
        q, w, mu = (np.array(g["vectors"][k]) for k in ("f", "w", "mu"))
        if "G" in g:
            sys.exit(f"{path}: equality constraints G are not handled here")
        guess = f["guesses"]["1"]
        v_ours, u_ours, r_ours = (np.array(guess[k]) for k in ("v", "u", "r"))
    n, nr = mm[0], hh[1]
    assert dim == 3 and nr == 3 * mu.size and mm[1] == n and hh[0] == n and q.size == n and w.size == nr

    problem = sn.GlobalFrictionContactProblem()
    problem.dimension = dim
    problem.numberOfContacts = mu.size
    m_nm, h_nm = numerics(*mm), numerics(*hh)  # kept alive with the problem
    problem.M, problem.H = m_nm, h_nm
    problem.q, problem.b, problem.mu = q, w, mu  # Siconos: M v = q + H r, u = Hᵀv + b

    # our guess in FCLIB's equations
    eq = product(*mm, v_ours) - product(*hh, r_ours) - q
    u_check = product(*hh, v_ours, transpose=True) + w
    print(f"{path}: {n} DOFs, {mu.size} contacts (mu {mu.min():g}..{mu.max():g}); our guess: "
          f"|Mv - Hr - f|/|f| = {np.linalg.norm(eq) / np.linalg.norm(q):.2e}, "
          f"max|u - (H^T v + w)|/max|u| = {np.abs(u_check - u_ours).max() / np.abs(u_ours).max():.2e}")
    err_options = sn.SolverOptions(sn.SICONOS_GLOBAL_FRICTION_3D_NSGS_WR)
    err = sn.gfc3d_compute_error(problem, r_ours.copy(), u_ours.copy(), v_ours.copy(), 1e-14, err_options,
                                 np.linalg.norm(q), np.linalg.norm(w))
    err = err[1] if isinstance(err, (tuple, list)) else err
    print(f"Siconos' error measure (gfc3d_compute_error) at our guess = {err:.2e}")

    for name in ("NSGS_WR", "NSN_AC"):
        info, res, v, u, r = solve(problem, n, nr, getattr(sn, f"SICONOS_GLOBAL_FRICTION_3D_{name}"))
        dv = np.abs(v - v_ours).max() / max(np.abs(v_ours).max(), 1e-300)
        dr = np.abs(r - r_ours).max() / max(np.abs(r_ours).max(), 1e-300)
        rn = r_ours[0::3]
        touching = int(np.sum(rn > 1e-9 * np.abs(r_ours).max()))
        print(f"Siconos gfc3d {name}: info {info}, its error {res:.2e}; contacts in contact {touching}")
        print(f"max|v_siconos - v_ours|/max|v_ours| = {dv:.2e}; max|r_siconos - r_ours|/max|r_ours| = {dr:.2e}")
        if info == 0:
            sys.exit(0 if dv <= tol and dr <= tol else 1)
    sys.exit(1)


if __name__ == "__main__":
    main()
