"""The six freedoms of a low-order pair, by the names of AP242's flags (``t_x`` .. ``r_z``).

Plain Python (no numpy): validate's messages use them and validate starts without numpy.
"""

from __future__ import annotations

__all__ = ["FREEDOM_NAMES", "motion_in_words"]

#: AP242 low_order_kinematic_pair's flags, in the order of its value's components
#: (tx, ty, tz, rx, ry, rz).
FREEDOM_NAMES = ("t_x", "t_y", "t_z", "r_x", "r_y", "r_z")


def motion_in_words(flags) -> str:
    """Freedom flags (t_x .. r_z, truthy where free) in words, for messages that set what a file
    says against what the standard derives: "translation along z, rotation about x and z"."""
    t = [a for a, f in zip("xyz", flags[:3]) if f]
    r = [a for a, f in zip("xyz", flags[3:]) if f]
    parts = ([f"translation along {' and '.join(t)}"] if t else []) + \
        ([f"rotation about {' and '.join(r)}"] if r else [])
    return ", ".join(parts) or "no motion"
