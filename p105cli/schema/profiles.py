"""Schema profiles: which EXPRESS schema interprets a file.

A profile names a long-form schema shipped in ``p105cli/schema/data/`` and
knows which Part 21 FILE_SCHEMA names select it:

``ap214``
    ``AUTOMOTIVE_DESIGN`` (AP214 AIM long form, ed. 3), with its variants
    such as ``AUTOMOTIVE_DESIGN_CC2`` and any version suffix
    (``AUTOMOTIVE_DESIGN { 1 0 10303 214 3 1 1 }``). It carries the 1996
    Part 105 kinematics.
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

__all__ = ["KNOWN_PROFILES", "DATA_DIR", "Profile", "UnknownSchemaError", "get_profile",
           "profile_for_header", "schema_names_of_header"]

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
    """One schema profile. ``schema`` is parsed on first use and kept."""

    def __init__(self, name: str, express_path: Path, description: str, patch=None):
        self.name = name
        self.express_path = Path(express_path)
        self.description = description
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
                        self._patch(s)
                    self._schema = s
        return s

    @property
    def schema_name(self) -> str:
        """The EXPRESS schema name in upper case (the TYPEOF prefix without the dot)."""
        return (self.schema.name or "").upper()

    def __repr__(self) -> str:
        return f"Profile({self.name!r}, {self.express_path.name!r})"


def _patch_p105(s: Schema) -> None:
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
                     "AP214 ed3 AIM long form (AUTOMOTIVE_DESIGN), 1996 Part 105 kinematics"),
    "ap242": Profile("ap242", DATA_DIR / AP242_FILE,
                     "AP242 MIM long form (WG12 N10962, edition 3), Part 105 ed2 kinematics"),
    "p105": Profile("p105", DATA_DIR / AP214_FILE,
                    "ISO 10303-105:1996 resource schemas: AP214 long form + su_parameters",
                    patch=_patch_p105),
}


def get_profile(name: str) -> Profile:
    """The profile called ``name`` (case-insensitive); UnknownSchemaError if none."""
    p = _PROFILES.get(str(name).strip().lower())
    if p is None:
        raise UnknownSchemaError(f"unknown schema profile {name!r}")
    return p


_SCHEMA_ID = re.compile(r"\s*([A-Za-z][A-Za-z0-9_]*)")


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
    (AP214 and AP242) are refused. Raises UnknownSchemaError."""
    if override is not None:
        return get_profile(override)
    names = schema_names_of_header(header)
    found = {p for p in map(_profile_of_schema_name, names) if p is not None}
    if not found:
        shown = ", ".join(repr(n) for n in names) or "none"
        raise UnknownSchemaError(f"no schema profile for FILE_SCHEMA {shown}", names)
    if found <= {"ap214", "p105"}:
        return _PROFILES["p105" if "p105" in found else "ap214"]
    if len(found) == 1:
        return _PROFILES[found.pop()]
    raise UnknownSchemaError("FILE_SCHEMA names schemas of different profiles: "
                             + ", ".join(repr(n) for n in names), names)
