"""An EXPRESS (ISO 10303-11) reader: tokenizer, recursive-descent parser, cache.

``parse_schemas(text)`` turns a whole file into a list of ``Schema`` objects
(see ``model.py``); ``parse_schema`` expects exactly one; ``load_schema(path)``
does the same for a file and keeps a pickled copy of the result in a cache
directory so the next load of the same bytes is fast. The copy keeps the
bodies of rules and algorithms and most of each entity's declarations as
pickles of their own, decoded when first read (``model.DEFERRED_FIELDS``):
a run evaluates a few hundred of the long form's thousands of declarations,
and loading AP242 builds 22,000 objects instead of 260,000.

The grammar followed is the one of ISO 10303-11 (1994 edition plus the
2004 edition's additions: EXTENSIBLE/GENERIC_ENTITY selects, BASED_ON,
ABSTRACT entities, SUBTYPE_CONSTRAINT, RENAMED). A file without a SCHEMA
header (an extracted list of declarations) is read as one anonymous schema.

Operator precedence (highest first), as in ISO 10303-11 clause 12:
  1. qualifiers . \\ [ ] and function calls
  2. ``**``
  3. unary ``+ - NOT``
  4. ``* / DIV MOD AND ||``
  5. ``+ - OR XOR``
  6. ``= <> < > <= >= :=: :<>: IN LIKE`` (not associative)
Following the standard's grammar, a unary operator applies to a primary or
a parenthesised expression (``-a ** 2`` is ``(-a) ** 2``) and ``**`` takes
one right operand (``a ** b ** c`` is a syntax error).

Deliberate leniencies (the standard forbids, real schemas never contain,
and nothing is lost): qualifiers after a parenthesised expression, an
aggregate initialiser or a QUERY; any order of declarations, CONSTANT and
LOCAL blocks in an algorithm head.

The reader is three modules: ``tokenizer.py`` (comments, tokens),
``parser.py`` (tokens -> ``model.py`` objects) and this one (the entry
points and the cache of parsed schemas).
"""

from __future__ import annotations

import copyreg
import gc
import hashlib
import io
import os
import pickle
from pathlib import Path

from p105cli.fileio import atomic_file

from .model import DEFERRED_FIELDS, Schema, SchemaError

__all__ = [
    "ExpressSyntaxError", "PARSER_VERSION", "parse_schemas", "parse_schema", "load_schema",
    "cache_dir", "SchemaError", "BUILTIN_FUNCTIONS", "BUILTIN_PROCEDURES", "strip_comments",
    "tokenize",
]

# Bump whenever the model, the parser's output or the cache's encoding changes: it keys the cache.
PARSER_VERSION = 2

# The reader proper is imported when a schema is parsed, not when a cached one is loaded (every
# command's start-up): its public names are looked up there on first use (PEP 562).
_READER_NAMES = {"BUILTIN_FUNCTIONS": "parser", "BUILTIN_PROCEDURES": "parser",
                 "ExpressSyntaxError": "tokenizer", "strip_comments": "tokenizer",
                 "tokenize": "tokenizer"}


def __getattr__(name: str):
    return reader_name(name, __name__)


def reader_name(name: str, asked_of: str):
    """``name`` of the reader's modules (``_READER_NAMES``), for a module's ``__getattr__``."""
    module = _READER_NAMES.get(name)
    if module is None:
        raise AttributeError(f"module {asked_of!r} has no attribute {name!r}")
    import importlib
    return getattr(importlib.import_module(f"{__package__}.{module}"), name)


def parse_schemas(text: str, filename: str = "<string>") -> list:
    """Every schema of ``text``, in order (see parser.parse_schemas)."""
    from .parser import parse_schemas as parse
    return parse(text, filename)


def parse_schema(text: str, filename: str = "<string>", name: str | None = None) -> Schema:
    """The one schema of ``text`` (or the one called ``name``)."""
    return _pick(parse_schemas(text, filename), name, filename)


def _pick(schemas: list, name, filename) -> Schema:
    if name is not None:
        for s in schemas:
            if s.name == name.lower():
                return s
        raise SchemaError(f"{filename}: no schema {name!r} (found: "
                          f"{', '.join(str(s.name) for s in schemas)})")
    if len(schemas) != 1:
        raise SchemaError(f"{filename}: {len(schemas)} schemas; say which one")
    return schemas[0]


def cache_dir() -> Path:
    """``$P105_CACHE_DIR``, else ``$XDG_CACHE_HOME/p105``, else ``~/.cache/p105``."""
    d = os.environ.get("P105_CACHE_DIR")
    if d:
        return Path(d)
    x = os.environ.get("XDG_CACHE_HOME")
    return Path(x) / "p105" if x else Path.home() / ".cache" / "p105"


# Compiled at install time (`make install` runs `python -m p105cli.schema.compile`),
# so a fresh install starts fast without writing to the user's cache.
COMPILED_DIR = Path(__file__).resolve().parent / "data" / "compiled"


def _cache_path(digest: str, directory: Path | None = None) -> Path:
    return (directory or cache_dir()) / f"express-v{PARSER_VERSION}-{digest}.pickle"


def load_schemas(path, cache: bool = True) -> list:
    """Every schema of the EXPRESS file ``path``, through the cache.

    The cache entry is keyed by the sha256 of the file's bytes and
    PARSER_VERSION, written atomically (temporary file + rename); a missing,
    unreadable or stale entry is silently rebuilt, and an unwritable cache
    directory only costs speed."""
    path = Path(path)
    data = path.read_bytes()
    filename = str(path)
    if cache:
        digest = hashlib.sha256(data).hexdigest()
        cp = _cache_path(digest)
        blob = None
        for candidate in (_cache_path(digest, COMPILED_DIR), cp):
            try:
                with open(candidate, "rb") as f:
                    blob = f.read()
                break
            except OSError:
                continue
        if blob is not None:
            enabled = gc.isenabled()
            gc.disable()
            try:
                obj = pickle.loads(blob)
            except Exception:
                obj = None
            finally:
                if enabled:
                    gc.freeze()  # a schema lives as long as the process: keep it out of collections
                    gc.enable()
            if (isinstance(obj, tuple) and len(obj) == 3 and obj[0] == PARSER_VERSION
                    and obj[1] == digest and isinstance(obj[2], list)):
                for s in obj[2]:
                    s.source = filename
                return obj[2]
    text = data.decode("utf-8", errors="replace")
    enabled = gc.isenabled()
    gc.disable()  # the parser only allocates; the collector would just rescan
    try:
        schemas = parse_schemas(text, filename)
    finally:
        if enabled:
            gc.enable()
    for s in schemas:
        s.source = filename
    if cache:
        _write_cache(cp, (PARSER_VERSION, digest, schemas))
    return schemas


def load_schema(path, name: str | None = None, cache: bool = True) -> Schema:
    """The schema of the EXPRESS file ``path`` (or the one called ``name``);
    see load_schemas for the cache."""
    return _pick(load_schemas(path, cache), name, str(path))


class _DeferringPickler(pickle.Pickler):
    """Pickles a schema with the bodies of its rules and algorithms apart (model.DEFERRED_FIELDS):
    each is a pickle of its own inside the instance's state, decoded when first read. Loading
    a long form then builds its declarations, not the 200,000 nodes of bodies a run mostly
    never evaluates."""

    def reducer_override(self, obj):
        names = DEFERRED_FIELDS.get(type(obj))
        if names is None:
            return NotImplemented
        state = dict(obj.__dict__)
        if "_deferred" not in state:  # else still encoded: kept as it is
            later = {n: state.pop(n) for n in names}
            state["_deferred"] = _encode(later)  # nested bodies deferred in their turn
        return copyreg.__newobj__, (type(obj),), state


def _encode(obj) -> bytes:
    buf = io.BytesIO()
    _DeferringPickler(buf, protocol=pickle.HIGHEST_PROTOCOL).dump(obj)
    return buf.getvalue()


def _write_cache(cp: Path, obj) -> None:
    # An unwritable cache only costs speed: failures are swallowed.
    try:
        blob = _encode(obj)
        cp.parent.mkdir(parents=True, exist_ok=True)
        with atomic_file(cp, binary=True) as f:
            f.write(blob)
    except (OSError, pickle.PicklingError, RecursionError):
        pass


def compile_package_schemas() -> list[Path]:
    """Parse the long forms shipped in the package and store them in COMPILED_DIR."""
    written = []
    for exp in sorted((Path(__file__).resolve().parent / "data").glob("*.exp")):
        data = exp.read_bytes()
        digest = hashlib.sha256(data).hexdigest()
        schemas = parse_schemas(data.decode("utf-8", errors="replace"), str(exp))
        target = _cache_path(digest, COMPILED_DIR)
        _write_cache(target, (PARSER_VERSION, digest, schemas))
        if not target.is_file():
            raise OSError(f"could not write {target}")
        written.append(target)
    for stale in set(COMPILED_DIR.glob("express-v*-*.pickle")) - set(written):
        stale.unlink()  # another parser version's or a replaced long form's: never read again
    return written
