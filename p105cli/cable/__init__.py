"""Cables on moving mechanisms: Kirchhoff-rod statics and the checks a designer needs.

Modules (each imported only when a scene asks for it, so importing this
package costs nothing):

* ``scene``    -- read and check a ``p105-scene/1`` file (units to SI, JSON paths in errors)
* ``rod``      -- the default solver: a discrete Kirchhoff rod with distributed weight
* ``patent``   -- the baseline of patent CN101727523A: Euler parameters, constant
                  vertical internal force, backward differences (first order)
* ``workflow`` -- the patent's key-point workflow: over-length check, warm-started
                  solve, symmetry-error check, node frames, end loads, bend radius
* ``display``  -- cable shapes and animations (matplotlib, optional ``plot`` extra)

See ``docs/cable.md``.
"""
