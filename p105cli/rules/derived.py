"""Explicit values where the schema derives: a harmless copy, or a contradiction.

ISO 10303-21 writes ``*`` for an attribute that a subtype re-declares as
DERIVE. Real producers often write the value instead (the dimensions of a
conversion-based unit, the freedom flags of a low-order pair, the name of
a kinematic pair). Whether that matters depends on the value: a copy of
what the schema derives is harmless, a different value is an
interoperability break (a reader that follows the schema sees another
mechanism than the writer meant). So each explicit value in a derived slot
is compared with the derivation, evaluated from the EXPRESS text
(``schema/evaluator``):

=====================  =====================================================
rule                   finding
=====================  =====================================================
SCH-DERIVED-EXPLICIT   (warning) the values equal the derivation (or the
                       derivation cannot be evaluated, said in the
                       message); write ``*``
SCH-DERIVED-CONFLICT   (error) a value differs from the derivation; the
                       message says both, in the domain's words where it
                       can (freedoms of a low-order pair, dimensions of a
                       unit)
=====================  =====================================================

One finding per instance and rule, naming all its attributes concerned.
The edition matters: the attributes an edition keeps explicit that a later
one derives (``Profile.explicit_derivations``, AP214 edition 1's
``conversion_based_unit.dimensions``) are conforming when written; they
are compared with the later derivation all the same, and a contradiction
is ``SCH-DERIVED-CONFLICT`` (AP242 states that rule as
``conversion_based_unit.wr1``).

Only the instances that write a value in a derived slot are looked at
(``conformance.check_population`` collects them as it decodes every record
anyway), and those of the edition's explicit derivations, from the type
index: a large file costs next to nothing.

Entry point: ``check_derived(pop, candidates=None) -> list[Finding]``.
"""

from __future__ import annotations

from ..kinematics.freedoms import FREEDOM_NAMES, motion_in_words
from ..schema.evaluator import EntityValue, EnumValue, Evaluator, NotEvaluable, TypedValue
from ..schema.instance import Instance
from ..schema.model import BinaryOp, Name
from .conformance import ERROR, WARNING, Finding, _a

__all__ = ["DERIVED_EXPLICIT", "DERIVED_CONFLICT", "RULES", "check_derived"]

DERIVED_EXPLICIT = "SCH-DERIVED-EXPLICIT"
DERIVED_CONFLICT = "SCH-DERIVED-CONFLICT"

RULES = {
    DERIVED_EXPLICIT: "A derived attribute is written as a value equal to its derivation instead "
                      "of '*'.",
    DERIVED_CONFLICT: "A value written where the schema derives the attribute contradicts the "
                      "derivation.",
}

# Instance equality for values the population holds (a context, a list of edges), value
# equality for values the derivation builds (the dimensions of a unit).
_SAME_INSTANCE = BinaryOp(":=:", Name("file_value"), Name("derived_value"))
_SAME_VALUE = BinaryOp("=", Name("file_value"), Name("derived_value"))

_DIMENSIONS = (("length_exponent", "length"), ("mass_exponent", "mass"), ("time_exponent", "time"),
               ("electric_current_exponent", "current"),
               ("thermodynamic_temperature_exponent", "temperature"),
               ("amount_of_substance_exponent", "amount"),
               ("luminous_intensity_exponent", "luminous intensity"))


def _derived_entities(schema, profile) -> dict:
    """{entity: [(supertype, attribute, later derivation or None)]} of every entity that
    re-declares an attribute as DERIVE, or whose derivation the edition left out."""
    out: dict = {}
    for name, ent in schema.entities.items():
        for a in ent.derived:
            if a.supertype is not None:
                out.setdefault(name, []).append((a.supertype, a.name, None))
    for (supertype, attribute), (entity, decl) in getattr(profile, "explicit_derivations",
                                                          {}).items():
        if entity in schema.entities:
            out.setdefault(entity, []).append((supertype, attribute, decl))
    return out


def check_derived(pop, candidates=None) -> list:
    """The SCH-DERIVED-EXPLICIT / SCH-DERIVED-CONFLICT findings of ``pop``, in id order.

    ``candidates``: the ids of the instances that write a value in a derived slot, when
    known (``conformance.check_population`` collects them while it decodes every record);
    else every instance of an entity type that re-declares an attribute as DERIVE is looked
    at. The instances of the edition's explicit derivations are looked at either way."""
    profile = pop.profile
    _ = profile.schema if profile is not None else None  # loads explicit_derivations
    entities = _derived_entities(pop.schema, profile)
    ids: set = set()
    for name, specs in entities.items():
        if candidates is None or any(decl is not None for *_, decl in specs):
            ids.update(pop.ids_of_type(name, subtypes=True))
    if candidates is not None:
        ids.update(i for i in candidates if i in pop)
    if not ids:
        return []
    ev = Evaluator(pop)
    standard = getattr(profile, "standard", None) or (pop.schema.name or "the schema")
    out: list = []
    for iid in sorted(ids):
        inst = pop.instance(iid)
        equal, differ, unknown = [], [], []
        for i, slot in enumerate(inst.layout.slots):
            raw = inst.raw(i)
            if raw is None or (type(raw) is dict and raw.get("derived") is True):
                continue  # '$' and '*' are conformance's business
            decl = None
            if not slot.derived:
                decl = _later_derivation(inst, slot, entities)
                if decl is None:
                    continue
            try:
                file_value = ev.convert(raw, slot.type, inst)
                derived = (ev.attribute(inst, slot.name, group=slot.entity) if decl is None
                           else ev.eval(decl[1].expr, self_obj=inst, ctx=decl[0]))
                same = ev.eval(_SAME_VALUE if type(derived) is EntityValue else _SAME_INSTANCE,
                               variables={"file_value": file_value, "derived_value": derived})
            except NotEvaluable as err:
                unknown.append((slot, str(err)))
                continue
            if same is True:
                if decl is None:
                    equal.append((slot, file_value))
            elif same is False:
                differ.append((slot, file_value, derived, decl))
            else:
                unknown.append((slot, "the derivation gives ? (indeterminate)"))
        etype = _type_label(inst.record)
        if differ:
            out.append(Finding(DERIVED_CONFLICT, ERROR, _conflict(ev, inst, differ, standard),
                               iid, etype, _names(s for s, *_ in differ)))
        if equal:
            shown = ", ".join(f"{s.name} = {_show(ev, v)}" for s, v in equal)
            out.append(Finding(DERIVED_EXPLICIT, WARNING,
                               f"written where {standard} derives {_it(equal)} ({shown}, equal to "
                               f"the derivation): write *", iid, etype, _names(s for s, _ in equal)))
        for slot, reason in unknown:
            if slot.derived:
                out.append(Finding(DERIVED_EXPLICIT, WARNING,
                                   f"written where {standard} derives it: write *; not compared "
                                   f"with the derivation ({reason})", iid, etype, slot.name))
    return out


def _later_derivation(inst, slot, entities):
    """(entity, DerivedAttribute) a later edition derives ``slot`` with, for an instance of
    that entity, else None."""
    for name in inst.types:
        for supertype, attribute, decl in entities.get(name, ()):
            if decl is not None and (supertype, attribute) == slot.key:
                return name, decl
    return None


def _conflict(ev, inst, differ, standard) -> str:
    said = ", ".join(f"{s.name} = {_show(ev, f)}" for s, f, _, _ in differ)
    derived = ", ".join(f"{s.name} = {_show(ev, d)}" for s, _, d, _ in differ)
    if all(decl is not None for *_, decl in differ):
        text = (f"file says {said}; the edition 3 long form derives {derived} ({standard} "
                f"writes it explicitly, and it must agree)")
    else:
        text = f"file says {said}; {standard} derives {derived}"
    if any(s.name in FREEDOM_NAMES for s, *_ in differ):
        text += _freedoms_in_words(ev, inst, differ)
    return text


def _freedoms_in_words(ev, inst, differ) -> str:
    """'(the file's pair allows translation along z; a prismatic_pair allows translation along x)'."""
    file_flags, derived_flags = {}, {}
    for i, slot in enumerate(inst.layout.slots):
        if slot.name not in FREEDOM_NAMES:
            continue
        try:
            d = ev.attribute(inst, slot.name, group=slot.entity)
        except NotEvaluable:
            return ""
        derived_flags[slot.name] = d
        raw = inst.raw(i)
        written = not (raw is None or (type(raw) is dict and raw.get("derived") is True))
        file_flags[slot.name] = ev.convert(raw, slot.type, inst) if written else d

    def words(flags):
        return motion_in_words([flags.get(n) is True for n in FREEDOM_NAMES])
    leaf = "+".join(sorted(inst.leaf_types))
    return f" (the file's pair allows {words(file_flags)}; {_a(leaf)} allows {words(derived_flags)})"


def _show(ev, v, depth: int = 0) -> str:
    """A value in EXPRESS words: TRUE, 'text', 2.5, #12, .ITEM., (a, b), units in dimensions."""
    if v is True:
        return "TRUE"
    if v is False:
        return "FALSE"
    if v is None:
        return "UNKNOWN"
    t = type(v)
    if t is float or t is int:
        return repr(v)
    if t is str:
        return "'" + (v if len(v) <= 40 else v[:40] + "...") + "'"
    if t is Instance or t is EntityValue:
        dims = _dimensions(ev, v)
        if t is Instance:
            return f"#{v.id}" + (f" ({dims})" if dims else "")
        return dims or "+".join(sorted(v.leaf_types)) + "(...)"
    if t is EnumValue:
        return f".{v.item.upper()}."
    if t is TypedValue:
        return _show(ev, v.value, depth)
    try:
        items = list(v)
    except TypeError:
        return "?"
    if depth > 1:
        return "(...)"
    shown = ", ".join(_show(ev, x, depth + 1) for x in items[:4])
    return "(" + shown + (", ..." if len(items) > 4 else "") + ")"


def _dimensions(ev, v) -> str:
    """Dimensional exponents in words ('length', 'mass time^-2', 'dimensionless'), else ''."""
    if "dimensional_exponents" not in v.types:
        return ""
    parts = []
    for attr, word in _DIMENSIONS:
        try:
            e = ev.attribute(v, attr)
        except NotEvaluable:
            return ""
        if type(e) not in (int, float):
            return ""
        if e:
            parts.append(word if e == 1 else f"{word}^{e:g}")
    return " ".join(parts) or "dimensionless"


def _type_label(record: dict) -> str:
    parts = record.get("complex")
    if parts is not None:
        return "+".join(str(p.get("type")) for p in parts)
    return str(record.get("type"))


def _names(slots) -> str:
    return ", ".join(s.name for s in slots)


def _it(items) -> str:
    return "it" if len(items) == 1 else "them"
