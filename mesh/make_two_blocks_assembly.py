#!/usr/bin/env python3
"""Writes two_blocks_assembly.inp: the two-block model of two_blocks.inp as Abaqus/CAE writes
an input with parts and an assembly.

    cd mesh && python3 make_two_blocks_assembly.py

Two parts, "lower" and "upper", each one block of two_blocks.inp: its hexahedra (labels from
1 in file order) and the nodes they use (labels from 1, in file order). The upper part is
written one unit down (z - 1, exact in binary for z in [1, 2]) and its instance "upper" is
translated by (0, 0, 1), so the assembled coordinates are the file's bit for bit. The named
faces (the file's sets of CPS4 elements) become element-based surfaces of the assembly, as
CAE writes them: an internal element set per face identifier with INSTANCE=, listed in the
order of the file's surface elements, and a *SURFACE naming it. Material, section and step
keywords are there as CAE writes them (the reader skips them).
"""

import pathlib

HERE = pathlib.Path(__file__).resolve().parent
# Abaqus C3D8 faces S1..S6 (1-based corners)
HEX_FACES = [(1, 2, 3, 4), (5, 8, 7, 6), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 8, 4), (4, 8, 5, 1)]


def read(path):
    nodes, elems, elsets = {}, {}, {}
    block, name = None, None
    for raw in path.read_text().splitlines():
        t = raw.strip()
        if not t or t.startswith("**"):
            continue
        if t.startswith("*"):
            parts = [p.strip() for p in t[1:].split(",")]
            key = parts[0].upper()
            params = {p.split("=")[0].strip().upper(): p.split("=")[1].strip() for p in parts[1:] if "=" in p}
            block, name = key, params.get("ELSET")
            if key == "ELEMENT":
                elsets.setdefault(name, [])
            continue
        f = [x.strip() for x in t.split(",") if x.strip()]
        if block == "NODE":
            nodes[int(f[0])] = [float(x) for x in f[1:]]
        elif block == "ELEMENT":
            elems[int(f[0])] = [int(x) for x in f[1:]]
            elsets[name].append(int(f[0]))
        elif block == "ELSET":
            elsets.setdefault(name, []).extend(int(x) for x in f)
    return nodes, elems, elsets


def main():
    nodes, elems, elsets = read(HERE / "two_blocks.inp")
    out = ["*Heading", "** two_blocks.inp as parts and an assembly (make_two_blocks_assembly.py)", "*Preprint, echo=NO, model=NO, history=NO, contact=NO"]
    parts = {}
    for block, dz in (("lower", 0.0), ("upper", 1.0)):
        hexes = elsets[block]
        used = set(n for e in hexes for n in elems[e])
        order = [n for n in nodes if n in used]  # file order
        node_no = {n: i + 1 for i, n in enumerate(order)}
        elem_no = {e: i + 1 for i, e in enumerate(hexes)}
        parts[block] = (hexes, node_no, elem_no)
        out += ["**", "** PARTS", "**", f"*Part, name={block}", "*Node"]
        for n in order:
            x, y, z = nodes[n]
            out.append(f"{node_no[n]:7d}, {x!r}, {y!r}, {z - dz!r}")
        out.append("*Element, type=C3D8")
        for e in hexes:
            out.append(f"{elem_no[e]}, " + ", ".join(str(node_no[n]) for n in elems[e]))
        out += [f"*Elset, elset={block}_all, generate", f" 1, {len(hexes)}, 1", f"** Section: {block}", f"*Solid Section, elset={block}_all, material={block}", ",", "*End Part"]
    out += ["**", "** ASSEMBLY", "**", "*Assembly, name=Assembly", "**"]
    for block, dz in (("lower", 0.0), ("upper", 1.0)):
        out.append(f"*Instance, name={block}, part={block}")
        if dz:
            out.append(f"          0.,           0.,          {dz!r}")
        out.append("*End Instance")
        out.append("**")
    for surf in ("upper_top", "upper_bottom", "upper_left", "upper_right", "lower_top", "lower_left"):
        block = surf.split("_")[0]
        hexes, node_no, elem_no = parts[block]
        by_face = {}
        for q in elsets[surf]:
            corners = set(elems[q][:4])
            hits = [(e, k) for e in hexes for k, face in enumerate(HEX_FACES) if set(elems[e][c - 1] for c in face) == corners]
            assert len(hits) == 1, (surf, q, hits)
            e, k = hits[0]
            by_face.setdefault(k + 1, []).append(elem_no[e])
        for k, labels in by_face.items():
            out.append(f"*Elset, elset=_{surf}_S{k}, internal, instance={block}")
            out += [", ".join(str(x) for x in labels[i : i + 16]) for i in range(0, len(labels), 16)]
        out.append(f"*Surface, type=ELEMENT, name={surf}")
        out += [f"_{surf}_S{k}, S{k}" for k in by_face]
    out += ["*End Assembly", "**", "** MATERIALS", "**"]
    for block in ("lower", "upper"):
        out += [f"*Material, name={block}", "*Elastic", "210000., 0.3"]
    out += ["**", "** STEP: Step-1", "**", "*Step, name=Step-1, nlgeom=NO", "*Static", "1., 1., 1e-05, 1.", "*End Step"]
    (HERE / "two_blocks_assembly.inp").write_text("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
