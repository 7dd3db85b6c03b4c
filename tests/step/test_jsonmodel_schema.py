"""Every JSON the CLI writes conforms to the shipped JSON Schema; bad JSON models are refused."""

from __future__ import annotations

import json
from importlib import resources

import jsonschema
import pytest

from conftest import cli_in_process, corpus_files, p21

SCHEMA = json.loads(resources.files("p105cli").joinpath("schemas/p105-1.schema.json").read_text())
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)
SMALL = [p for p in corpus_files() if p.stat().st_size < 1_000_000]


def test_schema_is_a_valid_draft_2020_12_schema():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)


@pytest.mark.parametrize("path", SMALL, ids=[p.name for p in SMALL])
def test_document_output_conforms(path):
    r = cli_in_process("parse", path)
    VALIDATOR.validate(json.loads(r.stdout))


@pytest.mark.parametrize("path", SMALL, ids=[p.name for p in SMALL])
def test_stream_output_conforms(path):
    lines = cli_in_process("parse", "--stream", path).stdout.decode().splitlines()
    frame_validator = jsonschema.Draft202012Validator(
        {**SCHEMA["$defs"]["stream_frame"], "$defs": SCHEMA["$defs"]})
    record_validator = jsonschema.Draft202012Validator(
        {**SCHEMA["$defs"]["instance"], "$defs": SCHEMA["$defs"]})
    frame_validator.validate(json.loads(lines[0]))
    for line in lines[1:]:
        record_validator.validate(json.loads(line))


def test_every_value_kind_conforms():
    text = p21("#1=A(1,-0.,'s',$,*,#1,.T.,\"0F\",(1,(2)),LENGTH_MEASURE(2.),());\n#2=(B()C(#1));")
    header = ("ISO-10303-21;HEADER;FILE_DESCRIPTION((''),'3;1');FILE_NAME('','',(''),(''),'','','');"
              "FILE_SCHEMA(('S'));FILE_POPULATION('S',$,$);ENDSEC;ANCHOR;<a>=#1;ENDSEC;DATA('d',('S'));")
    text2 = header + "#1=A();ENDSEC;DATA;#2=B(#1);ENDSEC;END-ISO-10303-21;"
    for t in (text, text2):
        r = cli_in_process("parse", input=t)
        assert r.returncode == 0, r.stderr
        VALIDATOR.validate(json.loads(r.stdout))


@pytest.mark.parametrize("bad,where", [
    ('{"format":"p105/2","header":{},"data":[]}', "/format"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[true]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[NaN]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[{"ref":"x"}]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a b","args":[]}]}', "/data/0/type"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":[]},{"id":1,"type":"b","args":[]}]}',
     "/data/1"),
    ('{"format":"p105/1","header":{},"data":[{"id":1,"type":"a","args":["\\ud800"]}]}', "/data/0/args/0"),
    ('{"format":"p105/1","header":{},"data":[', "1:"),
])
def test_malformed_models_are_exit_2_with_a_pointer(bad, where):
    r = cli_in_process("export", input=bad)
    assert r.returncode == 2, r.stderr
    err = r.stderr.decode()
    assert err.startswith("p105: error: <stdin>:") and where in err and "Traceback" not in err
