"""Pair motions (p105cli.kinematics.pairs): closed forms, identities, Jacobians, batching,
and the corpus generator's conventions."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from p105cli.corpus import geometry as cgeo
from p105cli.corpus import mechanisms as cmech
from p105cli.kinematics import pairs
from p105cli.kinematics.pairs import PAIR_KINDS, PAIRS, UnsupportedPairError, pair_type
from p105cli.kinematics.spatial import adjoint, hat, vee
from p105cli.kinematics.placements import ypr_rotation
from p105cli.kinematics.spatial import compose, inverse, rot_x, rot_y, rot_z, trans_x, trans_y, trans_z

PI = math.pi

#: Representative parameters for each pair kind.
PARAMS = {
    "screw": {"pitch": 4.0},
    "universal": {"input_skew_angle": 0.3},
    "gear": {"radius_first_link": 20.0, "radius_second_link": 30.0, "gear_ratio": 20.0 / 30.0},
    "rack_and_pinion": {"pinion_radius": 25.0},
}


#: Pairs without geometry parameters or locked values (the higher pairs, low order flags and the
#: spherical pair with pin are tested in test_higher_pairs.py).
SIMPLE_KINDS = sorted(k for k in PAIR_KINDS if k not in pairs.HIGHER_KINDS and k != "spherical_with_pin")


def M(kind, *q, **params):
    return PAIR_KINDS[kind].motion(np.array(q, float), **{**PARAMS.get(kind, {}), **params})


def close(a, b, tol=1e-12):
    np.testing.assert_allclose(a, b, rtol=0, atol=tol)


def rigid(T):
    R = T[..., :3, :3]
    close(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), 1e-12)
    close(np.linalg.det(R), 1.0, 1e-12)
    close(T[..., 3, :], np.broadcast_to([0, 0, 0, 1.0], T.shape[:-1]), 0)


# ------------------------------------------------------------------ closed forms at special values

def test_revolute_closed_forms():
    close(M("revolute", 0.0), np.eye(4))
    close(M("revolute", PI / 2)[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    close(M("revolute", PI)[:3, :3], np.diag([-1.0, -1.0, 1.0]))
    # 5.2.3: positive = counter-clockwise seen from +z: x goes to +y
    close(M("revolute", PI / 2) @ [1, 0, 0, 0], [0, 1, 0, 0])


def test_prismatic_layouts():
    close(M("prismatic", 2.5), trans_z(2.5))  # default: 1996 layout (Annex F: along z)
    close(M("prismatic", 2.5, layout="1996")[:3, 3], [0, 0, 2.5])
    close(M("prismatic", 2.5, layout="ap242")[:3, 3], [2.5, 0, 0])  # AP242: t_x = TRUE
    assert PAIRS["prismatic_pair"].defaults["layout"] == "1996"
    assert PAIRS["prismatic_pair_with_range"].defaults["layout"] == "ap242"
    close(PAIRS["prismatic_pair_with_range"].motion([2.5])[:3, 3], [2.5, 0, 0])
    with pytest.raises(ValueError, match="layout"):
        M("prismatic", 1.0, layout="ap214")


def test_screw_pitch_is_advance_per_turn():
    # AP242 derived actual_translation = pitch * angle / (2 PI)
    close(M("screw", 2 * PI, pitch=4.0), trans_z(4.0), 1e-12)
    close(M("screw", PI, pitch=4.0), compose(rot_z(PI), trans_z(2.0)))
    close(M("screw", -PI / 2, pitch=4.0)[:3, 3], [0, 0, -1.0])
    close(M("screw", 0.0, pitch=4.0), np.eye(4))


def test_cylindrical_is_revolute_times_prismatic():
    for th, d in [(0.0, 0.0), (PI / 2, 3.0), (PI, -1.5), (-2.0, 7.0)]:
        Mc = M("cylindrical", d, th)  # values: (actual_translation, actual_rotation)
        close(Mc, M("revolute", th) @ M("prismatic", d), 1e-12)
        close(Mc, M("prismatic", d) @ M("revolute", th), 1e-12)


def test_screw_is_constrained_cylindrical():
    for th in (-3.0, 0.4, 5.0):
        close(M("screw", th, pitch=4.0), M("cylindrical", 4.0 * th / (2 * PI), th), 1e-12)


def test_spherical_is_annex_e_ypr():
    close(M("spherical", 0, 0, 0), np.eye(4))
    y, p, r = 0.3, -0.7, 1.1
    close(M("spherical", y, p, r)[:3, :3], (rot_x(r) @ rot_y(p) @ rot_z(y))[:3, :3])
    close(M("spherical", PI / 2, 0, 0), rot_z(PI / 2))
    close(M("spherical", 0, PI / 2, 0), rot_y(PI / 2))
    close(M("spherical", 0, 0, PI), rot_x(PI))
    close(M("spherical", y, p, r)[:3, 3], [0, 0, 0], 0)


def test_universal_closed_forms():
    close(M("universal", 0, 0, input_skew_angle=None), np.eye(4))
    close(M("universal", 0, 0), np.eye(4))  # with skew 0.3: frames coincide at q = 0
    q1, q2 = 0.4, -1.2
    close(M("universal", q1, q2, input_skew_angle=None), rot_z(q1) @ rot_x(q2))
    close(M("universal", q1, q2, input_skew_angle=0.0), rot_z(q1) @ rot_x(q2))
    # the second axis a = (cos s, 0, sin s) is fixed in the cross and in link 2,
    # at pi/2 - s from the first axis z
    s = 0.3
    a = np.array([math.cos(s), 0.0, math.sin(s)])
    Mu = M("universal", q1, q2)
    close(Mu[:3, :3] @ a, rot_z(q1)[:3, :3] @ a)
    assert math.isclose(math.acos(a @ [0, 0, 1]), PI / 2 - s)
    # rotation about the second axis by pi flips the part normal to it
    Mpi = M("universal", 0.0, PI)[:3, :3]
    close(Mpi, 2 * np.outer(a, a) - np.eye(3))
    with pytest.raises(ValueError, match="WR1"):
        M("universal", 0.0, 0.0, input_skew_angle=2.0)


def test_homokinetic_is_pure_swing():
    close(M("homokinetic", 1.0, 0.0, input_skew_angle=None), np.eye(4))
    q1, q2 = 0.7, 0.5
    H = M("homokinetic", q1, q2, input_skew_angle=None)
    close(H, rot_z(q1) @ rot_x(q2) @ rot_z(-q1))
    # a rotation by q2 about (cos q1, sin q1, 0): that axis is fixed, the z axis swings by q2
    axis = np.array([math.cos(q1), math.sin(q1), 0.0])
    close(H[:3, :3] @ axis, axis)
    assert math.isclose(H[2, 2], math.cos(q2))
    # symmetric double Cardan joint: universal(q1, q2/2) then its mirror image
    half = rot_z(q1) @ rot_x(q2 / 2)
    close(H, half @ rot_x(q2 / 2) @ rot_z(-q1))
    with pytest.raises(ValueError, match="WR1"):
        M("homokinetic", q1, q2, input_skew_angle=0.1)


def test_planar_closed_forms():
    close(M("planar", 0, 0, 0), np.eye(4))
    P = M("planar", PI / 2, 3.0, -4.0)  # (actual_rotation, translation_x, translation_y)
    close(P, trans_x(3.0) @ trans_y(-4.0) @ rot_z(PI / 2))
    close(P[:3, 3], [3.0, -4.0, 0.0])


def test_unconstrained_and_fully_constrained():
    U = M("unconstrained", 1, 2, 3, 0.3, 0.2, 0.1)
    close(U[:3, 3], [1, 2, 3])
    close(U[:3, :3], ypr_rotation(0.3, 0.2, 0.1))
    close(M("unconstrained", 0, 0, 0, 0, 0, 0), np.eye(4))
    F = PAIR_KINDS["fully_constrained"]
    assert F.value_count == 0
    close(F.motion(np.zeros(0)), np.eye(4))
    assert F.motion(np.zeros((5, 7, 0))).shape == (5, 7, 4, 4)
    assert F.motion_jacobian(np.zeros((5, 0))).shape == (5, 6, 0)
    assert F.motion_derivative(np.zeros((5, 0))).shape == (5, 0, 4, 4)


def test_gear_closed_forms():
    g = PARAMS["gear"]
    c = g["radius_first_link"] + g["radius_second_link"]
    close(M("gear", 0.0), trans_x(c))
    # rotation_2 = -ratio * rotation_1 (gear_pair_value's derived attribute)
    q1 = 0.9
    G = M("gear", q1)
    close(G[:3, 3], [c * math.cos(q1), -c * math.sin(q1), 0.0], 1e-12)
    close(G, rot_z(-q1) @ trans_x(c) @ rot_z(-g["gear_ratio"] * q1), 1e-12)
    # pitch circles roll without slipping: the contact point has zero relative velocity.
    # contact point at distance r1 from gear 1's centre along the line of centres
    J = PAIR_KINDS["gear"].motion_jacobian([q1], **g, frame="spatial")[:, 0]
    v, w = J[:3], J[3:]
    contact = rot_z(-q1)[:3, :3] @ [g["radius_first_link"], 0, 0]
    close(v + np.cross(w, contact), np.zeros(3), 1e-10)
    with pytest.raises(UnsupportedPairError, match="bevel"):
        M("gear", 0.1, bevel=0.2)
    with pytest.raises(UnsupportedPairError, match="helical_angle"):
        PAIR_KINDS["gear"].motion_jacobian([0.1], **g, helical_angle=0.1)


def test_rack_and_pinion_closed_forms():
    r = PARAMS["rack_and_pinion"]["pinion_radius"]
    close(M("rack_and_pinion", 0.0), trans_y(r))
    d = r * PI / 2  # a quarter turn of the pinion, clockwise (1996 derived rotation -d/r)
    R = M("rack_and_pinion", d)
    close(R[:3, 3], [d, r, 0])
    close(R[:3, :3], rot_z(-PI / 2)[:3, :3], 1e-12)
    # rolling: the pinion point touching the rack (origin of the pitch line under the centre) is at rest
    J = PAIR_KINDS["rack_and_pinion"].motion_jacobian([d], pinion_radius=r, frame="spatial")[:, 0]
    contact = np.array([d, 0.0, 0.0])
    close(J[:3] + np.cross(J[3:], contact), np.zeros(3), 1e-12)


# ------------------------------------------------------------------ every pair: rigid, jacobian vs finite differences

def _fd_body(t, q, params, h=1e-6):
    M0 = t.motion(q, **params)
    out, dMs = [], []
    for i in range(t.value_count):
        e = np.zeros(t.value_count)
        e[i] = h
        dM = (t.motion(q + e, **params) - t.motion(q - e, **params)) / (2 * h)
        dMs.append(dM)
        out.append(vee(inverse(M0) @ dM))
    return np.stack(out, axis=-1) if out else np.zeros((6, 0)), dMs


ANGLE = st.floats(-math.pi, math.pi, allow_nan=False)
LENGTH = st.floats(-50.0, 50.0, allow_nan=False)


@st.composite
def pair_and_values(draw):
    kind = draw(st.sampled_from(SIMPLE_KINDS))
    t = PAIR_KINDS[kind]
    q = np.array([draw(ANGLE if ("rotation" in n or n in ("yaw", "pitch", "roll")) else LENGTH)
                  for n in t.value_names])
    params = {}
    if kind == "screw":
        params["pitch"] = draw(st.floats(-10.0, 10.0, allow_nan=False))
    elif kind == "universal":
        params["input_skew_angle"] = draw(st.none() | st.floats(-1.4, 1.4))
    elif kind == "prismatic":
        params["layout"] = draw(st.sampled_from(pairs.LAYOUTS))
    elif kind == "gear":
        r1, r2 = draw(st.floats(1.0, 60.0)), draw(st.floats(1.0, 60.0))
        params.update(radius_first_link=r1, radius_second_link=r2, gear_ratio=r1 / r2)
    elif kind == "rack_and_pinion":
        params["pinion_radius"] = draw(st.floats(2.0, 60.0))
        q = q * 0.2
    return t, q, params


@settings(max_examples=300, deadline=None)
@given(pair_and_values())
def test_jacobian_matches_central_differences(case):
    t, q, params = case
    M0 = t.motion(q, **params)
    rigid(M0)
    J = t.motion_jacobian(q, **params)
    assert J.shape == (6, t.value_count)
    J_fd, dMs = _fd_body(t, q, params)
    scale = max(1.0, float(np.abs(J).max(initial=0.0)), float(np.abs(M0[:3, 3]).max()))
    np.testing.assert_allclose(J, J_fd, rtol=0, atol=1e-7 * scale)
    # d M / d q helper
    D = t.motion_derivative(q, **params)
    assert D.shape == (t.value_count, 4, 4)
    for i, dM in enumerate(dMs):
        np.testing.assert_allclose(D[i], dM, rtol=0, atol=1e-7 * scale)
    # spatial Jacobian: dM/dq_i M^-1
    Js = t.motion_jacobian(q, frame="spatial", **params)
    for i, dM in enumerate(dMs):
        np.testing.assert_allclose(Js[:, i], vee(dM @ inverse(M0)), rtol=0, atol=1e-7 * scale)


def test_twist_helpers():
    rng = np.random.default_rng(1)
    xi = rng.normal(size=(4, 6))
    close(vee(hat(xi)), xi)
    T = M("unconstrained", 1, -2, 3, 0.3, -0.2, 1.1)
    close(hat(adjoint(T) @ xi[0]), T @ hat(xi[0]) @ inverse(T))


# ------------------------------------------------------------------ batching

@pytest.mark.parametrize("kind", SIMPLE_KINDS)
def test_batching_equals_per_element(kind):
    t = PAIR_KINDS[kind]
    params = PARAMS.get(kind, {})
    rng = np.random.default_rng(7)
    q = rng.uniform(-2.0, 2.0, size=(5, 7, t.value_count))
    Mb = t.motion(q, **params)
    Jb = t.motion_jacobian(q, **params)
    Db = t.motion_derivative(q, **params)
    Jsb = t.motion_jacobian(q, frame="spatial", **params)
    assert Mb.shape == (5, 7, 4, 4)
    assert Jb.shape == (5, 7, 6, t.value_count)
    assert Db.shape == (5, 7, t.value_count, 4, 4)
    for i in range(5):
        for j in range(7):
            np.testing.assert_array_equal(Mb[i, j], t.motion(q[i, j], **params))
            close(Jb[i, j], t.motion_jacobian(q[i, j], **params), 1e-14)
            close(Db[i, j], t.motion_derivative(q[i, j], **params), 1e-13)
            close(Jsb[i, j], t.motion_jacobian(q[i, j], frame="spatial", **params), 1e-12)


def test_batched_parameters_broadcast():
    r = np.array([10.0, 20.0, 40.0])
    q = np.full((3, 1), 5.0)
    Mb = PAIR_KINDS["rack_and_pinion"].motion(q, pinion_radius=r)
    for k in range(3):
        close(Mb[k], M("rack_and_pinion", 5.0, pinion_radius=r[k]))
    # one value, batched parameter
    Mb = PAIR_KINDS["screw"].motion([1.0], pitch=np.array([1.0, 2.0]))
    assert Mb.shape == (2, 4, 4)
    close(Mb[1, 2, 3], 2.0 / (2 * PI))


def test_argument_errors():
    with pytest.raises(ValueError, match=r"shape \(\.\.\., 2\)"):
        PAIR_KINDS["cylindrical"].motion([1.0])
    with pytest.raises(TypeError, match="missing"):
        PAIR_KINDS["screw"].motion([1.0])
    with pytest.raises(TypeError, match="unknown"):
        PAIR_KINDS["revolute"].motion([1.0], pitch=2.0)
    with pytest.raises(ValueError, match="frame"):
        PAIR_KINDS["revolute"].motion_jacobian([1.0], frame="world")


# ------------------------------------------------------------------ registry

def test_registry_names():
    for name in ("revolute_pair", "prismatic_pair", "screw_pair", "cylindrical_pair", "spherical_pair",
                 "universal_pair", "homokinetic_pair", "planar_pair", "unconstrained_pair",
                 "fully_constrained_pair", "gear_pair", "rack_and_pinion_pair"):
        assert name in PAIRS  # 1996 / AP214 names
    for name in ("revolute_pair_with_range", "prismatic_pair_with_range", "screw_pair_with_range",
                 "cylindrical_pair_with_range", "spherical_pair_with_range", "universal_pair_with_range",
                 "planar_pair_with_range", "gear_pair_with_range", "rack_and_pinion_pair_with_range"):
        assert name in PAIRS  # AP242 names
    assert pair_type("REVOLUTE_PAIR") is PAIRS["revolute_pair"]
    assert PAIRS["gear_pair_with_range"] is PAIRS["gear_pair"]
    counts = {"revolute_pair": 1, "prismatic_pair": 1, "screw_pair": 1, "cylindrical_pair": 2,
              "spherical_pair": 3, "universal_pair": 2, "homokinetic_pair": 2, "planar_pair": 3,
              "unconstrained_pair": 6, "fully_constrained_pair": 0, "gear_pair": 1,
              "rack_and_pinion_pair": 1}
    for name, n in counts.items():
        assert PAIRS[name].value_count == n
    with pytest.raises(UnsupportedPairError):
        pair_type("linear_flexible_and_pinion_pair")
    with pytest.raises(KeyError):
        pair_type("revolute_pair_range")  # a 1996 range entity, not a pair


def test_registry_names_are_schema_entities():
    import re
    from pathlib import Path
    schemas = Path(__file__).resolve().parents[3] / "shared" / "schema"
    if not schemas.is_dir():
        schemas = Path("/work/shared/schema")
    if not schemas.is_dir():
        pytest.skip("shared schema files not available")
    names = set()
    for f in ("kinematics_subset_AP214E3_P105_1996.exp", "kinematics_subset_AP242_N10962.exp"):
        names |= set(re.findall(r"^ENTITY\s+(\w+)", (schemas / f).read_text(), flags=re.M | re.I))
    names = {n.lower() for n in names}
    for name in list(PAIRS) + list(pairs.NOT_IMPLEMENTED):
        assert name in names, name


# ------------------------------------------------------------------ the corpus conventions

_CORPUS_KIND = {"revolute": "revolute", "prismatic": "prismatic", "gear": "gear",
                "rack_and_pinion": "rack_and_pinion"}


def _pairs_args(kind, value, params):
    if kind == "revolute":
        return [value["rotation"]], {}
    if kind == "prismatic":
        return [value["translation"]], {}
    if kind == "gear":
        return [value["rotation_1"]], {"radius_first_link": params["radius_first"],
                                       "radius_second_link": params["radius_second"],
                                       "gear_ratio": params["gear_ratio"]}
    if kind == "rack_and_pinion":
        return [value["displacement"]], {"pinion_radius": params["pinion_radius"]}
    raise AssertionError(kind)


@pytest.mark.parametrize("key", ["gear_train", "rack_and_pinion", "four_bar"])
@pytest.mark.parametrize("slide_axis,layout", [(2, "1996"), (0, "ap242")])
def test_corpus_link_poses_are_reproduced(key, slide_axis, layout):
    """The corpus's solved link poses satisfy T_first^-1 T_second = P1 M(q) P2^-1 with
    pairs.py's M at the pair values the corpus measured (and writes)."""
    factory = dict(cmech.MECHANISMS)[key] if hasattr(cmech, "MECHANISMS") else getattr(cmech, key)
    mech = factory()
    checked = 0
    for drive in list(mech.drives) + list(mech.sweep)[::7]:
        poses = mech.solve(drive)
        values = cmech.configuration(mech, drive, slide_axis)
        for p in mech.pairs:
            if p.kind not in _CORPUS_KIND:
                continue
            q, params = _pairs_args(p.kind, values[p.name], p.params)
            if p.kind == "prismatic":
                params["layout"] = layout
            Mq = PAIR_KINDS[_CORPUS_KIND[p.kind]].motion(np.array(q), **params)
            P1, P2 = cmech.pair_frames(p, slide_axis)
            T = compose(inverse(poses[p.first]), poses[p.second])
            scale = max(1.0, float(np.abs(T[:3, 3]).max()))
            np.testing.assert_allclose(pairs.link_transform(P1, Mq, P2), T, rtol=0, atol=1e-9 * scale)
            # and the same matrix as the corpus generator's own pair motion
            np.testing.assert_allclose(Mq, cgeo.pair_motion(p.kind, values[p.name], p.params, slide_axis),
                                       rtol=0, atol=1e-12 * scale)
            checked += 1
    assert checked > 0


def test_corpus_gear_and_rack_conventions_direct():
    """The conventions in the corpus generator's docstring, written out literally (independent of
    both modules), and the generator's pair_motion (which now delegates to pairs.py)."""
    r1, r2 = 20.0, 35.0
    g = {"radius_first": r1, "radius_second": r2, "gear_ratio": r1 / r2}
    for q1 in (0.0, PI / 2, PI, -2.5, 7.0):
        q2 = -(r1 / r2) * q1
        c, s, c2, s2 = math.cos(q1), math.sin(q1), math.cos(q2), math.sin(q2)
        # Rz(-q1) Tx(r1 + r2) Rz(q2)
        literal = np.array([[c, s, 0, 0], [-s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]) @ \
            np.array([[1, 0, 0, r1 + r2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]) @ \
            np.array([[c2, -s2, 0, 0], [s2, c2, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
        Mg = PAIR_KINDS["gear"].motion([q1], radius_first_link=r1, radius_second_link=r2, gear_ratio=r1 / r2)
        close(Mg, literal, 1e-12)
        close(cgeo.pair_motion("gear", {"rotation_1": q1}, g), literal, 1e-12)
    r = 25.0
    for d in (0.0, 10.0, -120.0, 25.0 * PI):
        a = -d / r
        # Tx(d) Ty(r) Rz(-d / r)
        literal = np.array([[math.cos(a), -math.sin(a), 0, d], [math.sin(a), math.cos(a), 0, r],
                            [0, 0, 1, 0], [0, 0, 0, 1.0]])
        close(PAIR_KINDS["rack_and_pinion"].motion([d], pinion_radius=r), literal, 1e-12)
        close(cgeo.pair_motion("rack_and_pinion", {"displacement": d}, {"pinion_radius": r}), literal, 1e-12)
    for layout, axis in (("1996", 2), ("ap242", 0)):
        close(cgeo.pair_motion("prismatic", {"translation": 3.0}, {}, axis)[:3, 3], np.eye(3)[axis] * 3.0, 0)


# ------------------------------------------------------------------ independent construction (scipy Rotation)

def _scipy_motion(kind, q, params):
    """Each lower pair's motion built from axis-angle rotations with scipy (no placements.py)."""
    from scipy.spatial.transform import Rotation as Rot

    def T(rot, t=(0.0, 0.0, 0.0)):
        out = np.eye(4)
        out[:3, :3] = rot.as_matrix()
        out[:3, 3] = t
        return out

    z, x = np.array([0, 0, 1.0]), np.array([1.0, 0, 0])
    if kind == "revolute":
        return T(Rot.from_rotvec(q[0] * z))
    if kind == "prismatic":
        return T(Rot.identity(), q[0] * (z if params.get("layout", "1996") == "1996" else x))
    if kind == "screw":
        return T(Rot.from_rotvec(q[0] * z), params["pitch"] * q[0] / (2 * PI) * z)
    if kind == "cylindrical":
        return T(Rot.from_rotvec(q[1] * z), q[0] * z)
    if kind == "spherical":
        return T(Rot.from_euler("zyx", q))
    if kind == "universal":
        s = params.get("input_skew_angle") or 0.0
        a = np.array([math.cos(s), 0.0, math.sin(s)])
        return T(Rot.from_rotvec(q[0] * z) * Rot.from_rotvec(q[1] * a))
    if kind == "homokinetic":
        return T(Rot.from_rotvec(q[1] * np.array([math.cos(q[0]), math.sin(q[0]), 0.0])))
    if kind == "planar":
        return T(Rot.from_rotvec(q[0] * z), (q[1], q[2], 0.0))
    if kind == "unconstrained":
        return T(Rot.from_euler("zyx", q[3:]), q[:3])
    if kind == "fully_constrained":
        return np.eye(4)
    if kind == "gear":
        c = params["radius_first_link"] + params["radius_second_link"]
        turn = Rot.from_rotvec(-q[0] * z)
        return T(turn * Rot.from_rotvec(-params["gear_ratio"] * q[0] * z), turn.apply(c * x))
    if kind == "rack_and_pinion":
        r = params["pinion_radius"]
        return T(Rot.from_rotvec(-q[0] / r * z), (q[0], r, 0.0))
    if kind == "low_order":
        return T(Rot.from_euler("zyx", q[3:][::-1]), q[:3])
    raise AssertionError(kind)


@pytest.mark.parametrize("kind", SIMPLE_KINDS)
def test_motion_matches_scipy_construction(kind):
    t = PAIR_KINDS[kind]
    rng = np.random.default_rng(sum(map(ord, kind)))
    specials = [np.zeros(t.value_count), np.full(t.value_count, PI), np.full(t.value_count, -PI / 2)]
    for q in specials + [rng.uniform(-3, 3, t.value_count) for _ in range(5)]:
        for params in ([PARAMS.get(kind, {})] + ([{"layout": "ap242"}] if kind == "prismatic" else [])
                       + ([{"input_skew_angle": None}] if kind == "universal" else [])):
            close(t.motion(q, **params), _scipy_motion(kind, q, params), 1e-11)


# ------------------------------------------------------------------ the generic low-order pair: its flags are the rule

def _flag_params(bits) -> dict:
    return dict(zip(pairs.FREEDOM_NAMES, (bool(b) for b in bits)))


#: Every named pair AP242 derives flags for, but homokinetic: its flags are the universal
#: pair's, and a generic pair with them is read as the universal pair (the supertype).
NAMED_LOW = [k for k in pairs.LOW_ORDER_NAMED if k != "homokinetic"]


@pytest.mark.parametrize("kind", NAMED_LOW)
def test_a_generic_pair_with_a_named_pairs_flags_moves_exactly_as_that_pair(kind):
    """The motion of low_order_kinematic_pair with the flags AP242 derives for ``kind`` is the
    named pair's at the values its components give: checked against the closed forms built with
    scipy's Rotation (the universal pair: Rz(rz) Rx(rx), not the generic Rx Ry Rz order)."""
    flags, comps = pairs.LOW_ORDER_NAMED[kind]
    assert pairs.named_low_order(flags) == kind
    t = PAIR_KINDS["low_order"]
    fp = _flag_params(flags)
    assert t.freedoms(fp) == sum(flags) == PAIR_KINDS[kind].freedoms()
    assert len(comps) == PAIR_KINDS[kind].value_count
    assert t.locked(fp) == tuple(not f for f in flags)
    named = {"layout": "ap242"} if kind == "prismatic" else {}
    rng = np.random.default_rng(sum(map(ord, kind)))
    q6 = rng.uniform(-2.5, 2.5, (6, 6)) * np.array(flags, float)
    qk = q6[:, list(comps)]
    truth_kind = "spherical" if kind == "spherical_with_pin" else kind  # its roll is 0 here
    truth = np.array([_scipy_motion(truth_kind, q, named) for q in qk])
    close(t.motion(q6, **fp), truth, 1e-12)
    # the same transform as the named pair's own, exactly (one motion, not two)
    assert np.array_equal(t.motion(q6, **fp), PAIR_KINDS[kind].motion(qk, **named))
    J = t.motion_jacobian(q6, **fp)
    close(J[..., list(comps)], PAIR_KINDS[kind].motion_jacobian(qk, **named), 0)
    unused = [i for i in range(6) if i not in comps]
    close(J[..., unused], np.zeros(J[..., unused].shape), 0)


def test_homokinetic_flags_name_the_universal_pair():
    assert pairs.LOW_ORDER_NAMED["homokinetic"][0] == pairs.LOW_ORDER_NAMED["universal"][0]
    assert pairs.named_low_order(pairs.LOW_ORDER_NAMED["homokinetic"][0]) == "universal"


def test_the_universal_flags_are_not_the_generic_composition():
    """Why the named pair's motion must win: for r_x, r_z the generic T Rx Ry Rz would be
    Rx(rx) Rz(rz), which is not the universal pair's Rz(q1) Rx(q2)."""
    t = PAIR_KINDS["low_order"]
    q = [0.0, 0.0, 0.0, 0.6, 0.0, 0.9]
    M = t.motion(q, **_flag_params((0, 0, 0, 1, 0, 1)))
    close(M, compose(rot_z(0.9), rot_x(0.6)))
    assert np.abs(M - compose(rot_x(0.6), rot_z(0.9))).max() > 0.1


UNNAMED_FLAGS = [bits for bits in ((n >> 5 & 1, n >> 4 & 1, n >> 3 & 1, n >> 2 & 1, n >> 1 & 1, n & 1)
                                   for n in range(64)) if pairs.named_low_order(bits) is None]


def test_unnamed_flag_sets_move_translation_first_then_x_y_z_rotations():
    """Flags no named pair has (54 of the 64): ``T(tx, ty, tz) Rx(rx) Ry(ry) Rz(rz)`` (scipy's
    intrinsic "XYZ" Euler angles), locked columns zero, free columns the finite differences."""
    from scipy.spatial.transform import Rotation

    assert len(UNNAMED_FLAGS) == 64 - (len(pairs.LOW_ORDER_NAMED) - 1)
    t = PAIR_KINDS["low_order"]
    rng = np.random.default_rng(7)
    for bits in UNNAMED_FLAGS:
        fp = _flag_params(bits)
        q = rng.uniform(-2, 2, 6) * np.array(bits, float)
        T = np.eye(4)
        T[:3, :3] = Rotation.from_euler("XYZ", q[3:]).as_matrix()
        T[:3, 3] = q[:3]
        close(t.motion(q, **fp), T, 1e-12)
        assert t.freedoms(fp) == sum(bits)
        J = t.motion_jacobian(q, **fp)
        M0inv, h = inverse(t.motion(q, **fp)), 1e-6
        for i, b in enumerate(bits):
            if not b:  # a locked value is not perturbed: its column is zero
                close(J[:, i], np.zeros(6), 0)
                continue
            e = np.eye(6)[i] * h
            dM = (t.motion(q + e, **fp) - t.motion(q - e, **fp)) / (2 * h)
            close(J[:, i], vee(M0inv @ dM), 1e-7)
