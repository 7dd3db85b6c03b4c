"""An evaluator of EXPRESS (ISO 10303-11) expressions and algorithms over a Population.

It runs the ASTs of ``model.py`` -- WHERE and UNIQUE rules, DERIVE and
INVERSE attributes, function and procedure bodies, global RULEs -- against
the instances of a ``Population``.

Values
    ``int``, ``float``, ``str``; ``True``/``False``/``None`` for the LOGICAL
    values TRUE/FALSE/UNKNOWN; ``INDETERMINATE`` for ``?``; ``Agg`` (a list
    with the aggregate kind, lower index and defined type names) for
    aggregates; ``Instance`` for instances of the population and
    ``EntityValue`` for entity values built in memory by entity constructors
    and ``||``; ``EnumValue`` for enumeration items; ``TypedValue`` for a
    simple value of a defined type (so that TYPEOF knows the type);
    ``BinaryValue`` for BINARY.

Semantics followed (ISO 10303-11, 1994 with the 2004 additions)
    * ``?`` propagates: arithmetic, string and aggregate operators, indexing
      and attribute references on ``?`` give ``?``; comparisons, IN and
      instance comparisons with a ``?`` operand give UNKNOWN; the logical
      operators treat ``?`` as UNKNOWN (Kleene three-valued logic). EXISTS
      and NVL test for ``?``; TYPEOF(?) is the empty set; SIZEOF, HIINDEX,
      ... of ``?`` are ``?``. An index out of bounds gives ``?``.
    * IF, WHILE and QUERY conditions select only on TRUE; UNTIL stops on TRUE.
      A REPEAT whose bounds or increment are ``?`` is not executed.
    * IN, set union/difference/intersection and UNIQUE use instance
      equality (``:=:``); ``=`` is value equality (entity instances are
      compared attribute by attribute), as are VALUE_IN and VALUE_UNIQUE.
    * An entity constructor ``e(args)`` builds a partial entity value with
      the attributes declared in ``e`` itself; ``||`` joins partial values
      into a complex one (``dummy_gri || direction(...)``).
    * TYPEOF gives upper-case ``'SCHEMA.NAME'`` strings for every entity
      type, defined type and SELECT type the value belongs to (SELECTs
      transitively), plus the unqualified simple and aggregation type names.
    * Assigning to a variable, binding a parameter and returning from a
      function coerce aggregates to the declared kind (a SET drops instance
      duplicates, an ARRAY takes its declared lower index) and wrap simple
      values of defined types. Aggregates are values: assignment copies.
    * ``ATAN(v1, v2)`` is ``atan(v1/v2)`` in [-pi/2, pi/2] (the schemas fix
      the quadrant themselves); DIV and MOD are Python's floor division and
      modulo (``a = (a DIV b) * b + a MOD b``).

Results of rules: ``True``, ``False`` or ``None`` (UNKNOWN or ``?``, which
does not violate a rule). A construct that cannot be evaluated raises
``NotEvaluable(reason)``.

The package splits the evaluator along its seams: ``values`` (the value
types), ``scope`` (scopes, control-flow signals, limits), ``schema_types``
(type descriptions, raw -> value conversion, TYPEOF), ``attributes``,
``expressions``, ``operators`` (comparisons and arithmetic),
``algorithms`` (calls and statements), ``builtins`` (the built-in
functions) and ``core`` (the ``Evaluator`` and its entry points). The
population is given to ``Evaluator``; ``population.py`` does not know the
evaluator.

A science module: no click, rich or numpy here.
"""

from .core import Evaluator
from .scope import MAX_CALL_DEPTH, MAX_STEPS
from .values import (
    INDETERMINATE, Agg, BinaryValue, EntityValue, EnumValue, NotEvaluable, TypedValue, TypeRef,
)

__all__ = ["Evaluator", "NotEvaluable", "INDETERMINATE", "Agg", "EntityValue", "EnumValue",
           "TypedValue", "BinaryValue", "TypeRef", "MAX_CALL_DEPTH", "MAX_STEPS"]
