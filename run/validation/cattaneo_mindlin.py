#!/usr/bin/python3
"""Cattaneo–Mindlin check of a solved run/validation/cattaneo_mindlin.toml.

Usage: run/validation/cattaneo_mindlin.py RESULT.h5
Reads the last load step (/fields) and the report, computes Hertz (plane strain, identical
materials, 1/E* = 2(1 − ν²)/E) and Cattaneo–Mindlin from the measured P and Q per unit length,
and prints: the stick zone (ends halfway between the outermost sticking node and the first
slipping one) against c = a·√(1 − Q/(μP)), and the relative 2-norm errors of the pressure
against Hertz and of the shear traction against q(x) = μp₀(√(1 − x²/a²) − (c/a)√(1 − x²/c²)).
"""
import json
import sys

import h5py
import numpy as np

E, NU, R, MU = 50000.0, 0.3, 8.0, 0.3


def main():
    f = h5py.File(sys.argv[1], "r")
    x = np.array(f["/mesh/coordinates"])
    st = np.array(f["/fields/contact_status"])
    p = np.array(f["/fields/contact_pressure"])
    q = np.array(f["/fields/contact_traction"])[:, 0]
    rep = json.loads(f.attrs["report"])
    t = x[:, 1].max()
    force = rep["contact"]["total_force_on_slave"]
    P, Q = force[2] / t, abs(force[0]) / t
    es = E / (2 * (1 - NU**2))
    a = np.sqrt(4 * P * R / (np.pi * es))
    c = a * np.sqrt(1 - Q / (MU * P))
    p0 = 2 * P / (np.pi * a)
    row = np.where((st > 0) & (x[:, 1] == 0))[0]
    xs = x[row, 0] - x[:, 0].max() / 2
    h = np.diff(np.sort(xs)).min()
    stick = np.sort(xs[st[row] == 2])
    lo, hi = stick[0] - h / 2, stick[-1] + h / 2
    hertz = p0 * np.sqrt(np.clip(1 - xs**2 / a**2, 0, None))
    cm = MU * hertz - np.where(np.abs(xs) < c, MU * p0 * (c / a) * np.sqrt(np.clip(1 - xs**2 / c**2, 0, None)), 0)
    ep = np.linalg.norm(p[row] - hertz) / np.linalg.norm(hertz)
    eq = np.linalg.norm(np.abs(q[row]) - cm) / np.linalg.norm(cm)
    print(f"P = {P:.2f}, Q = {Q:.2f} per unit length, Q/(μP) = {Q / (MU * P):.3f}, h = {h:.5f}")
    print(f"Hertz a = {a:.4f}, Cattaneo–Mindlin c = {c:.4f}")
    print(f"stick zone [{lo:.4f}, {hi:.4f}]: half-width {(hi - lo) / 2:.4f} ({((hi - lo) / 2 - c) / h:+.2f} h), centre {(hi + lo) / 2:+.4f}")
    print(f"relative 2-norm errors: pressure vs Hertz {ep:.3f}, shear traction vs Cattaneo–Mindlin {eq:.3f}")


if __name__ == "__main__":
    main()
