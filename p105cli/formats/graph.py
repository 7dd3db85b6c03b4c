"""``p105 graph``'s outputs: a mechanism's structure as JSON (``p105-graph/1``), Graphviz dot,
GraphML and Mermaid.

The structure itself (spanning tree, loops, mobility) is
:func:`p105cli.kinematics.graph.analyse`'s; this module only writes it.
"""

from __future__ import annotations

import json

from p105cli.kinematics.graph import Structure

__all__ = ["GRAPH_FORMAT", "FORMATS", "structure_document", "to_dot", "to_graphml", "to_mermaid", "render"]

#: The formats of :func:`render`.
FORMATS = ("json", "dot", "graphml", "mermaid")


GRAPH_FORMAT = "p105-graph/1"


def _loop_links(mech, loop):
    first = mech.pair(loop[0][0])
    at, out = first.link1, []
    for name, fwd in loop:
        out.append(at)
        p = mech.pair(name)
        at = p.link2 if fwd else p.link1
    return out


def structure_document(mech, st: Structure) -> dict:
    """The JSON-ready description of a :class:`Structure` (format ``p105-graph/1``).

    Keys: ``links``, ``joints``, ``tree``, ``loops``, ``components``, ``kind``,
    ``freedoms``, ``mobility``, ``mobility_gruebler``, ``rank``,
    ``redundant_constraints``, ``redundant_joints``, ``closure_residual``,
    ``tolerance``, ``size`` (metres), ``notes``.
    """
    comp_of = {ln: ci for ci, c in enumerate(st.components) for ln in c.links}
    parent = {child: (name, par) for name, par, child, _ in st.tree}
    depth = {}
    for ln in st.order:
        depth[ln] = depth[parent[ln][1]] + 1 if ln in parent else 0
    tree_pairs = {name for name, *_ in st.tree}
    loops_of = {}
    for li, lp in enumerate(st.loops):
        for name, _ in lp:
            loops_of.setdefault(name, []).append(li)
    redundant = set(st.redundant_joints)
    links = []
    for ln in st.order:
        link = mech.link(ln)
        links.append({"name": ln, "id": link.id, "base": ln == mech.base, "component": comp_of[ln],
                      "depth": depth[ln], "parent": parent[ln][1] if ln in parent else None,
                      "parent_joint": parent[ln][0] if ln in parent else None})
    joints = []
    for p in mech.pairs:
        joints.append({"name": p.name, "id": p.ids.get("pair"), "joint_id": p.ids.get("joint"),
                       "kind": p.kind, "link1": p.link1, "link2": p.link2, "freedoms": p.freedoms,
                       "actuated": bool(p.actuated), "tree": p.name in tree_pairs,
                       "loops": loops_of.get(p.name, []), "redundant": p.name in redundant})
    loops = [{"chord": st.chords[li], "links": _loop_links(mech, lp),
              "joints": [{"joint": name, "forward": fwd} for name, fwd in lp]}
             for li, lp in enumerate(st.loops)]
    comps = [{"root": c.root, "floating": c.floating, "links": c.links, "joints": c.pairs, "loops": c.loops,
              "freedoms": c.dof, "mobility": c.mobility, "mobility_gruebler": c.mobility_gruebler,
              "rank": c.rank, "redundant_constraints": c.redundant_constraints,
              "redundant_joints": c.redundant_joints} for c in st.components]
    return {"format": GRAPH_FORMAT, "mechanism": mech.name, "base": mech.base, "kind": st.kind,
            "links": links, "joints": joints,
            "tree": [{"joint": n, "parent": a, "child": b, "forward": f} for n, a, b, f in st.tree],
            "loops": loops, "components": comps, "freedoms": st.dof,
            "mobility": st.mobility, "mobility_gruebler": st.mobility_gruebler, "rank": st.rank,
            "redundant_constraints": st.redundant_constraints, "redundant_joints": st.redundant_joints,
            "closure_residual": st.closure_residual, "tolerance": st.tol, "size": st.size,
            "notes": list(st.notes)}


def _summary(st: Structure) -> str:
    mob = "unknown" if st.mobility is None else str(st.mobility)
    red = "unknown" if st.redundant_constraints is None else str(st.redundant_constraints)
    return (f"{st.kind}, {len(st.loops)} loop(s), mobility {mob} (Gruebler {st.mobility_gruebler}, "
            f"{red} redundant constraint(s))")


def _dot_id(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def to_dot(mech, st: Structure) -> str:
    """Graphviz DOT: links as nodes (base doubled), joints as edges first -> second link;
    spanning-tree edges solid, chords dashed, joints carrying redundant constraints red."""
    tree = {name for name, *_ in st.tree}
    red = set(st.redundant_joints)
    out = [f"digraph {_dot_id(mech.name)} {{",
           f"  label={_dot_id(mech.name + ': ' + _summary(st))};",
           "  node [shape=box];"]
    for ln in st.order:
        attrs = ', peripheries=2' if ln == mech.base else ""
        out.append(f"  {_dot_id(ln)} [label={_dot_id(ln)}{attrs}];")
    for p in mech.pairs:
        style = "solid" if p.name in tree else "dashed"
        color = ', color="red"' if p.name in red else ""
        out.append(f"  {_dot_id(p.link1)} -> {_dot_id(p.link2)} "
                   f"[label={_dot_id(p.name + chr(10) + p.kind)}, style={style}{color}];")
    out.append("}")
    return "\n".join(out) + "\n"


def to_graphml(mech, st: Structure) -> str:
    """GraphML: nodes = links (data: name, base, component), edges = joints (data: name, kind,
    freedoms, tree, loops, redundant); graph data: mobility, mobility_gruebler, redundant."""
    from xml.sax.saxutils import escape

    tree = {name for name, *_ in st.tree}
    red = set(st.redundant_joints)
    comp_of = {ln: ci for ci, c in enumerate(st.components) for ln in c.links}
    loops_of = {}
    for li, lp in enumerate(st.loops):
        for name, _ in lp:
            loops_of.setdefault(name, []).append(str(li))
    node_id = {ln: f"n{i}" for i, ln in enumerate(st.order)}
    keys = [("g_mechanism", "graph", "mechanism", "string"), ("g_kind", "graph", "kind", "string"),
            ("g_mobility", "graph", "mobility", "int"), ("g_gruebler", "graph", "mobility_gruebler", "int"),
            ("g_redundant", "graph", "redundant_constraints", "int"),
            ("n_name", "node", "name", "string"), ("n_base", "node", "base", "boolean"),
            ("n_component", "node", "component", "int"),
            ("e_name", "edge", "name", "string"), ("e_kind", "edge", "kind", "string"),
            ("e_freedoms", "edge", "freedoms", "int"), ("e_tree", "edge", "tree", "boolean"),
            ("e_loops", "edge", "loops", "string"), ("e_redundant", "edge", "redundant", "boolean")]
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           '<graphml xmlns="http://graphml.graphdrawing.org/xmlns" '
           'xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" '
           'xsi:schemaLocation="http://graphml.graphdrawing.org/xmlns '
           'http://graphml.graphdrawing.org/xmlns/1.0/graphml.xsd">']
    for kid, dom, name, typ in keys:
        out.append(f'  <key id="{kid}" for="{dom}" attr.name="{name}" attr.type="{typ}"/>')
    out.append('  <graph id="G" edgedefault="directed">')

    def data(key, value):
        if value is None:
            return ""
        if isinstance(value, bool):
            value = "true" if value else "false"
        return f'<data key="{key}">{escape(str(value))}</data>'

    out.append("    " + "".join([data("g_mechanism", mech.name), data("g_kind", st.kind),
                                 data("g_mobility", st.mobility), data("g_gruebler", st.mobility_gruebler),
                                 data("g_redundant", st.redundant_constraints)]))
    for ln in st.order:
        out.append(f'    <node id="{node_id[ln]}">' + data("n_name", ln) + data("n_base", ln == mech.base)
                   + data("n_component", comp_of[ln]) + "</node>")
    for k, p in enumerate(mech.pairs):
        out.append(f'    <edge id="e{k}" source="{node_id[p.link1]}" target="{node_id[p.link2]}">'
                   + data("e_name", p.name) + data("e_kind", p.kind) + data("e_freedoms", p.freedoms)
                   + data("e_tree", p.name in tree) + data("e_loops", " ".join(loops_of.get(p.name, [])))
                   + data("e_redundant", p.name in red) + "</edge>")
    out.append("  </graph>")
    out.append("</graphml>")
    return "\n".join(out) + "\n"


def _mermaid_text(s: str) -> str:
    return s.replace("&", "#amp;").replace('"', "#quot;").replace("<", "#lt;").replace(">", "#gt;")


def to_mermaid(mech, st: Structure) -> str:
    """Mermaid flowchart: links as nodes (the base as a stadium), joints as edges first -> second
    link, spanning-tree edges solid, chords dotted."""
    tree = {name for name, *_ in st.tree}
    node_id = {ln: f"n{i}" for i, ln in enumerate(st.order)}
    out = ["flowchart LR", f"  %% {_mermaid_text(mech.name)}: {_mermaid_text(_summary(st))}"]
    for ln in st.order:
        label = _mermaid_text(ln + (" (base)" if ln == mech.base else ""))
        out.append(f'  {node_id[ln]}(["{label}"])' if ln == mech.base else f'  {node_id[ln]}["{label}"]')
    for p in mech.pairs:
        label = _mermaid_text(f"{p.name}: {p.kind}")
        a, b = node_id[p.link1], node_id[p.link2]
        if p.name in tree:
            out.append(f'  {a} -- "{label}" --> {b}')
        else:
            out.append(f'  {a} -. "{label}" .-> {b}')
    return "\n".join(out) + "\n"


def render(mech, st: Structure, fmt: str) -> str:
    """The structure in one of :data:`FORMATS`, as text."""
    if fmt == "json":
        return json.dumps(structure_document(mech, st), indent=2, ensure_ascii=False, allow_nan=False) + "\n"
    return {"dot": to_dot, "graphml": to_graphml, "mermaid": to_mermaid}[fmt](mech, st)
