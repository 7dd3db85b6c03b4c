"""Part 21 exchange structures and their JSON model (no CLI code here)."""

from __future__ import annotations

from .errors import ModelError, StepError, StepStructureError, StepSyntaxError
from .jsonmodel import FORMAT, JsonDocument, read_json, write_json
from .reader import DataSection, StepFile, decode_bytes, read_step
from .writer import instance_text, write_step

__all__ = [
    "FORMAT", "DataSection", "JsonDocument", "ModelError", "StepError", "StepFile",
    "StepStructureError", "StepSyntaxError", "decode_bytes", "instance_text", "read_any",
    "read_json", "read_step", "sniff", "write_json", "write_step",
]


def sniff(text: str) -> str:
    """``'p21'`` or ``'json'`` from the first significant characters."""
    head = text.lstrip(" \t\r\n\ufeff")
    if head.startswith("{"):
        return "json"
    if head.startswith("/*") or head[:12].upper() == "ISO-10303-21":
        return "p21"
    return "unknown"


def read_any(text: str, source: str = "<input>"):
    """A StepFile or JsonDocument, whichever the text is."""
    kind = sniff(text)
    if kind == "json":
        return read_json(text, source)
    if kind == "p21":
        return read_step(text, source)
    err = StepSyntaxError("neither a Part 21 file (ISO-10303-21;) nor a p105/1 JSON model", 0, text)
    err.source = source
    raise err
