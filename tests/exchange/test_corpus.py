"""The authored corpus (p105cli.corpus): determinism, syntax, schema conformance, geometry.

The schema check here stands in until the validator lands: for every
instance of every corpus file, against the EXPRESS long form of its
profile (AP214 ed3 for ``ap214`` and ``p105``, AP242 N10962 for
``ap242``): the entity exists and is not abstract (complex instances: all
partial entities exist, are closed under supertypes, sorted, name no
ONEOF-exclusive pair, and no leaf is abstract), the attribute count is the
Part 21 one, ``*`` stands exactly at derived slots, ``$`` only at OPTIONAL
ones, and every value has its attribute's type (references to instances of
a compatible entity, selects of defined types typed, enumeration items
known, reals as reals). The ``p105`` profile adds ``su_parameters`` (as in
ISO 10303-105:1996: a geometric_representation_item, and a
``rigid_placement``).
"""

from __future__ import annotations

import json
import math
from functools import lru_cache

import numpy as np
import pytest

from conftest import ROOT, SHARED
from p105cli.corpus import EXAMPLES, MECHANISMS, PROFILES, file_name, write_text
from p105cli.schema import load_schema
from p105cli.schema.model import AggregateType, GenericType, Literal, NamedType, SelectType, SimpleType
from p105cli.step import read_step

CORPUS_DIR = ROOT / "tests" / "data" / "corpus"
SCHEMA_DIR = SHARED / "schema"
LONG_FORMS = {
    "ap214": SCHEMA_DIR / "AP214E3_2010_automotive_design_longform.exp",
    "p105": SCHEMA_DIR / "AP214E3_2010_automotive_design_longform.exp",
    "ap242": SCHEMA_DIR / "AP242_N10962_mim_lf.exp",
}
REFERENCE = SHARED / "reference" / "dh_arms_and_loops.json"

CASES = [(m, p) for m in MECHANISMS for p in PROFILES]
IDS = [file_name(m, p) for m, p in CASES]


@lru_cache(maxsize=None)
def generated(mechanism: str, profile: str) -> str:
    return write_text(mechanism, profile)


@lru_cache(maxsize=None)
def parsed(mechanism: str, profile: str) -> dict:
    f = read_step(generated(mechanism, profile), file_name(mechanism, profile))
    return {r["id"]: r for r in f.records()}


@lru_cache(maxsize=None)
def schema_for(profile: str):
    path = LONG_FORMS[profile]
    if not path.is_file():
        pytest.skip(f"long form not available: {path}")
    return load_schema(path)


# ---------------------------------------------------------------- files on disk

@pytest.mark.parametrize("mechanism,profile", CASES, ids=IDS)
def test_committed_file_is_regenerated_byte_for_byte(mechanism, profile):
    path = CORPUS_DIR / file_name(mechanism, profile)
    assert path.is_file(), f"{path} missing: run python3 -m p105cli.corpus tests/data/corpus"
    assert path.read_bytes() == generated(mechanism, profile).encode("ascii")


def test_generation_is_deterministic():
    m, p = "spherical_linkage", "ap242"
    assert write_text(m, p) == write_text(m, p)


def test_corpus_directory_holds_exactly_the_corpus():
    on_disk = sorted(x.name for x in CORPUS_DIR.iterdir())
    assert on_disk == sorted([*IDS, "README.md"])
    from p105cli.corpus import readme_text
    assert (CORPUS_DIR / "README.md").read_text(encoding="utf-8") == readme_text()


@pytest.mark.parametrize("example,source", sorted(EXAMPLES.items()))
def test_examples_are_corpus_copies(example, source):
    path = ROOT / "examples" / example
    assert path.is_file()
    mechanism, profile = source[:-4].rsplit("_", 1)
    text = path.read_text(encoding="ascii")
    assert text == write_text(mechanism, profile, name=example)
    # the same file as the corpus one but for its FILE_NAME
    assert text.replace(example, source, 1) == generated(mechanism, profile)


def test_generate_writes_all_files(tmp_path):
    from p105cli.corpus import generate
    written = generate(tmp_path / "c", tmp_path / "e")
    assert len(written) == len(CASES) + len(EXAMPLES) + 1
    for m, p in CASES:
        assert (tmp_path / "c" / file_name(m, p)).read_text() == generated(m, p)


# ---------------------------------------------------------------- syntax

@pytest.mark.parametrize("mechanism,profile", CASES, ids=IDS)
def test_parses(mechanism, profile):
    f = read_step(generated(mechanism, profile), file_name(mechanism, profile))
    assert not f.warnings
    records = list(f.records())
    assert [r["id"] for r in records] == list(range(1, len(records) + 1))
    assert f.header["file_schema"] == [PROFILES[profile]["schema"]]


# ---------------------------------------------------------------- schema conformance

class SchemaCheck:
    """Instance-level conformance of JSON-model records to an EXPRESS schema."""

    def __init__(self, schema, profile: str):
        self.s = schema
        self.extra: dict = {}  # entity -> (supertypes incl. itself, [(name, type, optional, derived)])
        self.extra_select: dict = {}
        if profile == "p105":
            ap242 = schema_for("ap242")
            slots = [(a.name, a.type, a.optional, a.derived) for a in ap242.p21_attributes("su_parameters")]
            self.extra["su_parameters"] = ({"su_parameters", "geometric_representation_item",
                                            "representation_item"}, slots)
            self.extra_select["rigid_placement"] = {"su_parameters"}
        self.errors: list[str] = []

    # types of an instance
    def entity_types(self, name: str) -> set:
        name = name.lower()
        if name in self.extra:
            return set(self.extra[name][0])
        return {name, *self.s.all_supertypes(name)}

    def record_types(self, rec: dict) -> set:
        if "complex" in rec:
            out = set()
            for part in rec["complex"]:
                out |= self.entity_types(part["type"])
            return out
        return self.entity_types(rec["type"])

    def known(self, name: str) -> bool:
        return name.lower() in self.s.entities or name.lower() in self.extra

    # the slots of a simple instance / of one partial entity of a complex instance
    def simple_slots(self, name: str) -> list:
        if name in self.extra:
            return self.extra[name][1]
        return [(a.name, a.type, a.optional, a.derived) for a in self.s.p21_attributes(name)]

    def partial_slots(self, part: str, present: set) -> list:
        s = self.s
        ent = s.entity(part)
        out = []
        for a in ent.attributes:
            if a.supertype is not None:
                continue
            typ, optional, derived, depth = a.type, a.optional, False, -1
            for other in present:
                e = s.entity(other)
                level = len(s.all_supertypes(other))
                for r in e.attributes:
                    if r.supertype is not None:
                        res = s.resolve_attribute(r.supertype, r.name)
                        if res is not None and res[0] == ent.name and res[1].name == a.name and level > depth:
                            typ, optional, depth = r.type, r.optional, level
                for r in e.derived:
                    if r.supertype is not None:
                        res = s.resolve_attribute(r.supertype, r.name)
                        if res is not None and res[0] == ent.name and res[1].name == a.name:
                            derived = True
            out.append((a.name, typ, optional, derived))
        return out

    # values
    def flatten_select(self, name: str, seen=None) -> tuple[set, set]:
        """(entity names, defined type names) a select type admits."""
        seen = seen or set()
        ents, types = set(self.extra_select.get(name, ())), set()
        decl = self.s.types[name]
        for item in decl.underlying.items:
            item = item.lower()
            if item in self.s.entities:
                ents.add(item)
            elif item in self.s.types and item not in seen:
                seen.add(item)
                if isinstance(self.s.types[item].underlying, SelectType):
                    e2, t2 = self.flatten_select(item, seen)
                    ents |= e2
                    types |= t2
                else:
                    types.add(item)
        return ents, types

    def check_value(self, v, ts, where: str, records: dict):
        err = self.errors.append
        if isinstance(ts, GenericType):
            return
        if isinstance(ts, SimpleType):
            kind = ts.name.lower()
            ok = {"real": type(v) is float, "number": type(v) in (float, int), "integer": type(v) is int,
                  "string": type(v) is str,
                  "boolean": isinstance(v, dict) and v.get("enum") in ("T", "F"),
                  "logical": isinstance(v, dict) and v.get("enum") in ("T", "F", "U"),
                  "binary": isinstance(v, dict) and "binary" in v}[kind]
            if not ok:
                err(f"{where}: {v!r} is not a {kind.upper()}")
            return
        if isinstance(ts, AggregateType):
            if type(v) is not list:
                err(f"{where}: {v!r} is not an aggregate")
                return
            lo, hi = ts.lower, ts.upper
            if isinstance(lo, Literal) and lo.kind == "integer" and len(v) < lo.value:
                err(f"{where}: {len(v)} elements, at least {lo.value} required")
            if isinstance(hi, Literal) and hi.kind == "integer" and len(v) > hi.value:
                err(f"{where}: {len(v)} elements, at most {hi.value} allowed")
            if ts.kind in ("set", "bag") or ts.unique:
                refs = [x["ref"] for x in v if isinstance(x, dict) and "ref" in x]
                if len(refs) != len(set(refs)):
                    err(f"{where}: the same instance twice in a {ts.kind.upper()}")
            for i, x in enumerate(v):
                if x is None:
                    if not ts.optional:
                        err(f"{where}[{i}]: $ in an aggregate of non-optional elements")
                    continue
                self.check_value(x, ts.element, f"{where}[{i}]", records)
            return
        if isinstance(ts, NamedType):
            name = ts.name.lower()
            if name in self.s.entities or name in self.extra:
                self.check_ref(v, {name}, where, records)
                return
            decl = self.s.types.get(name)
            if decl is None:
                err(f"{where}: unknown type {name}")
                return
            u = decl.underlying
            if isinstance(u, SelectType):
                ents, types = self.flatten_select(name)
                if isinstance(v, dict) and "ref" in v:
                    self.check_ref(v, ents, where, records)
                elif isinstance(v, dict) and set(v) == {"type", "value"}:
                    t = v["type"].lower()
                    if t not in types:
                        err(f"{where}: typed {t.upper()} is not a choice of select {name}")
                    else:
                        self.check_value(v["value"], NamedType(t), where + f"/{t}", records)
                else:
                    err(f"{where}: untyped value {v!r} for select {name} (defined types must be typed)")
                return
            if isinstance(u, type(None)):
                return
            from p105cli.schema.model import EnumerationType
            if isinstance(u, EnumerationType):
                if not (isinstance(v, dict) and set(v) == {"enum"} and v["enum"].lower() in u.items):
                    err(f"{where}: {v!r} is not an item of {name} {u.items}")
                return
            self.check_value(v, u, where, records)
            return
        err(f"{where}: cannot check type {ts!r}")

    def check_ref(self, v, allowed: set, where: str, records: dict):
        if not (isinstance(v, dict) and set(v) == {"ref"}):
            self.errors.append(f"{where}: {v!r} is not a reference (expected {sorted(allowed)})")
            return
        target = records.get(v["ref"])
        if target is None:
            self.errors.append(f"{where}: #{v['ref']} does not exist")
            return
        if not (self.record_types(target) & allowed):
            kind = target.get("type") or "+".join(p["type"] for p in target["complex"])
            self.errors.append(f"{where}: #{v['ref']} is a {kind}, not a {' or '.join(sorted(allowed))}")

    def check_slots(self, args: list, slots: list, where: str, records: dict):
        if len(args) != len(slots):
            self.errors.append(f"{where}: {len(args)} arguments, {len(slots)} expected "
                               f"({', '.join(('*' if d else '') + n for n, _, _, d in slots)})")
            return
        for v, (name, typ, optional, derived) in zip(args, slots):
            w = f"{where}.{name}"
            if derived:
                if v != {"derived": True}:
                    self.errors.append(f"{w}: derived attribute must be *, not {v!r}")
                continue
            if v == {"derived": True}:
                self.errors.append(f"{w}: * at an explicit attribute")
            elif v is None:
                if not optional:
                    self.errors.append(f"{w}: $ at a non-optional attribute")
            else:
                self.check_value(v, typ, w, records)

    def oneof_clashes(self, present: set) -> list:
        """Pairs of entities in ``present`` that a ONEOF of some supertype excludes."""
        s, out = self.s, []

        def covered(operand) -> bool:
            if isinstance(operand, str):
                return any(operand == p or operand in s.all_supertypes(p) for p in present)
            return any(covered(o) for o in operand.operands)

        def walk(expr):
            if isinstance(expr, str) or expr is None:
                return
            if expr.op == "oneof":
                hit = [o for o in expr.operands if covered(o)]
                if len(hit) > 1:
                    out.append(hit)
            for o in expr.operands:
                walk(o)

        for name in present:
            walk(s.entity(name).supertype_expr)
        return out

    def check_record(self, rec: dict, records: dict):
        where = f"#{rec['id']}"
        if "complex" in rec:
            names = [p["type"] for p in rec["complex"]]
            if names != sorted(names):
                self.errors.append(f"{where}: partial entities not in alphabetical order")
            unknown = [n for n in names if not self.known(n)]
            if unknown:
                self.errors.append(f"{where}: unknown entities {unknown}")
                return
            present = set(names)
            for n in names:
                missing = set(self.s.all_supertypes(n)) - present
                if missing:
                    self.errors.append(f"{where}: {n} needs its supertypes {sorted(missing)} in the instance")
            leaves = [n for n in names if not any(n in self.s.all_supertypes(m) for m in names)]
            if len(leaves) < 2:
                self.errors.append(f"{where}: a complex instance of the single leaf {leaves} (use a simple one)")
            for n in leaves:
                if self.s.entity(n).abstract:
                    self.errors.append(f"{where}: abstract leaf {n}")
            for clash in self.oneof_clashes(present):
                self.errors.append(f"{where}: ONEOF excludes {clash} together")
            for part in rec["complex"]:
                self.check_slots(part["args"], self.partial_slots(part["type"], present),
                                 f"{where} {part['type'].upper()}", records)
            return
        name = rec["type"]
        if not self.known(name):
            self.errors.append(f"{where}: unknown entity {name}")
            return
        if name not in self.extra and self.s.entity(name).abstract:
            self.errors.append(f"{where}: {name} is abstract")
        self.check_slots(rec["args"], self.simple_slots(name), f"{where} {name.upper()}", records)


def schema_errors(mechanism: str, profile: str) -> list[str]:
    records = parsed(mechanism, profile)
    check = SchemaCheck(schema_for(profile), profile)
    for rec in records.values():
        check.check_record(rec, records)
    return check.errors


@pytest.mark.parametrize("mechanism,profile", CASES, ids=IDS)
def test_conforms_to_the_long_form(mechanism, profile):
    errors = schema_errors(mechanism, profile)
    assert not errors, "\n".join(errors[:40])


def test_su_parameters_only_where_allowed():
    for m in MECHANISMS:
        for p in PROFILES:
            types = {r.get("type") for r in parsed(m, p).values()}
            if p == "ap214":
                assert "su_parameters" not in types
    assert any(r.get("type") == "su_parameters" for r in parsed("ur5_arm", "p105").values())
    assert any(r.get("type") == "su_parameters" for r in parsed("ur5_arm", "ap242").values())


def test_the_checker_catches_mistakes():
    """The conformance check is not vacuous."""
    records = {k: dict(v) for k, v in parsed("four_bar", "ap214").items()}
    pair = next(r for r in records.values() if r.get("type") == "revolute_pair")
    value = next(r for r in records.values() if r.get("type") == "revolute_pair_value")
    rng = next(r for r in records.values() if r.get("type") == "revolute_pair_range")
    link = next(r for r in records.values() if r.get("type") == "kinematic_link")
    bad = {
        "count": dict(pair, args=pair["args"][:-1]),
        "ref": dict(value, args=[{"ref": link["id"]}, value["args"][1]]),
        "dollar": dict(pair, args=[pair["args"][0], pair["args"][1], None, *pair["args"][3:]]),
        "star": dict(value, args=[value["args"][0], {"derived": True}]),
        "untyped select": dict(rng, args=[rng["args"][0], 1.0, 2.0]),
        "integer for real": dict(value, args=[value["args"][0], 3]),
        "unknown": {"id": 10**6, "type": "rigid_link_representation", "args": []},
        "su in ap214": {"id": 10**6, "type": "su_parameters", "args": ["", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]},
    }
    for what, rec in bad.items():
        check = SchemaCheck(schema_for("ap214"), "ap214")
        check.check_record(rec, records)
        assert check.errors, what
    records = {k: dict(v) for k, v in parsed("four_bar", "ap242").items()}
    pair = next(r for r in records.values() if r.get("type") == "revolute_pair_with_range")
    actuated = next(r for r in records.values()
                    if "complex" in r and r["complex"][0]["type"] == "actuated_kinematic_pair")
    bad = {
        "abstract": dict(pair, type="kinematic_pair", args=pair["args"][:6]),
        "not derived": dict(pair, args=[*pair["args"][:6], {"enum": "F"}, *pair["args"][7:]]),
        "missing supertype": dict(actuated, complex=[p for p in actuated["complex"]
                                                      if p["type"] != "item_defined_transformation"]),
        "order": dict(actuated, complex=actuated["complex"][::-1]),
        "oneof": dict(actuated, complex=sorted(actuated["complex"] + [
            {"type": "prismatic_pair", "args": []}], key=lambda p: p["type"])),
        "enum item": dict(actuated, complex=[dict(p, args=[{"enum": "SIDEWAYS"}] * 6)
                                             if p["type"] == "actuated_kinematic_pair" else p
                                             for p in actuated["complex"]]),
    }
    for what, rec in bad.items():
        check = SchemaCheck(schema_for("ap242"), "ap242")
        check.check_record(rec, records)
        assert check.errors, what


# ---------------------------------------------------------------- geometry read back from the files

def _matrix_axis2(records, ref) -> np.ndarray:
    rec = records[ref["ref"]]
    assert rec["type"] == "axis2_placement_3d"
    _, loc, axis, refdir = rec["args"]
    p = np.array(records[loc["ref"]]["args"][1])
    z = np.array(records[axis["ref"]]["args"][1])
    x = np.array(records[refdir["ref"]]["args"][1])
    z = z / np.linalg.norm(z)
    x = x - (x @ z) * z
    x = x / np.linalg.norm(x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, np.cross(z, x), z, p
    return T


def _rz(q):
    c, s = math.cos(q), math.sin(q)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def _tx(d, axis):
    T = np.eye(4)
    T[axis, 3] = d
    return T


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    T = np.eye(4)
    T[1:3, 1:3] = [[c, -s], [s, c]]
    return T


def _su(records, ref, factor) -> np.ndarray:
    """Tz(c) Rz(gamma) Tx(a) Rx(alpha) Tz(b) Rz(beta) (ISO 10303-105 5.4.17), composed here."""
    _, a, alpha, b, beta, c, gamma = records[ref["ref"]]["args"]
    return (_tx(c, 2) @ _rz(gamma * factor) @ _tx(a, 0) @ _rx(alpha * factor) @ _tx(b, 2)
            @ _rz(beta * factor))


def _placement(records, ref, factor):
    if records[ref["ref"]].get("type") == "su_parameters":
        return _su(records, ref, factor)
    return _matrix_axis2(records, ref)


def _degree_factor(records) -> float:
    for r in records.values():
        if "complex" in r:
            parts = {p["type"]: p["args"] for p in r["complex"]}
            if "conversion_based_unit" in parts and "plane_angle_unit" in parts:
                name, mwu = parts["conversion_based_unit"]
                assert name == "DEGREE"
                value = records[mwu["ref"]]["args"][0]
                assert value["type"] == "PLANE_ANGLE_MEASURE"
                return value["value"]
    raise AssertionError("no degree unit")


def _args_of(rec, entity):
    """The arguments of a simple instance, or of the named part of a complex one."""
    if "complex" in rec:
        return {p["type"]: p["args"] for p in rec["complex"]}
    return {rec["type"]: rec["args"]}


def _to_radians(raw, kind, factor):
    return raw * factor if kind in ("revolute", "gear") and type(raw) is float else raw


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    T = np.eye(4)
    T[0, 0], T[0, 2], T[2, 0], T[2, 2] = c, s, -s, c
    return T


def _motion_from_file(records, pair, value, kind, layout, factor, P1):
    """The motion of a gear, rack-and-pinion or point-on-planar-curve pair, composed here
    from the pair's and the value's attributes (conventions: p105cli.corpus.geometry)."""
    off = 0 if layout == "1996" else 1  # AP242 pairs and values carry a name first (and a * in pairs)
    pa = pair["args"]
    va = value["args"]
    if kind == "gear":
        r1, r2, _, _, ratio = pa[5 + off:10 + off]
        q1 = va[1 + off] * factor
        return _rz(-q1) @ _tx(r1 + r2, 0) @ _rz(-ratio * q1)
    if kind == "rack_and_pinion":
        r = pa[5 + off]
        d = va[1 + off]
        return _tx(d, 0) @ _tx(r, 1) @ _rz(-d / r)
    if kind == "point_on_planar_curve":
        point = records[va[1 + off]["ref"]]["args"]
        circle = records[point[1]["ref"]]["args"]
        u = point[2] * factor
        C = _matrix_axis2(records, circle[1]) @ np.array([circle[2] * math.cos(u), circle[2] * math.sin(u), 0, 1])
        if layout != "1996":  # the curve is in the link's frame, not the pair frame's
            C = np.linalg.inv(P1) @ C
        orient = va[2 + off]
        if layout == "1996":
            assert orient["type"] == "YPR_ROTATION"
            yaw, pitch, roll = (a * factor for a in orient["value"])
            R = _rx(roll) @ _ry(pitch) @ _rz(yaw)
        else:
            rot = records[orient["ref"]]["args"]
            k = np.array(records[rot[1]["ref"]]["args"][1])
            a = rot[2] * factor
            K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
            R = np.eye(4)
            R[:3, :3] = np.eye(3) + math.sin(a) * K + (1 - math.cos(a)) * K @ K
        T = np.eye(4)
        T[:3, 3] = C[:3]
        return T @ R
    raise AssertionError(kind)


def state_pairs(mechanism: str, profile: str, state: int = 0):
    """[(first link, second link, P1, P2, kind, value, name)] of one state, read from the file:
    state 0 is the initial state, then the configurations of the motion program.

    Links are identified by instance id; angles converted from the file's unit to radians."""
    records = parsed(mechanism, profile)
    factor = _degree_factor(records)
    layout = PROFILES[profile]["layout"]
    out = []
    if layout == "1996":
        states = [next(r for r in records.values() if r.get("type") == "initial_state")["args"][1]]
        states += [r["args"][0] for r in records.values() if r.get("type") == "configuration_definition"][1:]
        for vref in states[state]:
            v = records[vref["ref"]]
            pair = records[v["args"][0]["ref"]]
            name, _, i1, i2, jref = pair["args"][:5]
            joint = records[jref["ref"]]["args"]
            kind = pair["type"][:-5]
            P1, P2 = _placement(records, i1, factor), _placement(records, i2, factor)
            if kind in ("revolute", "prismatic"):
                value = _to_radians(v["args"][1], kind, factor)
            else:
                value = _motion_from_file(records, pair, v, kind, layout, factor, P1)
            out.append((joint[0]["ref"], joint[1]["ref"], P1, P2, kind, value, name))
    else:
        states = [r for r in records.values() if r.get("type") == "mechanism_state_representation"]
        assert states[0]["args"][0] == "initial state"
        for vref in states[state]["args"][1]:
            v = records[vref["ref"]]
            pair = records[v["args"][1]["ref"]]
            if "complex" in pair:
                parts = {p["type"]: p["args"] for p in pair["complex"]}
                name = parts["representation_item"][0]
                _, _, i1, i2 = parts["item_defined_transformation"]
                jref = parts["kinematic_pair"][0]
                kind = next(k for k in ("revolute", "prismatic") if f"{k}_pair" in parts)
            else:
                name, _, _, i1, i2, jref = pair["args"][:6]
                kind = pair["type"].replace("_with_range", "")[:-5]
            joint = records[jref["ref"]]["args"]
            P1, P2 = _placement(records, i1, factor), _placement(records, i2, factor)
            if kind in ("revolute", "prismatic"):
                value = _to_radians(v["args"][2], kind, factor)
            else:
                value = _motion_from_file(records, pair, v, kind, layout, factor, P1)
            out.append((joint[1]["ref"], joint[2]["ref"], P1, P2, kind, value, name))
    return out


def initial_pairs(mechanism: str, profile: str):
    return state_pairs(mechanism, profile, 0)


def close_loops(mechanism: str, profile: str, state: int = 0):
    """Link poses from a spanning tree of the pairs, and the residuals of the other pairs."""
    slide = PROFILES[profile]["slide_axis"]
    pairs = state_pairs(mechanism, profile, state)

    def motion(kind, q):
        if isinstance(q, np.ndarray):
            return q
        return _rz(q) if kind == "revolute" else _tx(q, slide)

    base = pairs[0][0]
    poses = {base: np.eye(4)}
    todo = list(pairs)
    progress = True
    while progress:
        progress = False
        for pr in list(todo):
            a, b, P1, P2, kind, q, _ = pr
            if a in poses and b not in poses:
                poses[b] = poses[a] @ P1 @ motion(kind, q) @ np.linalg.inv(P2)
            elif b in poses and a not in poses:
                poses[a] = poses[b] @ P2 @ np.linalg.inv(motion(kind, q)) @ np.linalg.inv(P1)
            else:
                continue
            todo.remove(pr)
            progress = True
    residuals = {name: float(np.abs(poses[a] @ P1 @ motion(kind, q) - poses[b] @ P2).max())
                 for a, b, P1, P2, kind, q, name in todo}
    return poses, residuals


@pytest.mark.parametrize("profile", list(PROFILES))
def test_four_bar_closes_at_the_initial_state(profile):
    poses, residuals = close_loops("four_bar", profile)
    assert len(poses) == 4
    assert list(residuals) == ["D"]
    assert residuals["D"] < 1e-9


LOOPS = {"four_bar": 1, "slider_crank": 1, "ur5_arm": 0, "gear_train": 2, "rack_and_pinion": 1,
         "cam_follower": 1, "spherical_linkage": 1}


@pytest.mark.parametrize("mechanism", list(MECHANISMS))
@pytest.mark.parametrize("profile", list(PROFILES))
@pytest.mark.parametrize("state", [0, 1, 2])
def test_loops_close_in_every_state(mechanism, profile, state):
    """Every pair's motion, composed from the file's placements and values, closes every loop."""
    poses, residuals = close_loops(mechanism, profile, state)
    assert len(poses) == len(MECHANISMS[mechanism]().links)
    assert len(residuals) == LOOPS[mechanism]
    assert max(residuals.values(), default=0.0) < 1e-9


def test_the_loop_check_sees_an_open_loop():
    pairs = state_pairs("four_bar", "ap242", 0)
    a, b, P1, P2, kind, q, name = pairs[1]
    bent = [*pairs[:1], (a, b, P1, P2, kind, q + 1e-6, name), *pairs[2:]]
    slide = PROFILES["ap242"]["slide_axis"]
    poses = {bent[0][0]: np.eye(4)}
    for a, b, P1, P2, kind, q, _ in bent[:3]:
        poses[b] = poses[a] @ P1 @ _rz(q) @ np.linalg.inv(P2)
    a, b, P1, P2, kind, q, _ = bent[3]
    assert np.abs(poses[a] @ P1 @ _rz(q) - poses[b] @ P2).max() > 1e-5 and slide == 0


def _named_axis2(records, name):
    ref = next(k for k, r in records.items() if r.get("type") == "axis2_placement_3d" and r["args"][0] == name)
    return _matrix_axis2(records, {"ref": ref})


@pytest.mark.parametrize("mechanism,link,frame", [("four_bar", "coupler", "point P"),
                                                   ("slider_crank", "rod", "centre"),
                                                   ("spherical_linkage", "coupler", "point P")])
def test_ap242_path_nodes_follow_the_states(mechanism, link, frame):
    """The prescribed path's placements are where the states put the path frame."""
    records = parsed(mechanism, "ap242")
    base = _named_axis2(records, "frame placement")  # the base link in the assembly (world)
    local = _named_axis2(records, f"{link} {frame}")
    link_ref = next(k for k, r in records.items() if r.get("type") == "kinematic_link" and r["args"][0] == link)
    for state, t in enumerate(["0", "0.5", "1"]):
        poses, _ = close_loops(mechanism, "ap242", state)
        node = _named_axis2(records, f"{frame} at t={t}")
        assert np.abs(base @ poses[link_ref] @ local - node).max() < 1e-9


def test_ap242_loops_are_head_to_tail():
    """WR1 of path and edge_loop for the kinematic loops."""
    for m in MECHANISMS:
        r = parsed(m, "ap242")
        for loop in (x for x in r.values() if x.get("type") == "kinematic_loop"):
            ends = []
            for oref in loop["args"][1]:
                _, _, _, jref, orient = r[oref["ref"]]["args"]
                _, start, end = r[jref["ref"]]["args"]
                if orient == {"enum": "F"}:
                    start, end = end, start
                ends.append((start["ref"], end["ref"]))
            for (s0, e0), (s1, e1) in zip(ends, ends[1:] + ends[:1]):
                assert e0 == s1, (m, loop["args"][0])


@pytest.mark.parametrize("profile", list(PROFILES))
def test_four_bar_matches_the_reference_solution(profile):
    if not REFERENCE.is_file():
        pytest.skip("reference data not available")
    ref = json.loads(REFERENCE.read_text())["closed_loop"]["fourbar"][0]
    sample = next(s for s in ref["samples"] if s["theta2_deg"] == 30)["branches"]["open"]
    values = {name: q for *_, q, name in initial_pairs("four_bar", profile)}
    assert abs(values["A"] - math.radians(30)) < 1e-12
    assert abs(values["A"] + values["B"] - sample["theta3_rad"]) < 1e-9
    assert abs(values["D"] - sample["theta4_rad"]) < 1e-9
    assert ref["a_crank"] * 1000 == 20.0 and ref["b_coupler"] * 1000 == 70.0


@pytest.mark.parametrize("profile", list(PROFILES))
def test_ur5_initial_state_reproduces_the_reference_pose(profile):
    if not REFERENCE.is_file():
        pytest.skip("reference data not available")
    sample = json.loads(REFERENCE.read_text())["arms"]["UR5"]["samples"][1]
    pairs = initial_pairs("ur5_arm", profile)
    T = np.eye(4)
    for a, b, P1, P2, kind, q, name in pairs:  # J1..J6 in order, a serial chain
        T = T @ P1 @ _rz(q) @ np.linalg.inv(P2)
    ref = np.array(sample["T"])
    ref[:3, 3] *= 1000.0
    assert np.abs(T - ref).max() < 1e-9
    assert np.allclose([q for *_, q, _ in pairs], sample["q"], atol=1e-12)


def test_pair_frames_are_link_items_and_shapes_share_the_link_context():
    """WR1/WR2 of kinematic_pair (1996) and pair_representation_relationship (AP242),
    WR1 of kinematic_link_representation_association."""
    for m in MECHANISMS:
        r = parsed(m, "ap214")
        relation = {x["args"][1]["ref"] for x in r.values()
                    if x.get("type") == "kinematic_link_representation_relation"}
        reps = {k: x for k, x in r.items() if x.get("type") == "kinematic_link_representation"}
        assert set(reps) == relation
        rep_of_link = {x["args"][0]["ref"]: x["args"][1]["ref"]
                       for x in r.values() if x.get("type") == "kinematic_link_representation_relation"}
        for x in r.values():
            if x.get("type", "").endswith("_pair") and len(x["args"]) >= 5 and x["type"] != "pair_actuator":
                joint = r[x["args"][4]["ref"]]["args"]
                assert x["args"][2] in reps[rep_of_link[joint[0]["ref"]]]["args"][1]
                assert x["args"][3] in reps[rep_of_link[joint[1]["ref"]]]["args"][1]
            if x.get("type") == "kinematic_link_representation_association":
                assert r[x["args"][2]["ref"]]["args"][2] == r[x["args"][3]["ref"]]["args"][2]
        r = parsed(m, "ap242")
        for x in r.values():
            if x.get("type") == "pair_representation_relationship":
                pair = r[x["args"][5]["ref"]]
                parts = _args_of(pair, None)
                if "item_defined_transformation" in parts:
                    i1, i2 = parts["item_defined_transformation"][2:4]
                else:
                    i1, i2 = pair["args"][3:5]
                assert i1 in r[x["args"][3]["ref"]]["args"][1]
                assert i2 in r[x["args"][4]["ref"]]["args"][1]
            if x.get("type") == "kinematic_link_representation_association":
                assert r[x["args"][2]["ref"]]["args"][2] == r[x["args"][3]["ref"]]["args"][2]


def test_initial_state_has_one_value_per_joint():
    """WR1 of initial_state (1996); the same for the AP242 initial state."""
    for m in MECHANISMS:
        for p in PROFILES:
            pairs = initial_pairs(m, p)
            names = [x[-1] for x in pairs]
            assert len(names) == len(set(names)) == len(MECHANISMS[m]().pairs)


def _refs(value, out):
    if isinstance(value, dict):
        if "ref" in value:
            out.append(value["ref"])
        elif "value" in value:
            _refs(value["value"], out)
    elif isinstance(value, list):
        for v in value:
            _refs(v, out)
    return out


@pytest.mark.parametrize("mechanism,profile", CASES, ids=IDS)
def test_every_representation_item_is_used_by_a_representation(mechanism, profile):
    """WR1 of representation_item (both long forms): SIZEOF(using_representations(SELF)) > 0,
    with using_representations following items and founded items that reference the item;
    and every representation and context is referenced or is a root."""
    records = parsed(mechanism, profile)
    check = SchemaCheck(schema_for(profile), profile)
    types = {k: check.record_types(r) for k, r in records.items()}
    users: dict = {}
    for k, r in records.items():
        args = r["args"] if "args" in r else [a for p in r["complex"] for a in p["args"]]
        for target in _refs(args, []):
            users.setdefault(target, set()).add(k)
    direct = {}
    for k, r in records.items():
        if "representation" in types[k]:
            for item in _refs(r["args"][1], []):
                direct.setdefault(item, set()).add(k)

    def used(k, seen) -> bool:
        if direct.get(k):
            return True
        for u in users.get(k, ()):
            if u not in seen and types[u] & {"representation_item", "founded_item"}:
                seen.add(u)
                if used(u, seen):
                    return True
        return False

    unused = [f"#{k} {r.get('type')}" for k, r in records.items()
              if "representation_item" in types[k] and not used(k, {k})]
    assert not unused, unused


def _slot_refs(check: SchemaCheck, rec: dict):
    """(declaring entity, attribute name, referenced id) for every reference in a record."""
    s = check.s
    if "complex" in rec:
        present = {p["type"] for p in rec["complex"]}
        for part in rec["complex"]:
            for v, (name, *_rest) in zip(part["args"], check.partial_slots(part["type"], present)):
                for ref in _refs(v, []):
                    yield part["type"], name, ref
        return
    if rec["type"] in check.extra:
        return
    for v, a in zip(rec["args"], s.p21_attributes(rec["type"])):
        for ref in _refs(v, []):
            yield a.entity, a.name, ref


@pytest.mark.parametrize("mechanism,profile", CASES, ids=IDS)
def test_inverse_attribute_cardinalities(mechanism, profile):
    """INVERSE attributes: exactly one referrer for a single-valued one, the bounds of a SET/BAG."""
    records = parsed(mechanism, profile)
    check = SchemaCheck(schema_for(profile), profile)
    s = check.s
    used: dict = {}
    for k, rec in records.items():
        for owner, name, ref in _slot_refs(check, rec):
            used.setdefault((ref, owner, name), set()).add(k)
    errors = []
    for k, rec in records.items():
        for t in sorted(check.record_types(rec)):
            ent = s.entities.get(t)
            if ent is None:
                continue
            for inv in ent.inverse:
                if inv.supertype is not None:
                    continue
                decl = s.resolve_attribute(inv.entity, inv.for_attribute)
                assert decl is not None, (inv.entity, inv.for_attribute)
                users = {u for u in used.get((k, decl[0], decl[1].name), ())
                         if inv.entity in check.record_types(records[u])}
                n = len(users)
                if inv.aggregate is None:
                    ok = n == 1
                else:
                    lo = inv.lower.value if isinstance(inv.lower, Literal) and inv.lower.kind == "integer" else 0
                    hi = inv.upper.value if isinstance(inv.upper, Literal) and inv.upper.kind == "integer" else None
                    ok = n >= lo and (hi is None or n <= hi)
                if not ok:
                    errors.append(f"#{k} {t}.{inv.name}: {n} referrers")
    assert not errors, errors[:20]
