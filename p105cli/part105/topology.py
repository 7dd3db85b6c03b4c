"""``p105 graph --enrich``: write a model back with Part 105 graph entities added.

For the AP242 layout (ISO 10303-105 ed. 2 as AP242 carries it) each mechanism's
``kinematic_topology_structure`` (the set of its joints) gets

* a ``kinematic_topology_tree_structure`` (a ``kinematic_topology_directed_structure``):
  the spanning tree found by :func:`p105cli.kinematics.graph.analyse`, one
  ``oriented_joint`` per tree edge, oriented from the parent link to the
  child link (``orientation`` TRUE when the joint's first link is the parent);
* when it has loops, a ``kinematic_topology_network_structure`` whose items
  are ``kinematic_loop`` s (``edge_loop`` s of ``oriented_joint`` s, each
  oriented in traversal order so that one joint's end link is the next one's
  start, and the last ends where the first starts).

Both take the topology structure's context and name it as ``parent``, which
their WHERE rules require (same context; joints a subset of the parent's).
A structure of a kind the file already has for that topology is not added
again (the file's own stays, untouched): enriching is additive and idempotent.
New instances get ids above the file's largest.

The 1996 layout (AP214's long form) does not carry the 1996 text's graph
entities (kinematic_tree_structure, kinematic_network_structure,
kinematic_loop, oriented_joint, joint_logical_relationship, clauses
5.4.70-5.4.77): AP214 dropped them, and the copy of the 1996 text we have
lacks the pages defining the first three. Writing them would make a file
that does not conform to its own FILE_SCHEMA, so :func:`enrich` refuses
such a model (:class:`EnrichError`) instead of guessing their attributes.

No click, no numpy.
"""

from __future__ import annotations

from ..schema.values import refs
from ..step.jsonmodel import extended

__all__ = ["EnrichError", "enrich"]


class EnrichError(ValueError):
    """The model cannot be enriched (layout without graph entities, or a joint not found)."""


def _ref(i: int) -> dict:
    return {"ref": i}


_refs = refs  # the ids of a list of references (schema/values.py)


def _simple_type(rec: dict):
    return rec.get("type")


def enrich(doc, analysed, profile: str):
    """A new JsonDocument: ``doc``'s instances and header, plus graph entities.

    ``analysed``: list of ``(mechanism, structure)`` (structures from
    :func:`analyse`); ``profile``: ``"ap242"`` (``"ap214"``/``"p105"`` raise
    :class:`EnrichError`). Returns ``(document, notes)``.
    """
    if profile != "ap242":
        raise EnrichError(
            f"--enrich needs the AP242 layout: the {profile} profile (AP214 long form, the 1996 "
            "Part 105 layout) has no kinematic graph entities (the 1996 text's kinematic_tree_structure, "
            "kinematic_network_structure, kinematic_loop and oriented_joint are not in AP214's schema); "
            "the output would not conform to its FILE_SCHEMA")
    data = list(doc.records())
    by_id = {}
    for rec in data:
        by_id[rec["id"]] = rec
    next_id = max(by_id, default=0) + 1
    notes, added = [], []

    joints_by_name = {}
    topologies, existing = [], {}
    for rec in data:
        t = _simple_type(rec)
        if t == "kinematic_joint":
            args = rec.get("args") or []
            if args and isinstance(args[0], str):
                joints_by_name.setdefault(args[0], []).append(rec["id"])
        elif t == "kinematic_topology_structure":
            topologies.append(rec)
        elif t in ("kinematic_topology_tree_structure", "kinematic_topology_network_structure"):
            args = rec.get("args") or []
            if len(args) >= 4 and isinstance(args[3], dict) and "ref" in args[3]:
                existing.setdefault(args[3]["ref"], set()).add(t)

    def new(type_name, args):
        nonlocal next_id
        rec = {"id": next_id, "type": type_name, "args": args}
        next_id += 1
        added.append(rec)
        return rec["id"]

    for mech, st in analysed:
        joint_id = {}
        for p in mech.pairs:
            jid = p.ids.get("joint")
            if jid is None:
                cands = joints_by_name.get(p.joint) or joints_by_name.get(p.name) or []
                jid = cands[0] if len(cands) == 1 else None
            if jid is None or jid not in by_id or _simple_type(by_id[jid]) != "kinematic_joint":
                raise EnrichError(f"mechanism {mech.name!r}: the kinematic_joint of pair {p.name!r} "
                                  "is not found in the file")
            joint_id[p.name] = jid
        wanted = set(joint_id.values())
        topo = [r for r in topologies if wanted <= set(_refs((r.get("args") or [None, None])[1]))]
        if not topo:
            raise EnrichError(f"mechanism {mech.name!r}: no kinematic_topology_structure holds its joints")
        topo.sort(key=lambda r: len(_refs(r["args"][1])))
        top = topo[0]
        context = top["args"][2]
        have = existing.get(top["id"], set())

        def oriented(pair_name, forward):
            return new("oriented_joint", ["", {"derived": True}, {"derived": True},
                                          _ref(joint_id[pair_name]), {"enum": "T" if forward else "F"}])

        if "kinematic_topology_tree_structure" in have:
            notes.append(f"mechanism {mech.name!r}: #{top['id']} already has a tree structure; kept")
        elif st.tree:
            items = [_ref(oriented(name, fwd)) for name, _parent, _child, fwd in st.tree]
            new("kinematic_topology_tree_structure",
                [f"{mech.name} spanning tree", items, context, _ref(top["id"])])
        if "kinematic_topology_network_structure" in have:
            notes.append(f"mechanism {mech.name!r}: #{top['id']} already has a network structure; kept")
        elif st.loops:
            loops = []
            for li, lp in enumerate(st.loops, 1):
                edges = [_ref(oriented(name, fwd)) for name, fwd in lp]
                loops.append(_ref(new("kinematic_loop", [f"loop {li}", edges])))
            new("kinematic_topology_network_structure", [f"{mech.name} loops", loops, context, _ref(top["id"])])

    return extended(doc, data, added), notes
