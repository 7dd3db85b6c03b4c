"""AP242 output loads in Open CASCADE (a peer reader), through cadquery-ocp.

`write_mechanism(..., occt_compat=True)` (`p105 export --schema ap242
--occt-compat`) must give files that Open CASCADE's STEP reader loads with
an empty check list and reads as its StepKinematics entities. The files
are the AP242 corpus files converted through our writer and the 1996
(AP214, p105) corpus files converted to AP242.
"""

from __future__ import annotations

import io
from collections import Counter

import pytest

OCP = pytest.importorskip("OCP")

from OCP.IFSelect import IFSelect_RetDone  # noqa: E402
from OCP.STEPControl import STEPControl_Reader  # noqa: E402

from conftest import ROOT  # noqa: E402
from p105cli.kinematics.reader import read_mechanisms  # noqa: E402
from p105cli.part105.write_mechanism import write_mechanism  # noqa: E402
from p105cli.step import read_step, write_step  # noqa: E402

CORPUS = ROOT / "tests" / "data" / "corpus"

MECHANISMS = ("four_bar", "slider_crank", "ur5_arm", "gear_train", "rack_and_pinion", "cam_follower",
              "spherical_linkage")


def expected_pairs(mech) -> Counter:
    """Open CASCADE's class for each pair of the model read by p105 (kind, range or not)."""
    out = Counter()
    for p in mech.pairs:
        camel = "".join(w.capitalize() for w in p.kind.split("_"))
        ranged = any(v is not None for v in (*p.lower, *p.upper))
        out[f"StepKinematics_{camel}Pair{'WithRange' if ranged else ''}"] += 1
    return out


ALWAYS = ("StepKinematics_KinematicLink", "StepKinematics_KinematicJoint", "StepKinematics_RigidLinkRepresentation",
          "StepKinematics_MechanismRepresentation", "StepKinematics_KinematicTopologyStructure",
          "StepKinematics_PairRepresentationRelationship", "StepKinematics_MechanismStateRepresentation",
          "StepKinematics_KinematicPropertyMechanismRepresentation",
          "StepKinematics_ProductDefinitionRelationshipKinematics",
          "StepKinematics_ContextDependentKinematicLinkRepresentation")


def _messages(check) -> list:
    out = []
    for k in range(1, check.NbFails() + 1):
        out.append("fail: " + check.CFail(k))
    for k in range(1, check.NbWarnings() + 1):
        out.append("warning: " + check.CWarning(k))
    return out


def load_in_occt(path):
    """(entity type counts, check messages by entity number) of Open CASCADE's reading."""
    reader = STEPControl_Reader()
    assert reader.ReadFile(str(path)) == IFSelect_RetDone
    ws = reader.WS()
    checks = ws.ModelCheckList()
    found = {}
    checks.Start()
    while checks.More():
        found[checks.Number()] = _messages(checks.Value())
        checks.Next()
    model = ws.Model()
    types = Counter(model.Value(i).DynamicType().Name() for i in range(1, model.NbEntities() + 1))
    return types, {k: v for k, v in found.items() if v}, checks.IsEmpty(False)


def convert(tmp_path, name, src, occt_compat=True):
    doc = read_step((CORPUS / f"{name}_{src}.stp").read_text(), f"{name}_{src}.stp")
    (mech,) = read_mechanisms(doc)
    out, diags = write_mechanism(mech, "ap242", source=doc, occt_compat=occt_compat)
    buf = io.StringIO()
    write_step(out, buf)
    path = tmp_path / f"{name}_{src}_occt.stp"
    path.write_text(buf.getvalue())
    return path, mech, diags


CASES = [(m, s) for m in MECHANISMS for s in ("ap242", "ap214")] + [("ur5_arm", "p105")]


@pytest.mark.parametrize("name,src", CASES, ids=[f"{m}-{s}" for m, s in CASES])
def test_occt_compat_output_loads_with_an_empty_check_list(tmp_path, name, src):
    path, mech, diags = convert(tmp_path, name, src)
    types, checks, empty = load_in_occt(path)
    assert checks == {} and empty
    assert "StepData_UndefinedEntity" not in types
    for t in ALWAYS:
        assert types[t] >= 1, t
    assert types["StepKinematics_KinematicLink"] == len(mech.links)
    assert types["StepKinematics_KinematicJoint"] == len(mech.pairs)
    pairs = expected_pairs(mech)
    assert sum(pairs.values()) == len(mech.pairs)
    for t, n in pairs.items():
        assert types[t] == n, (t, types[t])
    # actuation is what Open CASCADE cannot take: said, not dropped silently
    actuated = [p.name for p in mech.pairs if p.actuated]
    assert len([d for d in diags if "actuation not written" in d]) == len(actuated)


def test_standard_output_is_what_occt_misreads(tmp_path):
    """The reason for --occt-compat: the standard '*' of the derived flags and names is
    reported by Open CASCADE (and the actuated complex instance is not known to it)."""
    path, _, _ = convert(tmp_path, "slider_crank", "ap214", occt_compat=False)
    types, checks, empty = load_in_occt(path)
    assert not empty
    assert any("low_order_kinematic_pair.t_x" in m for msgs in checks.values() for m in msgs)


@pytest.mark.parametrize("which", ["low", "higher"])
def test_every_pair_kind_loads_in_occt(tmp_path, which):
    """Self-contained files (source=None) with one pair of every kind p105 writes."""
    from test_model_writer import _hand_built, _higher, text_of

    from p105cli.kinematics.model import Units

    mech = (_hand_built if which == "low" else _higher)(Units(1e-3, 0.0174532925199433, "millimetre", "degree"))
    doc, diags = write_mechanism(mech, "ap242", occt_compat=True)
    path = tmp_path / f"{which}.stp"
    path.write_text(text_of(doc))
    types, checks, empty = load_in_occt(path)
    assert checks == {} and empty
    for t, n in expected_pairs(mech).items():
        assert types[t] == n, (t, types[t])
    values = sum(n for t, n in types.items() if t.startswith("StepKinematics_") and t.endswith("PairValue"))
    assert values == len(mech.initial)
