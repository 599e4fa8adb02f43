#!/usr/bin/python3
"""Validates CityJSON Text Sequences (.city.jsonl) against the CityJSON 2.0 schemas: the first line
as a CityJSON object, every other line as a CityJSONFeature; also checks that each feature's id
is one of its CityObjects and that every vertex index points into its own vertices.
Usage: cityjsonseq.py SCHEMA_DIR FILE.city.jsonl [FILE...]; exit 0 when all are valid."""
import json
import os
import sys

import jsonschema


def indices(boundaries):
    if isinstance(boundaries, list):
        for b in boundaries:
            yield from indices(b)
    elif isinstance(boundaries, int):
        yield boundaries


schemas = sys.argv[1]
header_validator = jsonschema.Draft7Validator(json.load(open(os.path.join(schemas, "cityjson.min.schema.json"))))
feature_validator = jsonschema.Draft7Validator(json.load(open(os.path.join(schemas, "cityjsonfeature.min.schema.json"))))
bad = 0
for path in sys.argv[2:]:
    problems = []
    with open(path) as f:
        lines = f.read().splitlines()
    if not lines:
        problems.append("empty file")
    for number, line in enumerate(lines, 1):
        document = json.loads(line)
        validator = header_validator if number == 1 else feature_validator
        for e in list(validator.iter_errors(document))[:3]:
            problems.append(f"line {number}: {'/'.join(map(str, e.path))}: {e.message[:200]}")
        if number > 1:
            if document.get("id") not in document.get("CityObjects", {}):
                problems.append(f"line {number}: id {document.get('id')} is not one of its CityObjects")
            count = len(document.get("vertices", []))
            for o in document.get("CityObjects", {}).values():
                for g in o.get("geometry", []):
                    if any(i >= count for i in indices(g.get("boundaries", []))):
                        problems.append(f"line {number}: a vertex index beyond its {count} vertices")
    for p in problems[:5]:
        print(f"{path}: {p}")
    bad += bool(problems)
    if not problems:
        print(f"{path}: valid ({len(lines) - 1} features)")
sys.exit(1 if bad else 0)
