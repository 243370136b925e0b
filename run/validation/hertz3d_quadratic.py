#!/usr/bin/python3
"""Splits hertz3d.py's nodal pressure of a quadratic (hex20) slave face into corner and edge nodes and
adds the smoothed field (contact_pressure_smooth): run/validation/hertz3d_quadratic.py RESULT.h5 …"""
import sys; sys.path.insert(0, __import__('os').path.dirname(__import__('os').path.abspath(__file__)))
import hertz3d as H, numpy as np, h5py
for path in sys.argv[1:]:
    r=H.analyse(path)
    ps=np.array(h5py.File(path)['/fields/contact_pressure_smooth'])
    x,p,st,sel=r['x'],r['p'],r['st'],r['sel']
    a,p0,h=r['a'],r['p0'],r['h']
    ids=np.where(sel)[0]; rr=np.hypot(x[ids,0],x[ids,1]); ph=p0*np.sqrt(np.clip(1-rr**2/a**2,0,None))
    inner=rr<0.5*a
    # corner vs edge nodes on the slave face: the corners lie on the grid of spacing 2h
    corner=(np.abs(np.round(x[ids,0]/(2*h))*2*h-x[ids,0])<1e-9*h)&(np.abs(np.round(x[ids,1]/(2*h))*2*h-x[ids,1])<1e-9*h)
    rel=(p[ids]-ph)/p0
    print(f"{path}: h_node={h:.5f} a/h_node={a/h:.2f} a/h_cell={a/(2*h):.2f} 4F={r['F']:.3f} a={a:.4f} p0={p0:.2f}")
    print(f"  nodal lambda/w: pole {(r['ppole']-p0)/p0:+.2%}, peak {(r['pmax']-p0)/p0:+.2%}, L2 {r['l2']:.4f}, within a/2: corner nodes {rel[inner&corner].mean():+.2%}, edge/face-midside nodes {rel[inner&~corner].mean():+.2%}")
    rels=(ps[ids]-ph)/p0
    l2s=np.linalg.norm(ps[ids]-ph)/np.linalg.norm(ph)
    print(f"  smoothed: pole {(ps[ids][rr<1e-9*h][0]-p0)/p0:+.2%}, peak {(ps[ids].max()-p0)/p0:+.2%}, L2 {l2s:.4f}, within a/2: corner {rels[inner&corner].mean():+.2%}, midside {rels[inner&~corner].mean():+.2%}, rms {np.sqrt((rels[inner]**2).mean()):.2%}")
    print(f"  contact radius along x: last closed {r['rc']:.4f}, first open {r['ro']:.4f}, midpoint {(0.5*(r['rc']+r['ro'])-a)/h:+.2f} h_node from a")
