"""Schema functions run in Python: walks the interpreter would do in time exponential in
the depth of the data.

``using_representations(item)`` (ISO 10303-43, in both long forms) climbs from an item
through every representation item or founded item that uses it, along every path
(``using_items`` keeps only the current path to stop cycles), and collects the
representations holding any of them. In a B-rep a point is reached from each of its
vertices' edges, loops, faces and shells by many paths: interpreted, one call costs
milliseconds, and ``compatible_dimension`` and ``representation_item.wr1`` call it for
every point and direction. Here the representations of each item are computed once,
from those of its users:

    reps(x) = distinct(direct(x) ++ reps(u1) ++ reps(u2) ++ ...)

for the users u1, u2, ... of x in USEDIN order. On data without reference cycles this
is the EXPRESS function's value, in the same order (its SET unions keep first
occurrences, and a path check never fires without a cycle). Where a cycle is met the
interpreter runs the EXPRESS body instead, so the result is always the standard's.

``check_geometric_dimension(capt, dir, grc)`` (AP242, global rule
``compatible_dimension``) is a loop over every point and direction of the file: the
same loop here, with the evaluator's own attribute access and comparisons, so that
UNKNOWN and ``?`` behave as in the EXPRESS body.

``cross_product(arg1, arg2)`` (ISO 10303-42, both long forms; ``axis2_placement_3d.wr4``
calls it for every placement) normalises two directions and crosses them: the interpreter
builds four in-memory entity values per call. Here the same floating-point operations in the
same order (sum of squares from 0.0, SQRT, division; the cross terms as written), and the
result built by the evaluator's own entity constructor and ``||`` from ``dummy_gri``, so
the value is the one the body returns. Only two population directions of 2 or 3 finite real
ratios take this path; a zero direction (``normalise`` gives ``?``), an overflowing sum of
squares or anything else is left to the body.

``dimension_of(item)`` (the derived ``dim`` of every geometric item, read by the placement
rules) of a plain cartesian point or direction is the number of its coordinates or ratios,
as the body's first two branches count them; any other item goes through the body.

``collect_joints(items)`` (``mechanism_representation.wr1``) adds the joint of each pair to
a SET in a REPEAT; interpreted, every ``result := result + joint`` copies and re-checks the
whole set, quadratic in the pairs. Here the distinct joints in first-occurrence order (SET +
element keeps the set when the element is in it, instance equality being identity); a
joint that is not a population instance (``?``) is left to the body.

A native applies only to a FUNCTION of that name with the expected parameters; any other
argument (``?``, an in-memory entity value) is left to the interpreter.
"""

from __future__ import annotations

import math

from ..instance import Instance
from .builtins import hiindex
from .scope import _MISSING
from .values import _IND, Agg, _plain

_DIRECTION = frozenset({"direction"})
#: leaf types whose dimension_of is SIZEOF of an explicit list, and that list
_COUNTED = {frozenset({"cartesian_point"}): "coordinates", _DIRECTION: "direction_ratios"}


class _Cycle(Exception):
    """The users of an item lead back to it: the native gives way to the EXPRESS body."""


class Natives:
    """Python versions of schema functions (an ``Evaluator`` mixin)."""

    def _native_call(self, f, args):
        """The native result of FUNCTION ``f`` on ``args``, or ``_MISSING`` to interpret it."""
        native = _NATIVES.get(f.name) if self.natives else None
        if native is None or len(f.parameters) != native[1] or len(args) != native[1]:
            return _MISSING
        return native[0](self, f, args)

    def _using_representations(self, f, args):
        item = args[0]
        if type(item) is not Instance or item.pop is not self.pop:
            return _MISSING
        try:
            ids = self._representations_of(item.id)
        except _Cycle:
            return _MISSING
        instance = self.pop.instance
        return self._coerce(Agg("set", [instance(i) for i in ids]), f.return_type)

    def _item_users(self, iid: int) -> list:
        """Ids of the representation items and founded items using ``#iid``, distinct, in
        USEDIN order (``using_items``' QUERY over ``bag_to_set(USEDIN(item, ''))``)."""
        out: list = []
        seen: set = set()
        types_of = self.pop.types_of
        for zid in self.pop.usedin_ids(iid):
            if zid in seen:
                continue
            seen.add(zid)
            types = types_of(zid)
            if "representation_item" in types or "founded_item" in types:
                out.append(zid)
        return out

    def _representations_of(self, root: int) -> tuple:
        """Ids of the representations using ``#root`` directly or through items (see the
        module docstring); memoised per item for the evaluator's lifetime."""
        memo = self._reps_memo
        done = memo.get(root)
        if done is not None:
            return done
        usedin = self.pop.usedin_ids
        stack = [[root, self._item_users(root), 0]]
        on_path = {root}
        while stack:
            frame = stack[-1]
            users = frame[1]
            descended = False
            while frame[2] < len(users):
                u = users[frame[2]]
                frame[2] += 1
                if u in memo:
                    continue
                if u in on_path:
                    raise _Cycle(u)
                stack.append([u, self._item_users(u), 0])
                on_path.add(u)
                descended = True
                break
            if descended:
                continue
            node = frame[0]
            out: list = []
            seen: set = set()
            for rid in usedin(node, "representation.items"):
                if rid not in seen:
                    seen.add(rid)
                    out.append(rid)
            for u in users:
                for rid in memo[u]:
                    if rid not in seen:
                        seen.add(rid)
                        out.append(rid)
            memo[node] = tuple(out)
            on_path.discard(node)
            stack.pop()
        return memo[root]

    def _cross_product(self, f, args):
        ratios = [self._direction_ratios(a) for a in args]
        if ratios[0] is None or ratios[1] is None:
            return _MISSING
        if len(ratios[0]) == 2 or len(ratios[1]) == 2:
            return _IND  # arg.dim = 2: RETURN(?)
        v1, v2 = (_normalised(r) for r in ratios)
        if v1 is None or v2 is None:
            return _MISSING
        cross = [v1[1] * v2[2] - v1[2] * v2[1], v1[2] * v2[0] - v1[0] * v2[2],
                 v1[0] * v2[1] - v1[1] * v2[0]]
        node = f  # for the line of a NotEvaluable (none is expected here)
        dummy = self._constant("dummy_gri")
        res = self._combine(dummy, self._construct("direction", [Agg("bag", cross)], node), node)
        mag = 0.0
        for x in cross:
            mag = mag + x * x
        if not math.isfinite(mag):
            return _MISSING
        if mag > 0.0:
            result = self._combine(dummy, self._construct("vector", [res, math.sqrt(mag)], node), node)
        else:
            result = self._combine(dummy, self._construct("vector", [args[0], 0.0], node), node)
        return self._coerce(result, f.return_type)

    def _collect_joints(self, f, args):
        items = _plain(args[0])
        declared = [lv.type for lv in f.locals if lv.name == "result"]
        if type(items) is not Agg or len(declared) != 1:
            return _MISSING
        joints: list = []
        seen: set = set()
        for item in items:
            joint = self._attr(self._attr(item, "transformation_operator", None, None), "joint", None, None)
            if type(joint) is not Instance:
                return _MISSING
            if id(joint) not in seen:
                seen.add(id(joint))
                joints.append(joint)
        return self._coerce(self._coerce(Agg("set", joints), declared[0]), f.return_type)

    def _dimension_of(self, f, args):
        x = args[0]
        if type(x) is not Instance or x.pop is not self.pop:
            return _MISSING
        attribute = _COUNTED.get(x.leaf_types)
        if attribute is None:
            return _MISSING
        raw = x.get(attribute)
        if type(raw) is not list:
            return _MISSING
        declared = [lv.type for lv in f.locals if lv.name == "dim"]
        if len(declared) != 1:
            return _MISSING
        return self._coerce(self._coerce(len(raw), declared[0]), f.return_type)

    def _direction_ratios(self, x):
        """The ratios of a population direction (a plain one, whose ``dim`` is their count)
        when they are 2 or 3 finite reals, else None."""
        if type(x) is not Instance or x.pop is not self.pop or x.leaf_types != _DIRECTION:
            return None
        raw = x.get("direction_ratios")
        if type(raw) is not list or len(raw) not in (2, 3):
            return None
        for r in raw:
            if type(r) is not float or not math.isfinite(r):
                return None
        return raw

    def _check_geometric_dimension(self, f, args):
        capt, dirs, grc = (_plain(a) for a in args)
        functions = self.schema.functions
        in_contexts = functions.get("geometric_dimensionalities_in_contexts")
        using = functions.get("using_representations")
        if (in_contexts is None or using is None
                or any(type(a) is not Agg for a in (capt, dirs, grc))):
            return _MISSING
        globaldim = self._call_algorithm(in_contexts, [grc], None)
        groups = ((capt, "coordinates"), (dirs, "direction_ratios"))
        differs = self._compare
        if differs(">", globaldim, 0) is True:
            for items, attribute in groups:
                for x in items:
                    if differs("<>", self._size_of(x, attribute), globaldim) is True:
                        return False
            return True
        for items, attribute in groups:
            for x in items:
                reps = self._call_algorithm(using, [x], None)
                if type(reps) is not Agg or not reps:
                    return False  # SIZEOF(reps) > 0 is not TRUE: the ELSE branch
                n = self._size_of(x, attribute)
                for rep in reps:
                    dim = self._attr(self._attr(rep, "context_of_items"), "coordinate_space_dimension",
                                     "geometric_representation_context")
                    if differs("<>", n, dim) is True:
                        return False
        return True

    def _size_of(self, x, attribute: str):
        """HIINDEX(x.attribute) for a LIST attribute: the raw list's length when the
        instance's record holds a list there (read without keeping the record), else as
        the interpreter evaluates it."""
        if type(x) is Instance and x.pop is self.pop:
            raw = self.pop.peek(x.id, attribute)
            if type(raw) is list:
                return len(raw)
        return hiindex(self._attr(x, attribute))


def _normalised(ratios):
    """``normalise(d).direction_ratios`` of a direction, in the body's order of operations;
    None where the body returns ``?`` (zero length) or the sum of squares overflows."""
    mag = 0.0
    for r in ratios:
        mag = mag + r * r
    if not mag > 0.0 or not math.isfinite(mag):
        return None
    mag = math.sqrt(mag)
    return [r / mag for r in ratios]


#: function name -> (method, number of parameters)
_NATIVES = {
    "using_representations": (Natives._using_representations, 1),
    "check_geometric_dimension": (Natives._check_geometric_dimension, 3),
    "cross_product": (Natives._cross_product, 2),
    "dimension_of": (Natives._dimension_of, 1),
    "collect_joints": (Natives._collect_joints, 1),
}
