"""Layout conversion of a source: the mechanism read from it, rewritten in the target layout.

``Conversion(mech, profile, source, occt_compat, diags).run()`` gives ``(header, records)``
(:func:`.write_mechanism.write_mechanism` with ``source=`` wraps it). Every instance outside the
kinematic structure is kept with its id; the kinematic instances are rewritten by
:class:`.emit.Emitter`, with the ids of the source instances they replace where the role is the
same; whatever the target cannot say is one diagnostic naming the ``#id``.
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np

from p105cli.schema.population import Population
from p105cli.schema.profiles import profile_for_header
from p105cli.step.errors import ModelError
from p105cli.step.values import record_refs as _rec_refs, ref_id

from .builder import DERIVED, typed
from .catalogue import (APPLICATION, GEOMETRY_IN_KINEMATICS, HIGHER_GEOMETRY, HIGHER_VALUES,
                        LINK_REPRESENTATION_ENTITIES, LOOP_ENTITIES, MECHANISM_ENTITIES, PROFILES, KINEMATIC_ENTITIES)
from .emit import HIGHER_KINDS_WRITTEN, Emitter, IdBuilder, NotWritableError, write_kinematics
from .layout import link_reps, occurrence_placement, rep_links
from .model_file import ModelFile
from .pair_values import low_order_value_arguments, value_attributes

__all__ = ["Conversion", "RepairError"]


class RepairError(NotWritableError):
    """The source cannot be converted to a file that conforms to the target: the message says
    what cannot be repaired (``export --schema`` exits 1 with it, writing nothing)."""


def _fmt(v) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in v) + ")"


# ------------------------------------------------------------------ conversion

def _types(rec) -> frozenset:
    """The entity names a record is written with (its type, or its parts' types): what the
    diagnostics name and what the target schema must have."""
    if "complex" in rec:
        return frozenset(p["type"] for p in rec["complex"])
    return frozenset((rec["type"],))


_DIMENSIONS = {"length_unit": (1, 0, 0, 0, 0, 0, 0), "mass_unit": (0, 1, 0, 0, 0, 0, 0),
               "time_unit": (0, 0, 1, 0, 0, 0, 0), "plane_angle_unit": (0,) * 7, "solid_angle_unit": (0,) * 7,
               "ratio_unit": (0,) * 7}


class Conversion:
    """One conversion of ``source`` (the document ``mech`` was read from) to ``profile``: the
    source's instances are read by attribute name through a lenient ModelFile over its typed
    population, and their roles found through part105.layout and the population's back
    references; :meth:`run` gives ``(header, records)`` and appends to ``diags``."""

    def __init__(self, mech, profile, source, occt_compat, diags):
        """``source``: the ModelFile ``mech`` was read from (its population is the one this
        conversion reads), or a document (typed here, over the records the output keeps)."""
        given = source if isinstance(source, ModelFile) else None
        source = given.doc if given is not None else source
        self.mech, self.profile, self.src, self.occt, self.diags = mech, profile, source, occt_compat, diags
        self.prof = PROFILES[profile]
        records = list(source.records())  # decoded once: the output keeps most of them as they are
        self.records = {r["id"]: r for r in records}
        self.order = list(self.records)
        # the source typed by its schema: attributes by name (the lenient ModelFile), back
        # references (the population's index)
        if given is not None:
            self.pop, self.mf = given.pop, given.lenient()
        else:
            self.pop = Population(records, mech.profile or profile_for_header(getattr(source, "header", {}) or {}))
            self.mf = ModelFile(self.pop, lenient=True)
        self.types = {i: _types(r) for i, r in self.records.items()}
        self.extra_drop: set = set()  # non-kinematic source instances re-expressed (configurations)
        self.quiet: set = set()  # instances that may lose their last user without a diagnostic
        self.refs = {i: _rec_refs(r) for i, r in self.records.items()}  # computed once: files can be big

    # -- the source, read by attribute name
    def get(self, iid, attr):
        """The raw value of attribute ``attr`` (a name, or ``entity.name``) of ``#iid``; None when
        the instance is not in the source or has no such attribute."""
        return self.mf.get(iid, attr, None)

    def has(self, iid, attr) -> bool:
        """Whether ``#iid`` has the explicit attribute ``attr``."""
        return iid in self.records and self.mf.has(iid, attr)

    def ref(self, iid, attr):
        """The id the attribute names (unchecked: a dangling one too), or None."""
        return self.mf.ref_value(iid, attr)

    def refs_at(self, iid, attr) -> list:
        """The ids an aggregate attribute names, element by element (None for an element that is
        no reference: a sequence with one is not converted)."""
        return [ref_id(x) for x in self.get(iid, attr) or ()]

    def replaced(self, iid, values: dict) -> dict:
        """A copy of the source's record ``#iid`` with the named attributes set to ``values`` (an
        attribute the record does not have stays as it is)."""
        inst = self.pop.instance(iid)
        rec, lay = inst.record, inst.layout
        complex_ = "complex" in rec
        parts = [{**p, "args": list(p["args"])} for p in rec["complex"]] if complex_ else None
        args = None if complex_ else list(rec["args"])
        for attr, v in values.items():
            if attr not in lay.by_name:
                continue
            slot = lay.slots[lay.by_name[attr][0]]
            target = parts[slot.part]["args"] if complex_ else args
            if slot.pos < len(target):
                target[slot.pos] = v
        return {**rec, "complex": parts} if complex_ else {**rec, "args": args}

    def of_type(self, *names):
        names = set(names)
        return [i for i in self.order if self.types[i] & names]

    def referring(self, target, role):
        """Ids of the instances referring to ``#target`` through ``role`` (``entity.attribute``),
        in file order."""
        return list(dict.fromkeys(self.mf.usedin(target, role)))

    def referrers(self, target) -> list:
        """Ids of the instances referring to ``#target`` through any attribute, in file order."""
        return list(dict.fromkeys(rid for rid, _ in self.pop.backrefs(target)))

    def _link_rep(self, ln):
        """The source's representation of link ``ln`` (part105.layout's), else, for a link the
        source does not name by id, the link representation of that name."""
        iid = ln.id
        if iid in self.records:
            t = self.types[iid]
            if t & LINK_REPRESENTATION_ENTITIES:
                return iid
            if "kinematic_link" in t:
                return next(iter(link_reps(self.mf, iid)), None)
        for i in self.of_type(*LINK_REPRESENTATION_ENTITIES):
            if self.get(i, "representation.name") == ln.name:
                return i
        return None

    def _kin_link(self, ln, rep):
        if ln.id in self.records and "kinematic_link" in self.types[ln.id]:
            return ln.id
        if rep is None:
            return None
        return next(iter(rep_links(self.mf, rep)), None)

    def _pair_id(self, p):
        iid = p.ids.get("pair")
        if iid in self.records:
            return iid
        for i in self.order:
            if any(t.endswith("_pair") or t.endswith("_pair_with_range") for t in self.types[i]):
                # AP242 names a pair by representation_item.name; the 1996 layout derives that
                # from item_defined_transformation.name
                attr = ("representation_item.name" if self.has(i, "representation_item.name")
                        else "item_defined_transformation.name")
                if self.get(i, attr) == p.name:
                    return i
        return None

    def _pair_frames(self, pid):
        return self.ref(pid, "transform_item_1"), self.ref(pid, "transform_item_2")

    def _shape_of(self, rep):
        for r in self.referring(rep, "kinematic_link_representation_association.rep_1"):
            return self.ref(r, "rep_2")
        return None

    def _nauo_of(self, shape):
        """The assembly usage placing the product whose shape is ``#shape``: through the shape
        representation relationship (a complex instance with a transformation) that relates it."""
        for r in self.referring(shape, "representation_relationship.rep_1"):
            if not self.pop.instance(r).is_complex:
                continue
            for c in self.referring(r, "context_dependent_shape_representation.representation_relation"):
                pds = self.ref(c, "represented_product_relation")
                if pds in self.records:
                    return self.ref(pds, "definition")
        return None

    def _pd_of(self, shape):
        for r in self.referring(shape, "shape_definition_representation.used_representation"):
            pds = self.ref(r, "definition")
            if pds in self.records:
                return self.ref(pds, "definition")
        return None

    # -- the conversion
    def run(self):
        recs = self.records
        kin_names = KINEMATIC_ENTITIES - GEOMETRY_IN_KINEMATICS
        self.kin = {i for i in self.order if self.types[i] & kin_names}
        self.consumed: set = set()
        self.ids = defaultdict(dict)
        self.b = b = IdBuilder(1.0 / self.mech.units.angle, start=max(recs, default=0), free=self.kin)
        self.k = k = Emitter(self.mech, self.profile, b, self.mech.units.length, self.occt, self.diags)
        k.item_types = self.types
        k.ids = self.ids
        k.record_of = lambda ref: recs.get(ref_id(ref)) or next(
            (r for r in b.data if r["id"] == ref_id(ref)), None)

        old_rep = self._links()
        pair_items = self._pairs()
        pair_items |= self._higher_pairs()
        for ln in self.mech.links:  # named frames and other items of the link representations
            items = self.refs_at(old_rep[ln.name], "items")
            k.extra_items[ln.name] = [{"ref": i} for i in items if i not in pair_items and i is not None]
        self._initial_state()
        mech_ids = self._mechanism()
        self._supporting()
        self._contexts()

        write_kinematics(k, self.diags)
        if self.mech.pairs and not k.pairs:
            kinds = ", ".join(sorted({p.kind for p in self.mech.pairs}))
            raise RepairError(f"#{self.mech.ids.get('mechanism')}: none of the pairs of mechanism {self.mech.name!r} "
                              f"({kinds}) can be written in {self.profile}: the mechanism would have no joint, "
                              "which its schema does not allow; not converted")
        self._sequences(k, self.ids, self.consumed)
        k.finish()
        if getattr(k, "loops_written", False):
            self.consumed.update(self.of_type("kinematic_loop", "oriented_joint",
                                              "kinematic_topology_network_structure"))
        header = _target_header(self.src.header, self.prof)
        out = self._assemble()
        base_placement = mech_ids.get("base_placement")
        if (self.prof["layout"] == "ap242" and base_placement in self.kin
                and "mechanism_base_placement" in self.types[base_placement]):
            self._check_base(base_placement)
        return header, out

    # -- what the source says, role by role
    def _links(self) -> dict:
        """Each link's representation, context, shape, product definition and assembly usage."""
        k, recs, ids = self.k, self.records, self.ids
        old_rep = {}
        for ln in self.mech.links:
            rep = self._link_rep(ln)
            if rep is None:
                raise _model_error(f"link {ln.name!r}: no link representation in the source", ln.id)
            old_rep[ln.name] = rep
            k.link_ctx[ln.name] = self.get(rep, "context_of_items")
            shape = self._shape_of(rep)
            k.link_shape[ln.name] = None if shape is None else {"ref": shape}
            if shape is not None:
                pd, nauo = self._pd_of(shape), self._nauo_of(shape)
                if pd is not None:
                    k.link_pd[ln.name] = {"ref": pd}
                if nauo is not None:
                    k.link_nauo[ln.name] = {"ref": nauo}
            kl = self._kin_link(ln, rep)
            ids["link"][ln.name] = kl
            ids["link_rep"][ln.name] = rep
            self.consumed.update(x for x in (rep, kl) if x is not None)
            klras = self.referring(rep, "kinematic_link_representation_association.rep_1")
            if klras:
                ids["klra"][ln.name] = klras[0]
            self.consumed.update(klras)
            self.consumed.update(self.referring(rep, "kinematic_link_representation_relation.geometric_aspects"))
        return old_rep

    def _pairs(self) -> set:
        """Pairs: frames (reused when unchanged), joint, range, actuator; returns the source's
        pair frames (not items the link representations carry over)."""
        k, recs, ids = self.k, self.records, self.ids
        frames = set()
        for p in self.mech.pairs:
            pid = self._pair_id(p)
            if pid is None:
                continue
            self.consumed.add(pid)
            ids["pair"][p.name] = pid
            for which, f in enumerate(self._pair_frames(pid)):
                if f is None:
                    continue
                frames.add(f)
                t = self.types.get(f, ())
                if "axis2_placement_3d" in t or ("su_parameters" in t and self.prof["su"]):
                    k.frame_reuse[(p.name, which)] = {"ref": f}
            joint = p.ids.get("joint")
            if joint not in recs:
                joint = self.ref(pid, "kinematic_pair.joint")
                if "kinematic_joint" not in self.types.get(joint, ()):
                    joint = None
            if joint in recs:
                ids["joint"][p.name] = joint
                self.consumed.add(joint)
            for r in self.referrers(pid):
                t = self.types[r]
                if any(x.endswith("_pair_range") for x in t):
                    ids["range"][p.name] = r
                    self.consumed.add(r)
                elif "pair_actuator" in t:
                    ids["actuator"][p.name] = r
                    self.consumed.add(r)
                elif "pair_representation_relationship" in t:
                    self.consumed.add(r)
        return frames

    def _higher_pairs(self) -> set:
        """A higher pair's curves/surfaces stay as they are where their coordinates do (same
        layout, or the pair frame is the link frame); the source's geometry of the pair, its
        range and the 1996 frame backgrounds go quietly (re-expressed). Returns the items the
        link representations must not carry over."""
        k, recs = self.k, self.records
        src_layout = PROFILES.get(self.mech.profile or "", {}).get("layout")
        items = set()
        higher = [p for p in self.mech.pairs if p.kind in HIGHER_KINDS_WRITTEN and p.name in self.ids["pair"]]
        for p in higher:
            pid = self.ids["pair"][p.name]
            for key, which in HIGHER_GEOMETRY[p.kind][0]:
                g = p.ids.get(key)
                P = p.P1 if which == 1 else p.P2
                same = src_layout == self.prof["layout"] or np.allclose(P, np.eye(4), rtol=0.0, atol=1e-12)
                if g in recs and same:
                    k.curve_reuse[(p.name, key)] = {"ref": g}
            for r in [pid, *self.referrers(pid)]:
                for x in _rec_refs(recs[r]):
                    if x in recs and not self.types[x] & {"kinematic_joint", "axis2_placement_3d", "su_parameters"}:
                        items.add(x)
                        self.quiet.add(x)
        if higher:
            for i in self.of_type("kinematic_frame_background_representation"):
                self.quiet.update(self.refs_at(i, "items"))
                self.quiet.add(self.ref(i, "context_of_items"))
                self.consumed.add(i)
            self.consumed.update(self.of_type("kinematic_frame_based_transformation",
                                              "kinematic_frame_background_representation_association"))
            for i in self.of_type("representation"):  # the holders of the frame-based transformations
                held = self.refs_at(i, "items")
                if held and all("kinematic_frame_based_transformation" in self.types.get(x, ()) for x in held):
                    self.extra_drop.add(i)
        return items

    def _initial_state(self):
        recs = self.records
        ist = self.mech.ids.get("initial_state")
        if ist not in recs:
            return
        self.consumed.add(ist)
        t = self.types[ist]
        vals = (self.refs_at(ist, "pair_values") if "initial_state" in t  # 1996
                else self.refs_at(ist, "items") if "mechanism_state_representation" in t else [])
        by_pair = {}
        for vid in vals:
            if vid in recs:
                self.consumed.add(vid)
                by_pair[self.ref(vid, "applies_to_pair")] = vid
        for p in self.mech.pairs:
            pid = self.ids["pair"].get(p.name)
            if pid in by_pair:
                self.ids["value"][p.name] = by_pair[pid]

    def _mechanism(self) -> dict:
        """The mechanism, its structure, properties, ground and base (one mechanism per file:
        all of them are its); the mechanism-level ids the new instances take."""
        for i in self.kin:
            if self.types[i] & MECHANISM_ENTITIES:
                self.consumed.add(i)
        mech_ids = dict(self.mech.ids)
        for role, types in (("structure", ("kinematic_structure", "kinematic_topology_structure")),
                            ("mechanism", ("mechanism", "mechanism_representation")),
                            ("base_placement", ("mechanism_base_placement",))):
            if mech_ids.get(role) not in self.records:
                found = self.of_type(*types)
                if found:
                    mech_ids[role] = found[0]
        self.k.mech = _with_ids(self.mech, mech_ids)
        return mech_ids

    def _supporting(self):
        """World context, world origin, the assembly's product definition."""
        k = self.k
        world_ctx = None
        for etype in ("kinematic_ground_representation", "mechanism_representation", "kinematic_topology_structure"):
            found = self.of_type(etype)
            if found:
                world_ctx = self.get(found[0], "context_of_items")
                break
        k.world_ctx = world_ctx if world_ctx is not None else k.link_ctx[self.mech.base]
        found = self.of_type("kinematic_property_definition", "product_definition_kinematics")
        if not found:
            raise _model_error("the source has no product definition for the mechanism "
                               "(kinematic_property_definition / product_definition_kinematics)", None)
        k.assembly_pd = self.get(found[0], "property_definition.definition")
        for i in self.of_type("kinematic_ground_representation")[:1]:
            items = self.refs_at(i, "items")
            origin = next((x for x in items if "axis2_placement_3d" in self.types.get(x, ())), None)
            if origin is not None:
                k.world_origin = {"ref": origin}

    def _contexts(self):
        """The contexts the target's rules ask for, repaired where the source shares one
        context among representations the rules keep apart (build123d and Open CASCADE write
        one context for the whole mechanism): a link representation in the context of the shape
        it is associated with (kinematic_link_representation_association.wr1), each link
        representation in a context of its own (a pair_representation_relationship relates two
        contexts: representation_relationship_with_transformation.wr1), and, in the 1996 layout,
        the ground in a context of its own (mechanism_base_placement relates it to the base
        link's representation: the same rule). Each repair is one diagnostic."""
        k, ids = self.k, self.ids
        owner: dict = {}  # context id -> the link whose representation is in it
        # links with a shape first: their context is fixed by it, the others can take a copy
        for ln in sorted(self.mech.links, key=lambda ln: k.link_shape.get(ln.name) is None):
            rep = ids["link_rep"].get(ln.name)
            ctx = ref_id(k.link_ctx.get(ln.name))
            shape = ref_id(k.link_shape.get(ln.name))
            shape_ctx = self.mf.ref(shape, "context_of_items") if shape is not None else None
            if shape_ctx is not None and shape_ctx != ctx:
                if ctx is not None and not self._same_units(shape_ctx, ctx):
                    raise RepairError(f"#{rep}: link {ln.name!r}: its representation's context #{ctx} and "
                                      f"the context #{shape_ctx} of its shape #{shape} have other units; "
                                      "kinematic_link_representation_association.wr1 wants one context for "
                                      "both, and p105 does not convert the link's frames between units")
                self.diags.append(f"#{rep}: link {ln.name!r}: written in the context #{shape_ctx} of its shape "
                                  f"#{shape}, not #{ctx} (kinematic_link_representation_association.wr1: a link "
                                  "representation and its shape share one context)")
                ctx = shape_ctx
            if ctx in owner:
                if shape_ctx == ctx:
                    raise RepairError(f"#{rep}: the shapes of links {owner[ctx]!r} and {ln.name!r} are in one "
                                      f"context #{ctx}; their link representations must be in their shapes' "
                                      "context (kinematic_link_representation_association.wr1) and in two "
                                      "contexts (representation_relationship_with_transformation.wr1 of the "
                                      "pairs between them): not repaired")
                new = k.copy_context({"ref": ctx}, f"{ln.name} link")
                self.diags.append(f"#{rep}: link {ln.name!r}: its context #{ctx} is also link {owner[ctx]!r}'s; "
                                  f"written in a context of its own, #{ref_id(new)} "
                                  "(representation_relationship_with_transformation.wr1)")
                ctx = ref_id(new)
            owner[ctx] = ln.name
            k.link_ctx[ln.name] = {"ref": ctx}
        world = ref_id(k.world_ctx)
        if self.prof["layout"] == "1996" and world in owner:
            k.world_ctx = k.copy_context({"ref": world}, f"{self.mech.name} ground")
            self.diags.append(f"#{world}: the ground is written in a context of its own, "
                              f"#{ref_id(k.world_ctx)}, not in the context of link {owner[world]!r} "
                              "(representation_relationship_with_transformation.wr1 of mechanism_base_placement)")

    def _same_units(self, a, b) -> bool:
        """Whether contexts ``#a`` and ``#b`` give the same length and plane-angle units."""
        ua, ub = self.mf.context_units(a), self.mf.context_units(b)
        return all((x[0] if x else None) == (y[0] if y else None)
                   for x, y in ((ua.length, ub.length), (ua.angle, ub.angle)))

    # -- the output
    def _assemble(self) -> list:
        """Kept source instances and the new kinematics, with a diagnostic for everything of
        the source that is left out and not re-expressed."""
        kin, b = self.kin, self.b
        new = {r["id"]: r for r in b.data}
        # what of the source's kinematics is not re-expressed: kept as it is when the target has
        # its entities and everything it refers to is still there, of the same type (a motion
        # program in a same-layout conversion); else reported
        target_entities = _target_entities(self.profile)
        carried = self._carried(kin - self.consumed, kin, new, target_entities)
        for i in sorted(kin - self.consumed - carried):
            t = self.types[i]
            label = "+".join(sorted(t))
            if target_entities is not None and not all(x in target_entities for x in t):
                why = f"{label} does not exist in {self.profile}"
            elif t & LOOP_ENTITIES:
                why = f"{label} (loop structure) is not converted; `p105 graph` derives the loops"
            else:
                why = (f"{label} is not converted (p105 converts configuration sequences, not paths, other "
                       "programs or results)")
            self.diags.append(f"#{i}: {why}; left out")

        dropped = (kin - carried) | self.extra_drop
        # source records are shared, not copied: nothing here changes a record in place
        kept = {i: self.records[i] for i in self.order if i not in dropped}
        # a kept instance that still refers to a dropped one (whose id no new instance took)
        # goes too, with a diagnostic
        todo = sorted({r for d in dropped for r in self.referrers(d) if r in kept})
        while todo:
            i = todo.pop(0)
            if i not in kept:
                continue
            bad = [t for t in self.refs[i] if t in dropped and t not in new]
            if bad:
                label = "+".join(sorted(self.types[i]))
                self.diags.append(f"#{i}: {label} refers to #{bad[0]}, which is not converted; left out")
                del kept[i]
                dropped.add(i)
                todo.extend(sorted(r for r in self.referrers(i) if r in kept))
        self._fix_profile(kept, b, new)
        data = {**kept, **new}
        refs = {i: (self.refs[i] if rec is self.records.get(i) else _rec_refs(rec)) for i, rec in data.items()}
        for i in _collect_orphans(data, refs, lambda i: bool(self.pop.backrefs(i)), set(new)):
            t = self.types[i]
            if not t & _QUIET_ORPHANS and i not in self.quiet:
                self.diags.append(f"#{i}: {'+'.join(sorted(t))} was used only by instances that are not "
                                  "converted; left out")
        if target_entities is not None:
            for i in sorted(kept):
                missing = [t for t in sorted(self.types[i]) if t not in target_entities]
                if i in data and missing:
                    self.diags.append(f"#{i}: {'+'.join(sorted(self.types[i]))}: {missing[0]} does not exist "
                                      f"in {self.profile} (kept as it is)")
        return [data[i] for i in sorted(data)]

    def _check_base(self, iid):
        """AP242 has no mechanism_base_placement: the base is placed in the world only by the
        assembly (the base link's product occurrence). Say whether the converted file still
        carries the source's base placement that way."""
        T = np.asarray(self.mech.T_world_base)
        where = f"translation {_fmt(T[:3, 3] / self.mech.units.length)} in file units"
        T_back = self._assembly_base()
        tol = 1e-9 * max(1.0, self.mech.size())
        if T_back is not None and np.allclose(T_back, T, rtol=0.0, atol=tol):
            self.diags.append(f"#{iid}: mechanism_base_placement does not exist in AP242; the base link's "
                              f"placement ({where}) is carried by the assembly that places the base link")
        elif not np.allclose(T, np.eye(4), rtol=0.0, atol=tol):
            self.diags.append(f"#{iid}: mechanism_base_placement does not exist in AP242 and the assembly does "
                              f"not place the base link there: the base placement ({where}) is lost")

    def _assembly_base(self):
        """The base link's placement as an AP242 reader finds it in the converted file: the
        transformation of the product occurrence that the emitted link-shape association ties
        the base link to (``Emitter.write_ap242``), read from the source's instances the file
        keeps; the identity when the file ties the base to none; None when those instances give
        no placement."""
        k, base = self.k, self.mech.base
        nauo = ref_id(k.link_nauo.get(base))
        if k.link_shape.get(base) is None or nauo is None:
            return np.eye(4)
        d = self.mf.checked()
        try:
            if not d.is_a(nauo, "product_definition_relationship") or \
                    d.ref(nauo, "relating_product_definition", optional=True) != ref_id(k.assembly_pd):
                return np.eye(4)
            found = occurrence_placement(d, nauo)
            if found is not None:
                op, r1, r2 = found
                if d.is_a(op, "item_defined_transformation"):
                    return d.item_defined_transformation(op, d.scale(r1), d.scale(r2))
                return d.placement(op, d.scale(r2))
        except ModelError:
            return None
        return np.eye(4)

    def _carried(self, candidates, kin, new, target_entities) -> set:
        if self.occt or target_entities is None:
            return set()  # Open CASCADE would not read what p105 does not write itself
        dropped = set(kin) | self.extra_drop
        ok = {i for i in candidates if i not in new and all(t in target_entities for t in self.types[i])}
        changed = True
        while changed:
            changed = False
            for i in sorted(ok):
                for r in _rec_refs(self.records[i]):
                    if r in ok:
                        continue
                    if r in new:
                        good = _types(new[r]) == self.types.get(r)
                    else:
                        good = r in self.records and r not in dropped
                    if not good:
                        ok.discard(i)
                        changed = True
                        break
        return ok

    # -- the motion program's configuration sequences
    def _value_of(self, vid, pair_names):
        """(pair name, entity, arguments after the pair) of a pair value of either layout."""
        rec = self.records.get(vid)
        if rec is None or "complex" in rec or not rec["type"].endswith("_pair_value"):
            return None
        pair, rest = value_attributes(self.mf, vid)
        name = pair_names.get(pair)
        if name is None:
            return None
        kind = self.mech.pair(name).kind
        if rec["type"] == "low_order_kinematic_pair_value":  # read by its own type: as the pair's value
            got = low_order_value_arguments(kind, rest, self.mech.pair(name).params.get("layout", "ap242"))
            return None if got is None else (name, *got)
        if kind in HIGHER_VALUES:
            rest = self._higher_value(kind, rest)
            if rest is None:
                return None
        return name, rec["type"], rest

    def _higher_value(self, kind, rest):
        """A higher pair value's arguments with each point as ``("point", key, entity,
        parameters)`` (file units) and each rotation_about_direction as a ypr_rotation; the
        source's point and rotation instances go."""
        from p105cli.kinematics.placements import convert_spatial_to_ypr_rotation

        out = []
        for item, x in zip(HIGHER_VALUES[kind], rest):
            r = self.records.get(ref_id(x))
            if isinstance(item, tuple):
                if r is None or not _types(r) & {"point_on_curve", "point_on_surface"}:
                    return None
                self.extra_drop.add(r["id"])
                params = (("point_parameter",) if "point_on_curve" in _types(r)
                          else ("point_parameter_u", "point_parameter_v"))
                out.append(("point", item[1], r["type"], [self.get(r["id"], a) for a in params]))
            elif item == "ypr" and r is not None:
                d = self.records.get(self.ref(r["id"], "direction_of_axis"))
                if d is None:
                    return None
                ypr = convert_spatial_to_ypr_rotation(self.get(d["id"], "direction_ratios"),
                                                      self.get(r["id"], "rotation_angle"), self.mech.units.angle)
                out.append(typed("ypr_rotation", [float(v) for v in ypr]))
                self.extra_drop.update((r["id"], d["id"]))
            else:
                out.append(x)
        return out

    def _configs_1996(self, seq, initial_vals, pair_names):
        step_ids = self.refs_at(seq, "interpolated_configuration_sequence.interpolation")
        steps = [self.records.get(x) for x in step_ids]
        if not steps or any(s is None or "configuration_interpolation" not in _types(s) for s in steps):
            return None, []
        defs = ([self.ref(step_ids[0], "previous_configuration_definition")]
                + [self.ref(s, "next_configuration_definition") for s in step_ids])
        interps = [self.get(s, "configuration_interpolation.interpolation").get("enum", "UNDEFINED").lower()
                   for s in step_ids] + ["discontinuous"]
        used = [seq, *step_ids]
        out = []
        for d, interp in zip(defs, interps):
            if not (self.has(d, "pair_values") and self.has(d, "t_parameter")):
                return None, []
            vids = self.refs_at(d, "pair_values")
            t = self.get(d, "t_parameter")
            t = t.get("value") if isinstance(t, dict) else t
            used.append(d)
            out.append((vids, t, interp))
        return self._neutral(out, initial_vals, pair_names, used)

    def _configs_242(self, seq, initial_state, pair_names):
        seg_ids = self.refs_at(seq, "segments")
        segs = [self.records.get(x) for x in seg_ids]
        if not segs or any(s is None or "interpolated_configuration_segment" not in _types(s) for s in segs):
            return None, []
        used = [seq, *seg_ids]
        out = []
        for s in seg_ids:
            state = self.ref(s, "state")
            rec = self.records.get(state)
            if rec is None or "mechanism_state_representation" not in _types(rec):
                return None, []
            interp = self.get(s, "interpolation").get("enum", "UNDEFINED_INTERPOLATION_TYPE").lower().replace(
                "_interpolation_type", "")
            if state != initial_state:
                used.append(state)
            out.append((self.refs_at(state, "items") if state != initial_state else None,
                        self.get(s, "t_parameter"), interp))
        return self._neutral(out, None, pair_names, used)

    def _neutral(self, configs, initial_vals, pair_names, used):
        out = []
        for vids, t, interp in configs:
            if not isinstance(t, (int, float)) or (vids is not None and None in vids):
                return None, []  # a time or a pair value that is no number / no reference: not converted
            if vids is None or (initial_vals is not None and sorted(vids) == sorted(initial_vals)):
                out.append((None, float(t), interp))
                continue
            values = [self._value_of(v, pair_names) for v in vids]
            if any(v is None for v in values):
                return None, []
            used.extend(vids)
            out.append((values, float(t), interp))
        return out, used

    def _sequences(self, k, ids, consumed):
        if self.occt:
            return  # Open CASCADE does not read them: reported with the rest
        pair_names = {pid: name for name, pid in ids["pair"].items()}
        initial = self.mech.ids.get("initial_state")
        initial_vals = None
        if initial in self.records and "initial_state" in self.types[initial]:
            initial_vals = self.refs_at(initial, "pair_values")
        found = []
        for seq in self.of_type("interpolated_configuration_sequence"):
            if not self.has(seq, "segments"):  # 1996: a list of configuration interpolations
                configs, used = self._configs_1996(seq, initial_vals, pair_names)
                name = f"{self.mech.name} configurations"
                holders = self.referrers(seq)
            else:
                configs, used = self._configs_242(seq, initial, pair_names)
                name = self.get(seq, "representation_item.name")
                holders = [r for r in self.referrers(seq)
                           if "interpolated_configuration_representation" in self.types[r]]
                used.extend(holders)
            if configs:
                found.append((name, configs, used, holders))
        for name, configs, used, holders in found:
            # the values of a pair left out (a kind not written, reported) go with it
            configs = [(None if vals is None else [v for v in vals if v[0] in k.pairs], t, interp)
                       for vals, t, interp in configs]
            ctx = None
            if k.layout == "ap242":
                ctx = self._motion_context(k, holders)
            k.configuration_sequence(name, configs, ctx)
            consumed.update(used)
            self.extra_drop.update(i for i in used if i in self.records)
            if k.layout == "1996":  # a kinematic_control is written anew; AP242's motion context goes
                consumed.update(h for h in holders if "kinematic_control" in self.types[h])
                self.quiet.update(self.ref(h, "context_of_items") for h in holders
                                  if "interpolated_configuration_representation" in self.types[h])

    def _motion_context(self, k, holders):
        """The context of an interpolated_configuration_representation: the source's (AP242),
        else the world context with a (dimensionless) parameter."""
        for h in holders:
            if "interpolated_configuration_representation" in self.types[h]:
                return self.get(h, "context_of_items")
        ctx = ref_id(k.world_ctx)
        if ctx not in self.records or "complex" not in self.records[ctx]:
            return k.world_ctx
        rec = self.replaced(ctx, {"context_identifier": f"{self.mech.name} motion"})
        parts = [(part["type"], part["args"]) for part in rec["complex"]]
        twice = sorted({t for t, _ in parts if [u for u, _ in parts].count(t) > 1})
        if twice:  # a malformed complex instance is not copied into a new one
            raise _model_error(f"complex instance names {', '.join(twice)} more than once", ctx)
        parts.append(("geometric_representation_context_with_parameter", [None]))
        return k.b.add_complex(parts)

    # -- what differs between the layouts outside the kinematics
    def _fix_profile(self, kept, b, new):
        layout = self.prof["layout"]
        app, schema_name, year = APPLICATION[layout]
        for i, rec in kept.items():
            t = self.types[i]
            if "application_protocol_definition" in t and "complex" not in rec:
                kept[i] = self.replaced(i, {"application_interpreted_model_schema_name": schema_name,
                                            "application_protocol_year": year})
            if "conversion_based_unit" in t and "named_unit" in t:
                parts = []
                for part in rec["complex"]:
                    if part["type"] == "named_unit":
                        if self.prof["cbu_dimensions_explicit"]:
                            if self.get(i, "named_unit.dimensions") == DERIVED:
                                kind = next((x for x in t if x in _DIMENSIONS), "ratio_unit")
                                dims = b.add("dimensional_exponents", *[float(x) for x in _DIMENSIONS[kind]])
                                new[dims["ref"]] = b.data[-1]
                                part = {"type": "named_unit", "args": [dims]}
                        else:
                            part = {"type": "named_unit", "args": [DERIVED]}
                    parts.append(part)
                kept[i] = {"id": i, "complex": parts}
        if layout == "1996":
            # AP214's product_requires_id_owner: every product has an 'id owner' organization
            owned = False
            for i, rec in kept.items():
                if "applied_organization_assignment" in self.types[i]:
                    role = self.ref(i, "organization_assignment.role")
                    if role in kept and self.get(role, "organization_role.name") == "id owner":
                        owned = True
            products = [{"ref": i} for i in kept if "product" in self.types[i]]
            if products and not owned:
                org = b.add("organization", "p105cli", "p105cli", None)
                role = b.add("organization_role", "id owner")
                b.add("applied_organization_assignment", org, role, products)
                for r in b.data[-3:]:
                    new[r["id"]] = r


def _with_ids(mech, ids):
    import dataclasses

    return dataclasses.replace(mech, ids=ids)


def _target_entities(profile):
    try:
        from p105cli.schema.profiles import get_profile

        return get_profile(profile).schema.entities
    except Exception:  # the schema data is missing: no per-entity check
        return None


def _target_header(header, prof) -> dict:
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in (header or {}).items()}
    out["file_schema"] = [prof["schema"]]
    return out


#: Supporting geometry that goes with the kinematic instances it served, without a diagnostic
#: (the kinematics it belonged to is re-expressed or reported itself).
_QUIET_ORPHANS = frozenset((
    "cartesian_point", "direction", "vector", "axis2_placement_3d", "cartesian_transformation_operator_3d",
    "su_parameters", "dimensional_exponents", "rotation_about_direction",
))


def _collect_orphans(data: dict, refs: dict, was_referred, new_ids: set) -> list:
    """Remove kept instances that something referred to in the source and nothing refers to now
    (items of the replaced kinematics), transitively; returns their ids. ``refs``: the
    references of each record of ``data``."""
    removed = []
    refcount = defaultdict(int)
    for i in data:
        for t in refs[i]:
            refcount[t] += 1
    todo = [i for i in data if i not in new_ids and refcount[i] == 0 and was_referred(i)]
    while todo:
        i = todo.pop()
        if i not in data:
            continue
        data.pop(i)
        removed.append(i)
        for t in refs[i]:
            refcount[t] -= 1
            if refcount[t] == 0 and t in data and t not in new_ids and was_referred(t):
                todo.append(t)
    return sorted(removed)


def _model_error(message, iid):
    return ModelError(f"#{iid}: {message}" if isinstance(iid, int) else message)
