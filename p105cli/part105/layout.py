"""Part 105's two layouts, walked once: mechanisms, joints, pairs, links and their
representations, pair frames, base placement, initial state, and THE names of links and pairs.

=====================  ==================================  ==================================
                       1996 layout (ap214, p105)           AP242 layout
=====================  ==================================  ==================================
mechanism              ``mechanism``                       ``mechanism_representation``
its name               id of the product whose kinematic   its ``name``, else ``#id``
                       property it is, else ``#id``
pairs, joints          the structure's joints, each with   the ``pair_representation_
                       the one pair whose ``joint`` it is  relationship`` items
links of a joint       ``first_link``/``second_link``      ``edge_start``/``edge_end``
link representation    ``kinematic_link_representation_    ``represented_link``
                       relation``
base link              ``mechanism.base``                  ``kinematic_property_mechanism_
                                                           representation.base``
base placement         ``mechanism_base_placement``        the assembly placing the base
                                                           link's product
initial state          ``initial_state``                   ``mechanism_state_representation``
                                                           named "initial..." (else the first)
=====================  ==================================  ==================================

Names (one rule for every reader: ``read_mechanism``, the motion readers, the checks):

* a link is called by its ``name``, else its representation's ``name``, else ``#<link id>``;
* a pair by its name, else its joint's, else ``#<pair id>``;
* within a mechanism, a name that two links (or two pairs) share gets `` #<id>`` appended
  (``coupler #131``, ``coupler #132``): names stay deterministic and unique.

``mechanisms(mf)`` walks a checked :class:`~p105cli.part105.model_file.ModelFile` once (the
result is cached on the file) and raises ModelError naming the ``#id`` at fault. The
validator walks a lenient file with :func:`link_reps`, :func:`joint_links`,
:func:`frame_rep` and :func:`mechanism_parts`, which never raise.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

from .model_file import ModelFile, model_error

__all__ = ["PairLayout", "MechanismLayout", "mechanisms", "link_name", "unique_names", "link_reps",
           "rep_links", "joint_links", "frame_rep", "mechanism_parts", "link_name_of_representation",
           "link_frames"]


@dataclass
class PairLayout:
    """One pair as its mechanism's layout places it (instance ids)."""

    id: int
    joint: int
    link1: int
    link2: int
    frame_1: int
    frame_2: int
    rep_1: int                         # the link representations placing frame_1, frame_2
    rep_2: int
    name: str = ""                     # THE pair name (unique in its mechanism)
    joint_name: str = ""
    description: str = ""
    relationship: Optional[int] = None  # AP242 pair_representation_relationship
    range: Optional[int] = None         # the instance holding its limits (1996: *_pair_range)
    actuator: Optional[int] = None      # 1996 pair_actuator
    actuated: bool = False


@dataclass
class MechanismLayout:
    """One mechanism's topology: ids, the base link, links (-> representation), pairs,
    the initial state's values (pair id -> value id) and THE link names."""

    id: int
    layout: str
    name: str
    description: str = ""
    ids: dict = field(default_factory=dict)        # role -> instance id (structure, property, ...)
    base: Optional[int] = None
    links: dict = field(default_factory=dict)      # link id -> representation id (or None)
    pairs: list = field(default_factory=list)      # PairLayout, in file order
    values: dict = field(default_factory=dict)     # pair id -> initial pair value id
    link_names: dict = field(default_factory=dict)  # link id -> name
    base_placement: Optional[tuple] = None          # (operator, rep of its units 1, rep 2) or None
    _pair_frames: Optional[dict] = field(default=None, repr=False, compare=False)

    def pair_frames(self, link) -> set:
        """The pair frames on ``link`` (built once for all links: a long chain asks for each)."""
        if self._pair_frames is None:
            self._pair_frames = {}
            for p in self.pairs:
                self._pair_frames.setdefault(p.link1, set()).add(p.frame_1)
                self._pair_frames.setdefault(p.link2, set()).add(p.frame_2)
        return self._pair_frames.get(link, set())

    @property
    def link_order(self) -> list:
        """The base link first, then the others by id."""
        return [self.base] + sorted(x for x in self.links if x != self.base)

    def pair(self, pair_id: int) -> Optional[PairLayout]:
        return next((p for p in self.pairs if p.id == pair_id), None)


# --------------------------------------------------------------------------- the naming rule

def unique_names(raw: dict) -> dict:
    """Names made unique deterministically: a name used more than once gets `` #id``."""
    count: dict = {}
    for n in raw.values():
        count[n] = count.get(n, 0) + 1
    return {k: (n if count[n] == 1 else f"{n} #{k}") for k, n in raw.items()}


def link_name(mf: ModelFile, link: int, rep: Optional[int]) -> str:
    """A link's own name: its name, else its representation's, else ``#id`` (before
    :func:`unique_names`)."""
    return mf.string(link, "name") or (mf.string(rep, "name") if rep is not None else "") or f"#{link}"


def pair_name(mf: ModelFile, pair: int, joint_name: str) -> str:
    """A pair's own name: its name, else its joint's, else ``#id`` (before :func:`unique_names`)."""
    return (mf.string(pair, "representation_item.name", "item_defined_transformation.name", "name")
            or joint_name or f"#{pair}")


# --------------------------------------------------------------------------- links

def link_reps(mf: ModelFile, link) -> list:
    """The representations of ``link`` (1996: kinematic_link_representation_relation; AP242:
    represented_link), in file order."""
    if link is None:
        return []
    reps = []
    for rel in mf.usedin(link, "kinematic_link_representation_relation.topological_aspects"):
        g = mf.ref(rel, "geometric_aspects")
        if g is not None:
            reps.append(g)
    reps.extend(mf.usedin(link, "kinematic_link_representation.represented_link"))
    return list(dict.fromkeys(reps))


def rep_links(mf: ModelFile, rep) -> list:
    """The links ``rep`` represents (1996: through the relation; AP242: represented_link)."""
    out = []
    for rel in mf.usedin(rep, "kinematic_link_representation_relation.geometric_aspects"):
        t = mf.ref(rel, "topological_aspects")
        if t is not None:
            out.append(t)
    if mf.is_lenient:
        r = mf.ref(rep, "represented_link")
    else:
        r = mf.ref(rep, "represented_link") if mf.ref_value(rep, "represented_link") is not None else None
    if r is not None:
        out.append(r)
    return out


def joint_links(mf: ModelFile, joint) -> tuple:
    """(first link, second link) of a joint (1996: first_link/second_link; AP242:
    edge_start/edge_end); lenient: None for what is missing."""
    if joint is None:
        return None, None
    if mf.has(joint, "first_link"):
        return mf.ref(joint, "first_link"), mf.ref(joint, "second_link")
    return mf.ref(joint, "edge_start"), mf.ref(joint, "edge_end")


def frame_rep(mf: ModelFile, link, frame, *, hint=None, pair=None, which: int = 1) -> Optional[int]:
    """The representation of ``link`` that places ``frame`` (a pair frame on it): the hint (AP242
    rep_1/rep_2), else a representation of the link holding the frame, else the one link
    representation holding it. Checked: a frame placed in another link's representation, or in
    none, is an error. Lenient: the link's first representation then (None if it has none)."""
    cands = [] if hint is None or link not in rep_links(mf, hint) else [hint]
    cands += link_reps(mf, link)
    for r in cands:
        if frame in mf.refs(r, "items"):
            return r
    if mf.is_lenient:
        if cands:
            return cands[0]
        return next(iter(mf.usedin(frame, "kinematic_link_representation.items")), None) \
            if frame is not None else None
    for r in mf.usedin(frame, "representation.items"):
        if mf.is_a(r, "kinematic_link_representation"):
            others = [x for x in rep_links(mf, r) if x != link]
            if others:
                raise model_error(pair, f"transform_item_{which} #{frame} is placed in #{r}, the "
                                  f"representation of link #{others[0]}, not of its "
                                  f"{'first' if which == 1 else 'second'} link #{link}")
            return r
    if cands:
        return cands[0]
    raise model_error(frame, f"pair frame of link #{link} is in no link representation: its units "
                      "are unknown")


def link_frames(mf: ModelFile, ml: MechanismLayout, link) -> dict:
    """``{frame name: placement id}``: the placements of a link's representation that are no
    pair frame of the mechanism (named by their name, else ``#id``; made unique)."""
    rep = ml.links.get(link)
    if rep is None:
        return {}
    used = ml.pair_frames(link)
    items = [i for i in mf.refs(rep, "items")
             if i not in used and mf.is_a(i, "axis2_placement_3d", "su_parameters")]
    names = unique_names({i: mf.string(i, "name") or f"#{i}" for i in items})
    return {names[i]: i for i in items}


# --------------------------------------------------------------------------- the walk (checked)

def mechanisms(mf: ModelFile) -> list:
    """Every mechanism of the file as a :class:`MechanismLayout`, in file order (walked once
    per file)."""
    mf = mf.checked()
    return mf.cached("layout.mechanisms", lambda: _walk(mf))


def _walk(mf: ModelFile) -> list:
    if mf.layout == "1996":
        return [_read_1996(mf, m) for m in mf.ids_of_type("mechanism")]
    return [_read_ap242(mf, m) for m in mf.ids_of_type("mechanism_representation")]


def _add_pair(ml: MechanismLayout, p: PairLayout) -> None:
    ml.pairs.append(p)
    for link, rep in ((p.link1, p.rep_1), (p.link2, p.rep_2)):
        if ml.links.get(link) is None:  # the representation that holds the link's pair frames
            ml.links[link] = rep


def _pair(mf: ModelFile, ml: MechanismLayout, p, j, l1, l2, hints=(None, None)) -> PairLayout:
    if not mf.is_a(p, "kinematic_pair"):
        raise model_error(p, f"{mf.label(p)} is not a kinematic_pair")
    pj = mf.ref(p, "joint", types=("kinematic_joint",))
    if pj != j:
        raise model_error(p, f"pair's joint is #{pj}, not #{j}")
    f1 = mf.ref(p, "transform_item_1")
    f2 = mf.ref(p, "transform_item_2")
    rep1 = frame_rep(mf, l1, f1, hint=hints[0], pair=p, which=1)
    rep2 = frame_rep(mf, l2, f2, hint=hints[1], pair=p, which=2)
    pl = PairLayout(p, j, l1, l2, f1, f2, rep1, rep2, joint_name=mf.string(j, "name"),
                    description=mf.string(p, "item_defined_transformation.description", "description"))
    if ml.layout == "1996":
        pl.range = next(iter(mf.usedin(p, "simple_pair_range.applies_to_pair")), None)
    elif any(n.startswith(("lower_limit_", "range_on_")) for n in mf.names(p)):
        pl.range = p
    pl.actuated = mf.is_a(p, "actuated_kinematic_pair")
    pl.actuator = next(iter(mf.usedin(p, "pair_actuator.actuated_pair")), None)
    if pl.actuator is not None:
        pl.actuated = True
    return pl


def _no_pair(mf: ModelFile, j):
    """A joint of the structure with no pair: report a pair whose joint reference is unset or
    dangling first (that is the likely cause), else the joint."""
    for p in mf.ids_of_type("kinematic_pair"):
        r = mf.ref_value(p, "joint")
        if r is None or r not in mf.pop:
            mf.ref(p, "joint", types=("kinematic_joint",))  # raises, naming the pair
    raise model_error(j, "kinematic_joint has no kinematic_pair: its motion is unknown")


def _name_1996(mf: ModelFile, m, prop) -> str:
    """The id of the product whose kinematic property the mechanism is, else its name, else #id."""
    if prop is not None:
        pd = mf.ref(prop, "definition", optional=True)
        if pd is not None and mf.is_a(pd, "product_definition"):
            pdf = mf.ref(pd, "formation", optional=True)
            if pdf is not None and mf.is_a(pdf, "product_definition_formation"):
                prod = mf.ref(pdf, "of_product", optional=True)
                if prod is not None:
                    name = mf.string(prod, "id") or mf.string(prod, "name")
                    if name:
                        return name
    return f"#{m}"


def _read_1996(mf: ModelFile, m) -> MechanismLayout:
    struct = mf.ref(m, "structure_definition", types=("kinematic_structure",))
    base = mf.ref(m, "base", types=("kinematic_link",))
    prop = mf.ref(m, "containing_property", optional=True)
    ml = MechanismLayout(m, "1996", _name_1996(mf, m, prop), ids={"mechanism": m})
    ml.ids["structure"] = struct
    if prop is not None:
        ml.ids["property"] = prop
        ml.description = mf.string(prop, "description")
    ml.base = base
    ml.links[base] = None
    for j in mf.refs(struct, "joints", types=("kinematic_joint",)):
        pairs = mf.usedin(j, "kinematic_pair.joint")
        if not pairs:
            _no_pair(mf, j)
        if len(pairs) > 1:
            raise model_error(j, f"kinematic_joint has {len(pairs)} pairs "
                              f"({', '.join(f'#{p}' for p in pairs)}); Part 105 ties one pair to a joint")
        l1 = mf.ref(j, "first_link", types=("kinematic_link",))
        l2 = mf.ref(j, "second_link", types=("kinematic_link",))
        _add_pair(ml, _pair(mf, ml, pairs[0], j, l1, l2))
    # base placement: mechanism_base_placement (a transformation operator in the ground's context)
    for bp in mf.usedin(m, "mechanism_base_placement.base_of_mechanism"):
        ground = mf.ref(bp, "rep_1")
        op = mf.ref(bp, "transformation_operator")
        ml.base_placement = (op, ground, ground)
        ml.ids["base_placement"] = bp
        ml.ids["ground"] = ground
        break
    for st in mf.usedin(m, "initial_state.applies_to_mechanism"):
        ml.ids["initial_state"] = st
        for v in mf.refs(st, "pair_values", types=("pair_value",)):
            p = mf.ref(v, "applies_to_pair", types=("kinematic_pair",))
            ml.values.setdefault(p, v)
        break
    return _finish(mf, ml)


def _read_ap242(mf: ModelFile, m) -> MechanismLayout:
    ml = MechanismLayout(m, "ap242", mf.string(m, "name") or f"#{m}", ids={"mechanism": m})
    topo = mf.ref(m, "represented_topology", optional=True)
    if topo is not None:
        ml.ids["structure"] = topo
    base_rep = None
    for kp in mf.usedin(m, "kinematic_property_mechanism_representation.used_representation"):
        ml.ids["property"] = kp
        base_rep = mf.ref(kp, "base", types=("kinematic_link_representation",))
        pdk = mf.ref(kp, "definition", optional=True)
        if pdk is not None:
            ml.description = mf.string(pdk, "description")
            ml.ids["product_definition_kinematics"] = pdk
        break
    for item in mf.refs(m, "items"):
        if mf.is_a(item, "kinematic_pair"):  # build123d's AP242 writer
            p, prr, hints = item, None, (None, None)
            mf.deviation(p, f"{mf.label(p)} listed directly among the items of mechanism_representation #{m}; "
                         "AP242 links pairs to a mechanism through pair_representation_relationship "
                         "(read anyway)")
        elif not mf.is_a(item, "pair_representation_relationship"):
            raise model_error(m, f"items of {mf.label(m)} refers to #{item} ({mf.label(item)}), which is no "
                              "pair_representation_relationship")
        else:
            prr = item
            p = mf.ref(prr, "transformation_operator", types=("kinematic_pair",))
            hints = (mf.ref(prr, "rep_1", types=("kinematic_link_representation",)),
                     mf.ref(prr, "rep_2", types=("kinematic_link_representation",)))
        j = mf.ref(p, "joint", types=("kinematic_joint",))
        l1 = mf.ref(j, "edge_start", types=("kinematic_link",))
        l2 = mf.ref(j, "edge_end", types=("kinematic_link",))
        pl = _pair(mf, ml, p, j, l1, l2, hints=hints)
        pl.relationship = prr
        _add_pair(ml, pl)
    if topo is not None and mf.is_a(topo, "kinematic_topology_structure"):
        items = mf.refs(topo, "items")
        links = [x for x in items if mf.is_a(x, "kinematic_link")]
        if links:  # build123d's AP242 writer: the links of the joints, listed beside them
            mf.deviation(topo, f"kinematic_topology_structure lists the kinematic_link{'s' * (len(links) > 1)} "
                         f"{', '.join(f'#{x}' for x in links)} among its items; AP242 allows only "
                         "kinematic_joint there, the links are the joints' ends (read as the joints' ends)")
        for j in items:  # links of joints without a pair
            if mf.is_a(j, "kinematic_joint"):
                for a in ("edge_start", "edge_end"):
                    ml.links.setdefault(mf.ref(j, a, types=("kinematic_link",)), None)
    if base_rep is not None:
        base = mf.ref(base_rep, "represented_link", types=("kinematic_link",))
        ml.links.setdefault(base, base_rep)
    elif ml.links:
        base = next(iter(ml.links))  # no kinematic property: the first pair's first link
    else:
        raise model_error(m, "mechanism_representation has no pairs and no base link")
    ml.base = base
    if ml.links.get(base) is None and base_rep is not None:
        ml.links[base] = base_rep
    ml.base_placement = _assembly_placement(mf, ml, base)
    states = mf.usedin(m, "mechanism_state_representation.represented_mechanism")
    if states:
        named = [s for s in states if "initial" in mf.string(s, "name").lower()]
        st = (named or states)[0]
        ml.ids["initial_state"] = st
        ctx = mf.ref_value(st, "context_of_items")
        if ctx is not None:  # Open CASCADE's and build123d's writers
            own = mf.ref_value(m, "context_of_items")
            said = ("the same" if ctx == own else
                    f"another one: the mechanism's #{own} is used, as AP242 derives")
            mf.deviation(st, f"mechanism_state_representation writes its context #{ctx}, which AP242 derives "
                         f"from its mechanism #{m} (*); it is {said} (read anyway)")
        for v in mf.refs(st, "items"):
            if not mf.is_a(v, "pair_value"):
                continue
            p = mf.ref(v, "applies_to_pair", types=("kinematic_pair",))
            ml.values.setdefault(p, v)
    return _finish(mf, ml)


def _assembly_placement(mf: ModelFile, ml: MechanismLayout, base) -> Optional[tuple]:
    """AP242: the operator placing the base link in the mechanism's assembly (from the shape
    representation relationship of the base link's product occurrence), with the
    representations whose units it is read in; None if absent."""
    rep = ml.links.get(base)
    if rep is None:
        return None
    pdk = ml.ids.get("product_definition_kinematics")
    assembly_pd = mf.ref(pdk, "definition", optional=True) if pdk is not None else None
    for klra in mf.usedin(rep, "representation_relationship.rep_1"):
        if not mf.is_a(klra, "kinematic_link_representation_association"):
            continue
        for cd in mf.usedin(klra, "context_dependent_kinematic_link_representation.representation_relation"):
            pdrk = mf.ref(cd, "represented_product_relation", optional=True)
            nauo = mf.ref(pdrk, "definition", optional=True) if pdrk is not None else None
            if nauo is None or not mf.is_a(nauo, "product_definition_relationship"):
                continue
            if assembly_pd is not None and mf.ref(nauo, "relating_product_definition",
                                                  optional=True) != assembly_pd:
                continue
            found = occurrence_placement(mf, nauo)
            if found is not None:
                ml.ids["base_placement"] = found[0]
                return found
    return None


def occurrence_placement(mf: ModelFile, nauo) -> Optional[tuple]:
    """``(operator, rep_1, rep_2)``: the transformation that places a product occurrence
    (``nauo``) in its assembly, from the shape representation relationship of the occurrence
    (the representations are those the operator's units are read in); None if it has none."""
    for pds in mf.usedin(nauo, "property_definition.definition"):
        for cdsr in mf.usedin(pds, "context_dependent_shape_representation.represented_product_relation"):
            rel = mf.ref(cdsr, "representation_relation", optional=True)
            if not mf.is_a(rel, "representation_relationship_with_transformation"):
                continue
            return mf.ref(rel, "transformation_operator"), mf.ref(rel, "rep_1"), mf.ref(rel, "rep_2")
    return None


def _finish(mf: ModelFile, ml: MechanismLayout) -> MechanismLayout:
    """Link representations of the links that have none yet, and THE link and pair names."""
    for link in list(ml.links):
        if ml.links[link] is None:
            reps = link_reps(mf, link)
            ml.links[link] = reps[0] if reps else None
    ml.link_names = unique_names({link: link_name(mf, link, ml.links[link]) for link in ml.link_order})
    for link in ml.link_order:
        _shape_context(mf, ml.links[link])
    names = unique_names({p.id: pair_name(mf, p.id, p.joint_name) for p in ml.pairs})
    for p in ml.pairs:
        p.name = names[p.id]
    return ml


def _shape_context(mf: ModelFile, rep) -> None:
    """Lenient reading: a link representation associated with a shape in another context
    (build123d and Open CASCADE write one context for the whole mechanism) is one deviation;
    the link's frames are read in its own representation's context."""
    ctx = mf.ref_value(rep, "context_of_items") if rep is not None else None
    for klra in mf.usedin(rep, "kinematic_link_representation_association.rep_1"):
        shape = mf.ref_value(klra, "rep_2")
        shape_ctx = mf.ref_value(shape, "context_of_items") if shape in mf else None
        if (ctx is not None and shape_ctx is not None and shape_ctx != ctx
                and not mf.is_a(klra, "representation_relationship_with_transformation")):
            mf.deviation(klra, f"kinematic_link_representation_association relates link representation #{rep} "
                         f"(context #{ctx}) to shape #{shape} (context #{shape_ctx}); it wants one context for "
                         "both (its WR1): the link's frames are read in its representation's context #"
                         f"{ctx} (read anyway)")


# --------------------------------------------------------------------------- looking names up

def link_name_of_representation(mf: ModelFile, rep: Optional[int]) -> Optional[str]:
    """The name (as :func:`mechanisms` gives it) of the link that representation ``#rep`` stands
    for; a representation of no mechanism's link: its link's own name, else its name, else
    ``#rep``."""
    if rep is None:
        return None
    links = rep_links(mf, rep) if rep in mf else []
    for ml in mechanisms(mf):
        for link in links:
            if link in ml.link_names:
                return ml.link_names[link]
    if links:
        return link_name(mf, links[0], rep)
    return mf.string(rep, "name") or f"#{rep}"


# --------------------------------------------------------------------------- the lenient walk

def mechanism_parts(mf: ModelFile, mech) -> tuple:
    """Lenient: ``(pairs, links, base link representation)`` of a mechanism of either layout
    (pairs through its structure's joints and, in AP242, its pair relationships; links of those
    joints, and the 1996 base link); what is missing is left out."""
    joints: list = []
    pairs: list = []
    base_rep = None
    if mf.is_a(mech, "mechanism"):
        struct = mf.ref(mech, "structure_definition")
        joints = mf.refs(struct, "joints") if struct is not None else []
        base = mf.ref(mech, "base")
        reps = link_reps(mf, base)
        base_rep = reps[0] if reps else None
        links = [base] if base is not None else []
    else:
        links = []
        for prr in mf.refs(mech, "items"):
            p = mf.ref(prr, "transformation_operator")
            if p is not None and mf.is_a(p, "kinematic_pair"):
                pairs.append(p)
                j = mf.ref(p, "joint")
                if j is not None:
                    joints.append(j)
        topo = mf.ref(mech, "represented_topology")
        if topo is not None:
            joints.extend(j for j in mf.refs(topo, "items") if mf.is_a(j, "kinematic_joint"))
        for kp in mf.usedin(mech, "kinematic_property_mechanism_representation.used_representation"):
            b = mf.ref(kp, "base")
            if b is not None:
                base_rep = b
                break
    joints = list(dict.fromkeys(joints))
    for j in joints:
        pairs.extend(mf.usedin(j, "kinematic_pair.joint"))
        links.extend(x for x in joint_links(mf, j) if x is not None)
    return list(dict.fromkeys(pairs)), list(dict.fromkeys(links)), base_rep
