#!/usr/bin/env python3
"""Sweep one --set key (decomposition.penalty, solver.method, solver.preconditioner, ...) over the floating
table (the scenes of run/bench/warm_start_floating.py) with one binary (run/results/warm_start_floating3.txt).
Cells: nA, Newton steps summed, SMALSE outer steps (last solve), guard tightenings, max |du|/max |u|
against the first value's run.

usage: floating_sweep.py BINARY OUTDIR KEY V1 V2 ... [--only I,J]   (run/env.sh sourced; from the repository root)
"""
import sys
src = open("run/bench/warm_start_floating.py").read().replace("\nmain()\n", "\n")
exec(compile(src, "warm_start_floating.py", "exec"))
args = sys.argv[1:]
only = None
if "--only" in args:
    i = args.index("--only"); only = [int(x) for x in args[i + 1].split(",")]; args = args[:i] + args[i + 2:]
binary, outdir, key, values = args[0], args[1], args[2], args[3:]
for i, (name, scene, sets) in enumerate(SCENES):
    if only is not None and i not in only:
        continue
    if isinstance(scene, tuple):
        text = open(scene[0]).read()
        for old, new in scene[1]:
            text = text.replace(old, new, 1)
        scene = f"{outdir}/scene_{i}.toml"
        open(scene, "w").write(text)
    cells = []
    ref = None
    for v in values:
        out = f"{outdir}/{key.replace('.', '_')}_{v}_{i}.h5"
        r, e = run(binary, scene, sets + [f"{key}={v}"], out)
        if r is None:
            cells.append(f"{'fail':>16s}")
            continue
        if ref is None:
            ref = out
            d = 0.0
        else:
            _, d = same(ref, out)
        cells.append(f"{r['nA']:5d} {r['outer']:3d} {r['smalse_outer']!s:>3} {r['tight']} {d:7.1e}")
    print(f"{name:40s} " + " | ".join(cells), flush=True)
