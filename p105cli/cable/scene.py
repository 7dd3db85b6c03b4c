"""Scene files (``"format": "p105-scene/1"``): gravity, cables and the effects to simulate.

A scene adds to a Part 105 mechanism what the standard leaves out. This
module reads one (a ``dict`` from JSON or TOML), checks it, converts every
quantity to SI at read (so nothing downstream knows the file's units) and
returns immutable :class:`Scene` / :class:`CableSpec` objects. Errors are
:class:`SceneError` naming the JSON path (``$.cables[0].section.radius``).

Reading a scene imports numpy only: the solvers are imported by
``workflow`` when a cable asks for them. The JSON Schema of the format is
``p105cli/schemas/p105-scene-1.schema.json`` (``SCHEMA_PATH``); the checks
here are the same and more (rotation matrices, stiffness from a section).

Units (``"units"``; defaults SI): ``length`` m, mm, cm, km, in, ft;
``force`` N, kN, mN, lbf; ``mass`` kg, g, t, lb; ``pressure`` Pa, kPa,
MPa, GPa, psi. Derived: stiffness = force * length^2, linear density =
mass / length, density = mass / length^3, gravity = length / s^2, end
forces = force. Pose translations are lengths; rotations are unitless.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "SCENE_FORMAT", "SCHEMA_PATH", "EFFECTS", "CONDITIONS", "MODELS",
    "SceneError", "CableEnd", "CableSpec", "Scene",
    "read_scene", "load_scene_file", "scene_has_cables", "scene_needs_cables",
    "length_factor",
]

SCENE_FORMAT = "p105-scene/1"
SCHEMA_PATH = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                           "schemas", "p105-scene-1.schema.json")
EFFECTS = ("shape", "end_loads", "min_bend_radius", "overlength", "symmetry_check", "frames")
CONDITIONS = ("clamped", "pinned", "free")
MODELS = ("rod", "patent")
DEFAULT_EFFECTS = ("shape", "overlength")

_LENGTH = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "km": 1e3, "in": 0.0254, "ft": 0.3048}
_FORCE = {"N": 1.0, "kN": 1e3, "mN": 1e-3, "lbf": 4.4482216152605}
_MASS = {"kg": 1.0, "g": 1e-3, "t": 1e3, "lb": 0.45359237}
_PRESSURE = {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "psi": 6894.757293168361}
_UNIT_TABLES = {"length": _LENGTH, "force": _FORCE, "mass": _MASS, "pressure": _PRESSURE}


class SceneError(ValueError):
    """A scene that does not follow the format; ``path`` is the JSON path of the culprit."""

    def __init__(self, path: str, message: str, source: str | None = None):
        self.path = path
        self.message = message
        self.source = source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}scene {path}: {message}")


@dataclass(frozen=True)
class CableEnd:
    """One end: ``link`` (None = world), ``pose`` 4x4 in that link's frame (SI), condition, force (N)."""

    link: str | None
    pose: np.ndarray
    condition: str
    force: np.ndarray | None = None


@dataclass(frozen=True)
class CableSpec:
    """A cable, SI units: length m, stiffness (A, B, C) N m^2, linear density kg/m."""

    name: str
    length: float
    stiffness: tuple
    linear_density: float
    start: CableEnd
    end: CableEnd
    model: str = "rod"
    segments: int = 50
    tol: float = 1e-10
    richardson: bool = False
    effects: frozenset = frozenset(DEFAULT_EFFECTS)
    min_bend_radius: float | None = None
    symmetry_threshold: float = 1e-3      # fraction of L: the patent's "predetermined value"
    slack_warning: float = 0.02           # warn when (L - |R|)/L falls below this
    radius: float | None = None
    path: str = "$.cables[0]"

    def wants(self, effect: str) -> bool:
        return effect in self.effects


@dataclass(frozen=True)
class Scene:
    """A checked scene in SI units. ``gravity`` is None when the scene has none."""

    gravity: np.ndarray | None
    cables: tuple = field(default_factory=tuple)
    units: dict = field(default_factory=dict)
    length_unit: float = 1.0

    def weight(self, cable: CableSpec) -> np.ndarray:
        """Weight per unit length (N/m, world) of ``cable``."""
        if self.gravity is None:
            return np.zeros(3)
        return cable.linear_density * self.gravity


# --- cheap helpers for the CLI (no numpy work, no solver imports) -------------

def scene_has_cables(scene) -> bool:
    """True when a raw scene dict (or a :class:`Scene`) declares at least one cable."""
    if isinstance(scene, Scene):
        return bool(scene.cables)
    return isinstance(scene, dict) and isinstance(scene.get("cables"), list) and len(scene["cables"]) > 0


scene_needs_cables = scene_has_cables


def length_factor(scene) -> float:
    """Metres per length unit of a raw scene dict (1.0 when it gives none)."""
    units = scene.get("units") if isinstance(scene, dict) else None
    name = units.get("length", "m") if isinstance(units, dict) else "m"
    return _LENGTH.get(name, 1.0)


# --- reading ----------------------------------------------------------------------

def load_scene_file(path) -> dict:
    """The raw dict of a scene file: JSON, or TOML when the name ends in ``.toml``."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read()
    except OSError as err:
        raise SceneError("$", f"cannot read: {err.strerror}", path) from None
    return parse_scene_bytes(raw, path, toml=path.endswith(".toml"))


def looks_like_toml(raw: bytes) -> bool:
    """A scene without a file name (standard input): JSON is an object, so anything else is TOML."""
    return not raw.lstrip(b"\xef\xbb\xbf \t\r\n").startswith(b"{")


def parse_scene_bytes(raw: bytes, path: str, *, toml: bool) -> dict:
    """The raw dict of a scene's bytes (JSON, or TOML); errors name ``path``."""
    if toml:
        import tomllib
        try:
            return tomllib.loads(raw.decode("utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
            raise SceneError("$", f"not valid TOML: {err}", path) from None
    try:
        return json.loads(raw.decode("utf-8"))
    except UnicodeDecodeError as err:
        raise SceneError("$", f"not UTF-8: {err}", path) from None
    except json.JSONDecodeError as err:
        raise SceneError("$", f"not valid JSON at {path}:{err.lineno}:{err.colno}: {err.msg}", path) from None


def _num(v, path, *, positive=False, nonneg=False):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise SceneError(path, f"expected a finite number, got {json.dumps(v)[:40]}")
    v = float(v)
    if positive and not v > 0:
        raise SceneError(path, f"must be > 0, got {v:g}")
    if nonneg and v < 0:
        raise SceneError(path, f"must be >= 0, got {v:g}")
    return v


def _vec3(v, path):
    if not isinstance(v, list) or len(v) != 3:
        raise SceneError(path, "expected a list of 3 numbers")
    return np.array([_num(x, f"{path}[{i}]") for i, x in enumerate(v)])


def _obj(v, path, allowed, required=()):
    if not isinstance(v, dict):
        raise SceneError(path, f"expected an object, got {type(v).__name__}")
    for k in v:
        if k not in allowed:
            raise SceneError(f"{path}.{k}", f"unknown key (allowed: {', '.join(sorted(allowed))})")
    for k in required:
        if k not in v:
            raise SceneError(f"{path}.{k}", "missing")
    return v


def pose_matrix(v, path, length_unit=1.0, *, tol=1e-6) -> np.ndarray:
    """A 4x4 rigid placement from nested lists; translation scaled to metres."""
    if not isinstance(v, list) or len(v) not in (3, 4) or not all(isinstance(r, list) and len(r) == 4 for r in v):
        raise SceneError(path, "expected a 4x4 matrix (list of 4 rows of 4 numbers; the last row may be omitted)")
    T = np.eye(4)
    for i, row in enumerate(v):
        for j, x in enumerate(row):
            T[i, j] = _num(x, f"{path}[{i}][{j}]")
    if len(v) == 4 and np.max(np.abs(T[3] - [0, 0, 0, 1])) > tol:
        raise SceneError(f"{path}[3]", "last row must be [0, 0, 0, 1]")
    R = T[:3, :3]
    err = np.max(np.abs(R.T @ R - np.eye(3)))
    if err > tol or np.linalg.det(R) < 0:
        raise SceneError(path, f"rotation part is not a proper rotation (|R^T R - I| = {err:.2g})")
    # re-orthonormalise within the tolerance so downstream algebra is exact
    U, _, Vt = np.linalg.svd(R)
    T[:3, :3] = U @ Vt
    T[:3, 3] *= length_unit
    T[3] = [0.0, 0.0, 0.0, 1.0]
    return T


def _units(raw, path):
    if raw is None:
        return {}, {k: 1.0 for k in _UNIT_TABLES}
    _obj(raw, path, set(_UNIT_TABLES))
    factors = {}
    for k, table in _UNIT_TABLES.items():
        name = raw.get(k, next(iter(table)))
        if name not in table:
            raise SceneError(f"{path}.{k}", f"unknown unit {name!r} (known: {', '.join(table)})")
        factors[k] = table[name]
    return dict(raw), factors


def _end(raw, path, lu, fu):
    _obj(raw, path, {"link", "pose", "condition", "force"}, ("pose",))
    link = raw.get("link")
    if link is not None and (not isinstance(link, str) or not link):
        raise SceneError(f"{path}.link", "expected a link name or null (world)")
    cond = raw.get("condition", "clamped")
    if cond not in CONDITIONS:
        raise SceneError(f"{path}.condition", f"expected one of {', '.join(CONDITIONS)}, got {cond!r}")
    force = raw.get("force")
    if force is not None:
        force = _vec3(force, f"{path}.force") * fu
    return CableEnd(link=link, pose=pose_matrix(raw["pose"], f"{path}.pose", lu), condition=cond, force=force)


_CABLE_KEYS = {"name", "length", "section", "linear_density", "density", "start", "end",
               "numerics", "effects", "min_bend_radius", "symmetry_threshold", "slack_warning"}


def _cable(raw, path, f, names):
    _obj(raw, path, _CABLE_KEYS, ("name", "length", "section", "start", "end"))
    lu, fu, mu, pu = f["length"], f["force"], f["mass"], f["pressure"]
    name = raw["name"]
    if not isinstance(name, str) or not name:
        raise SceneError(f"{path}.name", "expected a non-empty string")
    if name in names:
        raise SceneError(f"{path}.name", f"duplicate cable name {name!r}")
    length = _num(raw["length"], f"{path}.length", positive=True) * lu
    sec = _obj(raw["section"], f"{path}.section",
               {"radius", "youngs_modulus", "poisson_ratio", "shear_modulus",
                "bending_stiffness", "torsional_stiffness"})
    sp = f"{path}.section"
    radius = _num(sec["radius"], f"{sp}.radius", positive=True) * lu if "radius" in sec else None
    if "bending_stiffness" in sec or "torsional_stiffness" in sec:
        for k in ("youngs_modulus", "poisson_ratio", "shear_modulus"):
            if k in sec:
                raise SceneError(f"{sp}.{k}", "give either stiffnesses or material constants, not both")
        if "bending_stiffness" not in sec or "torsional_stiffness" not in sec:
            k = "bending_stiffness" if "bending_stiffness" not in sec else "torsional_stiffness"
            raise SceneError(f"{sp}.{k}", "missing (bending_stiffness [A, B] and torsional_stiffness C go together)")
        ab = sec["bending_stiffness"]
        if not isinstance(ab, list) or len(ab) != 2:
            raise SceneError(f"{sp}.bending_stiffness", "expected [A, B] (force * length^2)")
        A, B = (_num(x, f"{sp}.bending_stiffness[{i}]", positive=True) * fu * lu**2 for i, x in enumerate(ab))
        C = _num(sec["torsional_stiffness"], f"{sp}.torsional_stiffness", positive=True) * fu * lu**2
    else:
        if radius is None:
            raise SceneError(f"{sp}.radius", "missing (a section is a radius with material constants, "
                                             "or bending_stiffness and torsional_stiffness)")
        if "youngs_modulus" not in sec:
            raise SceneError(f"{sp}.youngs_modulus", "missing")
        E = _num(sec["youngs_modulus"], f"{sp}.youngs_modulus", positive=True) * pu
        if "shear_modulus" in sec and "poisson_ratio" in sec:
            raise SceneError(f"{sp}.shear_modulus", "give poisson_ratio or shear_modulus, not both")
        if "shear_modulus" in sec:
            G = _num(sec["shear_modulus"], f"{sp}.shear_modulus", positive=True) * pu
        elif "poisson_ratio" in sec:
            nu = _num(sec["poisson_ratio"], f"{sp}.poisson_ratio")
            if not -1.0 < nu < 0.5 + 1e-12:
                raise SceneError(f"{sp}.poisson_ratio", f"must be in (-1, 0.5], got {nu:g}")
            G = E / (2.0 * (1.0 + nu))           # patent: G = E / 2(1 + v)
        else:
            raise SceneError(f"{sp}.poisson_ratio", "missing (or give shear_modulus)")
        I = math.pi * radius**4 / 4.0            # circular section: Ix = Iy, Iz = 2 Ix
        A = B = E * I
        C = G * 2.0 * I
    if "linear_density" in raw and "density" in raw:
        raise SceneError(f"{path}.density", "give linear_density or density, not both")
    if "linear_density" in raw:
        rho_l = _num(raw["linear_density"], f"{path}.linear_density", nonneg=True) * mu / lu
    elif "density" in raw:
        if radius is None:
            raise SceneError(f"{path}.density", "needs section.radius (or give linear_density)")
        rho_l = _num(raw["density"], f"{path}.density", nonneg=True) * mu / lu**3 * math.pi * radius**2
    else:
        rho_l = 0.0
    start = _end(raw["start"], f"{path}.start", lu, fu)
    end = _end(raw["end"], f"{path}.end", lu, fu)
    if start.condition == "free" and end.condition == "free":
        raise SceneError(f"{path}.end.condition", "both ends free: the cable is not held")
    num = _obj(raw.get("numerics", {}), f"{path}.numerics", {"model", "segments", "tol", "richardson"})
    model = num.get("model", "rod")
    if model not in MODELS:
        raise SceneError(f"{path}.numerics.model", f"expected one of {', '.join(MODELS)}, got {model!r}")
    seg = num.get("segments", 50)
    if isinstance(seg, bool) or not isinstance(seg, int) or not 2 <= seg <= 100000:
        raise SceneError(f"{path}.numerics.segments", f"expected an integer in 2..100000, got {seg!r}")
    tol = _num(num.get("tol", 1e-10), f"{path}.numerics.tol", positive=True)
    rich = num.get("richardson", False)
    if not isinstance(rich, bool):
        raise SceneError(f"{path}.numerics.richardson", "expected true or false")
    if model == "patent" and start.condition != "clamped":
        raise SceneError(f"{path}.start.condition", "the patent model needs a clamped start (its fixed end)")
    eff = raw.get("effects", list(DEFAULT_EFFECTS))
    if not isinstance(eff, list):
        raise SceneError(f"{path}.effects", f"expected a list of effect names ({', '.join(EFFECTS)})")
    for i, e in enumerate(eff):
        if e not in EFFECTS:
            raise SceneError(f"{path}.effects[{i}]", f"unknown effect {e!r} (known: {', '.join(EFFECTS)})")
    effects = frozenset(eff)
    mbr = raw.get("min_bend_radius")
    if mbr is not None:
        mbr = _num(mbr, f"{path}.min_bend_radius", positive=True) * lu
    if "min_bend_radius" in effects and mbr is None:
        raise SceneError(f"{path}.min_bend_radius", "the min_bend_radius effect needs its limit (a length)")
    sym = _num(raw.get("symmetry_threshold", 1e-3), f"{path}.symmetry_threshold", nonneg=True)
    slack = _num(raw.get("slack_warning", 0.02), f"{path}.slack_warning", nonneg=True)
    return CableSpec(name=name, length=length, stiffness=(A, B, C), linear_density=rho_l,
                     start=start, end=end, model=model, segments=seg, tol=tol, richardson=rich,
                     effects=effects, min_bend_radius=mbr, symmetry_threshold=sym,
                     slack_warning=slack, radius=radius, path=path)


def read_scene(raw, source: str | None = None) -> Scene:
    """Check a raw scene dict and convert it to SI. Raises :class:`SceneError`."""
    try:
        _obj(raw, "$", {"format", "units", "gravity", "cables", "description"}, ("format",))
        if raw["format"] != SCENE_FORMAT:
            raise SceneError("$.format", f"expected {SCENE_FORMAT!r}, got {raw['format']!r}")
        units, f = _units(raw.get("units"), "$.units")
        gravity = None
        if raw.get("gravity") is not None:
            gravity = _vec3(raw["gravity"], "$.gravity") * f["length"]
        cables_raw = raw.get("cables", [])
        if not isinstance(cables_raw, list):
            raise SceneError("$.cables", "expected a list")
        cables, names = [], set()
        for i, c in enumerate(cables_raw):
            spec = _cable(c, f"$.cables[{i}]", f, names)
            names.add(spec.name)
            cables.append(spec)
        return Scene(gravity=gravity, cables=tuple(cables), units=units, length_unit=f["length"])
    except SceneError as err:
        if source and err.source is None:
            raise SceneError(err.path, err.message, source) from None
        raise
