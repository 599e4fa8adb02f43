#!/usr/bin/python3
"""Validates CityJSON files against the CityJSON 2.0 JSON schema (structure only).
Usage: cityjson.py SCHEMA.json FILE.city.json [FILE...]; exit 0 when all are valid."""
import json
import sys

import jsonschema

schema = json.load(open(sys.argv[1]))
validator = jsonschema.Draft7Validator(schema)
bad = 0
for path in sys.argv[2:]:
    errors = sorted(validator.iter_errors(json.load(open(path))), key=lambda e: list(e.path))
    for e in errors[:5]:
        print(f"{path}: {'/'.join(map(str, e.path))}: {e.message[:300]}")
    bad += bool(errors)
    if not errors:
        print(f"{path}: valid")
sys.exit(1 if bad else 0)
