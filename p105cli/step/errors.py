"""Errors raised while reading or writing exchange structures.

They carry a location (character offset, or instance id) rather than a
formatted message, so each front end can say where the problem is in the
way its users expect: ``FILE:LINE:COL: message`` for text positions and
``FILE: #id: message`` for instances.
"""

from __future__ import annotations


class StepError(Exception):
    """Base class: the input is not a readable exchange structure."""

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message
        self.source = "<input>"

    def locate(self) -> str:
        return ""

    def __str__(self) -> str:
        where = self.locate()
        return f"{self.source}:{where}: {self.message}" if where else f"{self.source}: {self.message}"


class StepSyntaxError(StepError):
    """A lexical or grammatical error at a character offset of the text."""

    def __init__(self, message: str, offset: int, text: str | None = None):
        super().__init__(message)
        self.offset = offset
        self.line = self.column = 0
        if text is not None:
            self.attach_text(text)

    def attach_text(self, text: str) -> None:
        off = max(0, min(self.offset, len(text)))
        self.line = text.count("\n", 0, off) + 1
        self.column = off - (text.rfind("\n", 0, off) + 1) + 1

    def locate(self) -> str:
        return f"{self.line}:{self.column}" if self.line else ""


class StepStructureError(StepError):
    """A structural error tied to an entity instance (duplicate id, ...)."""

    def __init__(self, message: str, instance_id: int | None = None):
        super().__init__(message)
        self.instance_id = instance_id

    def locate(self) -> str:
        return f"#{self.instance_id}" if self.instance_id is not None else ""

    def __str__(self) -> str:
        where = self.locate()
        return f"{self.source}: {where}: {self.message}" if where else f"{self.source}: {self.message}"


class ModelError(StepError):
    """A JSON model that does not follow the p105/1 format."""

    def __init__(self, message: str, pointer: str = ""):
        super().__init__(message)
        self.pointer = pointer

    def locate(self) -> str:
        return self.pointer
