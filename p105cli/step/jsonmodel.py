"""The JSON model ``p105/1``: a lossless image of a Part 21 exchange structure.

Two forms carry the same content:

* the document, one JSON object::

    {"format":"p105/1","header":{...},"data":[
    {"id":1,"type":"cartesian_point","args":["",[0.0,0.0,0.0]]},
    ...
    ]}

  written with one instance per line so that ``grep`` and ``diff`` work;

* the stream (JSON Lines), for files too big for one document: a first
  record ``{"format":"p105/1","stream":true,"header":{...}}`` and then one
  instance record per line.

The value mapping lives in ``lexer.py`` (reading) and ``writer.py``
(writing); ``check_value`` here is its inverse check for JSON coming from
outside. docs/json-model.md is the prose version; the JSON Schema shipped
in ``p105cli/schemas/p105-1.schema.json`` is the machine-checked one.
"""

from __future__ import annotations

import json
import math
import re
from itertools import islice
from dataclasses import dataclass, field

from .errors import ModelError
from .index import MAX_INSTANCE_ID
from .lexer import MAX_NESTING
from .reader import DataSection

FORMAT = "p105/1"

_ENCODER = json.JSONEncoder(ensure_ascii=False, separators=(",", ":"),
                            check_circular=False, allow_nan=False)
dumps = _ENCODER.encode

_KEYWORD = re.compile(r"!?[A-Za-z_][A-Za-z0-9_]*\Z")
_ENUM = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_BINARY = re.compile(r"[0-3][0-9A-F]*\Z")
_SURROGATE = re.compile("[\ud800-\udfff]")


@dataclass
class JsonDocument:
    """A model read from JSON: everything decoded, records in a list."""

    header: dict
    sections: list[DataSection]
    data: list[dict]
    other_sections: list[dict] = field(default_factory=list)
    source: str = "<input>"
    #: A p105-scene/1 block (gravity, cables, effects) carried with the model; not Part 21 data.
    scene: dict | None = None

    def records(self):
        return iter(self.data)

    def __len__(self) -> int:
        return len(self.data)


def extended(doc, data: list, added: list) -> JsonDocument:
    """A new document: ``doc``'s header and other sections, the records ``data``
    (``doc``'s own, as read) followed by ``added``, which join the last DATA
    section (or a new one)."""
    sections = list(doc.sections)
    if sections:
        last = sections[-1]
        sections[-1] = DataSection(last.parameters, last.count + len(added))
    else:
        sections = [DataSection(None, len(added))]
    return JsonDocument(header=doc.header, sections=sections, data=data + added,
                        other_sections=list(getattr(doc, "other_sections", []) or []),
                        source=getattr(doc, "source", "<input>"), scene=getattr(doc, "scene", None))


# ---------------------------------------------------------------- writing

def _frame(doc) -> dict:
    """Everything but the instances, in the fixed key order of the format."""
    frame = {"format": FORMAT, "header": doc.header}
    sections = doc.sections
    if len(sections) != 1 or sections[0].parameters is not None:
        frame["data_sections"] = [{"parameters": s.parameters, "count": s.count} for s in sections]
    if doc.other_sections:
        frame["other_sections"] = list(doc.other_sections)
    scene = getattr(doc, "scene", None)
    if scene is not None:
        frame["scene"] = scene
    return frame


def write_json(doc, fh, stream: bool = False) -> None:
    """Write ``doc`` as a p105/1 document (or stream) to a text stream."""
    frame = _frame(doc)
    write = fh.write
    if stream:
        frame = {"format": FORMAT, "stream": True, **{k: v for k, v in frame.items() if k != "format"}}
        write(dumps(frame))
        write("\n")
        for batch in _batches(doc.records()):
            text = _encode_batch(batch, "\n")
            if text is not None:
                write(text)
                write("\n")
                continue
            for record in batch:
                write(dumps(record))
                write("\n")
        return
    text = dumps(frame)
    write(text[:-1])
    write(',\n"data":[')
    sep = "\n"
    for batch in _batches(doc.records()):
        text = _encode_batch(batch, ",\n")
        if text is not None:
            write(sep)
            write(text)
            sep = ",\n"
            continue
        for record in batch:
            write(sep)
            write(dumps(record))
            sep = ",\n"
    write("\n]}\n")


# Records encoded per call of the encoder (one C call instead of one per record).
_BATCH = 4096
_BOUNDARY = '},{"id":'


def _batches(records):
    """Lists of up to _BATCH records; if the records fail, those before come first."""
    it = iter(records)
    while True:
        batch: list = []
        try:
            batch.extend(islice(it, _BATCH))
        except BaseException:
            if batch:
                yield batch
            raise
        if not batch:
            return
        yield batch
        if len(batch) < _BATCH:
            return


def _encode_batch(batch: list, sep: str) -> str | None:
    """``sep.join(map(dumps, batch))`` in one call of the encoder, or None.

    The encoder writes a list of records as ``[r1,r2,...]``. When every
    record is a dict whose first key is "id", each boundary between two of
    them reads ``},{"id":``; if that string occurs exactly once per
    boundary, putting ``sep`` into each gives exactly the per-record texts.
    None when that does not hold or the encoder fails (the caller then
    encodes record by record, so errors come as before).
    """
    if set(map(type, batch)) != {dict} or list(map(next, map(iter, batch))).count("id") != len(batch):
        return None
    try:
        text = dumps(batch)
    except Exception:
        return None
    if text.count(_BOUNDARY) != len(batch) - 1:
        return None
    return text[1:-1].replace(_BOUNDARY, "}" + sep + '{"id":')


# ---------------------------------------------------------------- reading

def check_value(value, where: str) -> None:
    """Raise ModelError unless ``value`` is a valid p105/1 parameter value."""
    stack = [(value, where, 0)]
    while stack:
        v, path, depth = stack.pop()
        t = type(v)
        if t is str:
            if _SURROGATE.search(v):
                raise ModelError("string holds an unpaired surrogate", path)
        elif t is int or v is None:
            pass
        elif t is float:
            if not math.isfinite(v):
                raise ModelError("real is not finite", path)
        elif t is list:
            if depth >= MAX_NESTING:
                raise ModelError(f"lists nested deeper than {MAX_NESTING} levels", path)
            stack.extend((item, f"{path}/{i}", depth + 1) for i, item in enumerate(v))
        elif t is dict:
            keys = set(v)
            if keys == {"ref"}:
                if type(v["ref"]) is not int or v["ref"] < 0:
                    raise ModelError("reference must be a non-negative integer", path)
            elif keys == {"enum"}:
                if type(v["enum"]) is not str or not _ENUM.match(v["enum"]):
                    raise ModelError("enumeration must be a name", path)
            elif keys == {"derived"}:
                if v["derived"] is not True:
                    raise ModelError('derived marker must be {"derived": true}', path)
            elif keys == {"binary"}:
                if type(v["binary"]) is not str or not _BINARY.match(v["binary"]):
                    raise ModelError("binary must be a digit 0-3 then upper-case hex digits", path)
            elif keys == {"type", "value"}:
                if type(v["type"]) is not str or not _KEYWORD.match(v["type"]):
                    raise ModelError("typed parameter needs a type name", path)
                # Typed parameters nest like lists in the Part 21 grammar, so they count too.
                if depth >= MAX_NESTING:
                    raise ModelError(f"values nested deeper than {MAX_NESTING} levels", path)
                stack.append((v["value"], f"{path}/value", depth + 1))
            else:
                raise ModelError(f"unknown value object with keys {sorted(keys)}", path)
        else:
            raise ModelError(f"{t.__name__} is not a p105/1 value (booleans are enumerations: {{\"enum\": \"T\"}})", path)


def check_record(record, where: str) -> dict:
    if type(record) is not dict:
        raise ModelError("instance record must be an object", where)
    iid = record.get("id")
    if type(iid) is not int or iid < 0:
        raise ModelError("instance record needs a non-negative integer id", where)
    if iid > MAX_INSTANCE_ID:  # as a Part 21 instance name: the indexes hold 64-bit ids
        raise ModelError(f"instance id {iid} is too large (at most {MAX_INSTANCE_ID})", where)
    if "complex" in record:
        if set(record) != {"id", "complex"}:
            raise ModelError("complex instance takes only id and complex", where)
        parts = record["complex"]
        if type(parts) is not list or not parts:
            raise ModelError("complex must be a non-empty list", where)
        for j, part in enumerate(parts):
            if type(part) is not dict or set(part) != {"type", "args"}:
                raise ModelError("complex part needs type and args", f"{where}/complex/{j}")
            _check_typed(part, f"{where}/complex/{j}")
    else:
        if set(record) != {"id", "type", "args"}:
            raise ModelError("instance record takes id, type and args (or id and complex)", where)
        _check_typed(record, where)
    return record


def _check_typed(part: dict, where: str) -> None:
    if type(part["type"]) is not str or not _KEYWORD.match(part["type"]):
        raise ModelError("type must be an entity name", f"{where}/type")
    if type(part["args"]) is not list:
        raise ModelError("args must be a list", f"{where}/args")
    check_value(part["args"], f"{where}/args")


def _check_header(header, where: str = "/header") -> dict:
    if type(header) is not dict:
        raise ModelError("header must be an object", where)
    from .reader import HEADER_FIELDS
    for name, fields in HEADER_FIELDS.items():
        if name in header:
            entry = header[name]
            if type(entry) is not dict or set(entry) != set(fields):
                raise ModelError(f"{name} needs exactly the fields {', '.join(fields)}", f"{where}/{name}")
            check_value(list(entry.values()), f"{where}/{name}")
    if "file_schema" in header:
        fs = header["file_schema"]
        if type(fs) is not list or not all(type(s) is str for s in fs):
            raise ModelError("file_schema must be a list of strings", f"{where}/file_schema")
        check_value(fs, f"{where}/file_schema")
    other = header.get("other", [])
    if type(other) is not list:
        raise ModelError("other must be a list of header entities", f"{where}/other")
    for i, entry in enumerate(other):
        if type(entry) is not dict or set(entry) != {"type", "args"}:
            raise ModelError("header entity needs type and args", f"{where}/other/{i}")
        _check_typed(entry, f"{where}/other/{i}")
    extra = set(header) - set(HEADER_FIELDS) - {"file_schema", "other"}
    if extra:
        raise ModelError(f"unknown header key {sorted(extra)[0]!r}", where)
    return header


def _check_frame(frame: dict, count: int) -> tuple[dict, list[DataSection], list[dict], dict | None]:
    if frame.get("format") != FORMAT:
        raise ModelError(f"not a {FORMAT} model (format is {frame.get('format')!r})", "/format")
    header = _check_header(frame.get("header", {}))
    raw_sections = frame.get("data_sections")
    if raw_sections is None:
        sections = [DataSection(None, count)]
    else:
        if type(raw_sections) is not list or not raw_sections:
            raise ModelError("data_sections must be a non-empty list", "/data_sections")
        sections = []
        for i, s in enumerate(raw_sections):
            if (type(s) is not dict or set(s) != {"parameters", "count"} or type(s["count"]) is not int
                    or s["count"] < 0 or not (s["parameters"] is None or type(s["parameters"]) is list)):
                raise ModelError("data section needs parameters (list or null) and count", f"/data_sections/{i}")
            if s["parameters"] is not None:
                check_value(s["parameters"], f"/data_sections/{i}/parameters")
            sections.append(DataSection(s["parameters"], s["count"]))
        if sum(s.count for s in sections) != count:
            raise ModelError(f"data_sections count {sum(s.count for s in sections)} instances, data has {count}",
                             "/data_sections")
    other = frame.get("other_sections", [])
    if type(other) is not list:
        raise ModelError("other_sections must be a list", "/other_sections")
    for i, s in enumerate(other):
        if (type(s) is not dict or set(s) != {"keyword", "after_data", "text"}
                or s["keyword"] not in ("ANCHOR", "REFERENCE", "SIGNATURE")
                or type(s["after_data"]) is not int or type(s["text"]) is not str):
            raise ModelError("other section needs keyword, after_data and text", f"/other_sections/{i}")
        if not 0 <= s["after_data"] <= len(sections):
            raise ModelError(f"after_data must be between 0 and {len(sections)}", f"/other_sections/{i}")
        check_value(s["text"], f"/other_sections/{i}/text")
    scene = frame.get("scene")
    if scene is not None and type(scene) is not dict:
        raise ModelError("scene must be an object (a p105-scene/1 block)", "/scene")
    known = {"format", "stream", "header", "data", "data_sections", "other_sections", "scene"}
    extra = set(frame) - known
    if extra:
        raise ModelError(f"unknown top-level key {sorted(extra)[0]!r}", "/")
    return header, sections, other, scene


def _check_ids(data: list[dict]) -> None:
    seen = set()
    for i, record in enumerate(data):
        iid = record["id"]
        if iid in seen:
            raise ModelError(f"instance name #{iid} used more than once", f"/data/{i}")
        seen.add(iid)


def read_json(text: str, source: str = "<input>") -> JsonDocument:
    """Read a p105/1 document or stream, checking it fully."""
    try:
        return _read_json(text, source)
    except ModelError as err:
        err.source = source
        raise


def _loads(text: str, line_offset: int = 0):
    try:
        return json.loads(text)
    except RecursionError:
        raise ModelError("JSON nested too deeply") from None
    except ValueError as err:
        lineno = getattr(err, "lineno", 0) + line_offset
        col = getattr(err, "colno", 0)
        msg = getattr(err, "msg", str(err))
        raise ModelError(f"invalid JSON: {msg}", f"{lineno}:{col}") from None


def _read_json(text: str, source: str) -> JsonDocument:
    first, _, rest = text.partition("\n")
    frame = None
    if first.strip().startswith("{"):
        try:
            candidate = json.loads(first)
        except ValueError:
            candidate = None
        if type(candidate) is dict and candidate.get("stream") is True:
            frame = candidate
    if frame is not None:
        data = []
        for n, line in enumerate(rest.split("\n"), start=2):
            if line.strip():
                data.append(check_record(_loads(line, n - 1), f"line {n}"))
    else:
        frame = _loads(text)
        if type(frame) is not dict:
            raise ModelError("a p105/1 model is a JSON object", "/")
        data = frame.get("data")
        if type(data) is not list:
            raise ModelError("data must be a list of instance records", "/data")
        for i, record in enumerate(data):
            check_record(record, f"/data/{i}")
    header, sections, other, scene = _check_frame(frame, len(data))
    _check_ids(data)
    return JsonDocument(header, sections, data, other, source, scene)
