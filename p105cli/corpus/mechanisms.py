"""The corpus mechanisms: geometry, pair frames, drives, and position solvers.

Each mechanism is described once, independently of the schema profile:
its links (with their shapes and named frames, in link coordinates), its
pairs (with the pair frames on both links), where its base link sits in the
world, and a position solver ``solve(drive) -> {link: T_base_link}`` that
closes every loop for a value of the driving pair(s). The writers turn a
mechanism into Part 21 for a profile; the pair values they write are
*measured* from the solved link poses (:func:`configuration`), and every
measurement is checked against the pair's motion (see
:mod:`p105cli.corpus.geometry`), so a file cannot claim a state its
geometry does not have.

Lengths are millimetres and angles radians here; the writers convert angles
to the files' unit (the degree).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .geometry import (
    GeometryError, compose, frame, inverse, link_relative, pair_value, rot_x, rot_y, rot_z,
    su_parameters, trans, trans_x, trans_y, trans_z,
)

DEG = math.pi / 180.0

#: Post-multiplied to both frames of a prismatic pair in the AP242 layout:
#: the 1996 layout slides along the pair frames' z axis, AP242 along x, so
#: the AP242 frames are the 1996 ones turned to put their x axis where the
#: 1996 z axis was (``Ry(-90 deg)`` maps x onto z).
Z_TO_X = rot_y(-math.pi / 2)


@dataclass
class Link:
    name: str
    description: str
    outline: list  # polyline points of the link's shape, link coordinates (mm)
    circles: list = field(default_factory=list)  # (T in link frame, radius, name): circles of the shape
    frames: dict = field(default_factory=dict)  # other named frames of the link (4x4, link frame)


@dataclass
class Pair:
    name: str
    description: str
    kind: str  # revolute | prismatic | gear | rack_and_pinion | point_on_planar_curve
    first: str
    second: str
    frame_first: np.ndarray  # pair frame on the first link (1996 convention for prismatic pairs)
    frame_second: np.ndarray
    params: dict = field(default_factory=dict)
    limits: object = None  # None (unlimited), (lower, upper), or "auto" (from the sweep, with a margin)
    actuated: bool = False
    su_first: tuple | None = None  # Sheth-Uicker parameters of the frames, when written as su_parameters
    su_second: tuple | None = None
    #: For pairs whose value is not periodic (a gear's rotation_1 fixes rotation_2 =
    #: -ratio * rotation_1, so 210 deg and -150 deg differ): drive -> the value's branch.
    branch: Callable | None = None


@dataclass
class Mechanism:
    key: str
    title: str
    description: str
    links: list  # links[0] is the base (the link fixed to the ground)
    pairs: list
    base_pose: np.ndarray  # the base link's frame in the world
    solve: Callable  # drive -> {link name: T_base_link}
    drives: list  # driving values of the motion program; drives[0] is the initial state
    sweep: list  # a continuous sweep of driving values from drives[0] (for "auto" limits)
    path: tuple  # (link name, frame name): the frame whose path the motion program prescribes
    loops: list = field(default_factory=list)  # [(pair name, traversed first -> second)], closed
    use_su: bool = False  # write pair frames as su_parameters where the profile allows it
    margins: tuple = (5 * DEG, 2.0)  # "auto" limits: margin for angles, for lengths

    def link(self, name: str) -> Link:
        for ln in self.links:
            if ln.name == name:
                return ln
        raise KeyError(name)

    def pair(self, name: str) -> Pair:
        for p in self.pairs:
            if p.name == name:
                return p
        raise KeyError(name)


# ------------------------------------------------------------------ measuring pair values

def pair_frames(pair: Pair, slide_axis: int):
    """The pair's two frames for a layout whose prismatic pairs slide along ``slide_axis``."""
    if pair.kind == "prismatic" and slide_axis == 0:
        return compose(pair.frame_first, Z_TO_X), compose(pair.frame_second, Z_TO_X)
    if pair.kind == "prismatic" and slide_axis != 2:
        raise ValueError("prismatic pairs slide along z (1996) or x (AP242)")
    return pair.frame_first, pair.frame_second


def configuration(mech: Mechanism, drive, slide_axis: int = 2) -> dict:
    """``{pair name: value}`` measured from the solved link poses at ``drive``.

    Raises GeometryError when a pair's two frames do not differ by that
    pair's motion (to 1e-9).
    """
    poses = mech.solve(drive)
    out = {}
    for p in mech.pairs:
        f1, f2 = pair_frames(p, slide_axis)
        rel = link_relative(poses[p.first], f1, poses[p.second], f2)
        hint = None if p.branch is None else p.branch(drive)
        try:
            out[p.name] = pair_value(p.kind, rel, p.params, slide_axis, hint)
        except GeometryError as err:
            raise GeometryError(f"{mech.key}: pair {p.name!r} at drive {drive!r}: {err}") from None
    return out


_SCALAR = {"revolute": "rotation", "prismatic": "translation", "gear": "rotation_1",
           "rack_and_pinion": "displacement"}


def scalar_value(kind: str, value: dict) -> float:
    """The pair's single range-limited variable (radians or mm)."""
    return value[_SCALAR[kind]]


def resolved_limits(mech: Mechanism) -> dict:
    """``{pair name: (lower, upper) or None}``; "auto" limits are the extremes over the
    sweep widened by the margin and rounded outwards to whole degrees / millimetres."""
    auto = [p for p in mech.pairs if isinstance(p.limits, str)]
    out = {p.name: (None if isinstance(p.limits, str) else p.limits) for p in mech.pairs}
    if not auto:
        return out
    series = {p.name: [] for p in auto}
    for s in mech.sweep:
        conf = configuration(mech, s)
        for p in auto:
            series[p.name].append(scalar_value(p.kind, conf[p.name]))
    for p in auto:
        v = np.asarray(series[p.name])
        if p.kind in ("revolute", "gear"):
            v = np.unwrap(v)
            if v.max() - v.min() + 2 * mech.margins[0] >= 2 * math.pi:
                out[p.name] = None  # turns fully: unlimited
                continue
            lo = math.floor((v.min() - mech.margins[0]) / DEG) * DEG
            hi = math.ceil((v.max() + mech.margins[0]) / DEG) * DEG
        else:
            lo = math.floor(v.min() - mech.margins[1])
            hi = math.ceil(v.max() + mech.margins[1])
        out[p.name] = (float(lo), float(hi))
    return out


# ------------------------------------------------------------------ helpers

def _sweep(start: float, n: int = 720) -> list:
    return [start + 2.0 * math.pi * k / n for k in range(n + 1)]


def bar(length: float, width: float = 10.0) -> list:
    """Closed outline of a straight bar from the origin to (length, 0, 0) (link coordinates)."""
    h = width / 2.0
    return [(0.0, -h, 0.0), (length, -h, 0.0), (length, h, 0.0), (0.0, h, 0.0), (0.0, -h, 0.0)]


def _rz_at(x, y, angle) -> np.ndarray:
    return compose(trans(x, y, 0.0), rot_z(angle))


# ------------------------------------------------------------------ four-bar

#: The Grashof crank-rocker of the shared reference data (closed_loop.fourbar[0]),
#: in millimetres: crank a, coupler b, rocker c, ground d; A = (0, 0), D = (d, 0).
FOUR_BAR = {"a": 20.0, "b": 70.0, "c": 90.0, "d": 60.0}


def four_bar_angles(theta2: float, a=FOUR_BAR["a"], b=FOUR_BAR["b"], c=FOUR_BAR["c"], d=FOUR_BAR["d"],
                    sigma: int = 1) -> tuple[float, float]:
    """Coupler and rocker angles (theta3, theta4) from the crank angle, by intersecting the
    circle of radius b about B with the circle of radius c about D. ``sigma = +1`` is the
    open branch (C to the left of B->D), -1 the crossed one."""
    B = np.array([a * math.cos(theta2), a * math.sin(theta2)])
    D = np.array([d, 0.0])
    BD = D - B
    L = float(np.hypot(*BD))
    along = (b * b - c * c + L * L) / (2.0 * L)
    h2 = b * b - along * along
    if h2 < 0.0:
        raise GeometryError(f"four-bar cannot be assembled at theta2 = {theta2}")
    perp = np.array([-BD[1], BD[0]]) / L
    C = B + along * BD / L + sigma * math.sqrt(h2) * perp
    theta3 = math.atan2(C[1] - B[1], C[0] - B[0])
    theta4 = math.atan2(C[1] - D[1], C[0] - D[0])
    # one Newton step on the loop equations polishes the last bits
    for _ in range(2):
        f = np.array([a * math.cos(theta2) + b * math.cos(theta3) - d - c * math.cos(theta4),
                      a * math.sin(theta2) + b * math.sin(theta3) - c * math.sin(theta4)])
        J = np.array([[-b * math.sin(theta3), c * math.sin(theta4)],
                      [b * math.cos(theta3), -c * math.cos(theta4)]])
        dt = np.linalg.solve(J, -f)
        theta3 += dt[0]
        theta4 += dt[1]
    return theta3, theta4


def four_bar() -> Mechanism:
    a, b, c, d = (FOUR_BAR[k] for k in "abcd")
    P = np.array([b / 2.0, 25.0, 0.0])  # coupler point (coupler frame)

    def solve(theta2):
        t3, t4 = four_bar_angles(theta2)
        B = (a * math.cos(theta2), a * math.sin(theta2))
        return {"frame": np.eye(4), "crank": rot_z(theta2), "coupler": _rz_at(*B, t3),
                "rocker": _rz_at(d, 0.0, t4)}

    links = [
        Link("frame", "ground link: pivots A and D", [(0, 0, 0), (d / 2, -15, 0), (d, 0, 0)]),
        Link("crank", "input crank A-B", bar(a)),
        Link("coupler", "coupler B-C with coupler point P", [(0, 0, 0), (b, 0, 0), tuple(P), (0, 0, 0)],
             frames={"point P": trans(*P)}),
        Link("rocker", "output rocker D-C", bar(c)),
    ]
    I = np.eye(4)
    pairs = [
        Pair("A", "crank pivot on the frame", "revolute", "frame", "crank", I, I, actuated=True),
        Pair("B", "crank-coupler pin", "revolute", "crank", "coupler", trans_x(a), I, limits="auto"),
        Pair("C", "coupler-rocker pin", "revolute", "coupler", "rocker", trans_x(b), trans_x(c),
             limits="auto"),
        Pair("D", "rocker pivot on the frame", "revolute", "frame", "rocker", trans_x(d), I, limits="auto"),
    ]
    t0 = 30 * DEG
    return Mechanism(
        "four_bar", "planar four-bar linkage (Grashof crank-rocker)",
        "crank 20 mm, coupler 70 mm, rocker 90 mm, frame 60 mm; open branch; crank driven",
        links, pairs, compose(trans(150.0, 100.0, 0.0), rot_z(15 * DEG)), solve,
        drives=[t0, 90 * DEG, 150 * DEG], sweep=_sweep(t0), path=("coupler", "point P"),
        loops=[[("A", True), ("B", True), ("C", True), ("D", False)]])


# ------------------------------------------------------------------ offset slider-crank

SLIDER_CRANK = {"r": 30.0, "l": 110.0, "e": 15.0}


def slider_crank() -> Mechanism:
    r, l, e = (SLIDER_CRANK[k] for k in "rle")

    def solve(theta):
        A = (r * math.cos(theta), r * math.sin(theta))
        x = A[0] + math.sqrt(l * l - (e - A[1]) ** 2)
        phi = math.atan2(e - A[1], x - A[0])
        return {"frame": np.eye(4), "crank": rot_z(theta), "rod": _rz_at(*A, phi),
                "slider": trans(x, e, 0.0)}

    slide = rot_y(math.pi / 2)  # pair frames' z axis along the world x axis (the slide)
    I = np.eye(4)
    links = [
        Link("frame", "ground link: crank bearing O and slide guide",
             [(0, 0, 0), (0, e, 0), (l + r + 30, e, 0)]),
        Link("crank", "crank O-A", bar(r)),
        Link("rod", "connecting rod A-B", bar(l), frames={"centre": trans_x(l / 2)}),
        Link("slider", "slider (piston) with wrist pin B",
             [(-15, -8, 0), (15, -8, 0), (15, 8, 0), (-15, 8, 0), (-15, -8, 0)]),
    ]
    pairs = [
        Pair("O", "crank bearing", "revolute", "frame", "crank", I, I, actuated=True),
        Pair("A", "crank pin", "revolute", "crank", "rod", trans_x(r), I, limits="auto"),
        Pair("B", "wrist pin", "revolute", "rod", "slider", trans_x(l), I, limits="auto"),
        Pair("S", "slide guide", "prismatic", "frame", "slider", compose(trans_y(e), slide), slide,
             limits="auto"),
    ]
    t0 = 45 * DEG
    return Mechanism(
        "slider_crank", "offset slider-crank",
        "crank 30 mm, rod 110 mm, slide line offset 15 mm from the crank bearing; crank driven",
        links, pairs, compose(trans(0.0, 0.0, 200.0), rot_x(math.pi / 2)), solve,
        drives=[t0, 135 * DEG, 225 * DEG], sweep=_sweep(t0), path=("rod", "centre"),
        loops=[[("O", True), ("A", True), ("B", True), ("S", False)]])


# ------------------------------------------------------------------ 6R arm (UR5)

#: UR5, standard DH (a, alpha, d), from the shared reference data (roboticstoolbox 1.5
#: ``models.DH.UR5``), metres converted to millimetres.
UR5_DH = [
    (0.0, math.pi / 2, 89.459),
    (-425.0, 0.0, 0.0),
    (-392.25, 0.0, 0.0),
    (0.0, math.pi / 2, 109.15),
    (0.0, -math.pi / 2, 94.65),
    (0.0, 0.0, 82.3),
]

#: Joint vectors of the reference samples 1, 2 and 4 (``arms.UR5.samples``).
UR5_Q = [
    (1.4016381112532565, -1.2366119839093572, 1.4627488061335727, -3.0210241723387368,
     -1.678709182070071, 1.272035605888287),
    (-1.5770843562919428, -1.3740490526820286, 0.22811014243176153, 1.8044815533695377,
     2.744993232947098, -1.2872770105426268),
    (0.7862736276116591, 0.8458542757983509, 3.0911416660500484, 1.9132511801420575,
     -1.4843114129749622, 1.5468296041753833),
]


def dh_transform(theta, a, alpha, d) -> np.ndarray:
    """Standard DH: ``Rz(theta) Tz(d) Tx(a) Rx(alpha)``."""
    return compose(rot_z(theta), trans_z(d), trans_x(a), rot_x(alpha))


def ur5_arm() -> Mechanism:
    names = ["base", "shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3"]

    def solve(q):
        poses = {"base": np.eye(4)}
        T = np.eye(4)
        for k, (a, alpha, d) in enumerate(UR5_DH):
            T = compose(T, dh_transform(q[k], a, alpha, d))
            poses[names[k + 1]] = T
        return poses

    links = [Link("base", "robot base (link 0), mounted on the table", [(0, 0, 0), (0, 0, -50)])]
    pairs = []
    I = np.eye(4)
    for k, (a, alpha, d) in enumerate(UR5_DH):
        # Annex F (revolute): the pair frame on link k is the inverse of the DH transform
        # without the pair parameter: su = (a, alpha, -d, pi, 0, pi); on link k-1 it is link
        # k-1's own DH frame (su all zero).
        su2 = (a, alpha, -d, math.pi, 0.0, math.pi)
        f2 = inverse(compose(trans_z(d), trans_x(a), rot_x(alpha)))
        if np.abs(su_parameters(*su2) - f2).max() > 1e-12:
            raise GeometryError("Annex F su_parameters do not reproduce the DH pair frame")
        outline = [tuple(f2[:3, 3]), (0.0, 0.0, 0.0)]
        frames = {"flange": np.eye(4)} if k == 5 else {}
        links.append(Link(names[k + 1], f"link {k + 1} of the UR5", outline, frames=frames))
        pairs.append(Pair(f"J{k + 1}", f"joint {k + 1} (DH a={a:g} mm, d={d:g} mm)", "revolute",
                          names[k], names[k + 1], I, f2, limits=(-2 * math.pi, 2 * math.pi), actuated=True,
                          su_first=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0), su_second=su2))
    return Mechanism(
        "ur5_arm", "6R serial arm (UR5, standard DH)",
        "UR5 DH parameters (roboticstoolbox 1.5); pair frames by ISO 10303-105 Annex F; all joints driven",
        links, pairs, compose(trans(400.0, 250.0, 750.0), rot_z(30 * DEG)), solve,
        drives=list(UR5_Q), sweep=[UR5_Q[0]], path=("wrist_3", "flange"), use_su=True)


# ------------------------------------------------------------------ gear train

GEARS = {"r1": 20.0, "r2": 30.0, "r3": 15.0, "beta23": 60 * DEG}


def gear_train() -> Mechanism:
    r1, r2, r3, b23 = GEARS["r1"], GEARS["r2"], GEARS["r3"], GEARS["beta23"]
    O1 = np.zeros(3)
    O2 = O1 + np.array([r1 + r2, 0.0, 0.0])
    O3 = O2 + (r2 + r3) * np.array([math.cos(b23), math.sin(b23), 0.0])

    def solve(phi1):
        phi2 = -(r1 / r2) * phi1
        phi3 = -(r2 / r3) * phi2
        return {"housing": np.eye(4), "gear_1": _rz_at(*O1[:2], phi1), "gear_2": _rz_at(*O2[:2], phi2),
                "gear_3": _rz_at(*O3[:2], phi3)}

    def gear_link(name, r, what):
        return Link(name, f"{what}, pitch radius {r:g} mm", [(0, 0, 0), (r, 0, 0)],
                    circles=[(np.eye(4), r, "pitch circle")])

    links = [
        Link("housing", "gearbox housing with three bearings", [tuple(O1), tuple(O2), tuple(O3)]),
        gear_link("gear_1", r1, "input gear"),
        gear_link("gear_2", r2, "idler gear"),
        Link("gear_3", f"output gear, pitch radius {r3:g} mm", [(0, 0, 0), (r3, 0, 0)],
             circles=[(np.eye(4), r3, "pitch circle")], frames={"marker": trans_x(10.0)}),
    ]
    I = np.eye(4)
    turns = 10 * 2 * math.pi
    pairs = [
        Pair("bearing 1", "input shaft bearing", "revolute", "housing", "gear_1", trans(*O1), I,
             limits=(-turns, turns), actuated=True),
        Pair("bearing 2", "idler bearing", "revolute", "housing", "gear_2", trans(*O2), I),
        Pair("bearing 3", "output shaft bearing", "revolute", "housing", "gear_3", trans(*O3), I),
        Pair("mesh 1-2", "spur mesh input-idler", "gear", "gear_1", "gear_2", I, I,
             params={"radius_first": r1, "radius_second": r2, "gear_ratio": r1 / r2},
             limits=(-turns, turns), branch=lambda phi1: phi1),
        Pair("mesh 2-3", "spur mesh idler-output", "gear", "gear_2", "gear_3", rot_z(b23), rot_z(b23),
             params={"radius_first": r2, "radius_second": r3, "gear_ratio": r2 / r3},
             limits=(-turns * r1 / r2, turns * r1 / r2), branch=lambda phi1: -(r1 / r2) * phi1),
    ]
    t0 = 30 * DEG
    return Mechanism(
        "gear_train", "three-gear spur train (input, idler, output)",
        "pitch radii 20, 30 and 15 mm; output turns 4/3 of the input, same sense; input driven",
        links, pairs, trans(0.0, 0.0, 50.0), solve, drives=[t0, 120 * DEG, 210 * DEG], sweep=[t0],
        path=("gear_3", "marker"),
        loops=[[("bearing 1", True), ("mesh 1-2", True), ("bearing 2", False)],
               [("bearing 2", True), ("mesh 2-3", True), ("bearing 3", False)]])


# ------------------------------------------------------------------ rack and pinion

RACK = {"r": 25.0, "stroke": 120.0}


def rack_and_pinion() -> Mechanism:
    r, stroke = RACK["r"], RACK["stroke"]

    def solve(phi):
        return {"frame": np.eye(4), "pinion": rot_z(phi), "rack": trans(r * phi, -r, 0.0)}

    slide = rot_y(math.pi / 2)
    I = np.eye(4)
    links = [
        Link("frame", "ground link: pinion bearing and rack guide", [(0, 0, 0), (0, -r - 20, 0)]),
        Link("pinion", f"pinion, pitch radius {r:g} mm", [(0, 0, 0), (r, 0, 0)],
             circles=[(np.eye(4), r, "pitch circle")]),
        Link("rack", "rack; x along its pitch line", [(-150, 0, 0), (150, 0, 0), (150, -12, 0), (-150, -12, 0),
                                                         (-150, 0, 0)],
             frames={"end": trans_x(150.0)}),
    ]
    pairs = [
        Pair("bearing", "pinion bearing", "revolute", "frame", "pinion", I, I,
             limits=(-stroke / r, stroke / r), actuated=True),
        Pair("guide", "rack guide", "prismatic", "frame", "rack", compose(trans_y(-r), slide), slide,
             limits=(-stroke, stroke)),
        Pair("mesh", "rack-pinion mesh", "rack_and_pinion", "rack", "pinion", I, I,
             params={"pinion_radius": r}, limits=(-stroke, stroke)),
    ]
    t0 = 40 * DEG
    return Mechanism(
        "rack_and_pinion", "rack and pinion",
        "pinion pitch radius 25 mm; rack stroke +-120 mm; pinion driven",
        links, pairs, trans(0.0, 300.0, 100.0), solve, drives=[t0, 160 * DEG, -80 * DEG], sweep=[t0],
        path=("rack", "end"), loops=[[("bearing", True), ("mesh", False), ("guide", False)]])


# ------------------------------------------------------------------ cam and follower

CAM = {"R": 40.0, "e": 15.0}


def cam_follower() -> Mechanism:
    R, e = CAM["R"], CAM["e"]
    centre = np.array([e, 0.0, 0.0])

    def solve(phi):
        cx, cy = e * math.cos(phi), e * math.sin(phi)
        y = cy + math.sqrt(R * R - cx * cx)  # contact on the line x = 0, upper side
        return {"frame": np.eye(4), "cam": rot_z(phi), "follower": trans(0.0, y, 0.0)}

    slide = rot_x(-math.pi / 2)  # pair frames' z axis along the world y axis
    I = np.eye(4)
    links = [
        Link("frame", "ground link: cam shaft bearing and follower guide", [(0, 0, 0), (0, -30, 0)]),
        Link("cam", f"eccentric circular cam, radius {R:g} mm, eccentricity {e:g} mm", [(0, 0, 0), tuple(centre)],
             circles=[(trans(*centre), R, "cam profile")]),
        Link("follower", "translating knife-edge follower; origin at the knife edge", [(0, 0, 0), (0, 60, 0)],
             frames={"tip": np.eye(4)}),
    ]
    pairs = [
        Pair("shaft", "cam shaft bearing", "revolute", "frame", "cam", I, I, actuated=True),
        Pair("guide", "follower guide", "prismatic", "frame", "follower", slide, slide, limits="auto"),
        Pair("contact", "knife edge on the cam profile", "point_on_planar_curve", "cam", "follower", I, I,
             params={"circle_center": centre, "circle_radius": R}),
    ]
    t0 = 30 * DEG
    return Mechanism(
        "cam_follower", "eccentric cam with a translating knife-edge follower",
        "circular cam profile (radius 40 mm, 15 mm off the shaft) in the cam's frame; in-line follower; "
        "cam driven", links, pairs, trans(0.0, -200.0, 80.0), solve, drives=[t0, 120 * DEG, 240 * DEG],
        sweep=_sweep(t0), path=("follower", "tip"),
        loops=[[("shaft", True), ("contact", True), ("guide", False)]])


# ------------------------------------------------------------------ spherical four-bar

#: Arc lengths (angles between joint axes): frame a1 (u1-u4), crank a2 (u1-u2),
#: coupler a3 (u2-u3), rocker a4 (u4-u3); all axes meet at the origin.
SPHERICAL = {"a1": 50 * DEG, "a2": 20 * DEG, "a3": 60 * DEG, "a4": 45 * DEG, "rho": 100.0}


def spherical_axes(theta, s=SPHERICAL, branch: int = 1):
    """The four joint axes (unit vectors, frame coordinates) at crank angle ``theta``."""
    u1 = np.array([0.0, 0.0, 1.0])
    u4 = np.array([math.sin(s["a1"]), 0.0, math.cos(s["a1"])])
    u2 = np.array([math.sin(s["a2"]) * math.cos(theta), math.sin(s["a2"]) * math.sin(theta), math.cos(s["a2"])])
    c24 = float(u2 @ u4)
    A = np.array([[1.0, c24], [c24, 1.0]])
    x, y = np.linalg.solve(A, [math.cos(s["a3"]), math.cos(s["a4"])])
    w = np.cross(u2, u4)
    w /= np.linalg.norm(w)
    z2 = 1.0 - (x * x + y * y + 2 * x * y * c24)
    if z2 < 0:
        raise GeometryError(f"spherical four-bar cannot be assembled at theta = {theta}")
    u3 = x * u2 + y * u4 + branch * math.sqrt(z2) * w
    return u1, u2, u3 / np.linalg.norm(u3), u4


def spherical_linkage() -> Mechanism:
    rho = SPHERICAL["rho"]
    O = np.zeros(3)

    def link_frames(theta):
        u1, u2, u3, u4 = spherical_axes(theta)
        return {"frame": np.eye(4), "crank": frame(O, u1, u2), "coupler": frame(O, u2, u3),
                "rocker": frame(O, u4, u3)}, (u1, u2, u3, u4)

    def solve(theta):
        return link_frames(theta)[0]

    t0 = 60 * DEG
    poses, (u1, u2, u3, u4) = link_frames(t0)

    def local(link, origin_axis, toward):
        """A pair frame at rho * axis, z along the axis, x toward the link's other axis,
        expressed in the link's frame (from the initial configuration)."""
        W = frame(rho * origin_axis, origin_axis, toward)
        return compose(inverse(poses[link]), W)

    def arc(p, q, n=8):
        om = math.acos(max(-1.0, min(1.0, float(p @ q))))
        return [tuple(rho * (math.sin((1 - t) * om) * p + math.sin(t * om) * q) / math.sin(om))
                for t in np.linspace(0.0, 1.0, n + 1)]

    def in_link(link, pts):
        Ti = inverse(poses[link])
        return [tuple((Ti @ np.array([*p, 1.0]))[:3]) for p in pts]

    mid = (u2 + u3) / np.linalg.norm(u2 + u3)
    links = [
        Link("frame", "ground link: input axis u1 and output axis u4, 50 deg apart", in_link("frame", arc(u1, u4))),
        Link("crank", "input crank, axes 20 deg apart", in_link("crank", arc(u1, u2))),
        Link("coupler", "coupler, axes 60 deg apart", in_link("coupler", arc(u2, u3)),
             frames={"point P": local("coupler", mid, u3)}),
        Link("rocker", "output rocker, axes 45 deg apart", in_link("rocker", arc(u4, u3))),
    ]
    pairs = [
        Pair("input", "input bearing (axis u1)", "revolute", "frame", "crank",
             local("frame", u1, u4), local("crank", u1, u2), actuated=True),
        Pair("crank pin", "crank-coupler bearing (axis u2)", "revolute", "crank", "coupler",
             local("crank", u2, u1), local("coupler", u2, u3), limits="auto"),
        Pair("rocker pin", "coupler-rocker bearing (axis u3)", "revolute", "coupler", "rocker",
             local("coupler", u3, u2), local("rocker", u3, u4), limits="auto"),
        Pair("output", "output bearing (axis u4)", "revolute", "frame", "rocker",
             local("frame", u4, u1), local("rocker", u4, u3), limits="auto"),
    ]
    return Mechanism(
        "spherical_linkage", "spherical four-bar linkage (revolute axes meeting at one point)",
        "arcs: frame 50 deg, crank 20 deg, coupler 60 deg, rocker 45 deg; bearings on a 100 mm sphere; "
        "crank driven", links, pairs, trans(0.0, 0.0, 300.0), solve, drives=[t0, 150 * DEG, 270 * DEG],
        sweep=_sweep(t0), path=("coupler", "point P"),
        loops=[[("input", True), ("crank pin", True), ("rocker pin", True), ("output", False)]])


#: All corpus mechanisms, in file order.
MECHANISMS = {
    "four_bar": four_bar,
    "slider_crank": slider_crank,
    "ur5_arm": ur5_arm,
    "gear_train": gear_train,
    "rack_and_pinion": rack_and_pinion,
    "cam_follower": cam_follower,
    "spherical_linkage": spherical_linkage,
}
