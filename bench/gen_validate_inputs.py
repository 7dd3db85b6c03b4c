#!/usr/bin/env python3
"""Deterministic inputs for ``bench/bench_validate.py``.

``assembly(size)``: an AP242 assembly with a mechanism, the size of a real CAD export:
the reference four-bar (``examples/four_bar_ap242.stp``) whose four links each get an
``advanced_brep_shape_representation`` of plates with drilled holes, attached the way
build123d attaches a link's geometry (the link's ``kinematic_link_representation_
association`` points at the B-rep representation, in the link's context). A plate is a
box B-rep (planes, lines, vertices, loops, a closed shell) with ``HOLES`` cylindrical
through-holes whose edges carry p-curves in a 2D parametric context, as Open CASCADE
writes them; about 24 kB and 570 instances per plate.

``chain(n)``: a serial chain of ``n`` revolute pairs written by p105's own writer
(``part105.write_mechanism``, AP242 layout), the shape of ``crashes/D19_chain_1000_pairs``.

Usage::

    python bench/gen_validate_inputs.py assembly 20e6 > big.stp
    python bench/gen_validate_inputs.py chain 10000 > chain.stp
"""

from __future__ import annotations

import io
import math
import re
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
FOUR_BAR = REPO / "examples" / "four_bar_ap242.stp"
HOLES = 8


def _r(x: float) -> str:
    """A Part 21 real (always with a decimal point)."""
    s = f"{x:.6f}".rstrip("0")
    return "0." if s in ("0.", "-0.") else s


class _Writer:
    """Instances with consecutive ids, as text lines."""

    def __init__(self, first_id: int):
        self.next = first_id
        self.lines: list[str] = []

    def add(self, text: str) -> int:
        i = self.next
        self.next += 1
        self.lines.append(f"#{i}={text};")
        return i

    def point(self, *xyz) -> int:
        return self.add(f"CARTESIAN_POINT('',({','.join(_r(v) for v in xyz)}))")

    def direction(self, *xyz) -> int:
        return self.add(f"DIRECTION('',({','.join(_r(v) for v in xyz)}))")

    def placement(self, origin, axis=(0, 0, 1), ref=(1, 0, 0)) -> int:
        p, a, r = self.point(*origin), self.direction(*axis), self.direction(*ref)
        return self.add(f"AXIS2_PLACEMENT_3D('',#{p},#{a},#{r})")

    def line(self, start, end) -> int:
        d = [e - s for s, e in zip(start, end)]
        n = math.sqrt(sum(v * v for v in d))
        p, u = self.point(*start), self.direction(*(v / n for v in d))
        v = self.add(f"VECTOR('',#{u},{_r(n)})")
        return self.add(f"LINE('',#{p},#{v})")


def _plate(w: _Writer, ctx2d: int, ox: float, oy: float, size=(80.0, 50.0, 4.0)) -> int:
    """A drilled plate at (ox, oy); returns its manifold_solid_brep."""
    sx, sy, sz = size
    c = [(ox + x, oy + y, z) for z in (0.0, sz) for y in (0.0, sy) for x in (0.0, sx)]
    vertex = [w.add(f"VERTEX_POINT('',#{w.point(*p)})") for p in c]
    corner = {(i & 1, (i >> 1) & 1, i >> 2): i for i in range(8)}

    def edge(a, b):
        return w.add(f"EDGE_CURVE('',#{vertex[a]},#{vertex[b]},#{w.line(c[a], c[b])},.T.)")

    # 12 box edges, keyed by their two corners
    edges = {}
    for a in range(8):
        for bit in (1, 2, 4):
            b = a | bit
            if b != a:
                edges[(a, b)] = edge(a, b)

    def loop(cycle):
        oes = []
        for a, b in zip(cycle, cycle[1:] + cycle[:1]):
            e, same = (edges[(a, b)], ".T.") if (a, b) in edges else (edges[(b, a)], ".F.")
            oes.append(w.add(f"ORIENTED_EDGE('',*,*,#{e},{same})"))
        return w.add(f"EDGE_LOOP('',({','.join(f'#{o}' for o in oes)}))")

    k = corner
    bottom_c = [k[0, 0, 0], k[0, 1, 0], k[1, 1, 0], k[1, 0, 0]]
    top_c = [k[0, 0, 1], k[1, 0, 1], k[1, 1, 1], k[0, 1, 1]]
    sides = [([k[0, 0, 0], k[1, 0, 0], k[1, 0, 1], k[0, 0, 1]], (0, -1, 0)),
             ([k[1, 0, 0], k[1, 1, 0], k[1, 1, 1], k[1, 0, 1]], (1, 0, 0)),
             ([k[1, 1, 0], k[0, 1, 0], k[0, 1, 1], k[1, 1, 1]], (0, 1, 0)),
             ([k[0, 1, 0], k[0, 0, 0], k[0, 0, 1], k[0, 1, 1]], (-1, 0, 0))]
    bottom_plane = w.add(f"PLANE('',#{w.placement((ox, oy, 0.0), (0, 0, -1), (1, 0, 0))})")
    top_plane = w.add(f"PLANE('',#{w.placement((ox, oy, sz), (0, 0, 1), (1, 0, 0))})")
    faces = []
    bottom_bounds = [w.add(f"FACE_OUTER_BOUND('',#{loop(bottom_c)},.T.)")]
    top_bounds = [w.add(f"FACE_OUTER_BOUND('',#{loop(top_c)},.T.)")]
    for cyc, normal in sides:
        p0 = c[cyc[0]]
        plane = w.add(f"PLANE('',#{w.placement(p0, normal, (0, 0, 1))})")
        bound = w.add(f"FACE_OUTER_BOUND('',#{loop(cyc)},.T.)")
        faces.append(w.add(f"ADVANCED_FACE('',(#{bound}),#{plane},.T.)"))
    radius = 2.5
    for h in range(HOLES):
        cx, cy = ox + 10.0 + 60.0 * (h % 4) / 3.0, oy + 15.0 + 20.0 * (h // 4)
        vb = w.add(f"VERTEX_POINT('',#{w.point(cx + radius, cy, 0.0)})")
        vt = w.add(f"VERTEX_POINT('',#{w.point(cx + radius, cy, sz)})")
        circles = {}
        for z, plane in ((0.0, bottom_plane), (sz, top_plane)):
            circle3d = w.add(f"CIRCLE('',#{w.placement((cx, cy, z))},{_r(radius)})")
            p2 = w.add(f"CARTESIAN_POINT('',({_r(cx - ox)},{_r(cy - oy)}))")
            d2 = w.add("DIRECTION('',(1.,0.))")
            circle2d = w.add(f"CIRCLE('',#{w.add(f'AXIS2_PLACEMENT_2D({chr(39)}{chr(39)},#{p2},#{d2})')},"
                             f"{_r(radius)})")
            defrep = w.add(f"DEFINITIONAL_REPRESENTATION('',(#{circle2d}),#{ctx2d})")
            pcurve = w.add(f"PCURVE('',#{plane},#{defrep})")
            sc = w.add(f"SURFACE_CURVE('',#{circle3d},(#{pcurve}),.PCURVE_S1.)")
            v = vb if z == 0.0 else vt
            circles[z] = w.add(f"EDGE_CURVE('',#{v},#{v},#{sc},.T.)")
        seam = w.add(f"EDGE_CURVE('',#{vb},#{vt},#{w.line((cx + radius, cy, 0.0), (cx + radius, cy, sz))},.T.)")
        oe = [w.add(f"ORIENTED_EDGE('',*,*,#{circles[sz]},.F.)"),
              w.add(f"ORIENTED_EDGE('',*,*,#{seam},.F.)"),
              w.add(f"ORIENTED_EDGE('',*,*,#{circles[0.0]},.T.)"),
              w.add(f"ORIENTED_EDGE('',*,*,#{seam},.T.)")]
        wall_loop = w.add(f"EDGE_LOOP('',({','.join(f'#{o}' for o in oe)}))")
        cyl = w.add(f"CYLINDRICAL_SURFACE('',#{w.placement((cx, cy, 0.0))},{_r(radius)})")
        wall_bound = w.add(f"FACE_BOUND('',#{wall_loop},.T.)")
        faces.append(w.add(f"ADVANCED_FACE('',(#{wall_bound}),#{cyl},.F.)"))
        for z, bounds in ((0.0, bottom_bounds), (sz, top_bounds)):
            ring = w.add(f"ORIENTED_EDGE('',*,*,#{circles[z]},.T.)")
            ring_loop = w.add(f"EDGE_LOOP('',(#{ring}))")
            bounds.append(w.add(f"FACE_BOUND('',#{ring_loop},.F.)"))
    faces.append(w.add(f"ADVANCED_FACE('',({','.join(f'#{b}' for b in bottom_bounds)}),#{bottom_plane},.T.)"))
    faces.append(w.add(f"ADVANCED_FACE('',({','.join(f'#{b}' for b in top_bounds)}),#{top_plane},.T.)"))
    shell = w.add(f"CLOSED_SHELL('',({','.join(f'#{f}' for f in faces)}))")
    return w.add(f"MANIFOLD_SOLID_BREP('plate',#{shell})")


def assembly(target_bytes: float) -> str:
    """The four-bar with drilled plates on its links, about ``target_bytes`` long."""
    text = FOUR_BAR.read_text()
    head, rest = text.split("DATA;\n", 1)
    data, tail = rest.split("ENDSEC;\nEND-ISO-10303-21;", 1)
    last = max(int(m) for m in re.findall(r"^#(\d+)=", data, re.M))
    associations = re.findall(r"^#(\d+)=KINEMATIC_LINK_REPRESENTATION_ASSOCIATION\('([^']*)',\$,#(\d+),#(\d+)\);$",
                              data, re.M)
    context_of = {m[0]: m[1] for m in re.findall(r"^#(\d+)=RIGID_LINK_REPRESENTATION\('[^']*',\([^)]*\),#(\d+),",
                                                 data, re.M)}
    w = _Writer(last + 1)
    ctx2d = w.add("(GEOMETRIC_REPRESENTATION_CONTEXT(2)PARAMETRIC_REPRESENTATION_CONTEXT()"
                  "REPRESENTATION_CONTEXT('2D SPACE',''))")
    per_plate = 23_800  # bytes of one plate's instances
    plates = max(len(associations), int((target_bytes - len(text)) / per_plate))
    new_data = data
    for n, (assoc, name, link_rep, _shape) in enumerate(associations):
        count = plates // len(associations) + (n < plates % len(associations))
        solids = [_plate(w, ctx2d, 100.0 * (i % 10), 60.0 * (i // 10) + 1000.0 * n) for i in range(count)]
        frame = w.placement((0.0, 0.0, 0.0))
        brep = w.add(f"ADVANCED_BREP_SHAPE_REPRESENTATION('{name} plates',"
                     f"({','.join(f'#{s}' for s in [frame, *solids])}),#{context_of[link_rep]})")
        new_data = re.sub(rf"^#{assoc}=KINEMATIC_LINK_REPRESENTATION_ASSOCIATION\('([^']*)',\$,#{link_rep},#\d+\);$",
                          f"#{assoc}=KINEMATIC_LINK_REPRESENTATION_ASSOCIATION('\\1',$,#{link_rep},#{brep});",
                          new_data, flags=re.M)
    head = head.replace("planar four-bar linkage", "planar four-bar linkage with drilled plates (bench)")
    return f"{head}DATA;\n{new_data}" + "\n".join(w.lines) + f"\nENDSEC;\nEND-ISO-10303-21;{tail}"


def chain(n: int) -> str:
    """A serial chain of ``n`` revolute pairs (link i to link i+1), AP242, by p105's writer."""
    from p105cli.kinematics.model import Link, Mechanism, Pair
    from p105cli.kinematics.placements import axis2_placement_3d
    from p105cli.part105.write_mechanism import write_mechanism
    from p105cli.step import write_step

    links = [Link(f"L{i}") for i in range(n + 1)]
    pairs = []
    for i in range(n):
        # joint i at x = i on the world x axis, alternately about z and y
        axis = (0.0, 0.0, 1.0) if i % 2 == 0 else (0.0, 1.0, 0.0)
        frame = axis2_placement_3d((float(i), 0.0, 0.0), axis)
        pairs.append(Pair(f"J{i}", "revolute", f"L{i}", f"L{i + 1}", frame, frame))
    mech = Mechanism(f"chain{n}", links, pairs, "L0")
    doc, _ = write_mechanism(mech, "ap242")
    buf = io.StringIO()
    write_step(doc, buf)
    return buf.getvalue()


def main() -> int:
    kind, size = sys.argv[1], float(sys.argv[2])
    sys.stdout.write(assembly(size) if kind == "assembly" else chain(int(size)))
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(REPO))
    sys.exit(main())
