"""Scene files p105-scene/1: JSON Schema, parser, SI conversion, errors naming the JSON path."""

from __future__ import annotations

import copy
import json
import math

import jsonschema
import numpy as np
import pytest

from conftest import EXAMPLES
from p105cli.cable.scene import (SCHEMA_PATH, SceneError, load_scene_file, read_scene,
                                 scene_has_cables)

SCHEMA = json.loads(open(SCHEMA_PATH, encoding="utf-8").read())
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)
EXAMPLE = json.loads((EXAMPLES / "cable_scene.json").read_text())

ROT = [[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 0], [0, 0, 0, 1]]


def minimal(**cable):
    c = {"name": "c", "length": 1.0,
         "section": {"bending_stiffness": [1.0, 2.0], "torsional_stiffness": 0.5},
         "start": {"link": None, "pose": ROT}, "end": {"link": "arm", "pose": ROT, "condition": "pinned"}}
    c.update(cable)
    return {"format": "p105-scene/1", "cables": [c]}


def test_schema_is_a_valid_draft_2020_12_schema():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)


def test_example_validates_and_converts_to_si():
    VALIDATOR.validate(EXAMPLE)
    sc = read_scene(EXAMPLE)
    c = sc.cables[0]
    assert c.length == pytest.approx(0.6)
    # circular section (patent eq. 18-19): A = B = E pi a^4 / 4, C = G pi a^4 / 2, G = E / 2(1 + v)
    E, a, nu = 200e6, 4e-3, 0.4
    Ix = math.pi * a**4 / 4
    assert c.stiffness[0] == pytest.approx(E * Ix, rel=1e-14)
    assert c.stiffness[1] == pytest.approx(E * Ix, rel=1e-14)
    assert c.stiffness[2] == pytest.approx(E / (2 * (1 + nu)) * 2 * Ix, rel=1e-14)
    # density 1.5e-6 kg/mm^3 = 1500 kg/m^3 over a 4 mm radius
    assert c.linear_density == pytest.approx(1500 * math.pi * a**2, rel=1e-14)
    np.testing.assert_allclose(sc.gravity, [0, 0, -9.81])
    np.testing.assert_allclose(sc.weight(c), [0, 0, -9.81 * 1500 * math.pi * a**2])
    np.testing.assert_allclose(c.end.pose[:3, 3], [0.45, 0, 0])
    assert c.min_bend_radius == pytest.approx(0.04)
    assert c.effects == {"shape", "end_loads", "min_bend_radius", "overlength", "symmetry_check"}
    assert c.model == "rod" and c.segments == 40


def test_stiffness_given_directly_and_units():
    raw = minimal()
    raw["units"] = {"length": "mm", "force": "kN"}
    raw["cables"][0]["section"] = {"bending_stiffness": [3.0, 4.0], "torsional_stiffness": 5.0}
    raw["cables"][0]["linear_density"] = 2.0          # kg/mm
    c = read_scene(raw).cables[0]
    # kN mm^2 = 1e3 * 1e-6 N m^2
    np.testing.assert_allclose(c.stiffness, [3e-3, 4e-3, 5e-3], rtol=1e-14)
    assert c.linear_density == pytest.approx(2000.0)
    assert read_scene(raw).gravity is None
    np.testing.assert_allclose(read_scene(raw).weight(c), 0.0)


def test_shear_modulus_instead_of_poisson():
    raw = minimal(section={"radius": 0.01, "youngs_modulus": 1e9, "shear_modulus": 3e8})
    VALIDATOR.validate(raw)
    c = read_scene(raw).cables[0]
    assert c.stiffness[2] == pytest.approx(3e8 * math.pi * 1e-8 / 2, rel=1e-14)


def test_defaults():
    c = read_scene(minimal()).cables[0]
    assert c.start.condition == "clamped" and c.start.link is None
    assert c.end.link == "arm" and c.end.condition == "pinned"
    assert c.model == "rod" and c.segments == 50 and c.tol == 1e-10
    assert c.effects == {"shape", "overlength"}
    assert c.linear_density == 0.0


def _set(raw, path, value):
    node = raw
    for k in path[:-1]:
        node = node[k]
    if value is _DEL:
        del node[path[-1]]
    else:
        node[path[-1]] = value


_DEL = object()
C0 = ("cables", 0)

# (JSON path to change, new value, the path the parser must name, schema must reject too)
INVALID = [
    (("format",), "p105-scene/2", "$.format", True),
    (("extra",), 1, "$.extra", True),
    (("units",), {"length": "furlong"}, "$.units.length", True),
    (("gravity",), [0, -9.81], "$.gravity", True),
    (C0 + ("length",), -1.0, "$.cables[0].length", True),
    (C0 + ("length",), "long", "$.cables[0].length", True),
    (C0 + ("name",), _DEL, "$.cables[0].name", True),
    (C0 + ("colour",), "red", "$.cables[0].colour", True),
    (C0 + ("section",), {"radius": 0.01, "youngs_modulus": 1e9}, "$.cables[0].section.poisson_ratio", True),
    (C0 + ("section",), {"youngs_modulus": 1e9, "poisson_ratio": 0.3}, "$.cables[0].section.radius", True),
    (C0 + ("section",), {"bending_stiffness": [1.0], "torsional_stiffness": 1.0},
     "$.cables[0].section.bending_stiffness", True),
    (C0 + ("section",), {"radius": 0.01, "youngs_modulus": 1e9, "poisson_ratio": 0.7},
     "$.cables[0].section.poisson_ratio", True),
    (C0 + ("start", "condition"), "welded", "$.cables[0].start.condition", True),
    (C0 + ("start", "pose"), [[1, 0, 0], [0, 1, 0]], "$.cables[0].start.pose", True),
    (C0 + ("end", "pose"), [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]], "$.cables[0].end.pose[3]", False),
    (C0 + ("end", "pose"), [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], "$.cables[0].end.pose", False),
    (C0 + ("end", "pose"), [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], "$.cables[0].end.pose", False),
    (C0 + ("end", "force"), [1, 2], "$.cables[0].end.force", True),
    (C0 + ("numerics",), {"model": "fem"}, "$.cables[0].numerics.model", True),
    (C0 + ("numerics",), {"segments": 1}, "$.cables[0].numerics.segments", True),
    (C0 + ("numerics",), {"segments": 10.5}, "$.cables[0].numerics.segments", True),
    (C0 + ("effects",), ["shape", "stress"], "$.cables[0].effects[1]", True),
    (C0 + ("effects",), ["min_bend_radius"], "$.cables[0].min_bend_radius", True),
    (C0 + ("density",), 1000.0, "$.cables[0].density", False),       # needs a radius
]


@pytest.mark.parametrize("path,value,named,schema_too", INVALID)
def test_invalid_scenes_name_the_json_path(path, value, named, schema_too):
    raw = minimal()
    _set(raw, path, value)
    with pytest.raises(SceneError) as err:
        read_scene(raw)
    assert err.value.path == named
    assert named in str(err.value)
    if schema_too:
        assert not VALIDATOR.is_valid(raw)


def test_rules_beyond_the_schema():
    raw = minimal()
    raw["cables"].append(copy.deepcopy(raw["cables"][0]))
    with pytest.raises(SceneError, match=r"\$\.cables\[1\]\.name: duplicate"):
        read_scene(raw)
    raw = minimal(linear_density=1.0, density=1.0)
    assert not VALIDATOR.is_valid(raw)
    with pytest.raises(SceneError, match="not both"):
        read_scene(raw)
    raw = minimal()
    raw["cables"][0]["start"]["condition"] = "free"
    raw["cables"][0]["end"]["condition"] = "free"
    with pytest.raises(SceneError, match="not held"):
        read_scene(raw)
    raw = minimal(numerics={"model": "patent"})
    raw["cables"][0]["start"]["condition"] = "pinned"
    with pytest.raises(SceneError, match="patent"):
        read_scene(raw)


def test_nearly_orthonormal_pose_is_cleaned():
    raw = minimal()
    raw["cables"][0]["start"]["pose"] = [[1, 1e-8, 0, 0.5], [0, 1, 0, 0], [0, 0, 1, 0]]
    T = read_scene(raw).cables[0].start.pose
    np.testing.assert_allclose(T[:3, :3].T @ T[:3, :3], np.eye(3), atol=1e-15)
    np.testing.assert_allclose(T[3], [0, 0, 0, 1])


def test_files_json_and_toml(tmp_path):
    p = tmp_path / "s.json"
    p.write_text('{"format": "p105-scene/1",\n  "cables": [}\n')
    with pytest.raises(SceneError, match=r"s\.json:2:\d+"):
        load_scene_file(p)
    t = tmp_path / "s.toml"
    t.write_text('format = "p105-scene/1"\ngravity = [0, 0, -9.81]\n'
                 '[[cables]]\nname = "c"\nlength = 2.0\n'
                 'section = {bending_stiffness = [1.0, 1.0], torsional_stiffness = 1.0}\n'
                 'start = {pose = [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}\n'
                 'end = {pose = [[1,0,0,1],[0,1,0,0],[0,0,1,0]]}\n')
    raw = load_scene_file(t)
    VALIDATOR.validate(raw)
    sc = read_scene(raw, source=str(t))
    assert sc.cables[0].length == 2.0 and sc.cables[0].end.link is None
    raw["cables"][0]["length"] = 0
    with pytest.raises(SceneError, match=r"s\.toml: scene \$\.cables\[0\]\.length"):
        read_scene(raw, source=str(t))


def test_scene_has_cables():
    assert scene_has_cables(EXAMPLE)
    assert not scene_has_cables({"format": "p105-scene/1"})
    assert not scene_has_cables({"format": "p105-scene/1", "cables": []})
    assert not scene_has_cables(None)
    assert scene_has_cables(read_scene(EXAMPLE))
