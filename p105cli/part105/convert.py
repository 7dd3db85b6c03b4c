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

from p105cli.step.values import record_refs as _rec_refs, ref_id

from .builder import DERIVED, typed
from .catalogue import (APPLICATION, GEOMETRY_IN_KINEMATICS, HIGHER_GEOMETRY, HIGHER_VALUES,
                        LINK_REPRESENTATION_ENTITIES, LOOP_ENTITIES, MECHANISM_ENTITIES, PROFILES, kinematic_entity_names)
from .emit import HIGHER_KINDS_WRITTEN, Emitter, IdBuilder, write_kinematics

__all__ = ["Conversion"]


def _fmt(v) -> str:
    return "(" + ", ".join(f"{x:.6g}" for x in v) + ")"


# ------------------------------------------------------------------ conversion

def _types(rec) -> frozenset:
    if "complex" in rec:
        return frozenset(p["type"] for p in rec["complex"])
    return frozenset((rec["type"],))


def _args(rec, etype=None) -> list:
    if "complex" in rec:
        for p in rec["complex"]:
            if p["type"] == etype:
                return p["args"]
        return []
    return rec["args"]


_ref_of = ref_id


_DIMENSIONS = {"length_unit": (1, 0, 0, 0, 0, 0, 0), "mass_unit": (0, 1, 0, 0, 0, 0, 0),
               "time_unit": (0, 0, 1, 0, 0, 0, 0), "plane_angle_unit": (0,) * 7, "solid_angle_unit": (0,) * 7,
               "ratio_unit": (0,) * 7}


class Conversion:
    def __init__(self, mech, profile, source, occt_compat, diags):
        self.mech, self.profile, self.src, self.occt, self.diags = mech, profile, source, occt_compat, diags
        self.prof = PROFILES[profile]
        self.records = {r["id"]: r for r in source.records()}
        self.order = list(self.records)
        self.types = {i: _types(r) for i, r in self.records.items()}
        self.extra_drop: set = set()  # non-kinematic source instances re-expressed (configurations)
        self.quiet: set = set()  # instances that may lose their last user without a diagnostic
        self.refs = {i: _rec_refs(r) for i, r in self.records.items()}  # computed once: files can be big
        self.referrers = defaultdict(list)
        for i, refs in self.refs.items():
            for t in refs:
                self.referrers[t].append(i)

    # -- lookups in the source
    def of_type(self, *names):
        names = set(names)
        return [i for i in self.order if self.types[i] & names]

    def referring(self, target, etype, position, part=None):
        """Ids of ``etype`` instances whose argument ``position`` refers to ``target``."""
        out = []
        for i in self.referrers.get(target, ()):
            if etype in self.types[i]:
                a = _args(self.records[i], part or etype)
                if position < len(a) and _ref_of(a[position]) == target:
                    out.append(i)
        return out

    def _link_rep(self, ln):
        iid = ln.id
        if iid in self.records:
            t = self.types[iid]
            if t & LINK_REPRESENTATION_ENTITIES:
                return iid
            if "kinematic_link" in t:
                for r in self.referring(iid, "kinematic_link_representation_relation", 0):
                    return _ref_of(self.records[r]["args"][1])
                for r in self.referring(iid, "rigid_link_representation", 3):
                    return r
        for i in self.of_type(*LINK_REPRESENTATION_ENTITIES):
            if _args(self.records[i], next(iter(self.types[i] & LINK_REPRESENTATION_ENTITIES)))[0] == ln.name:
                return i
        return None

    def _kin_link(self, ln, rep):
        if ln.id in self.records and "kinematic_link" in self.types[ln.id]:
            return ln.id
        if rep is None:
            return None
        if "rigid_link_representation" in self.types[rep]:
            return _ref_of(self.records[rep]["args"][3])
        for r in self.referring(rep, "kinematic_link_representation_relation", 1):
            return _ref_of(self.records[r]["args"][0])
        return None

    def _pair_id(self, p):
        iid = p.ids.get("pair")
        if iid in self.records:
            return iid
        for i in self.order:
            if any(t.endswith("_pair") or t.endswith("_pair_with_range") for t in self.types[i]):
                a = _args(self.records[i], "representation_item") if "complex" in self.records[i] \
                    else self.records[i]["args"]
                if a and a[0] == p.name:
                    return i
        return None

    def _pair_frames(self, pid):
        rec = self.records[pid]
        if "complex" in rec:
            a = _args(rec, "item_defined_transformation")
            return _ref_of(a[2]), _ref_of(a[3])
        a = rec["args"]
        if "kinematic_joint" in self.types.get(_ref_of(a[4]) or -1, ()):  # 1996: name, description, t1, t2, joint
            return _ref_of(a[2]), _ref_of(a[3])
        return _ref_of(a[3]), _ref_of(a[4])

    def _shape_of(self, rep):
        for r in self.referring(rep, "kinematic_link_representation_association", 2):
            return _ref_of(self.records[r]["args"][3])
        return None

    def _nauo_of(self, shape):
        for r in self.referrers.get(shape, ()):
            if "representation_relationship" in self.types[r] and "complex" in self.records[r]:
                if _ref_of(_args(self.records[r], "representation_relationship")[2]) != shape:
                    continue
                for c in self.referring(r, "context_dependent_shape_representation", 0):
                    pds = _ref_of(self.records[c]["args"][1])
                    if pds in self.records:
                        return _ref_of(self.records[pds]["args"][2])
        return None

    def _pd_of(self, shape):
        for r in self.referring(shape, "shape_definition_representation", 1):
            pds = _ref_of(self.records[r]["args"][0])
            if pds in self.records:
                return _ref_of(self.records[pds]["args"][2])
        return None

    # -- the conversion
    def run(self):
        recs = self.records
        kin_names = kinematic_entity_names() - GEOMETRY_IN_KINEMATICS
        self.kin = {i for i in self.order if self.types[i] & kin_names}
        self.consumed: set = set()
        self.ids = defaultdict(dict)
        self.b = b = IdBuilder(1.0 / self.mech.units.angle, start=max(recs, default=0), free=self.kin)
        self.k = k = Emitter(self.mech, self.profile, b, self.mech.units.length, self.occt, self.diags)
        k.item_types = self.types
        k.ids = self.ids
        k.record_of = lambda ref: recs.get(_ref_of(ref)) or next(
            (r for r in b.data if r["id"] == _ref_of(ref)), None)

        old_rep = self._links()
        pair_items = self._pairs()
        pair_items |= self._higher_pairs()
        for ln in self.mech.links:  # named frames and other items of the link representations
            rep = old_rep[ln.name]
            rtype = next(iter(self.types[rep] & LINK_REPRESENTATION_ENTITIES))
            items = [_ref_of(x) for x in _args(recs[rep], rtype)[1]]
            k.extra_items[ln.name] = [{"ref": i} for i in items if i not in pair_items and i is not None]
        self._initial_state()
        mech_ids = self._mechanism()
        self._supporting()

        write_kinematics(k, self.diags)
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
            self._check_base(header, out, base_placement)
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
            rtype = next(iter(self.types[rep] & LINK_REPRESENTATION_ENTITIES))
            k.link_ctx[ln.name] = _args(recs[rep], rtype)[2]
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
            klras = self.referring(rep, "kinematic_link_representation_association", 2)
            if klras:
                ids["klra"][ln.name] = klras[0]
            self.consumed.update(klras)
            self.consumed.update(self.referring(rep, "kinematic_link_representation_relation", 1))
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
                a = _args(recs[pid], "kinematic_pair") if "complex" in recs[pid] else recs[pid]["args"]
                joint = next((_ref_of(x) for x in a if "kinematic_joint" in self.types.get(_ref_of(x) or -1, ())),
                             None)
            if joint in recs:
                ids["joint"][p.name] = joint
                self.consumed.add(joint)
            for r in self.referrers.get(pid, ()):
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
            for r in [pid, *self.referrers.get(pid, ())]:
                for x in _rec_refs(recs[r]):
                    if x in recs and not self.types[x] & {"kinematic_joint", "axis2_placement_3d", "su_parameters"}:
                        items.add(x)
                        self.quiet.add(x)
        if higher:
            for i in self.of_type("kinematic_frame_background_representation"):
                self.quiet.update(_ref_of(x) for x in recs[i]["args"][1])
                self.quiet.add(_ref_of(recs[i]["args"][2]))
                self.consumed.add(i)
            self.consumed.update(self.of_type("kinematic_frame_based_transformation",
                                              "kinematic_frame_background_representation_association"))
            for i in self.of_type("representation"):  # the holders of the frame-based transformations
                held = [_ref_of(x) for x in recs[i]["args"][1]]
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
        vals = recs[ist]["args"][1] if t & {"initial_state", "mechanism_state_representation"} else []
        by_pair = {}
        for v in vals:
            vid = _ref_of(v)
            if vid in recs:
                self.consumed.add(vid)
                pref = next((_ref_of(x) for x in recs[vid]["args"] if _ref_of(x) is not None), None)
                by_pair[pref] = vid
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
                world_ctx = self.records[found[0]]["args"][2]
                break
        k.world_ctx = world_ctx if world_ctx is not None else k.link_ctx[self.mech.base]
        found = self.of_type("kinematic_property_definition", "product_definition_kinematics")
        if not found:
            raise _model_error("the source has no product definition for the mechanism "
                               "(kinematic_property_definition / product_definition_kinematics)", None)
        k.assembly_pd = self.records[found[0]]["args"][2]
        for i in self.of_type("kinematic_ground_representation")[:1]:
            items = [_ref_of(x) for x in self.records[i]["args"][1]]
            origin = next((x for x in items if "axis2_placement_3d" in self.types.get(x, ())), None)
            if origin is not None:
                k.world_origin = {"ref": origin}

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
        todo = sorted({r for d in dropped for r in self.referrers.get(d, ()) if r in kept})
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
                todo.extend(sorted(r for r in self.referrers.get(i, ()) if r in kept))
        self._fix_profile(kept, b, new)
        data = {**kept, **new}
        refs = {i: (self.refs[i] if rec is self.records.get(i) else _rec_refs(rec)) for i, rec in data.items()}
        for i in _collect_orphans(data, refs, self.referrers, set(new)):
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

    def _check_base(self, header, data, iid):
        """AP242 has no mechanism_base_placement: the base is placed in the world only by the
        assembly (the base link's product occurrence). Say whether the converted file still
        carries the source's base placement that way."""
        from p105cli.step import DataSection
        from p105cli.step.jsonmodel import JsonDocument

        from p105cli.kinematics.reader import read_mechanisms

        T = np.asarray(self.mech.T_world_base)
        where = f"translation {_fmt(T[:3, 3] / self.mech.units.length)} in file units"
        try:
            back = read_mechanisms(JsonDocument(header, [DataSection(None, len(data))], data), self.profile)
            T_back = next(m for m in back if m.name == self.mech.name).T_world_base
        except Exception:
            T_back = None
        tol = 1e-9 * max(1.0, self.mech.size())
        if T_back is not None and np.allclose(T_back, T, rtol=0.0, atol=tol):
            self.diags.append(f"#{iid}: mechanism_base_placement does not exist in AP242; the base link's "
                              f"placement ({where}) is carried by the assembly that places the base link")
        elif not np.allclose(T, np.eye(4), rtol=0.0, atol=tol):
            self.diags.append(f"#{iid}: mechanism_base_placement does not exist in AP242 and the assembly does "
                              f"not place the base link there: the base placement ({where}) is lost")

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
        a = rec["args"]
        at = 0 if _ref_of(a[0]) is not None else 1  # 1996: (pair, ...); AP242: (name, pair, ...)
        name = pair_names.get(_ref_of(a[at]))
        if name is None:
            return None
        rest = a[at + 1:]
        kind = self.mech.pair(name).kind
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
            r = self.records.get(_ref_of(x))
            if isinstance(item, tuple):
                if r is None or not _types(r) & {"point_on_curve", "point_on_surface"}:
                    return None
                self.extra_drop.add(r["id"])
                out.append(("point", item[1], r["type"], list(r["args"][2:])))
            elif item == "ypr" and r is not None:
                d = self.records.get(_ref_of(r["args"][1]))
                if d is None:
                    return None
                ypr = convert_spatial_to_ypr_rotation(d["args"][1], r["args"][2], self.mech.units.angle)
                out.append(typed("ypr_rotation", [float(v) for v in ypr]))
                self.extra_drop.update((r["id"], d["id"]))
            else:
                out.append(x)
        return out

    def _configs_1996(self, seq, initial_vals, pair_names):
        steps = [self.records.get(_ref_of(x)) for x in self.records[seq]["args"][0]]
        if not steps or any(s is None or "configuration_interpolation" not in _types(s) for s in steps):
            return None, []
        defs = [_ref_of(steps[0]["args"][0])] + [_ref_of(s["args"][1]) for s in steps]
        interps = [s["args"][2].get("enum", "UNDEFINED").lower() for s in steps] + ["discontinuous"]
        used = [seq, *(_ref_of(x) for x in self.records[seq]["args"][0])]
        out = []
        for d, interp in zip(defs, interps):
            rec = self.records.get(d)
            if rec is None or len(rec.get("args", ())) < 2:
                return None, []
            vids = [_ref_of(x) for x in rec["args"][0]]
            t = rec["args"][1]
            t = t.get("value") if isinstance(t, dict) else t
            used.append(d)
            out.append((vids, t, interp))
        return self._neutral(out, initial_vals, pair_names, used)

    def _configs_242(self, seq, initial_state, pair_names):
        segs = [self.records.get(_ref_of(x)) for x in self.records[seq]["args"][1]]
        if not segs or any(s is None or "interpolated_configuration_segment" not in _types(s) for s in segs):
            return None, []
        used = [seq, *(_ref_of(x) for x in self.records[seq]["args"][1])]
        out = []
        for s in segs:
            state = _ref_of(s["args"][0])
            rec = self.records.get(state)
            if rec is None or "mechanism_state_representation" not in _types(rec):
                return None, []
            interp = s["args"][2].get("enum", "UNDEFINED_INTERPOLATION_TYPE").lower().replace("_interpolation_type", "")
            if state != initial_state:
                used.append(state)
            out.append(([_ref_of(x) for x in rec["args"][1]] if state != initial_state else None, s["args"][1],
                        interp))
        return self._neutral(out, None, pair_names, used)

    def _neutral(self, configs, initial_vals, pair_names, used):
        out = []
        for vids, t, interp in configs:
            if not isinstance(t, (int, float)):
                return None, []
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
            initial_vals = [_ref_of(x) for x in self.records[initial]["args"][1]]
        found = []
        for seq in self.of_type("interpolated_configuration_sequence"):
            a = self.records[seq]["args"]
            if len(a) == 1:
                configs, used = self._configs_1996(seq, initial_vals, pair_names)
                name = f"{self.mech.name} configurations"
                holders = self.referrers.get(seq, [])
            else:
                configs, used = self._configs_242(seq, initial, pair_names)
                name = a[0]
                holders = [r for r in self.referrers.get(seq, [])
                           if "interpolated_configuration_representation" in self.types[r]]
                used.extend(holders)
            if configs:
                found.append((name, configs, used, holders))
        for name, configs, used, holders in found:
            ctx = None
            if k.layout == "ap242":
                ctx = self._motion_context(k, holders)
            k.configuration_sequence(name, configs, ctx)
            consumed.update(used)
            self.extra_drop.update(i for i in used if i in self.records)
            if k.layout == "1996":  # a kinematic_control is written anew; AP242's motion context goes
                consumed.update(h for h in holders if "kinematic_control" in self.types[h])
                self.quiet.update(_ref_of(self.records[h]["args"][2]) for h in holders
                                  if "interpolated_configuration_representation" in self.types[h])

    def _motion_context(self, k, holders):
        """The context of an interpolated_configuration_representation: the source's (AP242),
        else the world context with a (dimensionless) parameter."""
        for h in holders:
            if "interpolated_configuration_representation" in self.types[h]:
                return self.records[h]["args"][2]
        ctx = self.records.get(_ref_of(k.world_ctx))
        if ctx is None or "complex" not in ctx:
            return k.world_ctx
        parts = []
        for part in ctx["complex"]:
            args = part["args"]
            if part["type"] == "representation_context":
                args = [f"{self.mech.name} motion", *args[1:]]
            parts.append((part["type"], args))
        parts.append(("geometric_representation_context_with_parameter", [None]))
        return k.b.add_complex(parts)

    # -- what differs between the layouts outside the kinematics
    def _fix_profile(self, kept, b, new):
        layout = self.prof["layout"]
        app, schema_name, year = APPLICATION[layout]
        for i, rec in kept.items():
            t = self.types[i]
            if "application_protocol_definition" in t and "complex" not in rec:
                a = list(rec["args"])
                if len(a) >= 3:
                    a[1], a[2] = schema_name, year
                    kept[i] = {**rec, "args": a}
            if "conversion_based_unit" in t and "named_unit" in t:
                parts = []
                for part in rec["complex"]:
                    if part["type"] == "named_unit":
                        if self.prof["cbu_dimensions_explicit"]:
                            if part["args"] and part["args"][0] == DERIVED:
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
                    role = _ref_of(rec["args"][1])
                    if role in kept and kept[role]["args"][0] == "id owner":
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


def _collect_orphans(data: dict, refs: dict, src_referrers, new_ids: set) -> list:
    """Remove kept instances that something referred to in the source and nothing refers to now
    (items of the replaced kinematics), transitively; returns their ids. ``refs``: the
    references of each record of ``data``."""
    removed = []
    refcount = defaultdict(int)
    for i in data:
        for t in refs[i]:
            refcount[t] += 1
    todo = [i for i in data if i not in new_ids and refcount[i] == 0 and src_referrers.get(i)]
    while todo:
        i = todo.pop()
        if i not in data:
            continue
        data.pop(i)
        removed.append(i)
        for t in refs[i]:
            refcount[t] -= 1
            if refcount[t] == 0 and t in data and t not in new_ids and src_referrers.get(t):
                todo.append(t)
    return sorted(removed)


def _model_error(message, iid):
    from p105cli.step.errors import ModelError

    return ModelError(f"#{iid}: {message}" if isinstance(iid, int) else message)
