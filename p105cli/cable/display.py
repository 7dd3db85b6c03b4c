"""Pictures of a cable run: shapes over the key points (PNG/SVG) and an animation (GIF/HTML).

As in the patent (step 234), the nodes of each key point are joined by a
Bezier fit: a C1 piecewise cubic through the nodes (Catmull-Rom tangents,
the Bezier control points at a third of each chord along them), drawn in
3D with matplotlib. matplotlib is optional (``pip install p105cli[plot]``)
and imported only here, when a picture is asked for; without it
:class:`DisplayError` says how to get it.

Input: the ``cable_state`` records of :func:`p105cli.cable.workflow.run_scene`
(other records are ignored), the ``nodes`` effect being required.
"""

from __future__ import annotations

import contextlib
import os
import sys

import numpy as np

from p105cli.fileio import atomic_file

__all__ = ["DisplayError", "bezier_fit", "plot_shapes", "animate"]


class DisplayError(RuntimeError):
    """A picture that cannot be made (matplotlib missing, no shapes in the records)."""


def _pyplot():
    try:
        import matplotlib
        matplotlib.use("Agg")          # files only: never open a window
        import matplotlib.pyplot as plt
    except ImportError:
        raise DisplayError("drawing cables needs matplotlib: pip install 'p105cli[plot]'") from None
    return plt


def bezier_fit(nodes, samples_per_span: int = 8) -> np.ndarray:
    """Points of the C1 cubic Bezier spline through ``nodes`` (k, 3): ((k-1)*samples+1, 3).

    Span i runs from P_i to P_{i+1} with control points P_i + T_i/3 and
    P_{i+1} - T_{i+1}/3, where T_i = (P_{i+1} - P_{i-1})/2 (one-sided at
    the ends). The curve passes through every node.
    """
    P = np.asarray(nodes, float)
    if P.ndim != 2 or P.shape[0] < 2:
        raise DisplayError("a cable shape needs at least two nodes")
    T = np.empty_like(P)
    T[1:-1] = 0.5 * (P[2:] - P[:-2])
    T[0] = P[1] - P[0]
    T[-1] = P[-1] - P[-2]
    b0, b3 = P[:-1], P[1:]
    b1, b2 = b0 + T[:-1] / 3.0, b3 - T[1:] / 3.0
    u = np.linspace(0.0, 1.0, samples_per_span + 1)[:-1, None, None]
    pts = ((1 - u) ** 3 * b0 + 3 * (1 - u) ** 2 * u * b1 + 3 * (1 - u) * u ** 2 * b2 + u ** 3 * b3)
    pts = np.transpose(pts, (1, 0, 2)).reshape(-1, 3)
    return np.vstack([pts, P[-1:]])


def _states(records):
    states = [r for r in records if r.get("type") == "cable_state" and r.get("nodes")]
    if not states:
        raise DisplayError("no cable shapes to draw (ask for the 'shape' effect)")
    return states


def _axes_limits(ax, states):
    allp = np.concatenate([np.asarray(s["nodes"], float) for s in states])
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    c, r = 0.5 * (lo + hi), 0.5 * float(np.max(hi - lo)) or 1.0
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")


def _picture_format(path, stdout_format: str) -> str:
    """The format a picture is written in: its file name's extension; ``-`` (standard output,
    no name to tell) the text format ``stdout_format``."""
    if os.fspath(path) == "-":
        return stdout_format
    return os.path.splitext(os.fspath(path))[1].lower().lstrip(".")


@contextlib.contextmanager
def _picture_file(path, binary: bool):
    """``path`` written atomically, or standard output for ``-``."""
    if os.fspath(path) == "-":
        sys.stdout.flush()
        yield sys.stdout.buffer if binary else sys.stdout
        (sys.stdout.buffer if binary else sys.stdout).flush()
        return
    with atomic_file(path, binary=binary) as fh:
        yield fh


def plot_shapes(records, path, *, title: str | None = None) -> None:
    """Every key point's shape, coloured by time, to ``path`` (.png or .svg; ``-``: SVG on
    standard output), written atomically."""
    fmt = _picture_format(path, "svg")
    if fmt not in ("png", "svg"):
        raise DisplayError(f"shapes are drawn to .png or .svg, not {fmt!r}")
    states = _states(records)
    plt = _pyplot()
    fig = plt.figure(figsize=(7, 6))
    try:
        ax = fig.add_subplot(projection="3d")
        cmap = plt.get_cmap("viridis")
        cables = sorted({s["cable"] for s in states})
        keys = sorted({s["key"] for s in states})
        for s in states:
            curve = bezier_fit(s["nodes"])
            col = cmap(keys.index(s["key"]) / max(len(keys) - 1, 1))
            ax.plot(curve[:, 0], curve[:, 1], curve[:, 2], color=col, lw=1.2)
            nodes = np.asarray(s["nodes"], float)
            ax.scatter(nodes[[0, -1], 0], nodes[[0, -1], 1], nodes[[0, -1], 2], color=col, s=8)
        _axes_limits(ax, states)
        ax.set_title(title or f"{', '.join(cables)}: {len(keys)} key points")
        # deterministic output: no timestamps in the file
        meta = {"Date": None} if fmt == "svg" else {"Software": "p105"}
        with _picture_file(path, binary=True) as fh:
            fig.savefig(fh, format=fmt, metadata=meta)
    finally:
        plt.close(fig)


def animate(records, path, *, fps: int = 5) -> None:
    """The cable moving through the key points: ``.gif`` (Pillow) or self-contained ``.html``
    (``-``: HTML on standard output)."""
    fmt = _picture_format(path, "html")
    if fmt not in ("gif", "html"):
        raise DisplayError(f"animations are written as .gif or .html, not {fmt!r}")
    states = _states(records)
    plt = _pyplot()
    from matplotlib import animation

    keys = sorted({s["key"] for s in states})
    by_key = {k: [s for s in states if s["key"] == k] for k in keys}
    fig = plt.figure(figsize=(6, 5))
    try:
        ax = fig.add_subplot(projection="3d")
        _axes_limits(ax, states)
        lines = {}

        def draw(i):
            k = keys[i]
            for s in by_key[k]:
                curve = bezier_fit(s["nodes"])
                if s["cable"] not in lines:
                    lines[s["cable"]], = ax.plot([], [], [], lw=1.5, label=s["cable"])
                ln = lines[s["cable"]]
                ln.set_data(curve[:, 0], curve[:, 1])
                ln.set_3d_properties(curve[:, 2])
            ax.set_title(f"key point {k}, t = {by_key[k][0]['t']:.4g}")
            return list(lines.values())

        anim = animation.FuncAnimation(fig, draw, frames=len(keys), interval=1000 // max(fps, 1), blit=False)
        if fmt == "gif":
            tmp = os.fspath(path) + ".part.gif"
            try:
                anim.save(tmp, writer=animation.PillowWriter(fps=fps))
                with open(tmp, "rb") as src, atomic_file(path, binary=True) as fh:
                    fh.write(src.read())
            finally:
                if os.path.exists(tmp):
                    os.unlink(tmp)
        else:
            html = anim.to_jshtml(fps=fps, default_mode="loop")
            with _picture_file(path, binary=False) as fh:
                fh.write("<!DOCTYPE html>\n<html><head><meta charset='utf-8'><title>cable</title></head>"
                         f"<body>\n{html}\n</body></html>\n")
    finally:
        plt.close(fig)
