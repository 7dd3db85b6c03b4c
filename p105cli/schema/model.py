"""The data model of a parsed EXPRESS (ISO 10303-11) schema.

Everything here is a plain dataclass: the parser (``parser.py``) builds
it, the cache pickles it (some fields deferred: ``DEFERRED_FIELDS``), and
later consumers (the evaluator, the Part 21 schema checks) only read it. Every node carries ``line``, the 1-based
source line where it starts, so that messages can point into the schema.

Names (entities, types, attributes, variables, enumeration items) are kept
lower case, as EXPRESS identifiers are case-insensitive. String literals
keep their case.

Expressions
    Literal, Name, SelfRef, BuiltinConstant, UnaryOp, BinaryOp, Interval,
    AttributeRef (``.attr``), GroupRef (``\\entity``), IndexRef (``[i]`` or
    ``[lo:hi]``), Call (function call or entity constructor; ``kind`` says
    which once the schema is known), AggregateInit, Query.

Statements
    NullStmt, Assignment, IfStmt, CaseStmt, RepeatStmt, ReturnStmt,
    EscapeStmt, SkipStmt, CompoundStmt, AliasStmt, ProcedureCall.

Types
    SimpleType, NamedType, AggregateType, GenericType, SelectType,
    EnumerationType.

Declarations
    Constant, TypeDecl, Entity (ExplicitAttribute, DerivedAttribute,
    InverseAttribute, UniqueRule, WhereRule, SupertypeOp), Function,
    Procedure, Rule, SubtypeConstraint, Interface, Schema.
"""

from __future__ import annotations

import pickle
import reprlib
import threading
from dataclasses import MISSING, dataclass, field, fields
from operator import attrgetter
from typing import Any, Optional, Union


class SchemaError(LookupError):
    """A question about the schema that the schema cannot answer
    (unknown entity, a SUBTYPE OF naming an undeclared entity, ...)."""


class _Fields:
    """The ``__init__``, ``==`` and ``repr`` of a dataclass, without compiling three methods
    per class at import: with 51 classes that was most of the import time of this module,
    on every command's start-up, and a loaded schema is unpickled, not constructed. ``==``
    and ``repr`` are shared; a class's ``__init__`` is compiled when it is first called.
    Same results as ``@dataclass(eq=True)`` (``node``)."""

    __slots__ = ()
    _compared = staticmethod(lambda obj: ())  # set by ``node``
    _shown: tuple = ()

    def __init__(self, *args, **kwargs):
        init = _compile_init(type(self))
        init(self, *args, **kwargs)

    def __eq__(self, other):
        if other.__class__ is self.__class__:
            return self._compared(self) == self._compared(other)
        return NotImplemented

    @reprlib.recursive_repr()
    def __repr__(self) -> str:
        return (f"{self.__class__.__qualname__}("
                + ", ".join(f"{n}={getattr(self, n)!r}" for n in self._shown) + ")")


_FACTORY = object()  # the default of a parameter whose field has a default_factory


def _compile_init(cls):
    """The ``__init__`` that ``@dataclass`` writes for ``cls``, set on the class."""
    params, body, env = [], [], {"_FACTORY": _FACTORY}
    for f in fields(cls):
        n = f.name
        if f.default_factory is not MISSING:
            env[f"_factory_{n}"] = f.default_factory
            params.append(f"{n}=_FACTORY")
            body.append(f"self.{n} = _factory_{n}() if {n} is _FACTORY else {n}")
        else:
            if f.default is not MISSING:
                env[f"_default_{n}"] = f.default
            params.append(n if f.default is MISSING else f"{n}=_default_{n}")
            body.append(f"self.{n} = {n}")
    exec(f"def __init__(self, {', '.join(params)}):\n    " + "\n    ".join(body or ["pass"]), env)
    init = env["__init__"]
    init.__qualname__ = f"{cls.__qualname__}.__init__"
    cls.__init__ = init
    return init


def node(cls):
    """``@dataclass(eq=True)`` with ``_Fields``' methods: ``__init__`` compiled on first
    use, ``==`` on the fields with ``compare`` (as a tuple, in order), repr of the fields
    with ``repr``."""
    cls = dataclass(init=False, eq=False, repr=False)(cls)
    names = tuple(f.name for f in fields(cls) if f.compare)
    get = attrgetter(*names) if names else None
    cls._compared = staticmethod(get if len(names) > 1 else   # attrgetter of one name: no tuple
                                 (lambda obj: (get(obj),)) if names else (lambda obj: ()))
    cls._shown = tuple(f.name for f in fields(cls) if f.repr)
    return cls


class Node(_Fields):
    """Base of every AST node; subclasses are dataclasses with ``line``."""

    __slots__ = ()


# --------------------------------------------------------------------------
# expressions


class Expr(Node):
    __slots__ = ()


@node
class Literal(Expr):
    """A literal. ``kind`` is one of ``integer`` (int), ``real`` (float),
    ``string`` (str; simple and encoded strings alike, already decoded),
    ``binary`` (str of '0'/'1' digits), ``logical`` (True, False, or None for
    UNKNOWN) and ``indeterminate`` (``?``; value None)."""

    kind: str
    value: Any
    line: int = 0
    encoded: bool = False  # string given as "..." (encoded) in the source


@node
class Name(Expr):
    """A bare identifier: attribute, variable, parameter, constant,
    enumeration item, or an entity/type name used as a population/type."""

    name: str
    line: int = 0


@node
class SelfRef(Expr):
    line: int = 0


@node
class BuiltinConstant(Expr):
    """``CONST_E`` or ``PI`` (name kept lower case)."""

    name: str
    line: int = 0


@node
class UnaryOp(Expr):
    """``op`` is ``not``, ``-`` or ``+``."""

    op: str
    operand: Expr
    line: int = 0


@node
class BinaryOp(Expr):
    """``op``: ``** * / div mod and || + - or xor = <> < > <= >= :=: :<>: in like``
    (word operators lower case)."""

    op: str
    left: Expr
    right: Expr
    line: int = 0


@node
class Interval(Expr):
    """``{low op1 item op2 high}``, each op ``<`` or ``<=``."""

    low: Expr
    op1: str
    item: Expr
    op2: str
    high: Expr
    line: int = 0


@node
class AttributeRef(Expr):
    """``base.attribute``."""

    base: Expr
    attribute: str
    line: int = 0


@node
class GroupRef(Expr):
    """``base\\entity`` (group qualifier)."""

    base: Expr
    entity: str
    line: int = 0


@node
class IndexRef(Expr):
    """``base[index]``, or ``base[index:upper]`` when ``upper`` is not None."""

    base: Expr
    index: Expr
    upper: Optional[Expr] = None
    line: int = 0


@node
class Call(Expr):
    """``name(args)``: a function call or an entity constructor (same syntax).

    ``kind`` is resolved after the whole file is read: ``builtin`` (an
    EXPRESS built-in function), ``function`` (a declared FUNCTION),
    ``entity`` (an entity constructor) or ``unknown``."""

    name: str
    args: list
    line: int = 0
    kind: str = "unknown"


@node
class AggregateElement(Node):
    """One element of an aggregate initialiser: ``value`` or ``value : repeat``."""

    value: Expr
    repeat: Optional[Expr] = None
    line: int = 0


@node
class AggregateInit(Expr):
    """``[e1, e2 : n, ...]``."""

    elements: list
    line: int = 0


@node
class Query(Expr):
    """``QUERY(variable <* aggregate | condition)``."""

    variable: str
    aggregate: Expr
    condition: Expr
    line: int = 0


# --------------------------------------------------------------------------
# statements


class Stmt(Node):
    __slots__ = ()


@node
class NullStmt(Stmt):
    line: int = 0


@node
class Assignment(Stmt):
    """``target := value;`` (target: Name with qualifiers)."""

    target: Expr
    value: Expr
    line: int = 0


@node
class IfStmt(Stmt):
    condition: Expr
    then_body: list
    else_body: Optional[list] = None  # None: no ELSE part
    line: int = 0


@node
class CaseAction(Node):
    labels: list
    body: Stmt
    line: int = 0


@node
class CaseStmt(Stmt):
    selector: Expr
    actions: list
    otherwise: Optional[Stmt] = None
    line: int = 0


@node
class RepeatStmt(Stmt):
    """REPEAT [variable := start TO end [BY increment]] [WHILE c] [UNTIL c]."""

    variable: Optional[str]
    start: Optional[Expr]
    end: Optional[Expr]
    increment: Optional[Expr]
    while_cond: Optional[Expr]
    until_cond: Optional[Expr]
    body: list
    line: int = 0


@node
class ReturnStmt(Stmt):
    value: Optional[Expr] = None
    line: int = 0


@node
class EscapeStmt(Stmt):
    line: int = 0


@node
class SkipStmt(Stmt):
    line: int = 0


@node
class CompoundStmt(Stmt):
    body: list
    line: int = 0


@node
class AliasStmt(Stmt):
    name: str
    target: Expr
    body: list
    line: int = 0


@node
class ProcedureCall(Stmt):
    """``name(args);`` — ``builtin`` for INSERT/REMOVE."""

    name: str
    args: list
    builtin: bool = False
    line: int = 0


# --------------------------------------------------------------------------
# types


class TypeSpec(Node):
    __slots__ = ()


@node
class SimpleType(TypeSpec):
    """INTEGER, REAL [(precision)], NUMBER, LOGICAL, BOOLEAN,
    STRING [(width) [FIXED]], BINARY [(width) [FIXED]]."""

    name: str
    width: Optional[Expr] = None  # STRING/BINARY width, REAL precision
    fixed: bool = False
    line: int = 0


@node
class NamedType(TypeSpec):
    """A reference to an entity or defined type by name."""

    name: str
    line: int = 0


@node
class AggregateType(TypeSpec):
    """LIST/SET/BAG/ARRAY [lower:upper] OF [OPTIONAL] [UNIQUE] element, or the
    generalised AGGREGATE [:label] OF element. Bounds are expressions (``?``
    is a Literal of kind ``indeterminate``); None when not given."""

    kind: str  # list | set | bag | array | aggregate
    element: TypeSpec
    lower: Optional[Expr] = None
    upper: Optional[Expr] = None
    optional: bool = False  # ARRAY only
    unique: bool = False  # ARRAY, LIST
    label: Optional[str] = None  # AGGREGATE : label
    line: int = 0


@node
class GenericType(TypeSpec):
    """GENERIC [:label] or GENERIC_ENTITY [:label] (kind ``generic`` /
    ``generic_entity``)."""

    kind: str
    label: Optional[str] = None
    line: int = 0


@node
class SelectType(TypeSpec):
    items: list  # names
    extensible: bool = False
    generic_entity: bool = False
    based_on: Optional[str] = None
    line: int = 0


@node
class EnumerationType(TypeSpec):
    items: list  # names (lower case)
    extensible: bool = False
    based_on: Optional[str] = None
    line: int = 0


# --------------------------------------------------------------------------
# declarations


@node
class WhereRule(Node):
    """A domain rule of a WHERE clause; ``label`` is None when unlabelled."""

    label: Optional[str]
    expr: Expr
    line: int = 0


@node
class Constant(Node):
    name: str
    type: TypeSpec
    value: Expr
    line: int = 0


@node
class TypeDecl(Node):
    name: str
    underlying: TypeSpec
    where: list = field(default_factory=list)
    line: int = 0


@node
class ExplicitAttribute(Node):
    """An explicit attribute. For a redeclaration ``SELF\\sup.attr [RENAMED n]``
    ``name`` is ``attr``, ``supertype`` is ``sup`` and ``renamed`` is ``n``."""

    name: str
    type: TypeSpec
    optional: bool = False
    supertype: Optional[str] = None
    renamed: Optional[str] = None
    line: int = 0

    @property
    def redeclared(self) -> bool:
        return self.supertype is not None

    @property
    def local_name(self) -> str:
        return self.renamed or self.name


@node
class DerivedAttribute(Node):
    name: str
    type: TypeSpec
    expr: Expr
    supertype: Optional[str] = None
    renamed: Optional[str] = None
    line: int = 0

    @property
    def redeclared(self) -> bool:
        return self.supertype is not None

    @property
    def local_name(self) -> str:
        return self.renamed or self.name


@node
class InverseAttribute(Node):
    """``name : [SET|BAG [lower:upper] OF] entity FOR [for_entity.]for_attribute``;
    ``aggregate`` is None for a single-valued inverse."""

    name: str
    entity: str
    for_attribute: str
    aggregate: Optional[str] = None
    lower: Optional[Expr] = None
    upper: Optional[Expr] = None
    for_entity: Optional[str] = None
    supertype: Optional[str] = None
    renamed: Optional[str] = None
    line: int = 0

    @property
    def redeclared(self) -> bool:
        return self.supertype is not None

    @property
    def local_name(self) -> str:
        return self.renamed or self.name


@node
class UniqueAttribute(Node):
    """An attribute of a uniqueness rule: ``name`` or ``SELF\\supertype.name``."""

    name: str
    supertype: Optional[str] = None
    line: int = 0


@node
class UniqueRule(Node):
    label: Optional[str]
    attributes: list  # of UniqueAttribute
    line: int = 0


@node
class SupertypeOp(Node):
    """A node of a supertype expression: ``op`` is ``oneof``, ``and`` or
    ``andor``; operands are entity names (str) or nested SupertypeOp."""

    op: str
    operands: list
    line: int = 0


SupertypeExpr = Union[str, SupertypeOp]


@node
class Entity(Node):
    name: str
    supertypes: list = field(default_factory=list)  # SUBTYPE OF (...), in order
    supertype_expr: Optional[SupertypeExpr] = None  # SUPERTYPE OF (...)
    abstract: bool = False  # ABSTRACT [SUPERTYPE]
    attributes: list = field(default_factory=list)  # ExplicitAttribute, declaration order
    derived: list = field(default_factory=list)  # DerivedAttribute
    inverse: list = field(default_factory=list)  # InverseAttribute
    unique: list = field(default_factory=list)  # UniqueRule
    where: list = field(default_factory=list)  # WhereRule
    line: int = 0
    subtypes: list = field(default_factory=list)  # computed: entities naming this one in SUBTYPE OF

    @property
    def abstract_supertype(self) -> bool:  # alias, the 1994 spelling
        return self.abstract

    def where_rule(self, label: str) -> WhereRule:
        label = label.lower()
        for w in self.where:
            if w.label == label:
                return w
        raise SchemaError(f"entity {self.name} has no WHERE rule {label}")


@node
class Parameter(Node):
    name: str
    type: TypeSpec
    var: bool = False  # VAR parameter (procedures)
    line: int = 0


@node
class LocalVariable(Node):
    name: str
    type: TypeSpec
    init: Optional[Expr] = None
    line: int = 0


@node
class Function(Node):
    name: str
    parameters: list
    return_type: TypeSpec
    declarations: list = field(default_factory=list)  # nested FUNCTION/PROCEDURE/ENTITY/TYPE
    constants: list = field(default_factory=list)
    locals: list = field(default_factory=list)
    body: list = field(default_factory=list)
    line: int = 0


@node
class Procedure(Node):
    name: str
    parameters: list
    declarations: list = field(default_factory=list)
    constants: list = field(default_factory=list)
    locals: list = field(default_factory=list)
    body: list = field(default_factory=list)
    line: int = 0


@node
class Rule(Node):
    """A global RULE name FOR (entities); WHERE rules over those populations."""

    name: str
    applies_to: list
    declarations: list = field(default_factory=list)
    constants: list = field(default_factory=list)
    locals: list = field(default_factory=list)
    body: list = field(default_factory=list)
    where: list = field(default_factory=list)
    line: int = 0


@node
class SubtypeConstraint(Node):
    name: str
    entity: str
    abstract: bool = False
    total_over: list = field(default_factory=list)
    expr: Optional[SupertypeExpr] = None
    line: int = 0


@node
class Interface(Node):
    """USE FROM / REFERENCE FROM; ``items`` are (name, alias-or-None)."""

    kind: str  # use | reference
    schema: str
    items: list = field(default_factory=list)
    line: int = 0


@node
class P21Attribute(_Fields):
    """One slot of a Part 21 simple instance (see Schema.p21_attributes).

    ``entity`` is the entity that first declares the attribute; ``type`` and
    ``optional`` are the effective ones after redeclarations; ``derived`` is
    True when the entity or one of its supertypes redeclares the attribute
    in a DERIVE clause (the slot is then written ``*``), and ``derived_in``
    names the entity that does so."""

    name: str
    entity: str
    type: TypeSpec
    optional: bool = False
    derived: bool = False
    derived_in: Optional[str] = None
    renamed: Optional[str] = None

    def __str__(self) -> str:
        return ("*" if self.derived else "") + self.name


# --------------------------------------------------------------------------
# deferred fields


class _Deferred:
    """A field that a cached schema stores encoded and decodes on first access.

    A run evaluates a few hundred of the thousands of rules and algorithms of a
    long form, so the cache (express.py) keeps their bodies as one pickle each, in
    the instance's ``_deferred`` slot; reading any deferred field decodes them all
    into the instance's ``__dict__``, which then shadows this non-data descriptor:
    later reads cost nothing. Objects built by the parser never hold ``_deferred``.
    """

    __slots__ = ("name", "class_value")

    def __init__(self, name: str, class_value):
        self.name = name
        self.class_value = class_value  # the dataclass default it replaces on the class

    def __get__(self, inst, owner=None):
        if inst is None:
            if self.class_value is _NO_DEFAULT:
                raise AttributeError(self.name)
            return self.class_value
        d = inst.__dict__
        with _DECODING:  # one decode per instance, even with threads
            blob = d.get("_deferred")
            if blob is not None:
                d.update(pickle.loads(blob))
                del d["_deferred"]
        try:
            return d[self.name]
        except KeyError:
            raise AttributeError(f"{type(inst).__name__!r} object has no attribute "
                                 f"{self.name!r}") from None


_NO_DEFAULT = object()
_DECODING = threading.Lock()

#: Per class, the fields the schema cache defers (see _Deferred): the bodies of WHERE rules,
#: derivations, functions, procedures and global rules, and the declarations of an entity but
#: its place in the type graph and its derivations (what is read of every entity). A Rule's
#: ``applies_to`` stays at hand (validate picks the rules that apply by it), and so does every
#: name.
DEFERRED_FIELDS = {
    Entity: ("attributes", "inverse", "unique", "where", "supertype_expr", "line"),
    WhereRule: ("expr",),
    DerivedAttribute: ("expr",),
    Function: ("parameters", "return_type", "declarations", "constants", "locals", "body", "line"),
    Procedure: ("parameters", "declarations", "constants", "locals", "body", "line"),
    Rule: ("declarations", "constants", "locals", "body", "where", "line"),
}
for _cls, _names in DEFERRED_FIELDS.items():
    for _name in _names:
        setattr(_cls, _name, _Deferred(_name, _cls.__dict__.get(_name, _NO_DEFAULT)))
del _cls, _names, _name


@node
class Schema(Node):
    """A parsed schema. ``name`` is None for a bare list of declarations
    (a file without SCHEMA ... END_SCHEMA, e.g. an extracted subset)."""

    name: Optional[str]
    version: Optional[str] = None
    interfaces: list = field(default_factory=list)
    constants: dict = field(default_factory=dict)
    types: dict = field(default_factory=dict)
    entities: dict = field(default_factory=dict)
    functions: dict = field(default_factory=dict)
    procedures: dict = field(default_factory=dict)
    rules: dict = field(default_factory=dict)
    subtype_constraints: dict = field(default_factory=dict)
    line: int = 0
    source: Optional[str] = field(default=None, compare=False)
    _memo: dict = field(default_factory=dict, compare=False, repr=False)

    # ---------------------------------------------------------- look-ups
    def __getstate__(self):
        state = dict(self.__dict__)
        state["_memo"] = {}
        return state

    def entity(self, name: str) -> Entity:
        try:
            return self.entities[name.lower()]
        except KeyError:
            raise SchemaError(f"no entity {name!r} in schema {self.name}") from None

    def all_supertypes(self, name: str) -> list:
        """Every supertype of ``name`` once, depth-first in SUBTYPE OF order
        (a supertype's own supertypes come right after it)."""
        key = ("sup", name.lower())
        memo = self._memo
        if key not in memo:
            out: list = []
            seen: set = set()

            def walk(ent: Entity) -> None:
                for s in ent.supertypes:
                    if s in seen:
                        continue
                    seen.add(s)
                    out.append(s)
                    walk(self._sup(ent, s))

            walk(self.entity(name))
            memo[key] = out
        return list(memo[key])

    def all_subtypes(self, name: str) -> list:
        """Every (direct or indirect) subtype of ``name`` once, depth-first."""
        out: list = []
        seen: set = set()

        def walk(ent: Entity) -> None:
            for s in ent.subtypes:
                if s not in seen:
                    seen.add(s)
                    out.append(s)
                    walk(self.entities[s])

        walk(self.entity(name))
        return out

    def is_subtype(self, a: str, b: str, proper: bool = False) -> bool:
        """True when entity ``a`` is ``b`` or one of its (indirect) subtypes;
        with ``proper=True`` ``a == b`` gives False."""
        a, b = a.lower(), b.lower()
        self.entity(a)
        self.entity(b)
        if a == b:
            return not proper
        return b in self.all_supertypes(a)

    def _sup(self, ent: Entity, s: str) -> Entity:
        try:
            return self.entities[s]
        except KeyError:
            raise SchemaError(f"entity {ent.name} (line {ent.line}) is a SUBTYPE OF "
                              f"undeclared entity {s!r}") from None

    def resolve_attribute(self, entity: str, attr: str):
        """The (declaring entity, declaration) of the attribute ``attr`` as
        seen from ``entity``: follows ``SELF\\x.attr`` redeclarations back
        to the original declaration. Returns None when not found."""
        ent = self.entity(entity)
        attr = attr.lower()
        for a in (*ent.attributes, *ent.derived, *ent.inverse):
            if a.supertype is None and a.name == attr:
                return ent.name, a
        for a in (*ent.attributes, *ent.derived, *ent.inverse):
            if a.supertype is not None and a.local_name == attr:
                return self.resolve_attribute(a.supertype, a.name)
        for s in ent.supertypes:
            r = self.resolve_attribute(self._sup(ent, s).name, attr)
            if r is not None:
                return r
        return None

    def most_specific_first(self, types) -> list:
        """The entity names among ``types`` known to this schema, subtypes before their
        supertypes (more supertypes first; ties by name), the order in which the
        first redeclaration met is the one that applies."""
        return sorted((t for t in types if t in self.entities),
                      key=lambda t: (-len(self.all_supertypes(t)), t))

    def redeclarations(self, entities) -> tuple[dict, dict, dict]:
        """Redeclarations (``SELF\\super.attr``) made by ``entities``, most specific first.

        Keys are ``(declaring entity, attribute name)`` of the original
        attribute; the first entity to redeclare it wins. Returns
        ``(retyped: key -> ExplicitAttribute, derived_in: key -> entity name,
        renamed: key -> new name)``.
        """
        retyped: dict = {}
        derived_in: dict = {}
        renamed: dict = {}
        for en in entities:
            e = self.entities[en]
            for a in e.attributes:
                if a.supertype is not None:
                    r = self.resolve_attribute(a.supertype, a.name)
                    if r is not None:
                        k = (r[0], r[1].name)
                        retyped.setdefault(k, a)
                        if a.renamed:
                            renamed.setdefault(k, a.renamed)
            for a in e.derived:
                if a.supertype is not None:
                    r = self.resolve_attribute(a.supertype, a.name)
                    if r is not None:
                        k = (r[0], r[1].name)
                        derived_in.setdefault(k, en)
                        if a.renamed:
                            renamed.setdefault(k, a.renamed)
        return retyped, derived_in, renamed

    def p21_attributes(self, name: str) -> list:
        """The ordered slots of a Part 21 simple instance of entity ``name``.

        Supertypes' explicit attributes come first (depth-first in SUBTYPE
        OF order, each supertype once), then the entity's own explicit
        attributes in declaration order. Redeclarations ``SELF\\x.a`` do not
        add slots; they change the type of the original slot, and a DERIVE
        redeclaration in the entity or one of its supertypes marks the slot
        ``derived`` (encoded ``*`` in Part 21)."""
        key = ("p21", name.lower())
        memo = self._memo
        if key not in memo:
            memo[key] = self._p21(name.lower())
        return [P21Attribute(a.name, a.entity, a.type, a.optional, a.derived, a.derived_in,
                             a.renamed) for a in memo[key]]

    def _p21(self, name: str) -> list:
        ent = self.entity(name)
        chain = [name, *self.all_supertypes(name)]
        # order: supertypes first (depth-first), then own
        order: list = []
        seen: set = set()

        def walk(e: Entity) -> None:
            for s in e.supertypes:
                if s not in seen:
                    seen.add(s)
                    walk(self._sup(e, s))
            for a in e.attributes:
                if a.supertype is None:
                    order.append((e.name, a))

        walk(ent)
        # redeclarations visible from `name`: the most specific one wins
        # (chain lists the entity first, then supertypes depth-first, so an
        # entity is always met before its own supertypes)
        retyped, derived_in, renamed = self.redeclarations(chain)
        out = []
        for owner, a in order:
            k = (owner, a.name)
            eff = retyped.get(k, a)
            d = derived_in.get(k)
            out.append(P21Attribute(a.name, owner, eff.type, eff.optional, d is not None, d,
                                    renamed.get(k)))
        return out

    def explicit_attribute_names(self, name: str) -> list:
        """Convenience: names of p21_attributes, derived slots prefixed ``*``."""
        return [str(a) for a in self.p21_attributes(name)]
