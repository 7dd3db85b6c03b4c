"""Kinematic paths of a link frame, and their sampling at parameter values ``t``.

A :class:`KinematicPath` is a chain of :class:`PathSegment` s, each running
from the frame ``T_start`` at ``t_start`` to ``T_end`` at ``t_end`` (4x4,
metres, in the path's coordinate system). A path of several segments is the
composite path of ISO 10303-105:1996 6.4.6 (AP242: a kinematic_path with
several segments); a single segment is a path_element.

Sampling rules (the standard's wording in brackets), all synchronised on
one fraction ``s = (t - t_start) / (t_end - t_start)`` of the segment
[6.4.9, 6.4.11: "orientation interpolation is synchronised with the
translation interpolation"]:

* **rotation**: always by slerp of the unit quaternions of the two end
  frames (constant angular velocity about a fixed axis); Euler or ypr angles
  are never interpolated.
* **linear** [6.4.10: linear interpolation between the node transforms]:
  translation ``p0 + s (p1 - p0)``.
* **circular** [6.4.9: the translation of the link frame's origin describes
  a circle]: the circle through start, ``via_point`` and end; the origin
  moves at constant angular speed along the arc from the start through the
  via point to the end.
* **curve_based** [6.4.11: the translation produces the curve]: the origin
  follows ``path_curve`` from the parameter of the start point to that of
  the end point, the curve parameter linear in ``s`` (found by closest-point
  projection; a closed conic is followed in its own sense, wrapping at 2 pi).
  The end frames must lie on the curve (the standard's informal
  propositions); they are checked to a tolerance relative to the segment.
* **point_to_point** [6.4.8: it "does not prescribe interpolation; it is
  left to the software using the data"]: linear translation and slerp, and
  the samples are labelled as not prescribed by the file
  (:attr:`PathSamples.prescribed` is False there).

A sample at a segment boundary belongs to the later segment, except the
last parameter of the path. Parameters outside the path's range are an
error, never extrapolated.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from p105cli.kinematics.spatial import slerp, transform
from p105cli.kinematics.model import frozen_array

__all__ = ["SEGMENT_KINDS", "PathSegment", "KinematicPath", "PathSamples", "PathError", "sample_path",
           "parameter_grid"]

SEGMENT_KINDS = ("point_to_point", "linear", "circular", "curve_based")

#: Relative tolerance (to the segment's size) for geometric consistency checks.
GEOM_TOL = 1e-6


class PathError(ValueError):
    """A path that cannot be sampled (degenerate circle, end off its curve, t out of range)."""


@dataclass(frozen=True)
class PathSegment:
    kind: str
    t_start: float
    t_end: float
    T_start: np.ndarray
    T_end: np.ndarray
    via_point: Optional[np.ndarray] = None
    curve: Any = None
    transition: str = ""
    id: Optional[int] = None

    def __post_init__(self):
        if self.kind not in SEGMENT_KINDS:
            raise PathError(f"unknown path segment kind {self.kind!r}")
        object.__setattr__(self, "T_start", frozen_array(self.T_start, (4, 4)))
        object.__setattr__(self, "T_end", frozen_array(self.T_end, (4, 4)))
        if self.via_point is not None:
            object.__setattr__(self, "via_point", frozen_array(self.via_point, (3,)))
        if not (np.isfinite(self.t_start) and np.isfinite(self.t_end) and self.t_end > self.t_start):
            raise PathError(f"{self._label()}: the parameter must increase along a segment "
                            f"(t from {self.t_start!r} to {self.t_end!r})")
        if self.kind == "circular" and self.via_point is None:
            raise PathError(f"{self._label()}: a circular path needs its via point")
        if self.kind == "curve_based" and self.curve is None:
            raise PathError(f"{self._label()}: a curve-based path needs its curve")
        # geometry checked (and prepared) once, when the path is read, not when sampled
        if self.kind == "circular":
            object.__setattr__(self, "_circle", _circle_through(self.T_start[:3, 3], self.via_point,
                                                                self.T_end[:3, 3], self._label(), self.size))
        elif self.kind == "curve_based":
            object.__setattr__(self, "_curve_span", _curve_parameters(self))

    def _label(self) -> str:
        return f"{self.kind} path segment" + (f" #{self.id}" if self.id is not None else "")

    @property
    def size(self) -> float:
        """A length scale of the segment for relative tolerances (metres, > 0)."""
        d = float(np.linalg.norm(self.T_end[:3, 3] - self.T_start[:3, 3]))
        scale = max(d, float(np.linalg.norm(self.T_start[:3, 3])), float(np.linalg.norm(self.T_end[:3, 3])))
        return scale if scale > 0.0 else 1.0


@dataclass(frozen=True)
class KinematicPath:
    """A path of a link frame: segments in increasing, contiguous ``t``.

    ``link``/``frame``: which link frame follows the path (when known: the
    link's name and the name of its frame, None for the link frame itself);
    ``role``: ``"prescribed"``, ``"resulting"`` or ``""``; ``holder_id``: the
    representation holding the path (what a kinematic_control names)."""

    name: str
    segments: tuple
    link: Optional[str] = None
    role: str = ""
    id: Optional[int] = None
    frame: Optional[str] = None
    holder_id: Optional[int] = None

    def __post_init__(self):
        segs = tuple(self.segments)
        if not segs:
            raise PathError(f"path {self.name!r} has no segments")
        object.__setattr__(self, "segments", segs)
        for a, b in zip(segs, segs[1:]):
            tol = 1e-12 * max(1.0, abs(a.t_end))
            if abs(a.t_end - b.t_start) > tol:
                raise PathError(f"path {self.name!r}: segment parameters are not contiguous "
                                f"(one ends at t={a.t_end!r}, the next starts at t={b.t_start!r})")

    @property
    def t_start(self) -> float:
        return self.segments[0].t_start

    @property
    def t_end(self) -> float:
        return self.segments[-1].t_end

    @property
    def breakpoints(self) -> np.ndarray:
        return np.array([s.t_start for s in self.segments] + [self.t_end])


@dataclass(frozen=True)
class PathSamples:
    t: np.ndarray            # (N,)
    T: np.ndarray            # (N, 4, 4) sampled frames
    segment: np.ndarray      # (N,) index of the segment each sample lies on
    prescribed: np.ndarray   # (N,) False where the file prescribes no interpolation (point_to_point)


# ----------------------------------------------------------------- circles

def _circle_through(p0, pv, p1, label: str, scale: float):
    """Centre, radius, in-plane axes (u towards p0, w = n x u) and the arc angle
    from p0 through pv to p1, of the circle through three points."""
    a, b = pv - p0, p1 - p0
    n = np.cross(a, b)
    nn = float(np.dot(n, n))
    if nn <= (GEOM_TOL * scale * scale) ** 2:
        raise PathError(f"{label}: start, via point and end are collinear or coincident; no circle passes "
                        "through them (ISO 10303-105 6.4.9 WR1, WR2)")
    # circumcentre of the triangle p0, pv, p1
    c = p0 + (np.dot(a, a) * np.cross(b, n) + np.dot(b, b) * np.cross(n, a)) / (2.0 * nn)
    r = float(np.linalg.norm(p0 - c))
    u = (p0 - c) / r
    nz = n / np.sqrt(nn)  # p0 -> pv -> p1 turns positively about nz
    w = np.cross(nz, u)

    def angle(p):
        d = p - c
        return float(np.mod(np.arctan2(np.dot(d, w), np.dot(d, u)), 2.0 * np.pi))

    return c, r, u, w, angle(p1), angle(pv)


# ----------------------------------------------------------------- curves

def _curve_range(curve):
    b = getattr(curve, "bounds", None)
    if b is not None:
        return float(b[0]), float(b[1]), False
    pts = getattr(curve, "points", None)
    if pts is not None:  # polyline: 0 .. n-1
        return 0.0, float(len(pts) - 1), False
    if hasattr(curve, "a") and hasattr(curve, "b"):  # circle / ellipse: periodic in radians
        return 0.0, 2.0 * np.pi, True
    return None, None, False  # a line: unbounded


def _project(curve, p, label: str, scale: float) -> float:
    """Parameter of the point of ``curve`` closest to ``p`` (must be on it)."""
    lo, hi, periodic = _curve_range(curve)
    if lo is None:  # line C(u) = pnt + u dir
        P, d, _ = curve.evaluate(np.array(0.0))
        u = float(np.dot(p - P, d) / np.dot(d, d))
    else:
        grid = np.linspace(lo, hi, 513)
        P, _, _ = curve.evaluate(grid)
        u = float(grid[np.argmin(np.sum((P - p) ** 2, axis=-1))])
        for _ in range(30):  # Newton on f(u) = dP . (P - p)
            P, d, dd = curve.evaluate(np.array(u))
            f = float(np.dot(d, P - p))
            fp = float(np.dot(dd, P - p) + np.dot(d, d))
            if fp <= 0.0:
                break
            step = f / fp
            u_new = u - step
            if not periodic:
                u_new = min(max(u_new, lo), hi)
            if abs(u_new - u) <= 1e-15 * max(1.0, abs(u)):
                u = u_new
                break
            u = u_new
        if periodic:
            u = float(np.mod(u, 2.0 * np.pi))
    P, _, _ = curve.evaluate(np.array(u))
    miss = float(np.linalg.norm(P - p))
    if miss > GEOM_TOL * scale:
        raise PathError(f"{label}: an end frame lies {miss:.3g} m off the path curve "
                        "(ISO 10303-105 6.4.11: the start and end points shall lie on the curve)")
    return u


def _curve_parameters(seg: PathSegment):
    label = seg._label()
    u0 = _project(seg.curve, seg.T_start[:3, 3], label, seg.size)
    u1 = _project(seg.curve, seg.T_end[:3, 3], label, seg.size)
    _, _, periodic = _curve_range(seg.curve)
    if periodic and u1 <= u0:
        u1 += 2.0 * np.pi  # follow the conic in its own sense
    return u0, u1


# ----------------------------------------------------------------- sampling

def _positions(seg: PathSegment, s: np.ndarray) -> np.ndarray:
    p0, p1 = seg.T_start[:3, 3], seg.T_end[:3, 3]
    if seg.kind in ("linear", "point_to_point"):
        return p0 + s[:, None] * (p1 - p0)
    if seg.kind == "circular":
        c, r, u, w, arc, _ = seg._circle
        phi = s * arc
        return c + r * (np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * w)
    u0, u1 = seg._curve_span
    P, _, _ = seg.curve.evaluate(u0 + s * (u1 - u0))
    return np.asarray(P).reshape(-1, 3)


def sample_path(path: KinematicPath, t) -> PathSamples:
    """Frames of ``path`` at parameters ``t`` (1-D array, within the path's range)."""
    t = np.atleast_1d(np.asarray(t, dtype=np.float64))
    if t.ndim != 1:
        raise PathError("t must be a 1-D array of parameter values")
    lo, hi = path.t_start, path.t_end
    tol = 1e-12 * max(1.0, abs(lo), abs(hi))
    bad = ~np.isfinite(t) | (t < lo - tol) | (t > hi + tol)
    if np.any(bad):
        raise PathError(f"path {path.name!r}: t = {t[np.argmax(bad)]!r} is outside its range [{lo!r}, {hi!r}]")
    t = np.clip(t, lo, hi)
    starts = np.array([s.t_start for s in path.segments])
    seg = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(path.segments) - 1)
    T = np.empty((t.shape[0], 4, 4))
    prescribed = np.ones(t.shape[0], dtype=bool)
    for k, sg in enumerate(path.segments):  # a loop over segments, vectorised over samples
        sel = np.nonzero(seg == k)[0]
        if sel.size == 0:
            continue
        s = (t[sel] - sg.t_start) / (sg.t_end - sg.t_start)
        R = slerp(sg.T_start, sg.T_end, s)
        T[sel] = transform(R, _positions(sg, s))
        if sg.kind == "point_to_point":
            prescribed[sel] = False
    return PathSamples(t, T, seg, prescribed)


def parameter_grid(t_start: float, t_end: float, *, step: float | None = None, count: int | None = None,
                   breakpoints=None) -> np.ndarray:
    """Sample parameters over ``[t_start, t_end]``: ``count`` evenly spaced values
    (both ends included), or every ``step`` from ``t_start`` plus ``t_end``;
    ``breakpoints`` (segment ends) are always included so every node is sampled."""
    if (step is None) == (count is None):
        raise ValueError("give exactly one of step and count")
    if count is not None:
        if count < 1:
            raise ValueError("count must be at least 1")
        t = np.linspace(t_start, t_end, count) if count > 1 else np.array([t_start])
    else:
        if not (step > 0.0 and np.isfinite(step)):
            raise ValueError("step must be a positive number")
        n = int(np.floor((t_end - t_start) / step * (1.0 + 1e-12)))
        if n > 10_000_000:
            raise ValueError(f"step {step!r} gives more than 10 million samples")
        t = t_start + step * np.arange(n + 1)
        t = np.append(t[t < t_end - 1e-12 * max(1.0, abs(t_end))], t_end)
    if breakpoints is not None:
        t = np.union1d(t, np.asarray(breakpoints, dtype=np.float64))
    return t
