"""EXPRESS (ISO 10303-11) schemas: reader, data model, Part 21 attribute order.

A science module: no click, no numpy (it is imported on the CLI's start-up
path). ``load_schema(path)`` is the usual entry point; see ``express.py``
(entry points, cache), ``tokenizer.py`` and ``parser.py`` for the reader,
``model.py`` for the data model, ``population.py`` and ``instance.py`` for
a model file seen through a schema, and ``evaluator/`` for EXPRESS run on it.
"""

from .express import (  # noqa: F401
    PARSER_VERSION, cache_dir, load_schema, load_schemas, parse_schema, parse_schemas, reader_name,
)
from .model import Entity, P21Attribute, Schema, SchemaError  # noqa: F401


def __getattr__(name: str):  # BUILTIN_FUNCTIONS, ExpressSyntaxError, ...: imported on first use
    return reader_name(name, __name__)
