#!/usr/bin/python3
"""Peer check of tresca-feti's Coulomb solution with Siconos (Debian python3-siconos).

Usage: run/peer/siconos_check.py DUAL.h5 [TOL]
DUAL.h5 is written by `tresca-feti solve SCENE --set output.export_dual="DUAL.h5"` (a Coulomb
scene on the monolithic dual): the local problem u = W r + q per contact (normal, t1, t2), μ,
and tresca-feti's r. Siconos' fc3d solver (NSGS with the Alart–Curnier local Newton) solves the
same problem from r = 0; the script prints both solutions' differences and Siconos' own error
measure of tresca-feti's r, and exits 1 when r differs by more than TOL (default 1e-6)
relative to max|r|.
"""
import sys

import h5py
import numpy as np
import siconos.numerics as sn


def main():
    path = sys.argv[1]
    tol = float(sys.argv[2]) if len(sys.argv) > 2 else 1e-6
    with h5py.File(path, "r") as f:
        w, q, mu, r_ours = (np.array(f[k]) for k in ("W", "q", "mu", "r"))
    n = q.size
    problem = sn.FrictionContactProblem(3, n // 3, w, q, mu)
    options = sn.SolverOptions(sn.SICONOS_FRICTION_3D_NSGS)
    options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = 100000
    options.dparam[sn.SICONOS_DPARAM_TOL] = 1e-14
    r = np.zeros(n)
    u = np.zeros(n)
    info = sn.fc3d_nsgs(problem, r, u, options) if hasattr(sn, "fc3d_nsgs") else sn.fc3d_driver(problem, r, u, options)
    err_siconos = options.dparam[sn.SICONOS_DPARAM_RESIDU]
    scale = max(np.abs(r_ours).max(), 1e-300)
    diff = np.abs(r - r_ours).max() / scale
    # Siconos' error measure evaluated at our r
    u_ours = w @ r_ours + q
    err_ours = sn.fc3d_compute_error(problem, r_ours, u_ours, 1e-14, options, np.linalg.norm(q))
    err_ours = err_ours[1] if isinstance(err_ours, (tuple, list)) else err_ours
    contacts = n // 3
    active = int(np.sum(r_ours[0::3] > 1e-12 * scale))
    print(f"contacts {contacts} (in contact {active}), Siconos NSGS info {info}, its error {err_siconos:.2e}")
    print(f"max|r_siconos - r_tresca_feti| / max|r| = {diff:.2e}; Siconos' error measure at tresca-feti's r = {err_ours:.2e}")
    sys.exit(0 if info == 0 and diff <= tol else 1)


if __name__ == "__main__":
    main()
