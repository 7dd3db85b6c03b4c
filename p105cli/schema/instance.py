"""An entity instance of a Population, and the layout of its record.

``Instance`` is what the rest of the schema layer hands around: the
evaluator recognises instances by this class, and ``Population`` makes one
per instance id. Kept apart from ``population.py`` so that the evaluator
needs no import of the population it is given.

A science module: no click, rich or numpy here.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

from .model import SchemaError

__all__ = ["Instance", "Layout", "Slot"]

@dataclass(frozen=True)
class Slot:
    """One explicit-attribute slot of an instance's record.

    ``entity``/``name``: the original declaration (``key``); ``type`` and
    ``optional`` the effective ones for this instance's types after
    redeclarations; ``derived``: a subtype re-derives it (Part 21 ``*``);
    ``renamed``: its name after ``RENAMED``; ``part``/``pos``: where the
    value sits in the record (part index of a complex record, 0 for a
    simple one; position in that part's arguments)."""

    name: str
    entity: str
    type: Any
    optional: bool
    derived: bool
    renamed: Optional[str]
    part: int
    pos: int

    @property
    def key(self) -> tuple:
        return (self.entity, self.name)


class Layout:
    """Where each explicit attribute of one record shape sits.

    The shape is the entity name of a simple record, or the tuple of part
    entity names (in written order) of a complex one."""

    __slots__ = ("shape", "types", "leaf_types", "slots", "by_key", "by_name", "part_offsets")

    def __init__(self, shape, types, leaf_types, slots, part_offsets):
        self.shape = shape
        self.types = types
        self.leaf_types = leaf_types
        self.slots = tuple(slots)
        self.part_offsets = tuple(part_offsets)
        self.by_key = {}
        self.by_name: dict = {}
        for i, s in enumerate(self.slots):
            self.by_key.setdefault(s.key, i)
            for n in (s.name, s.renamed, f"{s.entity}.{s.name}"):
                if n:
                    lst = self.by_name.setdefault(n, [])
                    if i not in lst:
                        lst.append(i)


class Instance:
    """One entity instance of a Population (one object per instance id)."""

    __slots__ = ("pop", "id", "_k", "_record", "_layout", "_values", "_tc", "__weakref__")

    def __init__(self, pop, instance_id: int, k: int):
        self.pop = pop
        self.id = instance_id
        self._k = k
        self._record = None
        self._layout = None
        self._values: dict = {}  # evaluator cache: attribute key -> value
        self._tc = None

    # ---------------------------------------------------------------- identity
    def __repr__(self) -> str:
        lt = self.leaf_types
        return f"#{self.id}={'+'.join(sorted(lt)) if lt else '?'}"

    @property
    def record(self) -> dict:
        """The decoded record (``{"id", "type", "args"}`` or ``{"id", "complex"}``)."""
        r = self._record
        if r is None:
            r = self._record = self.pop._decode(self._k)
        return r

    @property
    def offset(self):
        """Character offset of the instance in the Part 21 text (None for JSON input)."""
        return self.pop._offset(self._k)

    @property
    def line_col(self):
        """(line, column) of the instance in the Part 21 text, or None."""
        return self.pop._line_col(self._k)

    @property
    def layout(self) -> Layout:
        lay = self._layout
        if lay is None:
            lay = self._layout = self.pop._layout_of_record(self.record)
        return lay

    @property
    def types(self) -> frozenset:
        """Every entity this instance is an instance of (lower case)."""
        tc = self._tc
        if tc is None:
            tc = self._tc = self.pop.types_of(self.id)
        return tc

    @property
    def leaf_types(self) -> frozenset:
        """The most specific entity types of the instance."""
        return self.pop.leaf_types_of(self.id)

    @property
    def is_complex(self) -> bool:
        return self.pop._type_at(self._k) is None

    # ---------------------------------------------------------------- attributes
    def raw(self, slot_index: int):
        """The raw value in slot ``slot_index`` of the layout (None if missing)."""
        s = self.layout.slots[slot_index]
        rec = self.record
        if "complex" in rec:
            parts = rec["complex"]
            if s.part >= len(parts):
                return None
            args = parts[s.part].get("args")
            if args is None:
                attrs = parts[s.part].get("attrs") or {}
                return attrs.get(s.name)
        else:
            args = rec.get("args")
            if args is None:
                attrs = rec.get("attrs") or {}
                v = attrs.get(f"{s.entity}.{s.name}", attrs.get(s.name))
                return v
        return args[s.pos] if s.pos < len(args) else None

    def explicit_names(self) -> list:
        """Names of the explicit attributes, in record order."""
        return [s.name for s in self.layout.slots]

    def get(self, attr: str):
        """The raw value of explicit attribute ``attr`` (``name``, a RENAMED
        name, or ``entity.name`` to pick one of two same-named attributes).
        ``{"derived": True}`` for a slot written ``*``; None for ``$``.
        Raises SchemaError if the instance has no such explicit attribute."""
        lay = self.layout
        idx = lay.by_name.get(attr.lower())
        if not idx:
            raise SchemaError(f"#{self.id} ({'+'.join(sorted(self.leaf_types))}) has no "
                              f"explicit attribute {attr!r}")
        return self.raw(idx[0])
