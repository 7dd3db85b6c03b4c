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

from ..step.jsonmodel import extended
from .model_file import ModelFile

__all__ = ["EnrichError", "enrich"]


class EnrichError(ValueError):
    """The model cannot be enriched (layout without graph entities, or a joint not found)."""


def _ref(i: int) -> dict:
    return {"ref": i}


#: The structures enrich writes (subtypes of kinematic_topology_structure), each once per parent.
_ADDED = ("kinematic_topology_tree_structure", "kinematic_topology_network_structure")


def enrich(model, analysed, profile: str):
    """A new JsonDocument: the instances and header of ``model`` (a ModelFile, or a document),
    plus graph entities. The file's joints and topology structures are read by attribute
    name through the model file.

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
    mf = ModelFile.of(model, profile).lenient()
    data = list(mf.doc.records())
    next_id = max((rec["id"] for rec in data), default=0) + 1
    notes, added = [], []

    joints_by_name = {}
    for jid in mf.ids_of_type("kinematic_joint"):
        name = mf.get(jid, "name", None)
        if isinstance(name, str):
            joints_by_name.setdefault(name, []).append(jid)
    # the topology structures proper, not their subtypes (tree, network, ... structures)
    topologies = [t for t in mf.ids_of_type("kinematic_topology_structure")
                  if mf.leaf_types(t) == {"kinematic_topology_structure"}]
    existing = {}
    for t in _ADDED:
        for i in mf.ids_of_type(t):
            parent = mf.ref(i, "parent")
            if parent is not None:
                existing.setdefault(parent, set()).add(t)

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
            if jid is None or not mf.is_a(jid, "kinematic_joint"):
                raise EnrichError(f"mechanism {mech.name!r}: the kinematic_joint of pair {p.name!r} "
                                  "is not found in the file")
            joint_id[p.name] = jid
        wanted = set(joint_id.values())
        items = {t: mf.refs(t, "items") for t in topologies}
        topo = sorted((t for t in topologies if wanted <= set(items[t])), key=lambda t: (len(items[t]), t))
        if not topo:
            raise EnrichError(f"mechanism {mech.name!r}: no kinematic_topology_structure holds its joints")
        top = topo[0]
        context = mf.get(top, "context_of_items", None)
        have = existing.get(top, set())

        def oriented(pair_name, forward):
            return new("oriented_joint", ["", {"derived": True}, {"derived": True},
                                          _ref(joint_id[pair_name]), {"enum": "T" if forward else "F"}])

        if "kinematic_topology_tree_structure" in have:
            notes.append(f"mechanism {mech.name!r}: #{top} already has a tree structure; kept")
        elif st.tree:
            tree_items = [_ref(oriented(name, fwd)) for name, _parent, _child, fwd in st.tree]
            new("kinematic_topology_tree_structure",
                [f"{mech.name} spanning tree", tree_items, context, _ref(top)])
        if "kinematic_topology_network_structure" in have:
            notes.append(f"mechanism {mech.name!r}: #{top} already has a network structure; kept")
        elif st.loops:
            loops = []
            for li, lp in enumerate(st.loops, 1):
                edges = [_ref(oriented(name, fwd)) for name, fwd in lp]
                loops.append(_ref(new("kinematic_loop", [f"loop {li}", edges])))
            new("kinematic_topology_network_structure", [f"{mech.name} loops", loops, context, _ref(top)])

    return extended(mf.doc, data, added), notes
