"""p105 solve --branch and the branch output: the assembly chosen at the initial state and tracked.

Truth: the reference four-bar closed form (both branches, tagged by the side of C relative to
B->D), the offset slider-crank in closed form, and a loop whose closure is linear (one assembly
only). The invariant is anchored at the initial state's assembly (+1 there), so ``-`` is the
other assembly: the tests check that it is the other closed-form branch everywhere.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import test_solve
from conftest import ROOT
from test_solve import REFERENCE, _records, _reference_four_bar, four_bar, link_angles, wrap
from test_solve_hard import four_bar_closed_form, offset_slider_crank, sigma_of
from p105cli.kinematics import solver
from p105cli.kinematics.model import Link, Mechanism, Pair
from p105cli.kinematics.placements import compose, rot_x, rot_y, rot_z

UR5 = ROOT / "tests" / "data" / "corpus" / "ur5_arm_ap242.stp"
OTHER = {"open": "crossed", "crossed": "open"}
cli = test_solve.cli   # the in-process CLI fixture


@pytest.fixture(scope="module")
def fb():
    return json.loads(REFERENCE.read_text())["closed_loop"]["fourbar"][0]


def _model_file(mech, tmp_path, name="m.json"):
    from p105cli.part105.write_mechanism import write_mechanism
    from p105cli.step import write_json
    doc, _ = write_mechanism(mech, "ap242")
    path = tmp_path / name
    with open(path, "w") as fh:
        write_json(doc, fh)
    return path


def _want(fb, branch, key):
    return np.array([s["branches"][branch][key] for s in fb["samples"]])


@pytest.mark.parametrize("start", ["open", "crossed"])
def test_other_sign_reproduces_the_other_closed_form_branch(fb, start):
    mech = _reference_four_bar(fb, start)
    th = np.array([s["theta2_rad"] for s in fb["samples"]])
    for want_branch, sign in ((start, None), (start, +1), (OTHER[start], -1)):
        result = solver.solve_motion(mech, {"A": th}, tol=1e-13, branch=sign)
        assert result.status == ["ok"] * len(th)
        t2, t3, t4 = link_angles(result)
        assert np.abs(wrap(t3 - _want(fb, want_branch, "theta3_rad"))).max() < 1e-12
        assert np.abs(wrap(t4 - _want(fb, want_branch, "theta4_rad"))).max() < 1e-12
        sig = {sigma_of(fb["a_crank"], fb["b_coupler"], fb["c_rocker"], fb["d_ground"], a, b)
               for a, b in zip(t2, t3)}
        assert sig == set(_want(fb, want_branch, "sigma_side_of_BD"))
        assert set(result.branch) == {-1.0 if sign == -1 else 1.0}


def test_cli_branch_field_is_constant_along_a_grashof_crank_sweep(fb, tmp_path, cli):
    a, b, c, d = fb["a_crank"], fb["b_coupler"], fb["c_rocker"], fb["d_ground"]
    model = _model_file(_reference_four_bar(fb, "open"), tmp_path)
    sweep = ("--sweep", "A=0:6.283185307179586:73", "--tol", "1e-13", "--no-timings", "--to", "jsonl")
    runs = {}
    for br in ("initial", "+", "-"):
        r = cli("solve", model, *sweep, "--branch", br)
        assert r.returncode == 0, r.stderr
        runs[br] = r.stdout
        conf = [x for x in _records(r.stdout) if x["type"] == "configuration"]
        assert len(conf) == 73
        assert list(conf[0])[:5] == ["type", "index", "t", "status", "branch"]
        assert {x["branch"] for x in conf} == {-1 if br == "-" else 1}
        sigma = -1 if br == "-" else 1                     # the open branch is sigma +1
        for x in conf:
            t2 = x["pairs"]["A"]
            t3 = t2 + x["pairs"]["B"]
            w3, w4 = four_bar_closed_form(a, b, c, d, t2, sigma)
            assert abs(wrap(t3 - w3)) < 1e-12 and abs(wrap(x["pairs"]["D"] - w4)) < 1e-12
    assert runs["+"] == runs["initial"]                     # + is the initial state's assembly
    # the csv table has the branch column after status, the same signs
    r = cli("solve", model, *sweep[:-1], "csv", "--branch", "-")
    assert r.returncode == 0, r.stderr
    rows = r.stdout.decode().splitlines()
    head = rows[0].split(",")
    assert head[:4] == ["index", "t", "status", "branch"]
    assert {row.split(",")[3] for row in rows[1:]} == {"-1"}
    assert len(rows) == 74


@pytest.mark.parametrize("sigma", [+1, -1])
def test_offset_slider_crank_both_ways(sigma):
    mech, x_of, th0 = offset_slider_crank(sigma)
    seq = th0 + np.linspace(0.0, 2 * math.pi, 61)
    for sign, s in ((None, sigma), (1, sigma), (-1, -sigma)):
        result = solver.solve_motion(mech, {"O": seq}, tol=1e-13, branch=sign)
        assert result.status == ["ok"] * len(seq)
        want = np.array([x_of(t, s) for t in seq])
        assert np.abs(result.Q[:, 3] - want).max() < 1e-12
        assert set(result.branch) == {-1.0 if sign == -1 else 1.0}


def test_a_loop_with_one_assembly_has_no_other_branch(tmp_path, cli):
    # Three prismatic pairs along x, y and the diagonal: the closure is linear, one assembly.
    Rx, Ry, Rd = rot_y(math.pi / 2), rot_x(-math.pi / 2), compose(rot_z(math.pi / 4), rot_y(math.pi / 2))
    links = [Link(n) for n in ("frame", "s1", "s2")]
    pairs = [Pair("A", "prismatic", "frame", "s1", Rx, Rx, actuated=True),
             Pair("B", "prismatic", "s1", "s2", Ry, Ry),
             Pair("C", "prismatic", "frame", "s2", Rd, Rd)]
    mech = Mechanism("cross_slide", links, pairs, "frame",
                     initial={"A": (0.1,), "B": (0.09,), "C": (0.15,)})
    seq = np.linspace(0.1, 0.2, 5)
    ok = solver.solve_motion(mech, {"A": seq}, branch=1)
    assert ok.status == ["ok"] * 5 and np.abs(ok.Q[:, 1] - seq).max() < 1e-12
    assert np.abs(ok.Q[:, 2] - math.sqrt(2) * seq).max() < 1e-12
    none = solver.solve_motion(mech, {"A": seq}, branch=-1)
    assert none.status == ["not_assemblable"] * 5
    assert "requested assembly branch" in none.messages[0]
    blocks = list(solver.iter_motion(mech, {"A": seq}, branch=-1, block=2))      # streamed: the same
    assert [s for blk in blocks for s in blk.status] == ["not_assemblable"] * 5
    model = _model_file(mech, tmp_path)
    r = cli("solve", model, "--sweep", "A=0.1:0.2:5", "--branch", "-", "--to", "jsonl", "--no-timings")
    assert r.returncode == 1
    conf = [x for x in _records(r.stdout) if x["type"] == "configuration"]
    assert [x["status"] for x in conf] == ["not_assemblable"] * 5
    assert b"requested assembly branch (-) was not found" in r.stderr


def test_branch_on_a_tree_is_a_usage_error_and_trees_have_no_branch_output(cli):
    for br in ("+", "-"):
        r = cli("solve", UR5, "--branch", br, "--to", "jsonl")
        assert r.returncode == 2
        assert b"--branch" in r.stderr and b"no closed loop" in r.stderr and b"Traceback" not in r.stderr
        assert r.stdout == b""
    r = cli("solve", UR5, "--to", "jsonl", "--no-timings")
    assert r.returncode == 0, r.stderr
    conf = [x for x in _records(r.stdout) if x["type"] == "configuration"]
    assert conf and all("branch" not in x for x in conf)
    r = cli("solve", UR5, "--to", "csv")
    assert r.returncode == 0 and "branch" not in r.stdout.decode().splitlines()[0].split(",")


def test_branch_with_inverse_analysis_is_a_usage_error(tmp_path, cli):
    path = tmp_path / "path.jsonl"
    path.write_text(json.dumps({"t": 0.0, "pose": np.eye(4).tolist()}) + "\n")
    r = cli("solve", UR5, "--path", path, "--target-link", "x", "--branch", "-")
    assert r.returncode == 2 and b"--branch -" in r.stderr and b"--path" in r.stderr


def test_branch_with_free_passive_values_is_a_usage_error(fb, tmp_path, cli):
    # Nothing driven: the loop leaves a passive value free, the invariant is not defined.
    s0 = fb["samples"][0]["branches"]["open"]
    mech = four_bar(fb["a_crank"], fb["b_coupler"], fb["c_rocker"], fb["d_ground"], 0.0,
                    s0["theta3_rad"], s0["theta4_rad"], driven="none")
    with pytest.raises(solver.BranchUndefined, match=r"rank 3 < 4"):
        solver.solve_motion(mech, {}, branch=-1)
    assert solver.solve_motion(mech, {}).status == ["ok"]      # initial: as before
    r = cli("solve", _model_file(mech, tmp_path), "--branch", "+", "--to", "jsonl")
    assert r.returncode == 2 and b"not defined" in r.stderr and b"Traceback" not in r.stderr
