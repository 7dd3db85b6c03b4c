"""``python -m p105cli.schema.compile``: store the parsed long forms in the package (run by make)."""

import sys

from .express import compile_package_schemas


def main() -> int:
    for path in compile_package_schemas():
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
