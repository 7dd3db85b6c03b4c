"""A model file read once: document + profile (chosen once) + Population (built once) +
checked access to its instances.

``ModelFile.of(doc, profile=None)`` accepts what ``cli.inputs.load_document`` gives (a
``StepFile`` or ``JsonDocument``), a ``Population``, or a ``ModelFile`` (returned as is). The
profile is FILE_SCHEMA's unless given; a 1996-layout AP214 file holding su_parameters is read
as ``p105`` (:func:`p105cli.part105.catalogue.choose_profile`).

Access, checked (the model readers): ``ref``, ``refs``, ``number``, ``vector``, ``direction``,
``placement``, ``su`` ... raise :class:`~p105cli.step.errors.ModelError` whose message starts
with the ``#id`` at fault and names the attribute (``err.instance_id`` holds the id).

Access, lenient (the validator; ``ModelFile.of(..., lenient=True)`` or ``mf.lenient()``):
``get`` returns :data:`MISSING` for an attribute the instance lacks, ``ref`` returns None for
an unset, dangling or mistyped reference, ``refs`` skips what is no reference, ``number``
returns None; nothing raises.

Lenient reading (the analysis commands): where a file departs from its schema in a way whose
meaning is plain (build123d's AP242 kinematics: pairs listed directly among the mechanism's
items, links among the topology's items, explicit values where AP242 derives), the readers read
it anyway and record one deviation each with :meth:`ModelFile.deviation` (the ``#id`` and the
rule it breaks); the command prints them with :func:`take_deviations`. ``validate`` reports the
same departures as errors.

``scale(rep)`` gives the SI factors of a representation's context (:class:`ContextScale`); a
missing unit is an error only when a value of its kind is read.
"""

from __future__ import annotations

import math
import weakref
from typing import Optional

from ..schema.units import ANGLE, LENGTH, ContextUnits, UnitReader
from ..schema.values import number as _num
from ..schema.values import ref as _ref
from ..schema.values import untyped as _untyped
from ..step.errors import ModelError
from .catalogue import choose_profile, layout_of

# numpy and the kinematics maths are imported where a placement is computed: validating a file
# (the lenient walk) never needs them

__all__ = ["ModelFile", "ContextScale", "MISSING", "model_error", "open_population", "take_deviations"]

#: What lenient ``get`` returns for an attribute an instance does not have.
MISSING = object()

#: The largest magnitude of a number the model readers accept: the analysis multiplies
#: lengths, angles and their derivatives (norms, Jacobians, products of placements), which
#: must stay finite; no mechanism needs anything near it (the observable universe is 1e26 m).
MAX_MAGNITUDE = 1e100


def _too_large(x) -> bool:
    return abs(x) > MAX_MAGNITUDE


def model_error(iid, message: str) -> ModelError:
    """A ModelError whose message starts with ``#iid`` (``err.instance_id`` holds it)."""
    err = ModelError(f"#{iid}: {message}" if iid is not None else message)
    err.instance_id = iid
    return err


def _deviations_of(doc) -> dict:
    """The deviations found in ``doc`` (``(#id, message)`` -> None, in the order found): kept on
    the document, so that every model file read from it (a command may build more than one)
    reports to the same place, once."""
    found = getattr(doc, "_part105_deviations", None)
    if found is None:
        found = {}
        try:
            doc._part105_deviations = found
        except (AttributeError, TypeError):  # records given as a list: kept with the model file
            pass
    return found


def take_deviations(doc) -> list:
    """The deviations of ``doc`` (a document or a ModelFile) not taken yet, each as ``#id:
    message``; taking them empties the list (a command reports each once)."""
    if isinstance(doc, ModelFile):
        found = doc._deviations
    else:
        found = getattr(doc, "_part105_deviations", None) or {}
    out = _deviation_texts(found)
    found.clear()
    return out


def _deviation_texts(found: dict) -> list:
    return [f"#{i}: {m}" if i is not None else m for i, m in found]


def open_population(doc, profile=None):
    """``(Population, profile name)`` for ``doc``: FILE_SCHEMA's profile unless ``profile``
    is given (a name or a Profile), a 1996-layout AP214 file holding su_parameters read as
    ``p105``. Every command that reads mechanisms chooses its profile here."""
    from ..schema.population import Population
    from ..schema.profiles import get_profile, profile_for_header

    if isinstance(doc, ModelFile):
        return doc.pop, doc.profile
    if isinstance(doc, Population):
        name = doc.profile.name if doc.profile is not None else profile
        return doc, (name or "ap214")
    if profile is not None and not isinstance(profile, str):
        profile = profile.name  # a Profile
    if profile is not None:
        prof = get_profile(profile)
        return Population(doc, prof), prof.name
    prof = profile_for_header(getattr(doc, "header", {}))
    if prof.name != "ap214":
        return Population(doc, prof), prof.name
    # AP214's long form has no su_parameters: look for them in the document before choosing
    if getattr(doc, "index", None) is None and getattr(doc, "data", None) is None:
        doc = list(doc)  # records given as an iterable: read them once (a population would)
    name = choose_profile(prof.name, _holds_instance_of(doc, "su_parameters"))
    return Population(doc, prof if name == prof.name else get_profile(name)), name


def _holds_instance_of(doc, entity: str) -> bool:
    """Whether ``doc`` (a Part 21 file, a JSON document or a list of records) holds an instance
    naming ``entity`` (simple, or a part of a complex instance), found without typing the file:
    for an entity outside the schema (su_parameters in AP214) what a population would find."""
    def names(rec) -> list:
        return [p.get("type") for p in rec["complex"]] if "complex" in rec else [rec.get("type")]

    index = getattr(doc, "index", None)
    if index is not None and hasattr(doc, "record"):  # a Part 21 file: the type index
        if entity in index.types:
            return True
        # instances the index leaves untyped (complex ones) are decoded
        return any(entity in names(doc.record(index.ids[k])) for k, t in enumerate(index.types) if t is None)
    return any(entity in names(r) for r in (doc.data if hasattr(doc, "data") else doc))


class ContextScale:
    """SI factors of one representation's context; a missing unit is an error only when a
    value of its kind is read."""

    _WORDS = {LENGTH: "length", ANGLE: "plane-angle"}

    def __init__(self, mf: "ModelFile", rep: Optional[int]):
        self.rep = rep
        self.ctx = mf.ref(rep, "context_of_items") if rep is not None else None
        self.cu = mf.context_units(self.ctx)
        self._length = self._angle = None

    def _factor(self, kind) -> float:
        cu = self.cu
        u = cu.unit(kind)
        if u is not None:
            return float(u[0])
        word = self._WORDS[kind]
        if self.rep is None:
            raise model_error(None, f"no representation gives the {word} unit")
        if self.ctx is None:
            raise model_error(self.rep, f"representation has no context: its {word} unit is unknown")
        for _sev, ent, msg in cu.problems:
            if word in msg:
                raise model_error(ent, msg)
        if not cu.assigned:
            raise model_error(self.ctx, f"context is no global_unit_assigned_context: it gives no "
                              f"{word} unit to representation #{self.rep} (ISO 10303-105 5.2.5)")
        raise model_error(self.ctx, f"context assigns no {word} unit, but representation "
                          f"#{self.rep} has {word} values (ISO 10303-105 5.2.5)")

    @property
    def length(self) -> float:
        if self._length is None:
            self._length = self._factor(LENGTH)
        return self._length

    @property
    def angle(self) -> float:
        if self._angle is None:
            self._angle = self._factor(ANGLE)
        return self._angle

    def units(self) -> "Units":
        """The model's Units of this context (SI for a kind it does not give)."""
        from ..kinematics.model import Units

        lu, au = self.cu.length, self.cu.angle
        return Units(length=float(lu[0]) if lu else 1.0, angle=float(au[0]) if au else 1.0,
                     length_name=lu[1] if lu else "metre", angle_name=au[1] if au else "radian")


class ModelFile:
    """One model file: ``doc``, ``pop`` (its Population), ``profile`` (name), ``layout``
    (``"1996"`` or ``"ap242"``), ``schema``, ``source``; checked or lenient access."""

    def __init__(self, doc, profile=None, *, lenient: bool = False, _shared=None):
        if _shared is not None:
            other = _shared
            self.doc, self.pop, self.profile = other.doc, other.pop, other.profile
            self.units, self._scales, self._cache = other.units, other._scales, other._cache
            self._deviations = other._deviations
        else:
            self.pop, self.profile = open_population(doc, profile)
            self.doc = getattr(self.pop, "doc", doc)
            self.units = UnitReader(self.pop)
            self._scales: dict = {}
            self._cache: dict = {}  # results computed once per file (the layout walk, ...)
            self._deviations = _deviations_of(self.doc)
            # the population's model file: every reader given this population shares its walks
            self.pop._part105_model_file = weakref.ref(self)
        self.schema = self.pop.schema
        self.layout = layout_of(self.profile)
        self.is_lenient = lenient
        self._lenient_view = self if lenient else None
        self._checked_view = None if lenient else self
        self.source = getattr(self.doc, "source", None) or getattr(doc, "source", None)

    @classmethod
    def of(cls, doc, profile=None, *, lenient: bool = False) -> "ModelFile":
        """``doc`` as a ModelFile (a ModelFile is returned as is, or its lenient view)."""
        if isinstance(doc, ModelFile):
            return doc.lenient() if lenient else doc
        known = getattr(doc, "_part105_model_file", None)  # a Population a ModelFile was built on
        mf = known() if known is not None else None
        if mf is None:
            return cls(doc, profile, lenient=lenient)
        return mf.lenient() if lenient else mf.checked()

    def lenient(self) -> "ModelFile":
        """The lenient view of this file (same population, same caches)."""
        if self._lenient_view is None:
            self._lenient_view = ModelFile(None, lenient=True, _shared=self)
            self._lenient_view._checked_view = self
        return self._lenient_view

    def checked(self) -> "ModelFile":
        """The checked view of this file (same population, same caches)."""
        if self._checked_view is None:
            self._checked_view = ModelFile(None, lenient=False, _shared=self)
            self._checked_view._lenient_view = self
        return self._checked_view

    def cached(self, key, compute):
        """``compute()`` once per file (shared by the checked and the lenient view)."""
        if key not in self._cache:
            self._cache[key] = compute()
        return self._cache[key]

    def deviation(self, iid, message: str) -> None:
        """Record that ``#iid`` departs from the schema in the way ``message`` says (the rule it
        breaks, and how it is read anyway; a pair value projected onto its pair's freedoms); the
        same deviation is recorded once."""
        self._deviations.setdefault((iid, message), None)

    def deviations(self) -> list:
        """The deviations recorded so far and not taken (:func:`take_deviations`), each as
        ``#id: message``, in the order found."""
        return _deviation_texts(self._deviations)

    # ---------------------------------------------------------------- basics
    def __contains__(self, i) -> bool:
        return i is not None and i in self.pop

    def types(self, i) -> frozenset:
        if i is None:
            return frozenset()
        try:
            return self.pop.types_of(i)
        except (KeyError, TypeError):
            return frozenset()

    def is_a(self, i, *names) -> bool:
        t = self.types(i)
        return any(n in t for n in names)

    def leaf_types(self, i) -> frozenset:
        return self.pop.leaf_types_of(i)

    def label(self, i) -> str:
        """The instance's entity (parts of a complex instance joined by ``+``, sorted)."""
        try:
            return "+".join(sorted(self.leaf_types(i)))
        except (KeyError, TypeError):
            return ""

    def names(self, i) -> list:
        """The explicit attribute names of ``#i`` (``[]`` for an unknown instance)."""
        try:
            return self.pop.instance(i).explicit_names()
        except Exception:  # noqa: BLE001 - not decodable: no attributes
            return []

    def get(self, i, attr, default=MISSING):
        """The raw value of explicit attribute ``attr`` of ``#i``. Checked: an unknown instance
        or attribute raises (unless ``default`` is given); lenient: ``default`` (MISSING)."""
        if self.is_lenient:
            try:
                inst = self.pop.instance(i)
                if inst.record is None:
                    return default
                return inst.get(attr)
            except Exception:  # noqa: BLE001 - no such attribute / instance
                return default
        try:
            inst = self.pop.instance(i)
        except KeyError:
            raise model_error(i, "instance is not in the file") from None
        try:
            return inst.get(attr)
        except Exception:  # noqa: BLE001 - no such attribute for this instance's types
            if default is not MISSING:
                return default
            raise model_error(i, f"{self.label(i)} has no attribute {attr!r}") from None

    def has(self, i, attr) -> bool:
        """``#i`` has attribute ``attr`` (set or not)."""
        try:
            inst = self.pop.instance(i)
            if inst.record is None:
                return False
            inst.get(attr)
            return True
        except Exception:  # noqa: BLE001 - no such instance or attribute
            return False

    def ref(self, i, attr, *, optional: bool = False, types=None) -> Optional[int]:
        """The id ``#i.attr`` refers to. Checked: a ModelError naming ``#i`` when it is unset
        (unless ``optional``), dangling, or not of one of ``types``. Lenient: None then."""
        v = self.get(i, attr, None) if self.is_lenient else self.get(i, attr)
        if v is None or v is MISSING or (type(v) is dict and v.get("derived")):
            if optional or self.is_lenient:
                return None
            raise model_error(i, f"{self.label(i)} has no {attr} (it is unset)")
        return self._target(i, attr, _ref(v), types)

    def _target(self, i, attr, r, types, item=MISSING) -> Optional[int]:
        """``r``, the id ``#i.attr`` (or its element ``item``) names, if it is an instance of the
        file of one of ``types``. Checked: a ModelError saying which of those it is not;
        lenient: None then."""
        if self.is_lenient:
            if r is None or r not in self.pop or (types and not self.is_a(r, *types)):
                return None
            return r
        if r is None:
            what = "is not a reference" if item is MISSING else f"holds {item!r}, not a reference"
            raise model_error(i, f"{attr} of {self.label(i)} {what}")
        if r not in self.pop:
            raise model_error(i, f"{attr} of {self.label(i)} refers to #{r}, which is not in the file")
        if types and not self.is_a(r, *types):
            raise model_error(i, f"{attr} of {self.label(i)} refers to #{r} ({self.label(r)}), which is "
                              f"no {' or '.join(types)}")
        return r

    def ref_value(self, i, attr) -> Optional[int]:
        """The id an attribute's value names, unchecked (None when it is no reference)."""
        return _ref(self.get(i, attr, None))

    def first_ref(self, i, *attrs) -> Optional[int]:
        """Lenient: the reference of the first of ``attrs`` that ``#i`` has (None if it is no
        reference to an instance of the file)."""
        for a in attrs:
            if self.has(i, a):
                r = _ref(self.get(i, a, None))
                return r if r is not None and r in self.pop else None
        return None

    def refs(self, i, attr, *, types=None) -> list:
        """The ids of the aggregate attribute ``#i.attr`` (each checked like :meth:`ref`;
        lenient: what is no reference to an instance of ``types`` is skipped)."""
        v = _untyped(self.get(i, attr, None) if self.is_lenient else self.get(i, attr))
        if v is None or v is MISSING:
            return []
        if type(v) is not list:
            if self.is_lenient:
                return []
            raise model_error(i, f"{attr} of {self.label(i)} is not a list")
        out = (self._target(i, attr, _ref(x), types, x) for x in v)
        return [r for r in out if r is not None]

    def number(self, i, attr, *, optional: bool = False) -> Optional[float]:
        """A finite REAL of ``#i.attr``. Checked: a ModelError otherwise (None when unset and
        ``optional``); lenient: None otherwise."""
        v = self.get(i, attr, None) if self.is_lenient else self.get(i, attr)
        if v is None and optional:
            return None
        x = _num(v) if v is not MISSING else None
        if x is None or not math.isfinite(x):
            if self.is_lenient:
                return None
            raise model_error(i, f"{attr} of {self.label(i)} is {v!r}, not a finite number")
        if _too_large(x) and not self.is_lenient:
            raise model_error(i, f"{attr} of {self.label(i)} is {x!r}, beyond the magnitudes p105 computes "
                              f"with ({MAX_MAGNITUDE:g})")
        return x

    def string(self, i, *attrs) -> str:
        """The first of ``attrs`` that is a string (derived and unset ones skipped), else ''."""
        if i is None:
            return ""
        for a in attrs:
            v = _untyped(self.get(i, a, None))
            if isinstance(v, str):
                return v
        return ""

    def usedin(self, i, role: str) -> list:
        """Ids of the instances referring to ``#i`` through ``role`` (entity.attribute), in file order."""
        ent = role.split(".")[0]
        if ent not in self.schema.entities or i is None:
            return []
        return [inst.id for inst in self.pop.usedin(i, role)]

    def ids_of_type(self, entity: str) -> list:
        if entity not in self.schema.entities:
            return []
        return self.pop.ids_of_type(entity)

    # ---------------------------------------------------------------- units
    def context_units(self, ctx) -> ContextUnits:
        return self.units.context_units(ctx)

    def scale(self, rep) -> ContextScale:
        """The SI factors of representation ``#rep``'s context."""
        s = self._scales.get(rep)
        if s is None:
            s = self._scales[rep] = ContextScale(self.checked(), rep)
        return s

    # ---------------------------------------------------------------- geometry (checked)
    def vector(self, i, attr) -> list:
        v = _untyped(self.get(i, attr))
        if type(v) is not list or not v:
            raise model_error(i, f"{attr} of {self.label(i)} is not a list of numbers")
        out = [_num(x) for x in v]
        if None in out or not all(math.isfinite(x) for x in out):
            raise model_error(i, f"{attr} of {self.label(i)} is {v!r}, not a list of finite numbers")
        if any(map(_too_large, out)):
            raise model_error(i, f"{attr} of {self.label(i)} is {v!r}, beyond the magnitudes p105 computes "
                              f"with ({MAX_MAGNITUDE:g})")
        return out

    def direction(self, i, attr) -> Optional[list]:
        d = self.ref(i, attr, optional=True, types=("direction",))
        return None if d is None else self.vector(d, "direction_ratios")

    def placement(self, i, scale: ContextScale) -> "np.ndarray":
        """``#i`` (axis2_placement_3d, su_parameters or cartesian_transformation_operator_3d)
        as a 4x4 transform in metres; lengths and angles in ``scale``'s units."""
        from ..kinematics import placements as pl

        t = self.types(i)
        if "su_parameters" in t and "su_parameters" not in self.schema.entities:
            raise model_error(i, f"su_parameters is not part of the {self._profile_name()} profile; "
                              "read the file with profile p105 (ISO 10303-105:1996) or ap242")
        try:
            if "axis2_placement_3d" in t:
                loc = self.ref(i, "location", types=("cartesian_point",))
                xyz = self.vector(loc, "coordinates")
                if len(xyz) != 3:
                    raise model_error(loc, f"location of #{i} has {len(xyz)} coordinates, not 3")
                f = scale.length
                return pl.axis2_placement_3d([c * f for c in xyz], self.direction(i, "axis"),
                                             self.direction(i, "ref_direction"))
            if "su_parameters" in t:
                return pl.su_parameters(*self.su(i, scale))
            if "cartesian_transformation_operator_3d" in t:
                return self._cto3d(i, scale)
            if "item_defined_transformation" in t:
                return self.item_defined_transformation(i, scale, scale)
        except ValueError as e:  # degenerate axes (Part 42 WR) from placements
            raise model_error(i, f"{self.label(i)} is not a valid placement: {e}") from None
        raise model_error(i, f"{self.label(i) or 'instance'} is not a placement (axis2_placement_3d or "
                          "su_parameters)")

    def _profile_name(self) -> str:
        p = getattr(self.pop, "profile", None)
        return getattr(p, "name", None) or str(self.schema.name)

    def su(self, i, scale: ContextScale) -> tuple:
        """``(a, alpha, b, beta, c, gamma)`` of su_parameters ``#i`` in SI."""
        lf, af = scale.length, scale.angle
        a, alpha, b, beta, c, gamma = (self.number(i, n) for n in ("a", "alpha", "b", "beta", "c", "gamma"))
        return (a * lf, alpha * af, b * lf, beta * af, c * lf, gamma * af)

    def _cto3d(self, i, scale: ContextScale) -> "np.ndarray":
        """Part 42 ``cartesian_transformation_operator_3d`` as a rigid 4x4 (scale must be 1)."""
        import numpy as np

        from ..kinematics import placements as pl
        from ..kinematics import spatial

        axes = {a: self.direction(i, a) for a in ("axis1", "axis2", "axis3")}
        raw_scale = self.get(i, "scale", None)
        s = _num(raw_scale) if raw_scale is not None else 1.0
        if s is None or not math.isfinite(s) or abs(s - 1.0) > 1e-12:
            raise model_error(i, f"scale {raw_scale!r} of the transformation operator is not 1: it is "
                              "not a rigid placement")
        R = pl.build_axes(axes["axis3"], axes["axis1"])  # Part 42 base_axis: z, then x projected
        if axes["axis2"] is not None:
            y = np.asarray(axes["axis2"], float)
            if float(R[:, 1] @ y) <= 0.0:
                raise model_error(i, "axis1, axis2, axis3 are left-handed or degenerate: the operator "
                                  "is not a rigid placement")
        loc = self.ref(i, "local_origin", types=("cartesian_point",))
        xyz = self.vector(loc, "coordinates")
        return spatial.transform(R, [c * scale.length for c in xyz])

    def item_defined_transformation(self, i, scale1: ContextScale, scale2: ContextScale) -> "np.ndarray":
        """``T_rep2_rep1`` of an item_defined_transformation: ``T(item_2) @ inv(T(item_1))``."""
        from ..kinematics import spatial

        a = self.ref(i, "transform_item_1")
        b = self.ref(i, "transform_item_2")
        open_ = self._cache.setdefault("transformations being placed", set())
        if i in open_:  # a transform item that is (or leads back to) this transformation
            raise model_error(i, f"{self.label(i)} refers back to itself through its transform items: "
                              "it places nothing")
        open_.add(i)
        try:
            return self.placement(b, scale2) @ spatial.inverse(self.placement(a, scale1))
        finally:
            open_.discard(i)
