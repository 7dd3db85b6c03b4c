"""The EXPRESS data model (p105cli.schema.model): its nodes compare and print exactly as
the standard library's ``@dataclass(eq=True)`` would make them (model.node shares one
``==`` and one ``repr`` among all classes instead of compiling two per class)."""

from __future__ import annotations

import dataclasses
import inspect

import pytest

from p105cli.schema import model as M

CLASSES = [c for _, c in inspect.getmembers(M, inspect.isclass)
           if c.__module__ == M.__name__ and dataclasses.is_dataclass(c)]


def _twin(cls):
    """The same class declared with the standard library's @dataclass(eq=True)."""
    specs = []
    for f in dataclasses.fields(cls):
        kw = {"compare": f.compare, "repr": f.repr}
        if f.default is not dataclasses.MISSING:
            kw["default"] = f.default
        if f.default_factory is not dataclasses.MISSING:
            kw["default_factory"] = f.default_factory
        specs.append((f.name, f.type, dataclasses.field(**kw)))
    return dataclasses.make_dataclass(cls.__qualname__, specs, eq=True)


def _values(cls, tag: str) -> dict:
    # One distinct value per field, of several kinds (a node, a list, a float, a string).
    out = {}
    for k, f in enumerate(dataclasses.fields(cls)):
        kind = k % 4
        out[f.name] = (M.Name(f"{tag}{k}", k) if kind == 0 else [tag, k] if kind == 1
                       else float(k) + 0.5 if kind == 2 else f"{tag}-{f.name}")
    return out


def test_every_dataclass_of_the_model_is_covered():
    assert len(CLASSES) >= 50
    assert {"Entity", "Schema", "P21Attribute", "WhereRule", "Function"} <= {c.__name__ for c in CLASSES}


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_equality_and_repr_are_those_of_dataclasses(cls):
    twin = _twin(cls)
    base = _values(cls, "a")
    x, rx = cls(**base), twin(**base)
    assert repr(x) == repr(rx)
    assert (x == cls(**base)) is (rx == twin(**base)) is True
    for name in base:  # one field changed at a time: unequal exactly when the field is compared
        changed = {**base, name: _values(cls, "b")[name]}
        assert (x == cls(**changed)) is (rx == twin(**changed)), name
        assert (x != cls(**changed)) is (rx != twin(**changed)), name
    nan = float("nan")  # the same object compares equal inside the tuple, as in a dataclass
    first = next(iter(base))
    assert (cls(**{**base, first: nan}) == cls(**{**base, first: nan})) is (
        twin(**{**base, first: nan}) == twin(**{**base, first: nan}))
    assert (x == 1) is False and (x != "x") is True and x.__eq__(rx) is NotImplemented
    with pytest.raises(TypeError):
        hash(x)


@pytest.mark.parametrize("cls", CLASSES, ids=lambda c: c.__name__)
def test_construction_is_that_of_dataclasses(cls):
    twin = _twin(cls)
    base = _values(cls, "a")
    names = list(base)
    assert vars(cls(*base.values())) == vars(twin(*base.values())) == vars(cls(**base))
    required = [f.name for f in dataclasses.fields(cls)
                if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
    assert names[:len(required)] == required  # the parameters are the fields, in order
    only = {n: base[n] for n in required}
    x, rx = cls(**only), twin(**only)
    assert vars(x) == vars(rx)  # defaults, and a fresh object from each default_factory
    for f in dataclasses.fields(cls):
        if f.default_factory is not dataclasses.MISSING:
            assert getattr(x, f.name) == f.default_factory()
            assert getattr(x, f.name) is not getattr(cls(**only), f.name)
    with pytest.raises(TypeError):
        cls(*base.values(), "one too many")
    with pytest.raises(TypeError):
        cls(**base, no_such_field=1)
    if required:
        with pytest.raises(TypeError):
            cls(**{n: base[n] for n in required[1:]})
    sig, ref = inspect.signature(cls), inspect.signature(twin)
    assert [(p.name, p.kind) for p in sig.parameters.values()] == [
        (p.name, p.kind) for p in ref.parameters.values()]


def test_defaults_and_class_attributes_are_kept():
    e = M.Entity("e")
    assert e.supertypes == [] and e.supertypes is not M.Entity("f").supertypes
    assert (M.Literal.line, M.Function.line, M.WhereRule.line) == (0, 0, 0)
    with pytest.raises(AttributeError):
        M.Function.body  # noqa: B018 - a field without a default has no class attribute
    s = M.Schema("s")
    assert s == M.Schema("s", source="elsewhere")  # source and the memo are not compared
    assert "_memo" not in repr(s) and "source=None" in repr(s)


def test_recursive_repr_does_not_loop():
    a = M.AggregateInit([])
    a.elements.append(a)
    assert repr(a) == "AggregateInit(elements=[...], line=0)"
