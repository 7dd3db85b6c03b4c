"""The patent's key-point workflow: over-length, symmetry-error check, end loads, records, display."""

from __future__ import annotations

import json
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from conftest import EXAMPLES, ROOT
from p105cli.cable import workflow
from p105cli.cable.workflow import KeypointError, load_keypoints, run_scene

SCENE = json.loads((EXAMPLES / "cable_scene.json").read_text())
KEYS = str(EXAMPLES / "cable_keypoints.jsonl")


def pose(z, x, p):
    z, x = np.asarray(z, float), np.asarray(x, float)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, np.cross(z, x), z, p
    return T.tolist()


def states(records):
    return [r for r in records if r["type"] == "cable_state"]


def test_no_cables_imports_no_solver():
    code = (
        "import sys, json\n"
        "from p105cli.cable.workflow import run_scene\n"
        "recs = list(run_scene({'format': 'p105-scene/1', 'gravity': [0, 0, -9.81]}))\n"
        "bad = [m for m in ('p105cli.cable.rod', 'p105cli.cable.patent', 'p105cli.cable.display',"
        " 'p105cli.cable.catenary', 'scipy', 'matplotlib') if m in sys.modules]\n"
        "print(json.dumps({'bad': bad, 'recs': recs}))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout)
    assert res["bad"] == []
    assert [r["type"] for r in res["recs"]] == ["summary"]
    assert res["recs"][0]["states"] == 0 and res["recs"][0]["exit_code"] == 0
    # importing the package itself is free
    code = ("import sys, p105cli.cable\n"
            "print(sorted(m for m in sys.modules if m.startswith(('numpy', 'p105cli.cable.'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert out.stdout.strip() == "[]"


def test_example_path_end_loads_balance_weight_and_moments():
    recs = list(run_scene(SCENE, keypoints=KEYS))
    json.dumps(recs, allow_nan=False)                   # no NaN anywhere
    st = states(recs)
    summ = recs[-1]
    assert summ["type"] == "summary" and summ["exit_code"] == 0 and summ["states"] == 9 == len(st)
    assert summ["statuses"] == {"ok": 9} and summ["max_residual"] < 1e-8
    assert set(summ["time_s"]["per_effect"]) == {"solve", "overlength", "symmetry_check", "shape",
                                                 "end_loads", "min_bend_radius"}
    a = 4e-3
    w = np.array([0, 0, -9.81 * 1500 * np.pi * a * a])            # N/m
    keys = load_keypoints(KEYS)
    for r, kp in zip(st, keys):
        assert r["t"] == kp["t"] and r["status"] == "ok"
        nodes = np.array(r["nodes"])
        np.testing.assert_allclose(nodes[0], 0, atol=1e-12)
        np.testing.assert_allclose(nodes[-1], np.array(kp["pose"])[:3, 3] * 1e-3, atol=1e-12)
        seg = np.linalg.norm(np.diff(nodes, axis=0), axis=1)
        # inextensible: the node polygon is shorter than the curve by O((h kappa)^2)
        np.testing.assert_allclose(seg.sum(), 0.6, rtol=(0.6 / 40 * r["max_curvature"]) ** 2 / 10)
        fs, fe = (np.array(r["end_loads"][k]["force"]) for k in ("start", "end"))
        ms, me = (np.array(r["end_loads"][k]["moment"]) for k in ("start", "end"))
        # the two bodies carry the whole weight
        np.testing.assert_allclose(fs + fe, w * 0.6, atol=1e-10)
        # moment balance about the origin: bodies' moments + their forces' moments = moment of
        # the weight, integrated independently over the nodes (trapezoid on the node polygon)
        mid = 0.5 * (nodes[1:] + nodes[:-1])
        m_weight = np.sum(np.cross(mid, w) * seg[:, None], axis=0)
        total = ms + me + np.cross(nodes[0], fs) + np.cross(nodes[-1], fe)
        np.testing.assert_allclose(total, m_weight, atol=2e-3 * np.linalg.norm(w) * 0.6 * 0.6)
        assert r["min_bend_radius_ok"] == (r["max_curvature"] * 0.04 <= 1)
        assert r["symmetry"]["action"] == "none"


def _planar_scene(end_pose, model="rod", effects=("shape", "symmetry_check", "overlength"), **extra):
    """No gravity, ends on the x axis, section x axis horizontal: the cable buckles sideways
    (B < A: it bends about the vertical section axis y), out of the vertical plane, and that
    shape has a mirror twin across the plane."""
    c = {"name": "c", "length": 1.0,
         "section": {"bending_stiffness": [3.0, 1.0], "torsional_stiffness": 1.0},
         "start": {"link": None, "pose": pose([1, 0, 0], [0, 1, 0], [0, 0, 0])},
         "end": {"link": None, "pose": end_pose},
         "numerics": {"model": model, "segments": 30},
         "effects": list(effects)}
    c.update(extra)
    return {"format": "p105-scene/1", "cables": [c]}


def _path(xs, roll=0.0):
    x_axis = [0, np.cos(roll), np.sin(roll)]
    return [{"t": float(i), "pose": np.array(pose([1, 0, 0], x_axis, [x, 0, 0]))} for i, x in enumerate(xs)]


def test_overlength_stops_with_a_diagnostic_and_warns_before():
    kps = _path([0.7, 0.9, 0.995, 1.01, 0.8])
    recs = list(run_scene(_planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0])), keypoints=kps))
    kinds = [(r["type"], r.get("code")) for r in recs]
    assert kinds[:3] == [("cable_state", None), ("cable_state", None), ("cable_state", None)]
    assert ("diagnostic", "near_taut") in kinds[3:5]            # 0.5 % slack < 2 %
    err = [r for r in recs if r.get("level") == "error"]
    assert len(err) == 1 and err[0]["code"] == "overlength" and err[0]["key"] == 3
    assert err[0]["distance"] == pytest.approx(1.01) and err[0]["length"] == 1.0
    summ = recs[-1]
    assert summ["stopped"] and summ["stop_reason"] == "overlength" and summ["exit_code"] == 1
    assert summ["states"] == 3 and summ["key_points"] == 4      # key 4 never reached
    assert [r["slack"] for r in states(recs)] == pytest.approx([0.3, 0.1, 0.005])


def _flip_once(monkeypatch, target_x):
    """Make the solver land on the mirror branch once, at the key point whose end is at target_x:
    the failure the patent's symmetry check is for (Newton picks the twin closer to its guess)."""
    real = workflow._solver
    fired = []

    def fake(spec):
        solve = real(spec)

        def wrapped(problem, warm):
            sol = solve(problem, warm)
            if not fired and abs(problem.T_end[0, 3] - target_x) < 1e-12:
                fired.append(True)
                return workflow.mirror_solution(sol, problem.T_start[:3, 3], np.array([0.0, 1.0, 0.0]), "x")
            return sol
        return wrapped
    monkeypatch.setattr(workflow, "_solver", fake)
    return fired


@pytest.mark.parametrize("model", ["rod", "patent"])
def test_symmetry_error_is_mirrored_back_when_the_ends_are_symmetric(monkeypatch, model):
    scene = _planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0]), model=model)
    kps = _path([0.7, 0.66, 0.62])
    truth = states(run_scene(scene, keypoints=kps))
    d = np.array(truth[0]["nodes"])[:, 1]
    assert np.max(np.abs(d)) > 0.1                       # it bulges out of the vertical plane
    fired = _flip_once(monkeypatch, 0.66)
    recs = list(run_scene(scene, keypoints=kps))
    assert fired
    st = states(recs)
    assert [r["symmetry"]["action"] for r in st] == ["none", "mirrored", "none"]
    for a, b in zip(st, truth):
        np.testing.assert_allclose(a["nodes"], b["nodes"], atol=1e-9)
    assert recs[-1]["symmetry_corrections"] == {"mirrored": 1, "halved": 0}


def test_symmetry_error_is_rejected_and_halved_when_the_ends_are_not_symmetric(monkeypatch):
    # end section rolled 0.3 rad about its tangent: the mirror image is not a solution
    roll = 0.3
    scene = _planar_scene(np.array(_path([0.7], roll)[0]["pose"]).tolist())
    kps = _path([0.7, 0.66, 0.62], roll)
    truth = states(run_scene(scene, keypoints=kps))
    fired = _flip_once(monkeypatch, 0.66)
    recs = list(run_scene(scene, keypoints=kps))
    assert fired
    st = states(recs)
    assert [r["symmetry"]["action"] for r in st] == ["none", "halved", "none"]
    assert st[1]["halvings"] >= 1
    for a, b in zip(st, truth):
        np.testing.assert_allclose(a["nodes"], b["nodes"], atol=1e-7)
    assert recs[-1]["symmetry_corrections"] == {"mirrored": 0, "halved": 1}


def test_only_requested_effects_are_written():
    scene = _planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0]), effects=["shape"])
    r = states(run_scene(scene))[0]
    assert "nodes" in r
    for k in ("frames", "end_loads", "max_curvature", "min_bend_radius_ok", "symmetry", "slack"):
        assert k not in r
    summ = list(run_scene(scene))[-1]
    assert set(summ["time_s"]["per_effect"]) <= {"solve", "shape", "overlength"}
    scene = _planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0]), effects=["frames", "min_bend_radius"],
                          min_bend_radius=0.5)
    recs = list(run_scene(scene))
    r = states(recs)[0]
    assert "nodes" not in r
    F = np.array(r["frames"])
    assert F.shape == (31, 4, 4)
    np.testing.assert_allclose(F[:, 3], np.tile([0, 0, 0, 1.0], (31, 1)))
    # a buckled cable at d/L = 0.7 bends tighter than R = 0.5 m: a finding, exit 1
    assert r["max_curvature"] > 2 and r["min_bend_radius_ok"] is False
    assert any(x.get("code") == "min_bend_radius" for x in recs)
    assert recs[-1]["exit_code"] == 1 and recs[-1]["min_bend_radius_violations"] == 1


def test_motion_of_links_moves_the_cable_rigidly():
    """Cable ends on two links; moving both links by the same rigid motion moves the shape with it."""
    scene = _planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0]))
    scene["cables"][0]["start"]["link"] = "base"
    scene["cables"][0]["end"]["link"] = "arm"
    G = np.eye(4)
    c, s = np.cos(0.7), np.sin(0.7)
    G[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    G[:3, 3] = [0.2, -0.1, 0.3]
    motion = [(0.0, {"base": np.eye(4), "arm": np.eye(4)}), (1.0, {"base": G, "arm": G})]
    st = states(run_scene(scene, motion=motion))
    n0, n1 = np.array(st[0]["nodes"]), np.array(st[1]["nodes"])
    np.testing.assert_allclose(n1, n0 @ G[:3, :3].T + G[:3, 3], atol=1e-8)
    with pytest.raises(ValueError, match="link 'arm'"):
        list(run_scene(scene, motion=[(0.0, {"base": np.eye(4)})]))
    with pytest.raises(ValueError, match="link 'base'"):
        list(run_scene(scene))


def test_keypoint_files_jsonl_and_csv(tmp_path):
    kps = load_keypoints(KEYS)
    assert len(kps) == 9 and kps[1]["t"] == 0.125
    csv = tmp_path / "k.csv"
    rows = ["t," + ",".join(f"m{i}{j}" for i in range(3) for j in range(4))]
    for k in kps:
        rows.append(",".join(repr(float(v)) for v in [k["t"], *np.asarray(k["pose"])[:3].ravel()]))
    csv.write_text("\n".join(rows) + "\n")
    kc = load_keypoints(csv)
    assert [k["t"] for k in kc] == [k["t"] for k in kps]
    for a, b in zip(kc, kps):
        np.testing.assert_array_equal(a["pose"], b["pose"])
    bad = tmp_path / "bad.csv"
    bad.write_text(rows[0] + "\n" + rows[1] + "\n0.5,1,0,0\n")
    with pytest.raises(KeypointError, match=r"bad\.csv:3:1: 4 fields, the header has 13"):
        load_keypoints(bad)
    bad.write_text(rows[1] + "\n" + rows[2].replace("0.0,", "x,", 1) + "\n")
    with pytest.raises(KeypointError, match=r"bad\.csv:2:\d+: 'x' is not a number"):
        load_keypoints(bad)
    j = tmp_path / "k.jsonl"
    eye = '[[1,0,0,0],[0,1,0,0],[0,0,1,0]]'
    j.write_text(f'{{"t": 1, "pose": {eye}}}\n\n{{"t": 0.5, "pose": {eye}}}\n')
    with pytest.raises(KeypointError, match=r"k\.jsonl:3:1: t = 0\.5 goes back"):
        load_keypoints(j)
    j.write_text('{"t": 0, "pose": [[1,0,0,0],[0,2,0,0],[0,0,1,0]]}\n')
    with pytest.raises(KeypointError, match=r"k\.jsonl:1:1: the pose is not a rigid placement"):
        load_keypoints(j)
    j.write_text('{"t": 0, "pose": [[1,0,0,0]\n')
    with pytest.raises(KeypointError, match=r"k\.jsonl:1:\d+: Expecting"):
        load_keypoints(j)


def test_failed_solve_stops_with_exit_1(monkeypatch):
    scene = _planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0]))
    real = workflow._solver

    def fake(spec):
        solve = real(spec)

        def wrapped(problem, warm):
            import dataclasses
            sol = solve(problem, warm)
            return dataclasses.replace(sol, converged=False, status="not_converged")
        return wrapped
    monkeypatch.setattr(workflow, "_solver", fake)
    recs = list(run_scene(scene, keypoints=_path([0.7, 0.6])))
    assert [r["type"] for r in recs] == ["cable_state", "diagnostic", "summary"]
    assert recs[0]["status"] == "not_converged" and "nodes" not in recs[0]
    assert recs[-1]["exit_code"] == 1 and recs[-1]["stop_reason"] == "not_converged"


def test_display_writes_png_svg_and_gif(tmp_path):
    pytest.importorskip("matplotlib")
    from p105cli.cable.display import animate, bezier_fit, plot_shapes
    # the Bezier fit passes through every node and is C1
    P = np.array([[0, 0, 0], [1, 1, 0], [2, 0, 1], [3, 1, 1.0]])
    B = bezier_fit(P, samples_per_span=400)
    np.testing.assert_allclose(B[::400], P)
    d = np.diff(B, axis=0) * 400          # parameter derivative, one-sided on each side of a node
    np.testing.assert_allclose(d[399], d[400], atol=0.02)
    np.testing.assert_allclose(d[400], 0.5 * (P[2] - P[0]), atol=0.02)   # Catmull-Rom tangent
    recs = list(run_scene(_planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0])), keypoints=_path([0.7, 0.6])))
    png, svg, gif = tmp_path / "s.png", tmp_path / "s.svg", tmp_path / "a.gif"
    plot_shapes(recs, png)
    plot_shapes(recs, svg)
    animate(recs, gif, fps=2)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    root = ET.fromstring(svg.read_bytes())
    assert root.tag.endswith("svg")
    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "s.png", "s.svg"]   # no leftovers


def test_failed_solve_is_retried_by_halving_the_step(monkeypatch):
    """A solve that fails from the previous key point succeeds via an intermediate pose."""
    scene = _planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0]), effects=["shape"])
    kps = _path([0.7, 0.5])
    truth = states(run_scene(scene, keypoints=kps))
    real = workflow._solver
    calls = []

    def fake(spec):
        solve = real(spec)

        def wrapped(problem, warm):
            import dataclasses
            calls.append(problem.T_end[0, 3])
            sol = solve(problem, warm)
            if len(calls) == 2:        # the direct step 0.7 -> 0.5 "fails"
                return dataclasses.replace(sol, converged=False, status="not_converged")
            return sol
        return wrapped
    monkeypatch.setattr(workflow, "_solver", fake)
    st = states(run_scene(scene, keypoints=kps))
    assert calls == pytest.approx([0.7, 0.5, 0.6, 0.5])
    assert st[1]["halvings"] == 1 and st[1]["status"] == "ok"
    np.testing.assert_allclose(st[1]["nodes"], truth[1]["nodes"], atol=1e-8)


def test_continuous_family_is_kept_with_a_warning():
    """An isotropic cable between coaxial clamps buckles in any plane through the axis: the rod
    solver returns one member and says so; the workflow keeps it and warns."""
    scene = _planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, 0, 0]), effects=["shape"])
    scene["cables"][0]["section"] = {"bending_stiffness": [1.0, 1.0], "torsional_stiffness": 1.0}
    recs = list(run_scene(scene))
    st = states(recs)
    assert st[0]["status"] == "non_unique" and st[0]["converged"]
    # still the first buckling mode of the clamped-clamped elastica (closed form 0.31431 L)
    nodes = np.array(st[0]["nodes"])
    assert np.max(np.linalg.norm(nodes[:, 1:], axis=1)) == pytest.approx(0.31431261295610713, abs=2e-3)
    assert [r["code"] for r in recs if r["type"] == "diagnostic"] == ["non_unique"]
    assert recs[-1]["exit_code"] == 0 and recs[-1]["statuses"] == {"non_unique": 1}


def test_path_through_the_symmetric_configuration_keeps_its_side():
    """The end crosses the configuration where both mirror twins exist (end on the start's axis):
    warm starts keep the cable on the side it came from and the check does not fire spuriously."""
    scene = _planar_scene(pose([1, 0, 0], [0, 1, 0], [0.7, -0.1, 0]))
    kps = [{"t": float(i), "pose": np.array(pose([1, 0, 0], [0, 1, 0], [0.7, y, 0]))}
           for i, y in enumerate(np.linspace(-0.1, 0.1, 5))]
    recs = list(run_scene(scene, keypoints=kps))
    st = states(recs)
    assert [r["symmetry"]["action"] for r in st] == ["none"] * 5
    # side of the farthest node w.r.t. the vertical plane through the ends, key by key
    sides = []
    for r, kp in zip(st, kps):
        nodes = np.array(r["nodes"])
        n = workflow.symmetry_plane(nodes[0], nodes[-1], np.array([0, 0, 1.0]), 1.0)
        d = nodes @ n
        sides.append(np.sign(d[np.argmax(np.abs(d))]))
    assert len(set(sides)) == 1
    mid = np.array(st[2]["nodes"])                 # the symmetric configuration itself
    assert np.max(np.abs(mid[:, 1])) > 0.1
