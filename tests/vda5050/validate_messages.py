#!/usr/bin/env python3
"""Validates every VDA 5050 message a producer prints ("<topic>\\t<json>" per line) against the
official 2.1 JSON schemas next to this file, and checks that the validator is not asleep: each
message with one required key removed must fail.

usage: validate_messages.py PRODUCER [PRODUCER ...]   (each an executable to run)
"""
import json
import pathlib
import subprocess
import sys

import jsonschema

SCHEMAS = pathlib.Path(__file__).resolve().parent / "schemas"


def main():
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    validators = {}
    for name in ("order", "instantActions", "state", "connection", "factsheet"):
        schema = json.loads((SCHEMAS / f"{name}.schema").read_text())
        jsonschema.Draft202012Validator.check_schema(schema)
        validators[name] = (schema, jsonschema.Draft202012Validator(
            schema, format_checker=jsonschema.FormatChecker()))
    counts = {}
    failures = 0
    for producer in sys.argv[1:]:
        out = subprocess.run([producer], check=True, capture_output=True, text=True, timeout=120).stdout
        for n, line in enumerate(out.splitlines(), 1):
            topic, _, text = line.partition("\t")
            if topic not in validators:
                print(f"{producer}:{n}: unknown topic '{topic}'")
                failures += 1
                continue
            schema, validator = validators[topic]
            message = json.loads(text)
            errors = sorted(validator.iter_errors(message), key=lambda e: list(e.path))
            for e in errors:
                print(f"{producer}:{n}: {topic}: {'/'.join(map(str, e.path)) or '(root)'}: {e.message}")
            failures += len(errors)
            counts[topic] = counts.get(topic, 0) + 1
            required = schema.get("required", [])
            if required:
                broken = dict(message)
                broken.pop(required[-1], None)
                if validator.is_valid(broken):
                    print(f"{producer}:{n}: {topic} without '{required[-1]}' passed the schema")
                    failures += 1
    for topic in ("order", "instantActions", "state", "connection", "factsheet"):
        if counts.get(topic, 0) == 0:
            print(f"no '{topic}' message was produced")
            failures += 1
    print("validated:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())), f"; {failures} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
