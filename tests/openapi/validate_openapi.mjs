// Validates an OpenAPI document (docs/openapi.yaml) against the OpenAPI 3.0 schema with
// swagger-parser, then checks what the schema leaves optional but this project requires: every
// operation has a unique operationId and at least one tag, each tag declared in the top-level
// `tags`. Prints every problem found and exits 1 when there is one.
//
// Usage: node validate_openapi.mjs docs/openapi.yaml
import SwaggerParser from "@apidevtools/swagger-parser";

const METHODS = ["get", "put", "post", "delete", "options", "head", "patch", "trace"];

const file = process.argv[2];
if (!file) {
  console.error("usage: node validate_openapi.mjs <openapi.yaml>");
  process.exit(2);
}

const problems = [];
let api;
try {
  // parse() keeps the $refs; validate() below resolves a copy.
  api = await SwaggerParser.parse(file);
  await SwaggerParser.validate(structuredClone(api));
} catch (e) {
  problems.push(`${file}: not a valid OpenAPI document: ${e.message}`);
}

if (api) {
  const declared = new Set((api.tags ?? []).map((t) => t.name));
  const ids = new Map();
  for (const [path, item] of Object.entries(api.paths ?? {})) {
    for (const method of METHODS) {
      const op = item[method];
      if (!op) continue;
      const where = `${method.toUpperCase()} ${path}`;
      if (!op.operationId) {
        problems.push(`${where}: no operationId`);
      } else if (ids.has(op.operationId)) {
        problems.push(`${where}: operationId "${op.operationId}" is also ${ids.get(op.operationId)}'s`);
      } else {
        ids.set(op.operationId, where);
      }
      if (!Array.isArray(op.tags) || op.tags.length === 0) {
        problems.push(`${where}: no tags`);
      }
      for (const t of op.tags ?? []) {
        if (!declared.has(t)) problems.push(`${where}: tag "${t}" is not declared in the top-level tags`);
      }
    }
  }
  if (problems.length === 0) console.log(`${file}: valid OpenAPI ${api.openapi}, ${ids.size} operations`);
}

for (const p of problems) console.error(p);
process.exit(problems.length === 0 ? 0 : 1);
