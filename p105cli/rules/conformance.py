"""Schema conformance of Part 21 instances: what an EXPRESS schema says
about each instance's own encoding (types, arity, `$`/`*`, aggregates,
references, complex-instance legality), instance by instance.

WHERE rules, UNIQUE rules, global rules and inverse cardinalities are not
checked here (they need an expression evaluator over the population).

Entry points
    ``check_instance(record, schema, types_of) -> list[Finding]``
    ``check_population(records, schema, types_of) -> Iterator[Finding]``
    ``step_types_of(step_file, schema)`` builds a ``types_of`` for a
    ``p105cli.step.StepFile`` (index look-ups; complex instances decoded
    once, on demand).

``record`` is a decoded Part 21 instance as ``p105cli.step`` gives it;
``types_of(id)`` returns the full set of entity type names (lower case,
supertypes included) of instance ``#id``, or None when there is no such
instance. ``checker_for(schema)`` gives the cached per-schema checker;
its ``stats`` count, over the schema's lifetime, what was let through
unreported: ``bounds_skipped`` (aggregate values whose bound is an
expression, e.g. ``[1:segments]``, not evaluated) and
``untyped_select_values`` (a non-entity SELECT value written without its
typed parameter, accepted because exactly one type of the select fits;
Part 21 asks for the typed parameter). Take a copy before and after a
run to count one file.

Rule ids (stable; ``severity`` is ``error`` unless said otherwise)

=====================  =====================================================
rule                   what it checks
=====================  =====================================================
SCH-UNKNOWN-ENTITY     a simple instance whose entity type is not in the
                       schema; nothing else is checked for it (the analysis
                       commands read such files leniently; the gate does not)
SCH-ABSTRACT           an ABSTRACT entity instantiated without one of its
                       subtypes (a simple instance of it, or a part of a
                       complex instance with no subtype among the parts)
SCH-ARITY              a simple instance whose number of parameters differs
                       from ``Schema.p21_attributes`` (its attributes are
                       then not checked)
SCH-DERIVED            ``*`` where the attribute is not re-declared as
                       DERIVE (in the instance's type or a part of a complex
                       instance); ``$`` in a derived slot; ``*`` inside an
                       aggregate. An explicit value in a derived slot is not
                       checked here: ``rules/derived.py`` compares it with
                       the derivation (``SCH-DERIVED-EXPLICIT`` when equal,
                       ``SCH-DERIVED-CONFLICT`` when not)
SCH-OPTIONAL           ``$`` for an attribute that is not OPTIONAL (after
                       redeclarations), or as an aggregate element other
                       than in ``ARRAY OF OPTIONAL``
SCH-TYPE               the value does not fit the declared type: simple
                       types (INTEGER: integer; REAL: real, written with a
                       decimal point; NUMBER: either; STRING; BINARY;
                       BOOLEAN: .T./.F.; LOGICAL: .T./.F./.U.), defined
                       types through to their underlying type, enumeration
                       items, aggregates where a single value is expected
                       and the reverse, entity references to an instance
                       that is not of the declared entity type (nor a
                       subtype), SELECT values (a typed parameter must name
                       a non-SELECT defined type of the select, nested
                       selects included; an entity reference must be of an
                       entity type of the select; an untyped simple value is
                       accepted only when exactly one defined type of the
                       select fits it), typed parameters where no SELECT is
                       declared
SCH-DANGLING           a reference to an instance name that is not in the
                       population (``types_of`` returned None)
SCH-BOUNDS             aggregate size outside ``[lo:hi]`` (ARRAY: exactly
                       hi-lo+1); only literal integer bounds are evaluated
SCH-SET-UNIQUE         duplicate members in a SET, or in a LIST/ARRAY
                       declared UNIQUE (same instance, or equal values)
SCH-COMPLEX            complex (externally mapped) instance legality: every
                       part an entity of the schema, listed once, in
                       alphabetical order (of the upper-case names, as
                       written); every supertype of every part present as a
                       part; the set of types allowed by the supertype
                       expressions (ONEOF, AND, ANDOR; also checked for
                       simple instances, e.g. a subtype whose supertype says
                       ``ONEOF(a, b) AND ONEOF(c, d)`` alone) and SUBTYPE_
                       CONSTRAINTs; each part's parameter count equal to the
                       entity's own explicit attributes.  As a *warning*: a
                       complex instance whose types are one entity and its
                       supertypes (Part 21 asks for the internal mapping)
=====================  =====================================================

Findings on an attribute carry its name in ``attribute`` (for a part of a
complex instance ``part.attribute``); messages on aggregate elements start
with the element's index, e.g. ``[3]``. The ``entity_type`` of a complex
instance is its part names joined by ``+`` as written.

Supertype expressions are read as constraints: every ONEOF at any level
must hold for the subtypes present (for operands that share subtypes, as
the long forms' merged ``ONEOF(...) ANDOR ONEOF(...)`` do, this is
stricter than a literal reading of ISO 10303-11 Annex B, and is what the
modules that the long forms merge mean).

Everything that depends only on the schema (slot lists, compiled type
validators, the static supertype findings of a type combination) is
computed once per entity name or part combination and cached per schema.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Callable, Iterable, Iterator, Optional

from ..schema.model import (
    AggregateType, EnumerationType, Literal, NamedType, Schema, SelectType, SimpleType, UnaryOp,
)

__all__ = [
    "RULES", "Finding", "Checker", "checker_for", "check_instance", "check_population",
    "step_types_of",
]

UNKNOWN_ENTITY = "SCH-UNKNOWN-ENTITY"
ABSTRACT = "SCH-ABSTRACT"
ARITY = "SCH-ARITY"
DERIVED = "SCH-DERIVED"
OPTIONAL = "SCH-OPTIONAL"
TYPE = "SCH-TYPE"
DANGLING = "SCH-DANGLING"
BOUNDS = "SCH-BOUNDS"
SET_UNIQUE = "SCH-SET-UNIQUE"
COMPLEX = "SCH-COMPLEX"

RULES = {  # one sentence each, ready for diagnostics.register_rule
    UNKNOWN_ENTITY: "An entity instance's type is not an entity of the schema.",
    ABSTRACT: "An ABSTRACT entity is instantiated without one of its subtypes.",
    ARITY: "An entity instance has the wrong number of attributes for its EXPRESS type.",
    DERIVED: "'*' is written for an explicit attribute, '$' for a derived one, or '*' inside an "
             "aggregate.",
    OPTIONAL: "'$' is written for an attribute or aggregate element that is not OPTIONAL.",
    TYPE: "An attribute value does not fit its declared EXPRESS type.",
    DANGLING: "An attribute refers to an entity instance that is not in the file.",
    BOUNDS: "An aggregate has fewer or more elements than its declared bounds allow.",
    SET_UNIQUE: "A SET, or a LIST or ARRAY declared UNIQUE, holds the same member twice.",
    COMPLEX: "A complex entity instance is not a legal external mapping of its types.",
}

ERROR, WARNING = "error", "warning"


@dataclass(frozen=True, slots=True)
class Finding:
    rule: str
    severity: str
    message: str
    entity: Optional[int]
    entity_type: Optional[str]
    attribute: Optional[str] = None


TypesOf = Callable[[int], Optional[frozenset]]
# A validator appends (rule, message) pairs to `out` for a value that is
# neither None nor '*' at the top level (aggregates check their elements).
Validator = Callable[[object, TypesOf, list], None]


# --------------------------------------------------------------------------
# describing values in messages

def _show(value, limit: int = 40) -> str:
    t = type(value)
    if t is float or t is int:
        return repr(value)
    if t is str:
        s = value if len(value) <= limit else value[:limit] + "..."
        return "'" + s.replace("'", "''") + "'"
    if value is None:
        return "$"
    if t is list:
        inner = ",".join(_show(v, 12) for v in value[:4])
        return "(" + inner + (",..." if len(value) > 4 else "") + ")"
    if t is dict:
        if "ref" in value:
            return f"#{value['ref']}"
        if "enum" in value:
            return f".{value['enum']}."
        if "derived" in value:
            return "*"
        if "binary" in value:
            return f'"{value["binary"][:16]}"'
        if "type" in value:
            return f"{value['type']}({_show(value.get('value'), 20)})"
    return repr(value)


def _kind(value) -> str:
    t = type(value)
    if t is int:
        return f"the integer {value}"
    if t is float:
        return f"the real {value!r}"
    if t is str:
        return f"the string {_show(value)}"
    if t is list:
        return f"the list {_show(value)}"
    if value is None:
        return "$"
    if t is dict:
        if "ref" in value:
            return f"a reference #{value['ref']}"
        if "enum" in value:
            return f"the enumeration .{value['enum']}."
        if "derived" in value:
            return "*"
        if "binary" in value:
            return "a binary"
        if "type" in value:
            return f"the typed parameter {_show(value)}"
    return repr(value)


# --------------------------------------------------------------------------
# supertype expressions

def _leaves(expr) -> frozenset:
    if isinstance(expr, str):
        return frozenset((expr,))
    out: set = set()
    for o in expr.operands:
        out |= _leaves(o)
    return frozenset(out)


def _match(expr, present: frozenset) -> bool:
    """Whether the subtypes ``present`` (a non-empty subset of the
    expression's leaves) form a combination the expression allows."""
    if isinstance(expr, str):
        return present == {expr}
    op = expr.op
    if op == "oneof":
        return any(present <= _leaves(o) and _match(o, present) for o in expr.operands)
    parts = [(o, present & _leaves(o)) for o in expr.operands]
    if op == "and":
        return all(p and _match(o, p) for o, p in parts)
    # andor: each operand that is touched must hold; at least one is touched
    return any(p for _, p in parts) and all(_match(o, p) for o, p in parts if p)


def _fmt_expr(expr) -> str:
    if isinstance(expr, str):
        return expr
    return expr.op.upper() + "(" + ", ".join(_fmt_expr(o) for o in expr.operands) + ")"


# --------------------------------------------------------------------------
# plans

@dataclass(slots=True)
class _Slot:
    name: str          # attribute name used in findings
    optional: bool
    derived: bool
    validator: Validator
    fast: frozenset    # Python types accepted without calling the validator


@dataclass(slots=True)
class _Plan:
    label: str                      # entity_type of the findings
    static: list                    # (rule, severity, message) every instance gets
    slots: Optional[list] = None    # simple instance: list[_Slot]; None: don't check
    parts: Optional[list] = None    # complex: list[(name, list[_Slot]) or (name, None)]


_NO_FAST: frozenset = frozenset()


class Checker:
    """Schema-dependent checking state: compiled validators and plans,
    built on first use and kept for the schema's lifetime."""

    def __init__(self, schema: Schema):
        self.schema = schema
        self.stats = {"bounds_skipped": 0, "untyped_select_values": 0}
        self._entity_names = frozenset(schema.entities)
        self._plans: dict = {}
        self._complex_plans: dict = {}
        self._defined: dict = {}
        self._entity_validators: dict = {}
        self._select_domains: dict = {}
        self._closures: dict = {}
        self._constraints: dict = {}
        for c in schema.subtype_constraints.values():
            self._constraints.setdefault(c.entity, []).append(c)
        self._extensions: dict = {}
        for t in schema.types.values():
            u = t.underlying
            if isinstance(u, (SelectType, EnumerationType)) and u.based_on:
                self._extensions.setdefault(u.based_on, []).append(t.name)
        self._simple_validators = {
            "integer": self._kind_validator("INTEGER", (int,)),
            "real": self._kind_validator("REAL", (float,)),
            "number": self._kind_validator("NUMBER", (int, float)),
            "string": self._kind_validator("STRING", (str,)),
            "binary": self._binary_validator(),
            "boolean": self._enum_validator("BOOLEAN", ("T", "F")),
            "logical": self._enum_validator("LOGICAL", ("T", "F", "U")),
        }

    # ---------------------------------------------------------- public
    def check(self, record: dict, types_of: TypesOf, derived_values: Optional[set] = None) -> list:
        """The findings of one record; the id of a record that writes a value in a derived
        slot is added to ``derived_values`` (for ``rules/derived.py``)."""
        iid = record.get("id")
        complex_parts = record.get("complex")
        if complex_parts is not None:
            return self._check_complex(iid, complex_parts, types_of, derived_values)
        etype = record.get("type")
        plan = self._plans.get(etype)
        if plan is None:
            plan = self._plans[etype] = self._simple_plan(etype)
        out = [Finding(rule, sev, msg, iid, etype) for rule, sev, msg in plan.static]
        slots = plan.slots
        if slots is None:
            return out
        args = record.get("args", ())
        if len(args) != len(slots):
            out.append(Finding(ARITY, ERROR, f"{etype} takes {len(slots)} parameters "
                               f"({', '.join(map(_slot_str, slots))}), found {len(args)}",
                               iid, etype))
            return out
        self._check_slots(slots, args, types_of, out, iid, etype, "", derived_values)
        return out

    def closure(self, name: str) -> frozenset:
        """``name`` and all its supertypes (``{name}`` for an unknown name)."""
        c = self._closures.get(name)
        if c is None:
            if name in self.schema.entities:
                c = frozenset((name, *self.schema.all_supertypes(name)))
            else:
                c = frozenset((name,))
            self._closures[name] = c
        return c

    # ---------------------------------------------------------- slots
    def _check_slots(self, slots, args, types_of, out, iid, etype, prefix,
                     derived_values=None) -> None:
        for slot, v in zip(slots, args):
            if v is None:
                if slot.derived:
                    out.append(Finding(DERIVED, ERROR, f"{slot.name} is derived: write *, not $",
                                       iid, etype, prefix + slot.name))
                elif not slot.optional:
                    out.append(Finding(OPTIONAL, ERROR, f"{slot.name} is not OPTIONAL: $ not allowed",
                                       iid, etype, prefix + slot.name))
                continue
            if slot.derived:
                # an explicit value where the schema derives: whether it equals the
                # derivation needs the evaluator (rules/derived.py), not this check
                if derived_values is not None and not (type(v) is dict and v.get("derived") is True):
                    derived_values.add(iid)
                continue
            tv = type(v)
            if tv in slot.fast:
                continue
            if tv is dict and v.get("derived") is True:
                out.append(Finding(DERIVED, ERROR, f"{slot.name} is an explicit attribute: "
                                   f"* is only for derived ones", iid, etype, prefix + slot.name))
                continue
            errs: list = []
            slot.validator(v, types_of, errs)
            for rule, msg in errs:
                out.append(Finding(rule, ERROR, msg, iid, etype, prefix + slot.name))

    def _slot(self, name, optional, derived, tspec) -> _Slot:
        val = self.compile(tspec)
        return _Slot(name, optional, derived, val, getattr(val, "fast", _NO_FAST))

    # ---------------------------------------------------------- simple plans
    def _simple_plan(self, etype: str) -> _Plan:
        schema = self.schema
        if etype not in schema.entities:
            return _Plan(etype, [(UNKNOWN_ENTITY, ERROR,
                                  f"{etype} is not an entity of schema {schema.name}")])
        static = []
        if self._is_abstract(etype):
            static.append((ABSTRACT, ERROR, f"{etype} is ABSTRACT: instantiate one of its subtypes"
                           f" ({_few(schema.entities[etype].subtypes)})"))
        static += self._combination_findings(self.closure(etype), simple=etype)
        slots = [self._slot(a.name, a.optional, a.derived, a.type)
                 for a in schema.p21_attributes(etype)]
        return _Plan(etype, static, slots)

    def _is_abstract(self, name: str) -> bool:
        if self.schema.entities[name].abstract:
            return True
        return any(c.abstract for c in self._constraints.get(name, ()))

    def _combination_findings(self, types: frozenset, simple: Optional[str] = None) -> list:
        """SCH-COMPLEX findings of the supertype expressions and subtype
        constraints over an instance whose types are ``types``."""
        out = []
        ents = self.schema.entities
        for name in sorted(types):
            ent = ents.get(name)
            if ent is None:
                continue
            exprs = []
            if ent.supertype_expr is not None:
                exprs.append(ent.supertype_expr)
            for c in self._constraints.get(name, ()):
                if c.expr is not None:
                    exprs.append(c.expr)
                if c.total_over and types.isdisjoint(c.total_over):
                    out.append((COMPLEX, ERROR, f"an instance of {name} must also be one of "
                                f"{', '.join(c.total_over)} (TOTAL_OVER of {c.name})"))
            for expr in exprs:
                present = types & _leaves(expr)
                if present and not _match(expr, present):
                    what = (f"{simple} cannot be instantiated alone" if simple
                            else f"the combination {' + '.join(sorted(present))} is not allowed")
                    out.append((COMPLEX, ERROR, f"{what}: {name} is SUPERTYPE OF "
                                f"{_fmt_expr(expr)}"))
        return out

    # ---------------------------------------------------------- complex
    def _check_complex(self, iid, parts: list, types_of: TypesOf, derived_values=None) -> list:
        key = tuple(p.get("type") for p in parts)
        plan = self._complex_plans.get(key)
        if plan is None:
            plan = self._complex_plans[key] = self._complex_plan(key)
        label = plan.label
        out = [Finding(rule, sev, msg, iid, label) for rule, sev, msg in plan.static]
        if plan.parts is None:
            return out
        for (pname, slots), part in zip(plan.parts, parts):
            if slots is None:
                continue
            args = part.get("args", ())
            if len(args) != len(slots):
                out.append(Finding(COMPLEX, ERROR, f"part {pname} takes {len(slots)} parameters"
                                   f" (its own explicit attributes: "
                                   f"{', '.join(map(_slot_str, slots)) or 'none'}), found {len(args)}",
                                   iid, label, pname))
                continue
            self._check_slots(slots, args, types_of, out, iid, label, pname + ".", derived_values)
        return out

    def _complex_plan(self, names: tuple) -> _Plan:
        schema = self.schema
        ents = schema.entities
        label = "+".join(str(n) for n in names)
        static: list = []
        unknown = [n for n in names if n not in ents]
        if unknown:
            static.append((COMPLEX, ERROR, f"not entities of schema {schema.name}: "
                           f"{', '.join(map(str, unknown))}"))
            return _Plan(label, static)
        upper = [n.upper() for n in names]
        dups = sorted({n for n in names if names.count(n) > 1})
        if dups:
            static.append((COMPLEX, ERROR, f"part(s) listed more than once: {', '.join(dups)}"))
        elif upper != sorted(upper):
            static.append((COMPLEX, ERROR, "parts not in alphabetical order: expected "
                           + " ".join(sorted(upper))))
        given = frozenset(names)
        closure: set = set()
        for n in given:
            closure |= self.closure(n)
        closure = frozenset(closure)
        missing = sorted(closure - given)
        if missing:
            static.append((COMPLEX, ERROR, "supertypes missing from the external mapping: "
                           + ", ".join(missing)))
        for n in sorted(closure):
            if self._is_abstract(n) and not any(s in closure for s in ents[n].subtypes):
                static.append((ABSTRACT, ERROR, f"{n} is ABSTRACT and none of its subtypes is "
                               f"among the parts"))
        static += self._combination_findings(closure)
        leaves = [n for n in closure if not any(s in closure for s in ents[n].subtypes)]
        if len(leaves) == 1 and not missing and not dups:
            static.append((COMPLEX, WARNING, f"the types are {leaves[0]} and its supertypes: "
                           f"an instance of one leaf type takes the internal mapping "
                           f"{leaves[0].upper()}(...)"))
        # effective attribute declarations across all types of the instance
        retyped: dict = {}
        derived_in: dict = {}
        for en in sorted(closure):
            e = ents[en]
            for a in e.attributes:
                if a.supertype is not None:
                    r = schema.resolve_attribute(a.supertype, a.name)
                    if r is not None:
                        retyped.setdefault((r[0], r[1].name), []).append((en, a))
            for a in e.derived:
                if a.supertype is not None:
                    r = schema.resolve_attribute(a.supertype, a.name)
                    if r is not None:
                        derived_in.setdefault((r[0], r[1].name), en)
        plan_parts = []
        for n in names:
            slots = []
            for a in ents[n].attributes:
                if a.supertype is not None:
                    continue
                k = (n, a.name)
                cands = retyped.get(k)
                if cands:
                    # the most specific redeclarations; unrelated ones all apply
                    top = [c for c in cands
                           if not any(d[0] != c[0] and schema.is_subtype(d[0], c[0]) for d in cands)]
                    optional = all(c[1].optional for c in top)
                    vals = [self.compile(c[1].type) for c in top]
                    if len(vals) == 1:
                        slots.append(_Slot(a.name, optional, k in derived_in, vals[0],
                                           getattr(vals[0], "fast", _NO_FAST)))
                    else:
                        slots.append(_Slot(a.name, optional, k in derived_in, _all_of(vals),
                                           _NO_FAST))
                else:
                    slots.append(self._slot(a.name, a.optional, k in derived_in, a.type))
            plan_parts.append((n, slots))
        if dups:
            plan_parts = [(n, None) for n in names]
        return _Plan(label, static, parts=plan_parts)

    # ---------------------------------------------------------- type validators
    def compile(self, t) -> Validator:
        """A validator for a TypeSpec (cached for named types)."""
        if isinstance(t, NamedType):
            name = t.name
            if name in self.schema.entities:
                return self._entity_validator(name)
            if name in self.schema.types:
                return self._defined_validator(name)
            return _accept_any  # unknown name: the schema reader's business
        if isinstance(t, SimpleType):
            return self._simple_validators[t.name]
        if isinstance(t, AggregateType):
            return self._aggregate_validator(t)
        # GENERIC, GENERIC_ENTITY; a SELECT/ENUMERATION is only ever the
        # underlying type of a TYPE (compiled by _build_defined)
        return _accept_any

    @staticmethod
    def _kind_validator(label: str, pytypes: tuple) -> Validator:
        def v(value, types_of, out):
            if type(value) not in pytypes:
                out.append((TYPE, f"expected {label}, found {_kind(value)}"))
        v.fast = frozenset(pytypes)
        v.label = label
        return v

    @staticmethod
    def _binary_validator() -> Validator:
        def v(value, types_of, out):
            if not (type(value) is dict and "binary" in value):
                out.append((TYPE, f"expected BINARY, found {_kind(value)}"))
        v.label = "BINARY"
        return v

    @staticmethod
    def _enum_validator(label: str, items) -> Validator:
        items = frozenset(items)

        def v(value, types_of, out):
            if type(value) is dict:
                e = value.get("enum")
                if e in items:
                    return
                if e is not None:
                    out.append((TYPE, f".{e}. is not a value of {label} "
                                f"({', '.join('.' + i + '.' for i in sorted(items))})"))
                    return
            out.append((TYPE, f"expected {label}, found {_kind(value)}"))
        v.label = label
        return v

    def _entity_validator(self, name: str) -> Validator:
        v = self._entity_validators.get(name)
        if v is not None:
            return v
        known = self._entity_names

        def v(value, types_of, out):
            if type(value) is dict:
                r = value.get("ref")
                if r is not None:
                    ts = types_of(r)
                    if ts is None:
                        out.append((DANGLING, f"#{r} is not an instance of the file"))
                    elif name not in ts and not ts.isdisjoint(known):
                        out.append((TYPE, f"#{r} is {self._describe(ts)}, not {_a(name)}"))
                    return
            out.append((TYPE, f"expected a reference to {_a(name)}, found {_kind(value)}"))
        v.label = name
        self._entity_validators[name] = v
        return v

    def _describe(self, ts: frozenset) -> str:
        ents = self.schema.entities
        leaves = sorted(n for n in ts if n in ents and not any(s in ts for s in ents[n].subtypes))
        return _a("+".join(leaves)) if leaves else "an instance of unknown type"

    def _defined_validator(self, name: str) -> Validator:
        v = self._defined.get(name)
        if v is not None:
            return v
        cell: list = []

        def trampoline(value, types_of, out):  # recursion through the type graph
            cell[0](value, types_of, out)
        self._defined[name] = trampoline
        real = self._build_defined(name)
        cell.append(real)
        self._defined[name] = real
        return real

    def _build_defined(self, name: str) -> Validator:
        u = self.schema.types[name].underlying
        if isinstance(u, EnumerationType):
            return self._enumeration_validator(name)
        if isinstance(u, SelectType):
            return self._select_validator(name)
        inner = self.compile(u)
        fast = getattr(inner, "fast", None)
        base = getattr(inner, "label", None)

        def v(value, types_of, out):
            n = len(out)
            inner(value, types_of, out)
            if len(out) > n and base is not None and base != name:
                rule, msg = out[n]
                out[n] = (rule, msg.replace(f"expected {base}", f"expected {name} ({base})", 1))
        if fast is not None:
            v.fast = fast
        v.label = name
        return v

    def _enum_items(self, name: str, seen=None) -> set:
        seen = set() if seen is None else seen
        if name in seen or name not in self.schema.types:
            return set()
        seen.add(name)
        u = self.schema.types[name].underlying
        if not isinstance(u, EnumerationType):
            return set()
        items = set(u.items)
        if u.based_on:
            items |= self._enum_items(u.based_on, seen)
        for ext in self._extensions.get(name, ()):
            items |= self._enum_items(ext, seen)
        return items

    def _enumeration_validator(self, name: str) -> Validator:
        items = frozenset(i.upper() for i in self._enum_items(name))

        def v(value, types_of, out):
            if type(value) is dict:
                e = value.get("enum")
                if e in items:
                    return
                if e is not None:
                    out.append((TYPE, f".{e}. is not an item of {name} ({_few(sorted(items), '.')})"))
                    return
            out.append((TYPE, f"expected an item of enumeration {name}, found {_kind(value)}"))
        v.label = name
        return v

    def _select_domain(self, name: str):
        """(entity names, {defined type name: validator}, generic_entity) of
        a select, flattened through nested selects."""
        dom = self._select_domains.get(name)
        if dom is not None:
            return dom
        entities: set = set()
        typed: dict = {}
        generic = False
        seen: set = set()
        types = self.schema.types

        def walk(sel: str) -> None:
            nonlocal generic
            if sel in seen:
                return
            seen.add(sel)
            u = types[sel].underlying
            generic = generic or u.generic_entity
            items = list(u.items)
            if u.based_on and u.based_on in types:
                items.append(u.based_on)
            items += self._extensions.get(sel, ())
            for it in items:
                if it in self.schema.entities:
                    entities.add(it)
                elif it in types:
                    if isinstance(types[it].underlying, SelectType):
                        walk(it)
                    else:
                        typed[it] = None
        walk(name)
        dom = (frozenset(entities), typed, generic)
        self._select_domains[name] = dom
        for t in typed:  # compile after registering (selects may recurse)
            typed[t] = self._defined_validator(t)
        return dom

    def _select_validator(self, name: str) -> Validator:
        entities, typed, generic = self._select_domain(name)
        known = self._entity_names
        stats = self.stats

        def v(value, types_of, out):
            if type(value) is dict:
                r = value.get("ref")
                if r is not None:
                    ts = types_of(r)
                    if ts is None:
                        out.append((DANGLING, f"#{r} is not an instance of the file"))
                    elif not (generic or not ts.isdisjoint(entities) or ts.isdisjoint(known)):
                        if entities:
                            out.append((TYPE, f"#{r} is {self._describe(ts)}, not one of the "
                                        f"entity types of select {name} ({_few(sorted(entities))})"))
                        else:
                            out.append((TYPE, f"#{r}: select {name} has no entity types"))
                    return
                tname = value.get("type")
                if tname is not None and "value" in value:
                    low = tname.lower()
                    tv = typed.get(low)
                    if tv is None:
                        out.append((TYPE, f"{tname} is not a defined type of select {name} "
                                    f"({_few(sorted(typed))})"))
                    else:
                        n = len(out)
                        tv(value["value"], types_of, out)
                        for i in range(n, len(out)):
                            out[i] = (out[i][0], f"{tname}(...): {out[i][1]}")
                    return
            # an untyped value: accepted when exactly one defined type fits
            fits = []
            for tn, tv in typed.items():
                scratch: list = []
                tv(value, types_of, scratch)
                if not scratch:
                    fits.append(tn)
                    if len(fits) > 1:
                        break
            if len(fits) == 1:
                stats["untyped_select_values"] += 1
                return
            if fits:
                out.append((TYPE, f"{_kind(value)} is ambiguous in select {name} "
                            f"(fits {', '.join(fits)}, ...): write it as a typed parameter"))
            else:
                out.append((TYPE, f"{_kind(value)} is not a value of select {name} (a reference"
                            f"{' to ' + _few(sorted(entities)) if entities else ''} or a typed "
                            f"parameter {_few(sorted(typed))} expected)"))
        v.label = name
        return v

    def _aggregate_validator(self, t: AggregateType) -> Validator:
        kind = t.kind
        elem = self.compile(t.element)
        fast = getattr(elem, "fast", None)
        lo = _bound(t.lower)
        hi = _bound(t.upper)
        if t.lower is None:
            lo = 0
        if t.upper is None:
            hi = None
        skip = lo is _EXPR or hi is _EXPR
        if lo is _EXPR:
            lo = None
        if hi is _EXPR:
            hi = None
        optional_elements = kind == "array" and t.optional
        unique = kind == "set" or t.unique
        label = kind.upper()
        if kind == "array" and lo is not None and hi is not None:
            size_lo = size_hi = hi - lo + 1
            shape = f"ARRAY [{lo}:{hi}] (exactly {size_lo} elements)"
        else:
            size_lo, size_hi = (lo, hi) if kind != "array" else (None, None)
            shape = (f"{label} [{'?' if size_lo is None else size_lo}:"
                     f"{'?' if size_hi is None else size_hi}]")
        stats = self.stats

        def v(value, types_of, out):
            if type(value) is not list:
                out.append((TYPE, f"expected a {label}, found {_kind(value)}"))
                return
            n = len(value)
            if skip:
                stats["bounds_skipped"] += 1
            if (size_lo is not None and n < size_lo) or (size_hi is not None and n > size_hi):
                out.append((BOUNDS, f"{n} element{'s' if n != 1 else ''}, {shape} expected"))
            if fast is not None:
                for x in value:
                    if type(x) not in fast:
                        break
                else:
                    if unique and len(set(value)) != n:
                        _duplicates(value, label, out)
                    return
            for i, x in enumerate(value):
                if x is None:
                    if not optional_elements:
                        out.append((OPTIONAL, f"[{i}]: $ as an element of a {label} "
                                    f"(only ARRAY OF OPTIONAL allows it)"))
                    continue
                if type(x) is dict and x.get("derived") is True:
                    out.append((DERIVED, f"[{i}]: * as an element of a {label}"))
                    continue
                m = len(out)
                elem(x, types_of, out)
                for j in range(m, len(out)):
                    out[j] = (out[j][0], f"[{i}]: {out[j][1]}")
            if unique and n > 1:
                _duplicates(value, label, out)
        v.label = label
        return v


# --------------------------------------------------------------------------
# helpers

class _Expr:
    pass


_EXPR = _Expr()


def _bound(expr):
    """An int, None (``?``) or _EXPR (an expression, not evaluated)."""
    if expr is None:
        return None
    if isinstance(expr, Literal):
        if expr.kind == "integer":
            return expr.value
        if expr.kind == "indeterminate":
            return None
    if (isinstance(expr, UnaryOp) and expr.op in ("-", "+") and isinstance(expr.operand, Literal)
            and expr.operand.kind == "integer"):
        return -expr.operand.value if expr.op == "-" else expr.operand.value
    return _EXPR


def _freeze(v):
    t = type(v)
    if t is list:
        return ("l", tuple(_freeze(x) for x in v))
    if t is dict:
        return ("d", tuple(sorted((k, _freeze(x)) for k, x in v.items())))
    if t is float and v == 0.0:
        return 0.0
    return v


def _duplicates(value: list, label: str, out: list) -> None:
    seen: dict = {}
    dup = []
    for i, x in enumerate(value):
        k = _freeze(x)
        if k in seen:
            dup.append(f"[{i}] = [{seen[k]}] ({_show(x, 20)})")
        else:
            seen[k] = i
    if dup:
        out.append((SET_UNIQUE, f"duplicate members in a {label} that must be unique: "
                    + ", ".join(dup[:5]) + (", ..." if len(dup) > 5 else "")))


def _a(name: str) -> str:
    return ("an " if name[:1] in "aeiou" else "a ") + name


def _accept_any(value, types_of, out) -> None:
    return None


def _all_of(validators: list) -> Validator:
    def v(value, types_of, out):
        for x in validators:
            x(value, types_of, out)
    return v


def _few(names, dot: str = "", n: int = 6) -> str:
    names = list(names)
    shown = ", ".join(f"{dot}{x}{dot}" for x in names[:n])
    return shown + (f", ... ({len(names)} in all)" if len(names) > n else "")


def _slot_str(s: _Slot) -> str:
    return ("*" if s.derived else "") + s.name


# --------------------------------------------------------------------------
# per-schema cache and entry points

_CHECKERS: dict = {}


def checker_for(schema: Schema) -> Checker:
    """The cached Checker of ``schema`` (kept as long as the schema lives)."""
    key = id(schema)
    entry = _CHECKERS.get(key)
    if entry is not None and entry[0]() is schema:
        return entry[1]
    checker = Checker(schema)
    _CHECKERS[key] = (weakref.ref(schema, lambda _r, k=key: _CHECKERS.pop(k, None)), checker)
    return checker


def check_instance(record: dict, schema: Schema, types_of: TypesOf) -> list:
    """The findings of one decoded instance (see the module docstring)."""
    return checker_for(schema).check(record, types_of)


def check_population(records: Iterable[dict], schema: Schema, types_of: TypesOf,
                     derived_values: Optional[set] = None) -> Iterator[Finding]:
    """The findings of every instance, in the order of ``records``; the ids of the
    instances that write a value in a derived slot are added to ``derived_values``."""
    check = checker_for(schema).check
    for record in records:
        yield from check(record, types_of, derived_values)


def step_types_of(step_file, schema: Schema) -> TypesOf:
    """A ``types_of`` over a ``p105cli.step.StepFile``: simple instances
    from the index (no decoding), complex ones decoded once on demand."""
    checker = checker_for(schema)
    closure = checker.closure
    index = step_file.index
    slot = index.slot
    types = index.types
    complex_cache: dict = {}

    def types_of(iid: int):
        k = slot(iid)
        if k < 0:
            return None
        t = types[k]
        if t is not None:
            return closure(t)
        ts = complex_cache.get(iid)
        if ts is None:
            acc: set = set()
            for part in step_file.record(iid).get("complex", ()):
                acc |= closure(part["type"])
            ts = complex_cache[iid] = frozenset(acc)
        return ts
    return types_of
