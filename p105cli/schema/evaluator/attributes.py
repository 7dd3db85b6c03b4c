"""Attribute look-up: explicit attributes from the record, DERIVE
attributes by evaluating their expressions, INVERSE attributes from the
population's back references.
"""

from __future__ import annotations

from ..instance import Instance
from .scope import _MISSING, _Scope
from .values import Agg, EntityValue, EnumValue, NotEvaluable, TypeRef, _IND


class _AttrInfo:
    """How to obtain each attribute of an entity type set."""

    __slots__ = ("access", "names")

    def __init__(self, access, names):
        # (entity, attr) -> ('explicit',) | ('derive', ent, decl) | ('inverse', ent, decl)
        self.access = access
        self.names = names  # local name -> (entity, attr)


class Attributes:
    """Explicit, derived and inverse attribute look-up (an ``Evaluator`` mixin)."""

    # ---------------------------------------------------------------- attributes
    def _info(self, obj) -> _AttrInfo:
        types = obj.types
        info = self._infos.get(types)
        if info is None:
            info = self._infos[types] = self._make_info(types)
        return info

    def _make_info(self, types) -> _AttrInfo:
        s = self.schema
        known = s.most_specific_first(types)
        access: dict = {}
        override: dict = {}
        names: dict = {}
        for t in known:
            e = s.entities[t]
            for a in e.attributes:
                if a.supertype is None:
                    access[(t, a.name)] = ("explicit",)
            for a in e.derived:
                if a.supertype is None:
                    access[(t, a.name)] = ("derive", t, a)
            for a in e.inverse:
                if a.supertype is None:
                    access[(t, a.name)] = ("inverse", t, a)
        for t in known:
            e = s.entities[t]
            for a in e.derived:
                if a.supertype is not None:
                    k = self._resolve_key(a.supertype, a.name)
                    if k is not None:
                        override.setdefault(k, ("derive", t, a))
            for a in e.inverse:
                if a.supertype is not None:
                    k = self._resolve_key(a.supertype, a.name)
                    if k is not None:
                        override.setdefault(k, ("inverse", t, a))
        access.update(override)
        for t in known:
            e = s.entities[t]
            for a in (*e.attributes, *e.derived, *e.inverse):
                if a.supertype is None:
                    names.setdefault(a.name, (t, a.name))
                else:
                    k = self._resolve_key(a.supertype, a.name)
                    if k is not None:
                        names.setdefault(a.local_name, k)
        return _AttrInfo(access, names)

    def _resolve_key(self, entity: str, name: str):
        ck = (entity, name)
        if ck in self._keys:
            return self._keys[ck]
        k = None
        if entity in self.schema.entities:
            r = self.schema.resolve_attribute(entity, name)
            if r is not None:
                k = (r[0], r[1].name)
        self._keys[ck] = k
        return k

    def _find_key(self, obj, name, group, ctx):
        types = obj.types
        if group is not None:
            if group not in types:
                return None
            return self._resolve_key(group, name)
        if ctx is not None and ctx in types:
            k = self._resolve_key(ctx, name)
            if k is not None:
                return k
        return self._info(obj).names.get(name)

    def _attr(self, obj, name, group=None, ctx=None):
        if obj is _IND:
            return _IND
        to = type(obj)
        if to is Instance or to is EntityValue:
            key = self._find_key(obj, name, group, ctx)
            if key is None:
                self._anomaly(f"{obj!r} has no attribute {name}"
                              + (f" as {group}" if group else ""))
                return _IND
            return self._attr_by_key(obj, key)
        if to is TypeRef:
            return self._qualified_enum(obj.name, name)
        return _IND

    def _anomaly(self, msg: str) -> None:
        if len(self.anomalies) < 1000:
            self.anomalies.append(msg)

    def _qualified_enum(self, tname: str, item: str):
        td = self.schema.types.get(tname)
        if td is not None:
            et = self._enum_types_in(tname, item)
            if et is not None:
                return EnumValue(item, et)
        raise NotEvaluable(f"{tname}.{item} is not an enumeration item")

    def _attr_by_key(self, obj, key):
        info = self._info(obj)
        acc = info.access.get(key)
        if acc is None:
            return _IND
        kind = acc[0]
        if kind == "explicit":
            if type(obj) is Instance:
                cache = obj._values
                v = cache.get(key, _MISSING)
                if v is not _MISSING:
                    return v
                lay = obj.layout
                i = lay.by_key.get(key)
                if i is None:
                    v = _IND
                else:
                    v = self.convert(obj.raw(i), lay.slots[i].type, obj)
                cache[key] = v
                return v
            part = obj.parts.get(key[0])
            if part is None:
                return _IND
            return part.get(key[1], _IND)
        if kind == "derive":
            return self._derive(obj, key, acc[1], acc[2])
        return self._inverse(obj, key, acc[1], acc[2])

    def _derive(self, obj, key, ent, decl):
        is_inst = type(obj) is Instance
        if is_inst:
            dkey = ("derive",) + key
            v = obj._values.get(dkey, _MISSING)
            if v is not _MISSING:
                return v
            marker = (obj.id, key)
        else:
            marker = (id(obj), key)
        if marker in self._derive_active:
            raise NotEvaluable(f"derived attribute {ent}.{decl.name} depends on itself",
                               decl.line)
        self._derive_active.add(marker)
        try:
            sc = _Scope(self_obj=obj, ctx=ent)
            v = self._coerce(self.ev(decl.expr, sc), decl.type, sc)
        finally:
            self._derive_active.discard(marker)
        if is_inst:
            obj._values[dkey] = v
        return v

    def _inverse(self, obj, key, ent, decl):
        if type(obj) is not Instance:
            return Agg(decl.aggregate, ()) if decl.aggregate else _IND
        ikey = ("inverse",) + key
        v = obj._values.get(ikey, _MISSING)
        if v is not _MISSING:
            return v
        target_ent = decl.entity
        for_ent = decl.for_entity or target_ent
        rk = self._resolve_key(for_ent, decl.for_attribute)
        users = []
        if rk is not None:
            seen = set()
            pop = self.pop
            for rid, slot in pop.backrefs(obj.id):
                if slot < 0 or rid not in pop or rid in seen:
                    continue
                if target_ent not in pop.types_of(rid):
                    continue
                slots = pop._layout_of_id(rid).slots
                if slot < len(slots) and slots[slot].key == rk:
                    seen.add(rid)
                    users.append(pop.instance(rid))
        if decl.aggregate:
            v = Agg(decl.aggregate, users)
        else:
            v = users[0] if users else _IND
        obj._values[ikey] = v
        return v
