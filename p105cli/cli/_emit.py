"""Writing whole models with a progress bar on terminals; shared by parse and export."""

from __future__ import annotations

from .contract import Progress, diag


class _Counted:
    """The document with its records() counted into a progress bar."""

    def __init__(self, doc, progress: Progress):
        self._doc, self._progress = doc, progress

    def __getattr__(self, name):
        return getattr(self._doc, name)

    def records(self):
        advance = self._progress.advance
        for n, record in enumerate(self._doc.records(), 1):
            yield record
            if not n % 10_000:
                advance(10_000)


def emit_json(doc, out, stream: bool) -> None:
    from p105cli.step import write_json
    with Progress(len(doc), "writing JSON") as progress:
        write_json(_Counted(doc, progress), out, stream)


def emit_p21(doc, out) -> None:
    from p105cli.step import write_step
    if getattr(doc, "scene", None) is not None:
        # Part 21 has no place for it: say so rather than lose it silently
        diag("warning", f"{doc.source}: the model's scene block (p105-scene/1) is not Part 21 data and is "
                        "left out; keep the model as JSON (--to json) or save the scene to a file for --scene")
    with Progress(len(doc), "writing Part 21") as progress:
        write_step(_Counted(doc, progress), out)
