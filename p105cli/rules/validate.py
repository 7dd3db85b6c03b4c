"""``validate`` without the command line: one file in, one RunResult out.

What is checked, in order:

* ``P21-*``: the reader's syntax and structure errors (the file is then
  unreadable: exit 2) and its warnings;
* ``SCH-*`` conformance of every instance the schema knows
  (``conformance.py``: arity, types, selects, bounds, ``*`` and ``$``,
  references, complex instances);
* the schema's own WHERE, UNIQUE and global rules, evaluated from the
  EXPRESS text (``schema/evaluator/``) on the *kinematic closure*: every
  instance of a Part 105 entity and every instance it references,
  transitively. Geometry that no kinematic entity uses is checked for
  conformance but its rules are not evaluated (a 200k-instance CAD file
  would take minutes, and is not what this tool gates). A rule the
  evaluator cannot evaluate is one ``SCH-NOT-EVALUATED`` note, never a
  silent skip; the summary counts rules evaluated / applicable;
* ``KIN-*`` checks the schema cannot express (``kinematics.py``).
"""

from __future__ import annotations

import linecache
from itertools import chain
from pathlib import Path

from p105cli.part105.catalogue import KINEMATIC_ENTITIES
from p105cli.step.values import record_refs

from .conformance import RULES as CONFORMANCE_RULES
from .conformance import UNKNOWN_ENTITY, check_population
from .derived import RULES as DERIVED_RULES
from .derived import check_derived
from .diagnostics import NOT_EVALUATED, Diagnostic, RunResult, register_rule
from .kinematics import RULES as KINEMATICS_RULES
from .kinematics import check_kinematics

for _rule, _text in {**CONFORMANCE_RULES, **DERIVED_RULES, **KINEMATICS_RULES}.items():
    register_rule(_rule, _text)
register_rule("P21-SYNTAX", "The exchange structure is not valid ISO 10303-21 syntax.")
register_rule("P21-STRUCTURE", "The exchange structure repeats an instance name or is otherwise unusable.")
register_rule("P21-WARNING", "The reader accepted something the ISO 10303-21 grammar does not allow.")
register_rule("P21-ENCODING", "Raw 8-bit bytes that are not UTF-8 were read as ISO 8859-1: their "
                              "characters may be wrong.")
register_rule("P21-SCHEMA", "FILE_SCHEMA names no schema p105 knows; give one with --schema.")


def kinematic_entity_names() -> frozenset:
    """The Part 105 entity names (1996 and AP242 layouts) that start the kinematic closure
    (:data:`p105cli.part105.catalogue.KINEMATIC_ENTITIES`)."""
    return KINEMATIC_ENTITIES


def kinematic_closure(pop) -> list[int]:
    """Ids of the kinematic instances and everything they reference, in id order."""
    schema = pop.schema
    seeds: set[int] = set()
    for name in kinematic_entity_names():
        if name in schema.entities:
            seeds.update(pop.ids_of_type(name, subtypes=True))
    seen = set(seeds)
    todo = list(seeds)
    while todo:
        for r in record_refs(pop.instance(todo.pop()).record):
            if r not in seen and r in pop:  # a dangling reference leads nowhere
                seen.add(r)
                todo.append(r)
    return sorted(seen)


def rule_source(path: str | Path, line: int) -> str:
    """The EXPRESS text of the rule that starts at ``line`` (up to its ';')."""
    parts = []
    for k in range(line, line + 40):
        text = linecache.getline(str(path), k)
        if not text:
            break
        parts.append(text.strip())
        if text.rstrip().endswith(";"):
            break
    return " ".join(parts)


class Validation:
    """Collects the diagnostics of one file."""

    def __init__(self, source: str, doc=None):
        self.source = source
        self.doc = doc
        self.diagnostics: list[Diagnostic] = []
        self.applicable: set = set()
        self.not_evaluated: dict = {}

    def add(self, rule, severity, message, entity=None, entity_type=None, line=None, column=None):
        self.diagnostics.append(Diagnostic(rule, severity, message, self.source, line, column,
                                           entity, entity_type))

    def position(self, pop, iid):
        if pop is None or getattr(self.doc, "index", None) is None:
            return None, None
        lc = pop.instance(iid).line_col
        return (lc[0], lc[1]) if lc else (None, None)


def _type_label(types) -> str:
    return "+".join(sorted(types)) if types else ""


def validate_document(doc, source: str, schema: str | None = None, timings: bool = False) -> RunResult:
    """Validate a StepFile or JsonDocument; raises UnknownSchemaError for an unknown FILE_SCHEMA."""
    import time

    from p105cli.schema.population import Population
    from p105cli.schema.profiles import profile_for_header, stand_in_for

    started = time.perf_counter()
    profile = profile_for_header(doc.header, schema)
    pop = Population(doc, profile)
    v = Validation(source, doc)

    text = getattr(doc, "text", None)
    encoding = getattr(doc, "not_utf8", None)
    summary = encoding.summary() if encoding is not None else None
    for message, offset in getattr(doc, "warnings", ()):
        if (message, offset) == summary:
            continue  # the reader's one-line summary: the lines follow as P21-ENCODING
        line, col = doc.line_col(offset) if text is not None else (None, None)
        v.add("P21-WARNING", "warning", message, line=line, column=col)
    if encoding is not None:
        for message, offset in encoding.details(text):
            line, col = doc.line_col(offset)
            v.add("P21-ENCODING", "warning", message, line=line, column=col)

    def types_of(iid):  # conformance's contract: None for a dangling reference
        return pop.types_of(iid) if iid in pop else None

    stand_in = stand_in_for(doc.header, profile)
    writes_derived: set = set()  # instances with a value in a derived slot
    findings = list(check_population(doc.records(), profile.schema, types_of, writes_derived))
    for f in chain(findings, check_derived(pop, writes_derived)):
        line, col = v.position(pop, f.entity) if f.entity is not None else (None, None)
        message = f"{f.attribute}: {f.message}" if f.attribute else f.message
        severity = f.severity
        if stand_in is not None and f.rule == UNKNOWN_ENTITY:
            # p105 has no long form of the declared schema: it may well know the type
            severity = "warning"
            message += f" ({stand_in}, which FILE_SCHEMA declares, is read as {profile.standard})"
        v.add(f.rule, severity, message, f.entity, f.entity_type, line, col)

    _evaluate_rules(pop, profile, v)

    for f in check_kinematics(pop):
        line, col = v.position(pop, f.entity) if f.entity is not None else (None, None)
        message = f"{f.attribute}: {f.message}" if getattr(f, "attribute", None) else f.message
        v.add(f.rule, f.severity, message, f.entity, f.entity_type, line, col)

    for (rule, reason) in sorted(v.not_evaluated.items()):
        v.add(NOT_EVALUATED, "note", f"{rule} not evaluated: {reason}")
    evaluated = len(v.applicable) - len(v.not_evaluated)
    return RunResult.make(source, v.diagnostics, rules_evaluated=evaluated,
                          rules_applicable=len(v.applicable),
                          seconds=time.perf_counter() - started if timings else 0.0)


def _evaluate_rules(pop, profile, v: Validation) -> None:
    from p105cli.schema.evaluator import Evaluator, NotEvaluable

    ev = Evaluator(pop)
    schema = profile.schema
    closure = kinematic_closure(pop)
    present_types: set = set()
    for iid in closure:
        inst = pop.instance(iid)
        present_types.update(inst.types)
        for ent, w in ev.applicable_where_rules(inst):
            rule = f"SCH-{ent}.{w.label}"
            v.applicable.add(rule)
            if rule in v.not_evaluated:
                continue
            try:
                result = ev.where_rule(inst, ent, w)
            except NotEvaluable as err:
                v.not_evaluated[rule] = str(err)
                continue
            if result is False:
                line, col = v.position(pop, iid)
                v.add(rule, "error", f"violates WHERE rule {ent}.{w.label}: "
                      f"{rule_source(profile.express_path, w.line)}", iid, _type_label(inst.leaf_types),
                      line, col)

    for ent in sorted(present_types):
        entity = schema.entities.get(ent)
        if entity is None:
            continue
        for ur in entity.unique:
            rule = f"SCH-{ent}.{ur.label}"
            v.applicable.add(rule)
            try:
                groups = ev.unique_rule(ent, ur)
            except NotEvaluable as err:
                v.not_evaluated[rule] = str(err)
                continue
            for group in groups:
                first = group[0]
                for inst in group[1:]:
                    line, col = v.position(pop, inst.id)
                    v.add(rule, "error", f"violates UNIQUE rule {ent}.{ur.label}: same values as "
                          f"#{first.id}", inst.id, _type_label(inst.leaf_types), line, col)

    for name in sorted(schema.rules):
        rule_decl = schema.rules[name]
        if not any(e in present_types for e in rule_decl.applies_to):
            continue
        labels = [w.label or f"wr{i}" for i, w in enumerate(rule_decl.where, 1)]
        ids = [f"SCH-{name}.{label}" for label in labels]
        v.applicable.update(ids)
        try:
            results = ev.global_rule(rule_decl)
        except NotEvaluable as err:
            for rid in ids:
                v.not_evaluated[rid] = str(err)
            continue
        for label, result in results.items():
            if result is False:
                v.add(f"SCH-{name}.{label}", "error", f"violates global rule {name}.{label}")


def list_rules(profile) -> list[tuple[str, str]]:
    """Every rule id the profile's schema can report, with its EXPRESS source."""
    schema = profile.schema
    out = [(rule, text) for rule, text in sorted({**CONFORMANCE_RULES, **DERIVED_RULES,
                                                  **KINEMATICS_RULES}.items())]
    for name in sorted(schema.entities):
        entity = schema.entities[name]
        for w in entity.where:
            out.append((f"SCH-{name}.{w.label}", rule_source(profile.express_path, w.line)))
        for ur in entity.unique:
            out.append((f"SCH-{name}.{ur.label}", rule_source(profile.express_path, ur.line)))
    for name in sorted(schema.rules):
        for i, w in enumerate(schema.rules[name].where, 1):
            out.append((f"SCH-{name}.{w.label or f'wr{i}'}", rule_source(profile.express_path, w.line)))
    return out
