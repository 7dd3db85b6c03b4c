"""Write a :class:`~p105cli.kinematics.model.Mechanism` as Part 105 data, in any profile.

``write_mechanism(mech, profile, *, source=None, occt_compat=False)``
returns ``(JsonDocument, diagnostics)``.

Profiles (:data:`p105cli.part105.catalogue.PROFILES`):

* ``ap214`` - the Part 105:1996 layout as AP214's long form carries it
  (FILE_SCHEMA AUTOMOTIVE_DESIGN; pair frames are axis2_placement_3d only);
* ``p105`` - the same layout with ``su_parameters`` allowed;
* ``ap242`` - the AP242 (Part 105 ed. 2) layout.

Two modes:

* ``source=None``: a complete, self-contained file: the units of
  ``mech.units``, contexts, one product per link and the mechanism
  assembly (links placed at the initial state), link representations, the
  pairs with their ranges and actuation (and the higher pairs' curves and
  surfaces), the base (placement), the initial state and, in AP242, the
  loops. Built with :class:`~p105cli.part105.builder.Builder` (units,
  contexts, placements, products) and the records of
  :class:`~p105cli.part105.emit.Emitter` (the kinematics).
* ``source`` = the document the mechanism was read from: a *conversion*
  (:class:`~p105cli.part105.convert.Conversion`).
  Every instance outside the kinematic structure (products, shapes,
  geometry, units, contexts) is kept with its id; the kinematic instances
  are rewritten in the target layout; new instances get the ids of the
  source instances they replace where the role is the same (pair, joint,
  link, range, actuator, initial-state values), else ids above the source's
  maximum; references are remapped. Supporting items that only the old
  kinematic instances used (a replaced pair frame, the 1996 base
  placement's operator) go with them.

The motion program's configuration sequences are converted between the
layouts; other kinematic instances the writer does not produce (paths,
programs, results) are kept as they are when the target has their
entities and all they refer to is still there with the same type (a
same-layout conversion keeps them), else left out.

Nothing is dropped silently: whatever the target layout cannot say, and
every kinematic instance of the source that is neither re-expressed nor
kept, is one diagnostic string naming the ``#id``. See docs/conversion.md
for the layout differences and choices.

``occt_compat`` (AP242): Open CASCADE's reader misreads the standard ``*``
of derived attributes: it takes the derived freedom flags of a
``low_order_kinematic_pair`` subtype as all TRUE, the derived name of a
pair as missing, the derived context of a mechanism state as missing; it
reads a typed ``YPR_ROTATION`` orientation as a bad real, and it does not
know the ``actuated_kinematic_pair`` complex instance, ``kinematic_loop``
or the interpolated configuration entities. With ``occt_compat`` the flags
(``.T.``/``.F.``, the values the schema derives), the pair's name and the
state's context are written explicitly, orientations as the equal
``rotation_about_direction``, and actuation, loops and configuration
sequences are left out (a diagnostic each): the file loads in Open
CASCADE with an empty check list, at the price of SCH-* conformance
findings for the explicit values where the schema says ``*``.

SI inside the model; the writer converts to the file's units (``mech.units``,
or the source's units in a conversion).
"""

from __future__ import annotations

import math

import numpy as np

from p105cli.kinematics.placements import compose
from p105cli.step.values import ref_id

from .catalogue import APPLICATION, PROFILES
from .emit import SUPPORTED_KINDS, Emitter, IdBuilder, write_kinematics

__all__ = ["PROFILES", "write_mechanism", "SUPPORTED_KINDS"]


def write_mechanism(mech, profile: str, *, source=None, occt_compat: bool = False):
    """``(JsonDocument, diagnostics)``: ``mech`` in ``profile`` (see the module docstring)."""
    from p105cli.step import DataSection
    from p105cli.step.jsonmodel import JsonDocument

    from .convert import Conversion

    profile = profile.lower()
    if profile not in PROFILES:
        raise ValueError(f"unknown profile {profile!r} (one of {', '.join(PROFILES)})")
    diags: list[str] = []
    if occt_compat and PROFILES[profile]["layout"] != "ap242":
        diags.append(f"--occt-compat applies to AP242 output only; ignored for {profile}")
        occt_compat = False
    other = []
    if source is None:
        header, data = _standalone(mech, profile, occt_compat, diags)
        name = "<generated>"
    else:
        header, data = Conversion(mech, profile, source, occt_compat, diags).run()
        name = getattr(source, "source", "<input>")
        sections = list(getattr(source, "sections", ()) or ())
        if len(sections) > 1 or any(sec.parameters is not None for sec in sections):
            diags.append(f"the source's {len(sections)} DATA section(s) and their parameters are written as one "
                         "DATA section without parameters")
        for sec in getattr(source, "other_sections", ()) or ():
            if sec.get("keyword") == "SIGNATURE":
                diags.append("the SIGNATURE section is left out: it signs the source's bytes, not the converted file")
                continue
            other.append({**sec, "after_data": min(int(sec.get("after_data", 1)), 1)})
    scene = getattr(source, "scene", None) if source is not None else None
    return JsonDocument(header, [DataSection(None, len(data))], data, other, name, scene), diags



# ------------------------------------------------------------------ unit helpers

def _unit_choice(units) -> tuple[str | None, str, list[str]]:
    """(SI prefix or None, angle unit name, notes) that rebuild ``units``."""
    notes = []
    prefixes = {1.0: None, 1e-3: "milli", 1e-2: "centi", 1e-1: "deci", 1e3: "kilo", 1e-6: "micro"}
    prefix = None
    for f, p in prefixes.items():
        if math.isclose(units.length, f, rel_tol=1e-12):
            prefix = p
            break
    else:
        notes.append(f"length unit {units.length_name!r} ({units.length} m) is not an SI-prefixed metre: "
                     "written in millimetres")
        prefix = "milli"
    if math.isclose(units.angle, math.pi / 180.0, rel_tol=1e-12):
        angle = "degree"
    elif math.isclose(units.angle, 1.0, rel_tol=1e-12):
        angle = "radian"
    else:
        notes.append(f"plane-angle unit {units.angle_name!r} is neither radian nor degree: written in degrees")
        angle = "degree"
    return prefix, angle, notes


_PREFIX_FACTOR = {None: 1.0, "milli": 1e-3, "centi": 1e-2, "deci": 1e-1, "kilo": 1e3, "micro": 1e-6}


# ------------------------------------------------------------------ self-contained files

def _forward_poses(mech) -> dict:
    """``{link: T_base_link}`` at the initial state, by the solver's forward kinematics
    (:func:`p105cli.kinematics.solver.link_poses`) along the spanning tree from the base (a
    loop's closing pair is not used; a part not connected to the base is placed from its
    first link). A pair whose motion is not a function of its values (a rolling surface
    pair) places its second link at its first's."""
    from p105cli.kinematics.solver import link_poses, plan

    pl = plan(mech)
    X, _, _ = link_poses(pl, mech.initial_vector(), unsupported="identity")
    return {ln: X[i] for ln, i in pl.link_index.items()}


def _standalone(mech, profile, occt_compat, diags):
    prof = PROFILES[profile]
    prefix, angle, notes = _unit_choice(mech.units)
    diags.extend(notes)
    lf = _PREFIX_FACTOR[prefix]
    degree = mech.units.angle if angle == "degree" and not notes else math.pi / 180.0
    angle_factor = 1.0 / degree if angle == "degree" else 1.0
    b = IdBuilder(angle_factor)
    b.units(cbu_dimensions_explicit=prof["cbu_dimensions_explicit"], length_prefix=prefix, angle=angle,
            uncertainty=1e-10 / lf, degree_factor=degree)
    k = Emitter(mech, profile, b, lf, occt_compat, diags)
    k.record_of = lambda ref: next((r for r in b.data if r["id"] == ref_id(ref)), None)
    key = mech.name
    k.world_ctx = b.context(f"{key} world")
    k.link_ctx = {ln.name: b.context(f"{key} link {ln.name}") for ln in mech.links}

    app, schema_name, year = APPLICATION[prof["layout"]]
    pf = b.product_frame(app, schema_name, year)
    origins, parts = {}, {}
    for ln in mech.links:
        origins[ln.name] = b.axis2(np.eye(4), f"{ln.name} link frame")
        parts[ln.name] = b.part(pf, f"{key}-{ln.name}", ln.name, ln.description, [origins[ln.name]],
                                k.link_ctx[ln.name], shape_name=f"{ln.name} shape")
        k.link_shape[ln.name] = parts[ln.name]["shape"]
        k.link_pd[ln.name] = parts[ln.name]["pd"]
        k.extra_items[ln.name] = [k.axis2(T, fname) for fname, T in ln.frames.items()]
    poses = _forward_poses(mech)
    world = b.axis2(np.eye(4), "world")
    placements = {ln.name: k.axis2(compose(mech.T_world_base, poses[ln.name]), f"{ln.name} placement")
                  for ln in mech.links}
    assembly = b.part(pf, key, mech.name, mech.description, [world, *placements.values()], k.world_ctx,
                      shape_name=f"{key} assembly")
    k.assembly_pd = assembly["pd"]
    k.world_origin = world
    for n, ln in enumerate(mech.links, start=1):
        usage = b.assembly_usage(assembly, parts[ln.name], f"{key}.{n}", ln.name, origins[ln.name],
                                 placements[ln.name])
        k.link_nauo[ln.name] = usage["nauo"]
    products = [assembly["product"], *(parts[ln.name]["product"] for ln in mech.links)]
    b.add("product_related_product_category", "part", None, products)
    if prof["layout"] == "1996":
        org = b.add("organization", "p105cli", "p105cli", None)
        b.add("applied_organization_assignment", org, b.add("organization_role", "id owner"), products)
    write_kinematics(k, diags)
    k.finish()
    header = {
        "file_description": {"description": [f"mechanism {mech.name}; {prof['label']}"],
                             "implementation_level": "2;1"},
        "file_name": {"name": f"{mech.name}.stp", "time_stamp": "", "author": [""], "organization": [""],
                      "preprocessor_version": "p105cli", "originating_system": "p105cli", "authorization": ""},
        "file_schema": [prof["schema"]],
    }
    return header, b.data

