"""The typed instance layer: a Part 21 (or p105/1 JSON) model seen through a schema.

``Population(doc, profile)`` puts an EXPRESS schema (from a profile, see
``profiles.py``) over the records of a ``StepFile`` or ``JsonDocument``:

* every instance is resolved to its entity types. A simple instance
  ``#1=CARTESIAN_POINT(...)`` is of its entity and all the entity's
  supertypes. A complex instance ``#2=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(...))``
  is resolved against the subtype graph: its *leaf types* are the entities
  named in it that are no supertype of another one named in it, and its
  full type set is the union of the leaf types and all their supertypes;
* explicit attributes are found by name. A simple instance lists them in
  the Part 21 order of ``Schema.p21_attributes`` (supertypes first); a
  complex instance is written in the external mapping of ISO 10303-21
  (11.2.5.3): one partial record per entity, each with that entity's own
  explicit attributes, so ``Instance.get`` collects each part's own
  attributes;
* back references (who refers to whom, through which attribute) are
  indexed once, on the first ``usedin`` call, by decoding every record once;
  before that nothing is decoded that is not asked for. ``ids_of_type``
  works from the reader's index (type names of simple instances) and only
  decodes complex instances.

``Instance.get`` returns the raw record value (the JSON-shaped Part 21
value: ``{"ref": n}``, ``{"enum": "X"}``, ...). Derived and inverse
attributes are the EXPRESS evaluator's business: ``Evaluator(population)``
(``evaluator/``) is given a population; this module knows nothing of it.

A science module: no click, rich or numpy here.
"""

from __future__ import annotations

from array import array

from .instance import Instance, Layout, Slot
from .model import Schema

__all__ = ["Population", "Instance", "Layout", "Slot"]

_MISSING = object()
_KEEP_USEDIN = 32  # usedin results kept for instances referred to at least this often
_NO_SLOT = 4095  # back-reference slot code for an argument no attribute describes
_SLOT_BITS = 12


class Population:
    """The instances of one model, typed by one schema.

    ``doc``: a StepFile, a JsonDocument, or a list of records. ``profile``:
    a Profile, a profile name, a parsed Schema, or None to choose the profile
    from the document's FILE_SCHEMA (``profiles.profile_for_header``)."""

    def __init__(self, doc, profile=None):
        if isinstance(profile, Schema):
            self.profile = None
            self.schema = profile
        else:
            from .profiles import get_profile, profile_for_header
            if profile is None:
                profile = profile_for_header(getattr(doc, "header", {}))
            elif isinstance(profile, str):
                profile = get_profile(profile)
            self.profile = profile
            self.schema = profile.schema
        self.doc = doc
        self.prefix = (self.schema.name or "").upper() + "."
        index = getattr(doc, "index", None)
        if index is not None and hasattr(doc, "_decode_slot"):
            self._sf = doc
            self._ids = index.ids
            self._types = index.types
            self._slot = index.slot
            self._records = None
        else:
            data = doc.data if hasattr(doc, "data") else list(doc)
            self._sf = None
            self._records = data
            self._ids = array("q", (r["id"] for r in data))
            self._types = [r.get("type") if "complex" not in r else None for r in data]
            table = {r["id"]: k for k, r in enumerate(data)}
            self._slot = lambda i, _t=table: _t.get(i, -1)
        self._instances: dict = {}
        self._complex_types: dict = {}  # slot -> (types, leaf types)
        self._closure: dict = {}  # entity name -> frozenset(types)
        self._layouts: dict = {}
        self._by_type = None
        self._extents: dict = {}  # (entity, subtypes) -> ids, in file order
        self._usedin: dict = {}  # (id, role) -> referring instances, for much-used instances
        self._role_keys: dict = {}
        self._backrefs = None

    # ---------------------------------------------------------------- basics
    def __len__(self) -> int:
        return len(self._ids)

    def __contains__(self, instance_id) -> bool:
        return self._slot(instance_id) >= 0

    def ids(self):
        """Every instance id, in file order."""
        return iter(self._ids)

    def instances(self):
        for i in self._ids:
            yield self.instance(i)

    def _decode(self, k: int) -> dict:
        if self._sf is not None:
            return self._sf._decode_slot(k)
        return self._records[k]

    def _offset(self, k: int):
        return self._sf.index.starts[k] if self._sf is not None else None

    def _line_col(self, k: int):
        return self._sf.line_col(self._sf.index.starts[k]) if self._sf is not None else None

    def _type_at(self, k: int):
        return self._types[k]

    def instance(self, instance_id: int) -> Instance:
        """The Instance ``#instance_id`` (cached; KeyError if absent)."""
        inst = self._instances.get(instance_id)
        if inst is None:
            k = self._slot(instance_id)
            if k < 0:
                raise KeyError(instance_id)
            inst = self._instances[instance_id] = Instance(self, instance_id, k)
        return inst

    # ---------------------------------------------------------------- types
    def type_closure(self, entity: str) -> frozenset:
        """``entity`` and all its supertypes (just ``entity`` if the schema lacks it)."""
        c = self._closure.get(entity)
        if c is None:
            if entity in self.schema.entities:
                c = frozenset((entity, *self.schema.all_supertypes(entity)))
            else:
                c = frozenset((entity,))
            self._closure[entity] = c
        return c

    def resolve_types(self, names) -> tuple:
        """(full type set, leaf types) of an instance naming entities ``names``."""
        names = [n.lower() for n in names]
        full: set = set()
        for n in names:
            full |= self.type_closure(n)
        leaf = frozenset(n for n in names
                         if not any(n != m and n in self.type_closure(m) for m in names))
        return frozenset(full), leaf

    def _complex_at(self, k: int) -> tuple:
        r = self._complex_types.get(k)
        if r is None:
            rec = self._decode(k)
            parts = rec.get("complex")
            if parts is None:  # a simple record where the index had no type
                r = (self.type_closure(rec["type"]), frozenset((rec["type"],)))
            else:
                r = self.resolve_types([p["type"] for p in parts])
            self._complex_types[k] = r
        return r

    def types_of(self, instance_id: int) -> frozenset:
        """All entity names (lower case) the instance is an instance of."""
        k = self._slot(instance_id)
        if k < 0:
            raise KeyError(instance_id)
        t = self._types[k]
        if t is not None:
            return self.type_closure(t)
        return self._complex_at(k)[0]

    def leaf_types_of(self, instance_id: int) -> frozenset:
        k = self._slot(instance_id)
        if k < 0:
            raise KeyError(instance_id)
        t = self._types[k]
        if t is not None:
            return frozenset((t,))
        return self._complex_at(k)[1]

    def is_instance_of(self, instance_id: int, entity: str) -> bool:
        return entity.lower() in self.types_of(instance_id)

    def _type_slots(self) -> tuple:
        """The type index: slots of the simple instances by entity name, and slots of the
        complex ones by their full type set (each complex record decoded once)."""
        if self._by_type is None:
            by: dict = {}
            cx: dict = {}
            for k, t in enumerate(self._types):
                if t is None:
                    cx.setdefault(self._complex_at(k), []).append(k)
                else:
                    lst = by.get(t)
                    if lst is None:
                        by[t] = [k]
                    else:
                        lst.append(k)
            self._by_type = (by, cx)
        return self._by_type

    def ids_of_type(self, entity: str, subtypes: bool = True) -> list:
        """Ids of the instances of ``entity`` (and of its subtypes unless
        ``subtypes=False``, which keeps instances whose leaf types name it),
        in file order: the type extent, from the type index (built on the first
        call, kept per entity)."""
        entity = entity.lower()
        key = (entity, subtypes)
        got = self._extents.get(key)
        if got is not None:
            return list(got)
        by, cx = self._type_slots()
        if subtypes and entity in self.schema.entities:
            wanted = {entity, *self.schema.all_subtypes(entity)}
        else:
            wanted = {entity}
        slots: list = []
        if len(wanted) < len(by):
            for t in wanted:
                lst = by.get(t)
                if lst:
                    slots.extend(lst)
        else:
            for t, lst in by.items():
                if t in wanted:
                    slots.extend(lst)
        for (types, leaf), lst in cx.items():
            if entity in (types if subtypes else leaf):
                slots.extend(lst)
        slots.sort()
        ids = self._ids
        got = self._extents[key] = tuple(ids[k] for k in slots)
        return list(got)

    def instances_of(self, entity: str, subtypes: bool = True) -> list:
        return [self.instance(i) for i in self.ids_of_type(entity, subtypes)]

    # ---------------------------------------------------------------- layouts
    def _layout_of_record(self, rec: dict) -> Layout:
        parts = rec.get("complex")
        if parts is None:
            return self.layout_for(rec["type"])
        return self.layout_for(tuple(p["type"] for p in parts))

    def layout_for(self, shape) -> Layout:
        """The Layout of a simple record of entity ``shape`` (str) or of a
        complex record with parts ``shape`` (tuple, in written order)."""
        lay = self._layouts.get(shape)
        if lay is None:
            lay = self._layouts[shape] = self._make_layout(shape)
        return lay

    def _make_layout(self, shape) -> Layout:
        s = self.schema
        if isinstance(shape, str):
            types = self.type_closure(shape)
            leaf = frozenset((shape,))
            slots = []
            if shape in s.entities:
                for pos, a in enumerate(s.p21_attributes(shape)):
                    slots.append(Slot(a.name, a.entity, a.type, a.optional, a.derived,
                                      a.renamed, 0, pos))
            return Layout(shape, types, leaf, slots, [0])
        types, leaf = self.resolve_types(shape)
        known = s.most_specific_first(types)
        retyped, derived_in, renamed = s.redeclarations(known)
        slots = []
        offsets = []
        for part, pname in enumerate(shape):
            offsets.append(len(slots))
            e = s.entities.get(pname.lower())
            if e is None:
                continue
            pos = 0
            for a in e.attributes:
                if a.supertype is not None:
                    continue
                k = (e.name, a.name)
                eff = retyped.get(k, a)
                slots.append(Slot(a.name, e.name, eff.type, eff.optional, k in derived_in,
                                  renamed.get(k), part, pos))
                pos += 1
        return Layout(shape, types, leaf, slots, offsets)

    # ---------------------------------------------------------------- back references
    def _build_backrefs(self) -> dict:
        back: dict = {}
        records = self._sf.records() if self._sf is not None else self._records
        layout_for = self.layout_for
        for rec in records:
            rid = rec["id"] << _SLOT_BITS
            parts = rec.get("complex")
            if parts is None:
                args = rec.get("args")
                if args is None and "attrs" in rec:  # named attributes (JSON model)
                    attrs = rec["attrs"] or {}
                    args = [attrs.get(f"{s.entity}.{s.name}", attrs.get(s.name))
                            for s in layout_for(rec["type"]).slots]
                groups = ((args or (), 0, None),)
            else:
                lay = layout_for(tuple(p["type"] for p in parts))
                offs = lay.part_offsets
                groups = []
                for pi, p in enumerate(parts):
                    n_own = ((offs[pi + 1] if pi + 1 < len(offs) else len(lay.slots)) - offs[pi])
                    groups.append((p.get("args") or (), offs[pi], n_own))
            for args, base, n_own in groups:
                for pos, v in enumerate(args):
                    tv = type(v)
                    if tv is dict:
                        r = v.get("ref")
                        if r is None:
                            continue
                        targets = (r,)
                    elif tv is list:
                        targets = _refs_in(v)
                        if not targets:
                            continue
                    else:
                        continue
                    slot = base + pos if n_own is None or pos < n_own else _NO_SLOT
                    if slot > _NO_SLOT:
                        slot = _NO_SLOT
                    code = rid | slot
                    for t in targets:
                        lst = back.get(t)
                        if lst is None:
                            back[t] = [code]
                        elif lst[-1] != code:
                            lst.append(code)
        return back

    def backrefs(self, instance_id: int) -> list:
        """(referrer id, slot index) for every reference to ``#instance_id``
        (slot index into the referrer's Layout, or -1 for an argument no
        attribute describes), in file order of the referrers; the first
        call indexes the whole population."""
        if self._backrefs is None:
            self._backrefs = self._build_backrefs()
        mask = (1 << _SLOT_BITS) - 1
        out = []
        for code in self._backrefs.get(instance_id, ()):
            slot = code & mask
            out.append((code >> _SLOT_BITS, -1 if slot == _NO_SLOT else slot))
        return out

    def role_key(self, role: str):
        """``'schema.entity.attribute'`` (or ``entity.attribute``) -> the
        (declaring entity, attribute) key it designates, or None."""
        got = self._role_keys.get(role, _MISSING)
        if got is _MISSING:
            got = self._role_keys[role] = self._role_key(role)
        return got

    def _role_key(self, role: str):
        bits = [b for b in role.lower().split(".") if b]
        if len(bits) < 2:
            return None
        ent, attr = bits[-2], bits[-1]
        if ent not in self.schema.entities:
            return None
        r = self.schema.resolve_attribute(ent, attr)
        if r is None:
            return None
        return ent, (r[0], r[1].name)

    def usedin(self, instance_id: int, role: str | None = None) -> list:
        """USEDIN: the instances referring to ``#instance_id`` through
        attribute ``role`` (``'schema.entity.attribute'``; the schema part is
        not checked) or through any attribute when ``role`` is None or ''.
        One entry per (referrer, attribute) pair, like EXPRESS's bag."""
        key = (instance_id, role or "")
        got = self._usedin.get(key)
        if got is None:
            got = tuple(self.instance(i) for i in self.usedin_ids(instance_id, role))
            if self._backrefs is not None and len(self._backrefs.get(instance_id, ())) >= _KEEP_USEDIN:
                # an assembly's root is used by every occurrence, and rules ask who uses it
                # (in one role or another) once per occurrence: kept for such instances only,
                # to spare memory
                self._usedin[key] = got
        return list(got)

    def usedin_ids(self, instance_id: int, role: str | None = None) -> list:
        """The ids of :meth:`usedin`, without making instances."""
        refs = self.backrefs(instance_id)
        if not refs:
            return []
        if not role:
            return [rid for rid, _slot in refs if rid in self]
        rk = self.role_key(role)
        if rk is None:
            return []
        ent, key = rk
        out = []
        for rid, slot in refs:
            if slot < 0 or rid not in self:
                continue
            if ent not in self.types_of(rid):
                continue
            slots = self._layout_of_id(rid).slots
            if slot < len(slots) and slots[slot].key == key:
                out.append(rid)
        return out

    def peek(self, instance_id: int, attr: str):
        """The raw value of explicit attribute ``attr`` (as ``Instance.get``), without keeping
        the decoded record of an instance not yet decoded (a rule that reads one attribute
        of every point of a B-rep need not hold 200,000 records)."""
        inst = self._instances.get(instance_id)
        k = self._slot(instance_id)
        if (inst is not None and inst._record is not None) or k < 0 or self._types[k] is None:
            return self.instance(instance_id).get(attr)
        rec = self._decode(k)
        args = rec.get("args")
        lay = self.layout_for(rec["type"])
        idx = lay.by_name.get(attr.lower())
        if args is None or not idx:
            return self.instance(instance_id).get(attr)
        pos = lay.slots[idx[0]].pos
        return args[pos] if pos < len(args) else None

    def _layout_of_id(self, instance_id: int) -> Layout:
        """The Layout of an instance; simple ones without decoding the record."""
        t = self._types[self._slot(instance_id)]
        if t is not None:
            return self.layout_for(t)
        return self.instance(instance_id).layout

    def roles_of(self, instance_id: int) -> set:
        """ROLESOF: 'SCHEMA.ENTITY.ATTRIBUTE' strings of the roles in which the instance is used."""
        out = set()
        for rid, slot in self.backrefs(instance_id):
            if slot < 0 or rid not in self:
                continue
            slots = self._layout_of_id(rid).slots
            if slot < len(slots):
                s = slots[slot]
                out.add(f"{self.prefix}{s.entity.upper()}.{s.name.upper()}")
        return out


def _refs_in(value: list) -> list:
    out = []
    stack = [value]
    while stack:
        for x in stack.pop():
            tx = type(x)
            if tx is dict:
                r = x.get("ref")
                if r is not None:
                    out.append(r)
                elif "value" in x and type(x["value"]) is list:
                    stack.append(x["value"])
            elif tx is list:
                stack.append(x)
    return out
