#!/usr/bin/env python3
"""Products (nA) of the floating scenes (bodies held by contact alone: SMALSE-M) and of the Hertz
sphere pressed by a traction or by a displacement, for two binaries (before / after), and whether
their displacements agree bit for bit (run/results/warm_start_floating.txt).

usage: warm_start_floating.py BEFORE AFTER OUTDIR   (run/env.sh sourced; from the repository root)
"""
import json
import subprocess
import sys

import h5py
import numpy as np

FB = "run/validation/floating_block.toml"
TL = "run/validation/tied_lap_joint.toml"
# the variants tests/floating.rs builds from these by text: (base, [(old, new)])
DRAGGED = (FB, [('[[traction]]\nface = "upper.xmin"\np = [0.3, 0.0, 0.0]\n', '[[dirichlet]]\nface = "upper.xmin"\ncomponents = ["x"]\nvalue = [0.001, 0.0, 0.0]\n')])
STACK = (
    TL,
    [
        ('[[tie]]\nslave = "washer.zmin"\nmaster = "upper.zmax"\n', '[[tie]]\nslave = "upper.zmin"\nmaster = "lower.zmax"\n'),
        ('[[contact.pair]]\nslave = "upper.zmin"\nmaster = "lower.zmax"\n', '[[contact.pair]]\nslave = "washer.zmin"\nmaster = "upper.zmax"\n'),
        ('face = "upper.xmin"\np = [0.3, 0.0, 0.0]', 'face = "washer.xmin"\np = [0.3, 0.0, 0.0]'),
    ],
)
ONE_HEX = (
    FB,
    [
        ('friction = { type = "coulomb", mu = 0.3 }', ""),
        ("p = [0.3, 0.0, 0.0]", "p = [0.0, 0.0, 0.0]"),
        ("[mesh]", '[[dirichlet]]\nface = "upper.xmin"\ncomponents = ["x"]\n[[dirichlet]]\nface = "upper.ymin"\ncomponents = ["y"]\n[mesh]'),
    ],
)
SCENES = [
    ("hertz sphere, displacement", "run/bench/hertz_sphere_displacement.toml", []),
    ("hertz sphere, traction", "run/bench/hertz_sphere_traction.toml", []),
    ("hertz sphere, traction, 3k DOFs", "run/bench/hertz_sphere_traction.toml", ["body.0.box.nodes=[11, 11, 5]", "body.1.box.nodes=[9, 9, 5]"]),
    ("floating block", FB, []),
    ("floating block, 4 subdomains", FB, ["decomposition.subdomains=4"]),
    ("floating block dragged 1e-3, Newton", DRAGGED, ["solver.coulomb=\"newton\""]),
    ("floating block dragged 1e-3, fixed point", DRAGGED, ["solver.coulomb=\"fixed-point\""]),
    ("floating block dragged 1e-3, lagged", DRAGGED, ["solver.coulomb=\"lagged\""]),
    ("one-hexahedron body, frictionless", ONE_HEX, ["body.0.box.nodes=[2, 2, 2]"]),
    ("one-hexahedron body, 3x3x3 nodes", ONE_HEX, ["body.0.box.nodes=[3, 3, 3]"]),
    ("block on a tied stack, mortar", STACK, ["contact.pair.0.discretization=\"mortar\""]),
    ("tied lap joint", TL, []),
    ("tied lap joint, 2 subdomains, 3 steps", TL, ["decomposition.subdomains=2", "load.steps=3", "traction.1.factors=[0.0, 0.5, 1.0]", "traction.0.factors=[0.5, 1.0, 1.0]"]),
]


def run(binary, scene, sets, out):
    cmd = ["timeout", "900", binary, "solve", "-q", scene, "--out", out]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None, p.stderr.strip().splitlines()[-1:]
    r = json.load(open(out[:-3] + ".json"))
    s = r["solver"]
    sm = (r.get("tfeti") or {}).get("smalse") or {}
    return {"nA": s["nA"], "outer": s["outer_iterations"], "smalse_outer": sm.get("outer", "-"), "tight": len(s.get("eps_tightened", []))}, None


def same(a, b):
    with h5py.File(a) as fa, h5py.File(b) as fb:
        names = []
        fa.visit(lambda n: names.append(n) if isinstance(fa[n], h5py.Dataset) else None)
        diff = 0.0
        bitwise = True
        for n in names:
            x, y = np.asarray(fa[n][()]), np.asarray(fb[n][()])
            if x.shape != y.shape or x.dtype != y.dtype:
                return False, float("inf")
            if x.tobytes() != y.tobytes():
                bitwise = False
                if n.endswith("displacement") and x.dtype.kind == "f":
                    diff = max(diff, float(np.abs(x - y).max() / max(np.abs(y).max(), 1e-300)))
        return bitwise, diff


def main():
    before, after, outdir = sys.argv[1:4]
    rows = []
    for i, (name, scene, sets) in enumerate(SCENES):
        if isinstance(scene, tuple):
            text = open(scene[0]).read()
            for old, new in scene[1]:
                assert old in text, (name, old)
                text = text.replace(old, new, 1)
            scene = f"{outdir}/scene_{i}.toml"
            open(scene, "w").write(text)
        res = []
        for tag, b in (("before", before), ("after", after)):
            res.append(run(b, scene, sets, f"{outdir}/{tag}_{i}.h5"))
        (rb, eb), (ra, ea) = res
        if rb is None or ra is None:
            rows.append(f"{name:40s} failed: {eb or ''} {ea or ''}")
            continue
        bit, d = same(f"{outdir}/before_{i}.h5", f"{outdir}/after_{i}.h5")
        rows.append(
            f"{name:40s} {rb['nA']:6d} {ra['nA']:6d}   {rb['outer']:4d} {ra['outer']:4d}   {rb['smalse_outer']!s:>4} {ra['smalse_outer']!s:>4}   {rb['tight']} {ra['tight']}   "
            + ("bitwise" if bit else f"u differs {d:.1e} rel.")
        )
        print(rows[-1], flush=True)
    print()
    print(f"{'scene':40s} {'nA before':>6s} {'after':>6s}  outer b/a  SMALSE outer b/a  guard tightenings b/a  result")
    print("\n".join(rows))


main()
