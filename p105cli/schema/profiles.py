"""Schema profiles: which EXPRESS schema interprets a file.

A profile names a long-form schema shipped in ``p105cli/schema/data/`` and
knows which Part 21 FILE_SCHEMA names select it:

``ap214``
    ``AUTOMOTIVE_DESIGN`` (AP214 AIM long form, ed. 3), with its variants
    such as ``AUTOMOTIVE_DESIGN_CC2`` and any version suffix
    (``AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 }``). It carries the 1996
    Part 105 kinematics. A file that declares edition 1 in its object
    identifier (``{ 1 0 10303 214 1 1 1 1 }``, ISO 10303-214:2001) is read
    with the edition 1 variant of the profile (same name, ``edition`` 1):
    the edition 3 long form without the derivations edition 1 did not have
    (:data:`EDITION_1_EXPLICIT`: ``conversion_based_unit`` writes
    ``named_unit.dimensions`` explicitly, as AP242 does). Editions 2 and 3
    and a name without identifier get the edition 3 long form.
``ap242``
    ``AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF``, any edition (the
    edition 3 long form WG12 N10962 is shipped; it has every kinematics
    entity of editions 1 to 5).
``p105``
    The 1996 Part 105 resource schemas as ISO 10303-105:1996 defines them:
    the AP214 long form plus entity ``su_parameters`` (5.4.17) as a member
    of the SELECT ``rigid_placement`` (5.3.1), which AP214's long form
    dropped. Built by loading the AP214 schema and patching the parsed
    model; the file on disk is not touched. Chosen by the Part 105 resource
    schema names (``KINEMATIC_STRUCTURE_SCHEMA``, ...) in FILE_SCHEMA, or
    explicitly (``override='p105'``). Its schema keeps the name
    ``AUTOMOTIVE_DESIGN``, so TYPEOF strings match the AP214 rules.

A science module: no click, rich or numpy here.
"""

from __future__ import annotations

import re
import threading
from pathlib import Path

from .express import load_schema, parse_schema
from .model import Schema, SchemaError, SelectType

__all__ = ["KNOWN_PROFILES", "DATA_DIR", "EDITION_1_EXPLICIT", "Profile", "UnknownSchemaError",
           "get_profile", "profile_for_header", "schema_edition", "schema_names_of_header",
           "stand_in_for"]

DATA_DIR = Path(__file__).resolve().parent / "data"
AP214_FILE = "AP214E3_2010_automotive_design_longform.exp"
AP242_FILE = "AP242_N10962_mim_lf.exp"

KNOWN_PROFILES = ("ap214", "ap242", "p105")

# ISO 10303-105:1996 clause 5.4.17 (the same text as AP242's long form).
SU_PARAMETERS_EXPRESS = """
SCHEMA p105_patch;
ENTITY su_parameters
  SUBTYPE OF (geometric_representation_item);
  a     : length_measure;
  alpha : plane_angle_measure;
  b     : length_measure;
  beta  : plane_angle_measure;
  c     : length_measure;
  gamma : plane_angle_measure;
WHERE
  WR1: SELF\\geometric_representation_item.dim = 3;
END_ENTITY;
END_SCHEMA;
"""

# The 1996 Part 105 resource schemas, as a file written against them names them.
P105_RESOURCE_SCHEMAS = frozenset((
    "KINEMATIC_STRUCTURE_SCHEMA", "KINEMATIC_MOTION_REPRESENTATION_SCHEMA",
    "KINEMATIC_ANALYSIS_CONTROL_AND_RESULT_SCHEMA",
))


#: AP214 edition 1 (ISO 10303-214:2001, Part 41:1994 units): attributes that the edition 3 long
#: form re-declares as DERIVE but edition 1 keeps explicit, as (entity, supertype, attribute).
#: AP242 keeps the same one explicit too (with WHERE rule conversion_based_unit.wr1).
EDITION_1_EXPLICIT = (("conversion_based_unit", "named_unit", "dimensions"),)

# The part number of each application protocol in FILE_SCHEMA's object identifier
# ({ 1 0 10303 <part> <edition> ... }), and the protocols p105 knows by name only.
_PART_OF_PROFILE = {"ap214": 214, "p105": 214, "ap242": 442}
_UNSUPPORTED = {
    "CONFIG_CONTROL_DESIGN": "AP203 edition 1",
    "AP203_CONFIGURATION_CONTROLLED_3D_DESIGN_OF_MECHANICAL_PARTS_AND_ASSEMBLIES_MIM_LF":
        "AP203 edition 2",
}


class UnknownSchemaError(LookupError):
    """No profile interprets the file (or an unknown profile name was asked for).

    ``str()`` names the schema(s) found and lists the known profiles."""

    def __init__(self, message: str, schemas=()):
        super().__init__(message)
        self.message = message
        self.schemas = list(schemas)
        self.known = KNOWN_PROFILES

    def __str__(self) -> str:
        return f"{self.message} (known profiles: {', '.join(KNOWN_PROFILES)})"


class Profile:
    """One schema profile. ``schema`` is parsed on first use and kept.

    ``edition``: the edition of the application protocol whose rules the
    schema holds; ``standard``: its name in words (``AP214 edition 1``),
    for messages. ``explicit_derivations``: ``{(supertype, attribute):
    (entity, DerivedAttribute)}`` of the derivations this edition does not
    have (the attribute stays explicit), filled when the schema is loaded;
    a value written there can still be compared with what later editions
    derive."""

    def __init__(self, name: str, express_path: Path, description: str, patch=None,
                 edition: int | None = None, standard: str | None = None):
        self.name = name
        self.express_path = Path(express_path)
        self.description = description
        self.edition = edition
        self.standard = standard or name.upper()
        self.explicit_derivations: dict = {}
        self._patch = patch
        self._schema: Schema | None = None
        self._lock = threading.Lock()

    @property
    def schema(self) -> Schema:
        s = self._schema
        if s is None:
            with self._lock:
                s = self._schema
                if s is None:
                    if not self.express_path.is_file():
                        raise SchemaError(f"profile {self.name}: schema file {self.express_path} "
                                          "is missing (is the package data installed?)")
                    # load_schema unpickles (or parses) a fresh object on every
                    # call, so patching it cannot leak into another profile.
                    s = load_schema(self.express_path)
                    if self._patch is not None:
                        self._patch(self, s)
                    self._schema = s
        return s

    @property
    def schema_name(self) -> str:
        """The EXPRESS schema name in upper case (the TYPEOF prefix without the dot)."""
        return (self.schema.name or "").upper()

    def __repr__(self) -> str:
        ed = f", edition={self.edition}" if self.edition is not None else ""
        return f"Profile({self.name!r}, {self.express_path.name!r}{ed})"


def _patch_edition_1(profile: Profile, s: Schema) -> None:
    """AP214 edition 3 long form -> edition 1: drop the DERIVE re-declarations of
    :data:`EDITION_1_EXPLICIT` (kept in ``profile.explicit_derivations``)."""
    for entity, supertype, attribute in EDITION_1_EXPLICIT:
        ent = s.entities.get(entity)
        decl = next((a for a in ent.derived if a.supertype == supertype and a.name == attribute),
                    None) if ent is not None else None
        if decl is None:
            raise SchemaError(f"{profile.standard}: {s.name} does not derive "
                              f"{entity}.{supertype}.{attribute}")
        ent.derived.remove(decl)
        profile.explicit_derivations[(supertype, attribute)] = (entity, decl)
    s._memo.clear()  # p21 orders computed before the patch are stale


def _patch_p105_edition_1(profile: Profile, s: Schema) -> None:
    _patch_edition_1(profile, s)
    _patch_p105(profile, s)


def _patch_p105(profile: Profile, s: Schema) -> None:
    """AP214 long form -> the 1996 Part 105 resource schemas: add su_parameters
    (5.4.17) and make it a member of the SELECT rigid_placement (5.3.1)."""
    patch = parse_schema(SU_PARAMETERS_EXPRESS, "<p105 profile: ISO 10303-105:1996 5.4.17>")
    ent = patch.entities["su_parameters"]
    if "su_parameters" not in s.entities:
        for sup in ent.supertypes:
            if sup not in s.entities:
                raise SchemaError(f"p105 profile: {s.name} has no entity {sup}")
        ent.subtypes = []
        s.entities["su_parameters"] = ent
        for sup in ent.supertypes:
            subs = s.entities[sup].subtypes
            if "su_parameters" not in subs:
                subs.append("su_parameters")
    rp = s.types.get("rigid_placement")
    if rp is None or not isinstance(rp.underlying, SelectType):
        raise SchemaError(f"p105 profile: {s.name} has no SELECT rigid_placement")
    if "su_parameters" not in rp.underlying.items:
        rp.underlying.items.append("su_parameters")
    s._memo.clear()  # supertypes/p21 orders computed before the patch are stale


_PROFILES = {
    "ap214": Profile("ap214", DATA_DIR / AP214_FILE,
                     "AP214 ed3 AIM long form (AUTOMOTIVE_DESIGN), 1996 Part 105 kinematics",
                     edition=3, standard="AP214 edition 3"),
    "ap242": Profile("ap242", DATA_DIR / AP242_FILE,
                     "AP242 MIM long form (WG12 N10962, edition 3), Part 105 ed2 kinematics",
                     edition=3, standard="AP242"),
    "p105": Profile("p105", DATA_DIR / AP214_FILE,
                    "ISO 10303-105:1996 resource schemas: AP214 long form + su_parameters",
                    patch=_patch_p105, edition=3, standard="AP214 edition 3"),
}

# The edition 1 variants (same names): chosen by FILE_SCHEMA's object identifier only.
_EDITION_1 = {
    "ap214": Profile("ap214", DATA_DIR / AP214_FILE,
                     "AP214 ed1 (AUTOMOTIVE_DESIGN { 1 0 10303 214 1 ... }): the ed3 long form "
                     "without the derivations edition 1 did not have",
                     patch=_patch_edition_1, edition=1, standard="AP214 edition 1"),
    "p105": Profile("p105", DATA_DIR / AP214_FILE,
                    "ISO 10303-105:1996 resource schemas in an AP214 edition 1 file",
                    patch=_patch_p105_edition_1, edition=1, standard="AP214 edition 1"),
}


def get_profile(name: str) -> Profile:
    """The profile called ``name`` (case-insensitive); UnknownSchemaError if none."""
    p = _PROFILES.get(str(name).strip().lower())
    if p is None:
        raise UnknownSchemaError(f"unknown schema profile {name!r}")
    return p


_SCHEMA_ID = re.compile(r"\s*([A-Za-z][A-Za-z0-9_]*)")
_OBJECT_ID = re.compile(r"\{([0-9\s]*)\}")


def schema_edition(entry: str):
    """``(part, edition)`` from a FILE_SCHEMA entry's object identifier
    (``'AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'`` -> ``(214, 1)``), or
    None without one (ISO 10303-21 8.2.3: ``{ 1 0 10303 <part> <version> ... }``)."""
    m = _OBJECT_ID.search(entry or "")
    if m is None:
        return None
    arcs = m.group(1).split()
    if len(arcs) < 5 or arcs[:3] != ["1", "0", "10303"]:
        return None
    return int(arcs[3]), int(arcs[4])


def _profile_of_schema_name(entry: str):
    m = _SCHEMA_ID.match(entry or "")
    if not m:
        return None
    ident = m.group(1).upper()
    if ident == "AUTOMOTIVE_DESIGN" or ident.startswith("AUTOMOTIVE_DESIGN_"):
        return "ap214"
    if ident == "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF":
        return "ap242"
    if ident in P105_RESOURCE_SCHEMAS:
        return "p105"
    return None


def schema_names_of_header(header) -> list:
    """The FILE_SCHEMA strings of a header (dict as read_step/read_json give it)."""
    if not isinstance(header, dict):
        return []
    fs = header.get("file_schema")
    if isinstance(fs, str):
        return [fs]
    if isinstance(fs, (list, tuple)):
        return [x for x in fs if isinstance(x, str)]
    return []


def profile_for_header(header, override: str | None = None) -> Profile:
    """The profile for a file's header: ``override`` (a profile name) when
    given, else from FILE_SCHEMA. The 1996 Part 105 resource schemas select
    ``p105`` (also when listed next to AUTOMOTIVE_DESIGN); names of no
    profile next to a known one are ignored; two different known families
    (AP214 and AP242) are refused. Raises UnknownSchemaError.

    The edition comes from FILE_SCHEMA's object identifier whichever way
    the profile was chosen: an AP214 edition 1 identifier selects the
    edition 1 variant of ``ap214`` and ``p105``."""
    names = schema_names_of_header(header)
    if override is not None:
        return _edition_variant(get_profile(override), names)
    found = {p for p in map(_profile_of_schema_name, names) if p is not None}
    if not found:
        shown = ", ".join(repr(n) for n in names) or "none"
        known = [_UNSUPPORTED[m.group(1).upper()] for m in map(_SCHEMA_ID.match, names)
                 if m and m.group(1).upper() in _UNSUPPORTED]
        why = f" ({', '.join(known)}: p105 ships no long form for it)" if known else ""
        raise UnknownSchemaError(f"no schema profile for FILE_SCHEMA {shown}{why}", names)
    if found <= {"ap214", "p105"}:
        return _edition_variant(_PROFILES["p105" if "p105" in found else "ap214"], names)
    if len(found) == 1:
        return _edition_variant(_PROFILES[found.pop()], names)
    raise UnknownSchemaError("FILE_SCHEMA names schemas of different profiles: "
                             + ", ".join(repr(n) for n in names), names)


def stand_in_for(header, profile: Profile) -> str | None:
    """The FILE_SCHEMA name ``profile`` stands in for when p105 has no long form of that
    exact schema (a variant such as ``AUTOMOTIVE_DESIGN_CC2``, a pre-standard draft), else
    None: entity types unknown to the profile may then be known to the declared schema."""
    exact = {"ap214": ("AUTOMOTIVE_DESIGN",), "p105": ("AUTOMOTIVE_DESIGN", *P105_RESOURCE_SCHEMAS),
             "ap242": ("AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF",)}.get(profile.name, ())
    for entry in schema_names_of_header(header):
        m = _SCHEMA_ID.match(entry or "")
        if m and _profile_of_schema_name(entry) is not None and m.group(1).upper() not in exact:
            return m.group(1).upper()
    return None


def _edition_variant(profile: Profile, names) -> Profile:
    """``profile``, or its edition 1 variant when FILE_SCHEMA declares edition 1 of its
    application protocol."""
    part = _PART_OF_PROFILE.get(profile.name)
    for entry in names:
        ed = schema_edition(entry)
        if ed is not None and ed[0] == part and ed[1] == 1 and profile.name in _EDITION_1:
            return _EDITION_1[profile.name]
    return profile
