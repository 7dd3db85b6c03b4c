"""``python3 -m p105cli.corpus OUTDIR [--examples DIR]``: regenerate the authored corpus."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import EXAMPLES, MECHANISMS, PROFILES, generate


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="python3 -m p105cli.corpus",
        description=f"Write the {len(MECHANISMS) * len(PROFILES)} corpus files "
                    f"(<mechanism>_<profile>.stp; profiles {', '.join(PROFILES)}) into OUTDIR.")
    parser.add_argument("outdir", type=Path, help="output directory (the repo keeps them in tests/data/corpus)")
    parser.add_argument("--examples", type=Path, default=None, metavar="DIR",
                        help=f"also write {', '.join(EXAMPLES)} there; by default the repo's examples/ "
                             "when OUTDIR is its tests/data/corpus")
    args = parser.parse_args(argv)
    examples = args.examples
    if examples is None:
        out = args.outdir.resolve()
        if out.parts[-3:] == ("tests", "data", "corpus") and (out.parents[2] / "examples").is_dir():
            examples = out.parents[2] / "examples"
    for path in generate(args.outdir, examples):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
