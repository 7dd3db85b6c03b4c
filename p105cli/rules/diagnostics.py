"""The diagnostics model of ``p105 validate``: findings, their order, selection and exit codes.

A :class:`Diagnostic` is one finding of one rule against one file, optionally pinned
to a position (1-based line and column) and to an entity instance (``#id`` and its
type). Rule ids look like ``P21-SYNTAX`` (exchange structure), ``SCH-ARITY`` and
``SCH-kinematic_joint.wr1`` (EXPRESS schema checks, where rules named
``SCH-<entity>.<label>``), ``KIN-UNITS`` (kinematics consistency); the note
``SCH-NOT-EVALUATED`` records a schema rule that p105 could not evaluate, so a
report always states its coverage.

Severities rank ``note < warning < error``. ``--fail-on LEVEL`` makes the run fail
(exit 1) when any diagnostic reaches LEVEL; a file that cannot be read at all exits 2.

Nothing here depends on the command line: the CLI maps its options onto
:func:`parse_patterns`, :func:`select_rules`, :func:`worst_exit` and :func:`exit_code`.
"""

from __future__ import annotations

import enum
import fnmatch
import hashlib
import operator
import re
from dataclasses import dataclass, field
from typing import Iterable, Sequence

__all__ = [
    "Severity", "SEVERITIES", "Diagnostic", "Summary", "RunResult",
    "NOT_EVALUATED", "parse_patterns", "rule_matches", "rule_selected", "select_rules",
    "worst_exit", "exit_code", "register_rule", "rule_description",
]

#: The rule id of the note that records an EXPRESS rule p105 did not evaluate.
NOT_EVALUATED = "SCH-NOT-EVALUATED"


class Severity(enum.IntEnum):
    """Severity levels, ranked so that a larger value is more severe."""

    NOTE = 1
    WARNING = 2
    ERROR = 3

    @property
    def label(self) -> str:
        """The lower-case name used in every report format: ``error``, ``warning``, ``note``."""
        return self.name.lower()

    @classmethod
    def parse(cls, value: "str | Severity") -> "Severity":
        """``"error"``/``"warning"``/``"note"`` (any case) or a Severity; ValueError otherwise."""
        if isinstance(value, Severity):
            return value
        try:
            return cls[str(value).strip().upper()]
        except KeyError:
            raise ValueError(f"unknown severity {value!r} (expected one of: "
                             f"{', '.join(SEVERITIES)})") from None


#: Severity labels from the most to the least severe (the order of report counts).
SEVERITIES: tuple[str, ...] = ("error", "warning", "note")

_NO_SPACE = re.compile(r"^[^\s,]+$")


def _basename(path: str) -> str:
    """The last component of ``path``, for POSIX and Windows separators alike."""
    return path.replace("\\", "/").rstrip("/").rsplit("/", 1)[-1] or path


@dataclass(frozen=True)
class Diagnostic:
    """One finding. ``severity`` is stored as its label (``"error"``, ``"warning"``, ``"note"``).

    ``line`` and ``column`` are 1-based and ``None`` when unknown; ``entity`` is the
    instance id (the ``12`` of ``#12``) and ``entity_type`` its upper-case type name.
    Instances sort by (file, line, column, rule, entity), unknown positions first,
    then by the remaining fields, so every sort of the same findings is identical.
    """

    rule: str
    severity: str
    message: str
    file: str
    line: int | None = None
    column: int | None = None
    entity: int | None = None
    entity_type: str | None = None

    def __post_init__(self):
        if not isinstance(self.rule, str) or not _NO_SPACE.match(self.rule):
            raise ValueError(f"rule id must be a non-empty string without spaces or commas: "
                             f"{self.rule!r}")
        object.__setattr__(self, "severity", Severity.parse(self.severity).label)
        for name in ("line", "column", "entity"):
            v = getattr(self, name)
            if v is None or type(v) is int:
                continue
            if isinstance(v, bool):
                raise TypeError(f"Diagnostic.{name} must be an int or None, not {v!r}")
            try:  # numpy integers and the like
                object.__setattr__(self, name, int(operator.index(v)))
            except TypeError:
                raise TypeError(f"Diagnostic.{name} must be an int or None, not {v!r}") from None

    @property
    def rank(self) -> Severity:
        """The severity as a :class:`Severity` (comparable)."""
        return Severity[self.severity.upper()]

    @property
    def fingerprint(self) -> str:
        """A stable identity of the finding that survives edits elsewhere in the file.

        The first 16 hex digits of the SHA-256 of the UTF-8 text
        ``rule NUL basename(file) NUL entity NUL entity_type NUL message``
        (``entity``/``entity_type`` empty when unknown). Line and column are left out
        on purpose, and so is the directory, so a finding keeps its fingerprint when
        lines are inserted above it or the file is checked from another directory.
        """
        parts = (self.rule, _basename(self.file),
                 "" if self.entity is None else str(self.entity),
                 self.entity_type or "", self.message)
        data = "\0".join(parts).encode("utf-8", "surrogatepass")
        return hashlib.sha256(data).hexdigest()[:16]

    @property
    def sort_key(self) -> tuple:
        def pos(v):
            return (0, 0) if v is None else (1, v)
        return (self.file, pos(self.line), pos(self.column), self.rule, pos(self.entity),
                -self.rank, self.message, self.entity_type or "")

    def __lt__(self, other: "Diagnostic") -> bool:
        if not isinstance(other, Diagnostic):
            return NotImplemented
        return self.sort_key < other.sort_key

    def __le__(self, other):
        if not isinstance(other, Diagnostic):
            return NotImplemented
        return self.sort_key <= other.sort_key

    def __gt__(self, other):
        if not isinstance(other, Diagnostic):
            return NotImplemented
        return self.sort_key > other.sort_key

    def __ge__(self, other):
        if not isinstance(other, Diagnostic):
            return NotImplemented
        return self.sort_key >= other.sort_key

    def as_dict(self) -> dict:
        """The JSON form: rule, severity, message, file, line, column, entity, entity_type
        and fingerprint, in that order."""
        return {"rule": self.rule, "severity": self.severity, "message": self.message,
                "file": self.file, "line": self.line, "column": self.column,
                "entity": self.entity, "entity_type": self.entity_type,
                "fingerprint": self.fingerprint}


# -- selection ---------------------------------------------------------------------------

def parse_patterns(values: "str | Iterable[str] | None") -> tuple[str, ...]:
    """Rule patterns from option values: each comma-separated, blanks dropped, order kept.

    ``parse_patterns(["SCH-*,KIN-UNITS", "P21-*"]) == ("SCH-*", "KIN-UNITS", "P21-*")``.
    """
    if values is None:
        return ()
    if isinstance(values, str):
        values = [values]
    out: list[str] = []
    for value in values:
        for part in value.split(","):
            part = part.strip()
            if part and part not in out:
                out.append(part)
    return tuple(out)


def rule_matches(rule: str, patterns: "str | Iterable[str] | None") -> bool:
    """Whether ``rule`` matches any fnmatch-style glob in ``patterns`` (case-sensitive)."""
    return any(fnmatch.fnmatchcase(rule, p) for p in parse_patterns(patterns))


def rule_selected(rule: str, select=None, ignore=None) -> bool:
    """Whether a rule is checked: it matches ``select`` (everything when empty) and no ``ignore``.

    ``ignore`` wins over ``select``. Matching is case-sensitive, since rule ids mix case
    (``SCH-kinematic_joint.wr1``). The CLI uses this to decide which rules to evaluate.
    """
    sel = parse_patterns(select)
    if sel and not rule_matches(rule, sel):
        return False
    return not rule_matches(rule, ignore)


def select_rules(diags: Iterable[Diagnostic], select=None, ignore=None) -> list[Diagnostic]:
    """The diagnostics whose rule passes :func:`rule_selected`, in their given order."""
    sel, ign = parse_patterns(select), parse_patterns(ignore)
    return [d for d in diags if rule_selected(d.rule, sel, ign)]


# -- exit codes --------------------------------------------------------------------------

def worst_exit(diags: Iterable[Diagnostic], fail_on: "str | Severity" = "error",
               exit_zero: bool = False) -> int:
    """1 when any diagnostic is at least as severe as ``fail_on``, else 0.

    ``exit_zero`` (``--exit-zero``) makes it 0 whatever was found.
    """
    threshold = Severity.parse(fail_on)
    if exit_zero:
        return 0
    return 1 if any(d.rank >= threshold for d in diags) else 0


def exit_code(results: Iterable["RunResult"], fail_on: "str | Severity" = "error",
              exit_zero: bool = False) -> int:
    """The process exit code for a run over several files: the worst of the per-file codes.

    2 for a file that could not be read at all (``--exit-zero`` does not hide that: it
    is a failure to check, not a finding), else 1 when a diagnostic reaches ``fail_on``
    (unless ``exit_zero``), else 0.
    """
    threshold = Severity.parse(fail_on)
    worst = 0
    for r in results:
        code = 2 if not r.readable else worst_exit(r.diagnostics, threshold, exit_zero)
        worst = max(worst, code)
    return worst


# -- summaries ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Summary:
    """Counts and coverage of one file's check, or of a whole run (see :meth:`combine`).

    ``rules_evaluated``/``rules_applicable``: how many of the rules that apply to the
    file were actually evaluated (for a run, the sums over its files). ``not_evaluated``
    counts the ``SCH-NOT-EVALUATED`` notes. ``seconds`` is the wall time spent.
    """

    files: int = 1
    errors: int = 0
    warnings: int = 0
    notes: int = 0
    rules_evaluated: int = 0
    rules_applicable: int = 0
    not_evaluated: int = 0
    seconds: float = 0.0
    unreadable: int = 0

    @property
    def counts(self) -> dict[str, int]:
        """``{"error": n, "warning": n, "note": n}``."""
        return {"error": self.errors, "warning": self.warnings, "note": self.notes}

    @classmethod
    def from_diagnostics(cls, diags: Iterable[Diagnostic], rules_evaluated: int = 0,
                         rules_applicable: int = 0, seconds: float = 0.0,
                         readable: bool = True) -> "Summary":
        n = {"error": 0, "warning": 0, "note": 0}
        not_eval = 0
        for d in diags:
            n[d.severity] += 1
            not_eval += d.rule == NOT_EVALUATED
        return cls(files=1, errors=n["error"], warnings=n["warning"], notes=n["note"],
                   rules_evaluated=rules_evaluated, rules_applicable=rules_applicable,
                   not_evaluated=not_eval, seconds=float(seconds),
                   unreadable=0 if readable else 1)

    @classmethod
    def combine(cls, summaries: Iterable["Summary"]) -> "Summary":
        """The run's summary: every field added up."""
        total = cls(files=0)
        for s in summaries:
            total = cls(files=total.files + s.files, errors=total.errors + s.errors,
                        warnings=total.warnings + s.warnings, notes=total.notes + s.notes,
                        rules_evaluated=total.rules_evaluated + s.rules_evaluated,
                        rules_applicable=total.rules_applicable + s.rules_applicable,
                        not_evaluated=total.not_evaluated + s.not_evaluated,
                        seconds=total.seconds + s.seconds,
                        unreadable=total.unreadable + s.unreadable)
        return total

    def as_dict(self) -> dict:
        """The JSON form (``seconds`` rounded to milliseconds)."""
        return {"files": self.files, "errors": self.errors, "warnings": self.warnings,
                "notes": self.notes, "rules_evaluated": self.rules_evaluated,
                "rules_applicable": self.rules_applicable, "not_evaluated": self.not_evaluated,
                "unreadable": self.unreadable, "seconds": round(self.seconds, 3)}


@dataclass(frozen=True)
class RunResult:
    """The outcome of checking one file. ``diagnostics`` is kept sorted (a tuple).

    ``readable`` is False when the file could not be read at all (exit code 2); its
    diagnostics then say why.
    """

    file: str
    diagnostics: Sequence[Diagnostic] = ()
    summary: Summary = field(default_factory=Summary)
    readable: bool = True

    def __post_init__(self):
        object.__setattr__(self, "diagnostics", tuple(sorted(self.diagnostics)))

    @classmethod
    def make(cls, file: str, diagnostics: Iterable[Diagnostic], rules_evaluated: int = 0,
             rules_applicable: int = 0, seconds: float = 0.0,
             readable: bool = True) -> "RunResult":
        """A result whose summary is counted from its diagnostics."""
        diags = tuple(diagnostics)
        return cls(file, diags, Summary.from_diagnostics(diags, rules_evaluated,
                                                         rules_applicable, seconds, readable),
                   readable)


# -- rule catalogue (for reports that describe their rules, e.g. SARIF) -------------------

_DEFAULT_RULES: dict[str, str] = {
    "P21-SYNTAX": "The exchange structure is not valid ISO 10303-21 syntax.",
    "SCH-ARITY": "An entity instance has the wrong number of attributes for its EXPRESS type.",
    NOT_EVALUATED: "An EXPRESS rule that applies to the file was not evaluated by p105.",
    "KIN-UNITS": "Kinematic quantities lack consistent length or plane angle units.",
}
# Extended by register_rule() as checkers are imported (rules/validate.py registers its own).
_RULES: dict[str, str] = dict(_DEFAULT_RULES)

_PREFIXES = {
    "P21-": "ISO 10303-21 exchange structure check",
    "SCH-": "EXPRESS schema conformance check",
    "KIN-": "Kinematics consistency check",
}

_WHERE_RULE = re.compile(r"SCH-([A-Za-z0-9_]+)\.([A-Za-z0-9_]+)")


def register_rule(rule: str, description: str) -> None:
    """Record a one-sentence description of ``rule`` for reports (later registrations win)."""
    _RULES[rule] = description


def rule_description(rule: str) -> str:
    """A one-sentence description of a rule id: registered, or derived from its form."""
    if rule in _RULES:
        return _RULES[rule]
    m = _WHERE_RULE.fullmatch(rule)
    if m:
        return f"EXPRESS rule {m.group(2)} of entity {m.group(1)}."
    for prefix, text in _PREFIXES.items():
        if rule.startswith(prefix):
            return f"{text}: {rule}."
    return f"p105 rule {rule}."
