#!/usr/bin/env python3
"""docs/site.schema.json against the shipped sites and the corpus of bad files.

Every shipped site must validate; each corpus file must be refused by the schema exactly when
corpus/expect.json says so ("refuse": structural problems both the schema and loadSite() refuse;
"accept": geometric problems only loadSite() can see). site_test holds loadSite() to the same list.
"""
import glob
import json
import os
import sys

import jsonschema

src = sys.argv[1]
schema = json.load(open(os.path.join(src, "docs/site.schema.json")))
jsonschema.Draft202012Validator.check_schema(schema)
v = jsonschema.Draft202012Validator(schema)
failed = 0
sites = sorted(glob.glob(os.path.join(src, "sim/scenarios/*.site.json")))
corpus = os.path.join(src, "tests/unit/site/corpus")
for path in sites + [os.path.join(corpus, "good.site.json")]:
    errors = [e.message for e in v.iter_errors(json.load(open(path)))]
    if errors:
        failed += 1
        print(f"FAIL {path}: the schema refuses a good site: {errors[:3]}")
expect = json.load(open(os.path.join(corpus, "expect.json")))
for name, e in sorted(expect.items()):
    errors = list(v.iter_errors(json.load(open(os.path.join(corpus, name + ".site.json")))))
    got = "refuse" if errors else "accept"
    if got != e["schema"]:
        failed += 1
        print(f"FAIL {name}: schema says {got}, expected {e['schema']}")
checked = len(sites) + 1 + len(expect)
print(f"{checked - failed} passed, {failed} failed")
sys.exit(1 if failed else 0)
