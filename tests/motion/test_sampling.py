"""``p105 interpolate`` end to end, on the corpus and on edited copies of it
(linear and circular segments), checked against the file's own numbers."""

import csv
import io
import json
import re

import numpy as np
import pytest

from conftest import ROOT

FOUR_BAR = ROOT / "tests" / "data" / "corpus" / "four_bar_ap242.stp"


def records(out: bytes):
    return [json.loads(line) for line in out.decode().splitlines()]


def axis2(text: str, pid: int, scale=1e-3) -> np.ndarray:
    """An AXIS2_PLACEMENT_3D of the Part 21 text as a 4x4, built by hand (Part 42 build_axes)."""
    ents = dict(re.findall(r"^#(\d+)=(.*);$", text, re.M))
    num = lambda s: [float(x) for x in s.split(",")]  # noqa: E731
    loc, ax, ref = re.match(r"AXIS2_PLACEMENT_3D\('[^']*',#(\d+),#(\d+),#(\d+)\)", ents[str(pid)]).groups()
    p = np.array(num(re.search(r"\(([^()]*)\)\)$", ents[loc]).group(1))) * scale
    z = np.array(num(re.search(r"\(([^()]*)\)\)$", ents[ax]).group(1)))
    x = np.array(num(re.search(r"\(([^()]*)\)\)$", ents[ref]).group(1)))
    z /= np.linalg.norm(z)
    x = x - (x @ z) * z
    x /= np.linalg.norm(x)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, np.cross(z, x), z, p
    return T


def test_nodes_of_the_corpus_path_are_the_files_placements(p105):
    text = FOUR_BAR.read_text()
    r = p105("interpolate", "--what", "paths", FOUR_BAR)
    assert r.returncode == 0, r.stderr
    recs = records(r.stdout)
    frames = [x for x in recs if x["type"] == "frame"]
    assert [f["t"] for f in frames] == [0.0, 0.5, 1.0]
    assert {f["link"] for f in frames} == {"coupler"}
    for f, pid in zip(frames, (231, 235, 240)):
        assert np.abs(np.array(f["matrix"]) - axis2(text, pid)).max() < 1e-15
        assert f["prescribed"] is False  # point-to-point segments prescribe no interpolation
    assert recs[-1]["type"] == "summary" and recs[-1]["units"] == {"length": "m", "angle": "rad"}


@pytest.fixture
def edited(tmp_path):
    """The four-bar with a linear and a circular segment (via point off the chord)."""
    text = FOUR_BAR.read_text()
    text = text.replace("#236=POINT_TO_POINT_PATH(0.5,*,#235);", "#236=LINEAR_PATH(0.5,*,#235);")
    text = text.replace("#241=POINT_TO_POINT_PATH(1.,*,#240);",
                        "#241=CIRCULAR_PATH(1.,.CONTINUOUS.,#240,#900);\n"
                        "#900=CARTESIAN_POINT('via',(120.,155.,0.));")
    f = tmp_path / "four_bar_paths.stp"
    f.write_text(text)
    return f, text


def test_linear_and_circular_segments(p105, edited):
    f, text = edited
    r = p105("interpolate", "--what", "paths", "--count", "201", "--quaternion", "xyzw", f)
    assert r.returncode == 0, r.stderr
    frames = [x for x in records(r.stdout) if x["type"] == "frame"]
    T = np.array([x["matrix"] for x in frames])
    t = np.array([x["t"] for x in frames])
    T0, T1, T2 = axis2(text, 231), axis2(text, 235), axis2(text, 240)
    lin = t <= 0.5
    s = t[lin] / 0.5
    assert np.abs(T[lin, :3, 3] - (T0[:3, 3] + s[:, None] * (T1[:3, 3] - T0[:3, 3]))).max() < 1e-15
    # circular segment: equidistant from the circumcentre of start, via, end (solved independently)
    P = np.array([T1[:3, 3], [0.120, 0.155, 0.0], T2[:3, 3]])
    A = 2 * (P[1:, :2] - P[0, :2])
    b = np.sum(P[1:, :2] ** 2, axis=1) - np.sum(P[0, :2] ** 2)
    c = np.linalg.solve(A, b)
    rad = np.linalg.norm(P[0, :2] - c)
    circ = t >= 0.5
    assert np.abs(np.linalg.norm(T[circ, :2, 3] - c, axis=1) - rad).max() < 1e-12
    assert np.abs(T[circ, 2, 3]).max() < 1e-15
    # it passes the via point
    assert np.min(np.linalg.norm(T[circ, :2, 3] - P[1, :2], axis=1)) < rad * 0.02
    # quaternions are labelled and agree with the matrices
    from scipy.spatial.transform import Rotation
    q = np.array([x["quaternion"]["value"] for x in frames])
    assert frames[0]["quaternion"]["order"] == "xyzw"
    assert np.abs(Rotation.from_quat(q).as_matrix() - T[:, :3, :3]).max() < 1e-14
    assert (q[:, 3] >= 0).all()


def test_csv_output_matches_jsonl(p105, edited):
    f, _ = edited
    js = [x for x in records(p105("interpolate", "--what", "paths", "--step", "0.1", f).stdout)
          if x["type"] == "frame"]
    r = p105("interpolate", "--what", "paths", "--step", "0.1", "--to", "csv", f)
    assert r.returncode == 0, r.stderr
    rows = list(csv.DictReader(io.StringIO(r.stdout.decode())))
    assert len(rows) == len(js) == 11
    for row, rec in zip(rows, js):
        assert float(row["t"]) == rec["t"]
        assert [float(row[f"m{i}{j}"]) for i in range(3) for j in range(4)] == \
            [v for r_ in rec["matrix"][:3] for v in r_]


def test_bad_requests(p105, edited):
    f, _ = edited
    r = p105("interpolate", "--what", "paths", "--t", "2.0", f)
    assert r.returncode == 2 and b"outside its range" in r.stderr and r.stdout == b""
    r = p105("interpolate", "--path", "nope", f)
    assert r.returncode == 2 and b"no path named 'nope'" in r.stderr
    r = p105("interpolate", "--step", "0.1", "--count", "3", f)
    assert r.returncode == 2 and b"at most one of" in r.stderr
    r = p105("interpolate", "--to", "csv", f)
    assert r.returncode == 2 and b"--what paths" in r.stderr


def test_degenerate_circle_names_the_segment(p105, tmp_path):
    text = FOUR_BAR.read_text().replace(
        "#241=POINT_TO_POINT_PATH(1.,*,#240);",
        "#241=CIRCULAR_PATH(1.,.CONTINUOUS.,#240,#900);\n#900=CARTESIAN_POINT('via',(125.35098721641174,"
        "157.66974346320953,0.));")
    f = tmp_path / "bad.stp"
    f.write_text(text)
    r = p105("interpolate", "--what", "paths", f)
    assert r.returncode == 2 and b"#241" in r.stderr and b"collinear or coincident" in r.stderr
    assert b"Traceback" not in r.stderr


def test_1996_paths_have_no_geometry_and_say_so(p105):
    r = p105("interpolate", "--what", "paths", ROOT / "tests" / "data" / "corpus" / "four_bar_ap214.stp")
    assert r.returncode == 1
    assert b"#227" in r.stderr and b"without geometry" in r.stderr


def test_curve_based_segment_on_a_circle_entity(p105, tmp_path):
    """A curve_based_path on a Part 42 circle through both nodes (centre solved here)."""
    text = FOUR_BAR.read_text()
    T1, T2 = axis2(text, 235), axis2(text, 240)
    p1, p2, via = T1[:3, 3] * 1e3, T2[:3, 3] * 1e3, np.array([120.0, 155.0, 0.0])
    P = np.array([p1, via, p2])
    A = 2 * (P[1:, :2] - P[0, :2])
    b = np.sum(P[1:, :2] ** 2, axis=1) - np.sum(P[0, :2] ** 2)
    c = np.linalg.solve(A, b)
    rad = float(np.linalg.norm(p1[:2] - c))
    text = text.replace("#241=POINT_TO_POINT_PATH(1.,*,#240);",
                        "#241=CURVE_BASED_PATH(1.,.CONTINUOUS.,#240,#901);\n"
                        f"#900=CARTESIAN_POINT('',({float(c[0])!r},{float(c[1])!r},0.));\n"
                        "#902=DIRECTION('',(0.,0.,1.));\n#903=DIRECTION('',(1.,0.,0.));\n"
                        "#904=AXIS2_PLACEMENT_3D('',#900,#902,#903);\n"
                        f"#901=CIRCLE('',#904,{rad!r});")
    f = tmp_path / "curve.stp"
    f.write_text(text)
    r = p105("interpolate", "--what", "paths", "--count", "51", f)
    assert r.returncode == 0, r.stderr
    frames = [x for x in records(r.stdout) if x["type"] == "frame"]
    T = np.array([x["matrix"] for x in frames])
    t = np.array([x["t"] for x in frames])
    on = t >= 0.5
    assert np.abs(np.linalg.norm(T[on, :2, 3] - c * 1e-3, axis=1) - rad * 1e-3).max() < 1e-12
    # the circle's parameter (angle) moves linearly in t, counter-clockwise (the circle's sense)
    ang = np.unwrap(np.arctan2(T[on, 1, 3] - c[1] * 1e-3, T[on, 0, 3] - c[0] * 1e-3))
    assert np.ptp(np.diff(ang)) < 1e-9 and np.all(np.diff(ang) > 0)
    assert np.abs(T[-1] - T2).max() < 1e-12


@pytest.mark.parametrize("profile", ["ap214", "ap242"])
@pytest.mark.parametrize("key", ["four_bar", "slider_crank"])
def test_configuration_sequences_against_the_corpus_solver(p105, key, profile):
    """The motion program's configurations are the corpus generator's solved states
    (computed here from its own position solver), linearly interpolated between them."""
    from p105cli.corpus import MECHANISMS, configuration

    mech = MECHANISMS[key]()
    axis = 0 if profile == "ap242" else 2
    truth = [configuration(mech, d, axis) for d in mech.drives]
    names = [p.name for p in mech.pairs]

    def si(state):  # corpus values: radians and millimetres
        out = {}
        for p in mech.pairs:
            (v,) = state[p.name].values()
            out[p.name] = v * (1e-3 if p.kind in ("prismatic", "rack_and_pinion") else 1.0)
        return out

    f = ROOT / "tests" / "data" / "corpus" / f"{key}_{profile}.stp"
    r = p105("interpolate", "--what", "configurations", "--t", "0", "--t", "0.25", "--t", "0.5",
                "--t", "1", "--no-nodes", f)
    assert r.returncode == 0, r.stderr
    recs = [x for x in records(r.stdout) if x["type"] == "configuration"]
    assert [x["t"] for x in recs] == [0.0, 0.25, 0.5, 1.0]
    nodes = [si(s) for s in truth]
    expect = [nodes[0], {n: 0.5 * (nodes[0][n] + nodes[1][n]) for n in names}, nodes[1], nodes[2]]
    for rec, want in zip(recs, expect):
        assert set(rec["pairs"]) == set(names)
        for n in names:
            # the file holds the solver's values to 12 significant digits (p105cli.corpus.digits)
            assert rec["pairs"][n] == pytest.approx(want[n], rel=5e-12, abs=5e-11)
    assert recs[1]["interpolation"] == "linear" and recs[1]["prescribed"] is True
