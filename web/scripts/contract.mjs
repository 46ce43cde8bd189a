// Validates messages against the station's contract (src/generated/api.schema.json) with ajv:
// used by the dashboard's tests (fixtures are real messages) and by the browser test
// (tests/browser/live.mjs: every message the daemon sends to the page).

import { readFileSync } from "node:fs";
import { createRequire } from "node:module";
import { fileURLToPath } from "node:url";

const require = createRequire(import.meta.url);
const Ajv = require("ajv");

export const SCHEMA_FILE = fileURLToPath(new URL("../src/generated/api.schema.json", import.meta.url));

// The formats schemars writes for Rust's number types, checked as Rust would have them.
const int = (min, max) => ({ type: "number", validate: (x) => Number.isInteger(x) && x >= min && x <= max });
const FORMATS = {
  double: { type: "number", validate: Number.isFinite },
  uint8: int(0, 255),
  uint16: int(0, 65535),
  uint32: int(0, 4294967295),
  uint64: int(0, Number.MAX_SAFE_INTEGER),
  // Rust's usize (a count).
  uint: int(0, Number.MAX_SAFE_INTEGER),
  int32: int(-2147483648, 2147483647),
  int64: int(Number.MIN_SAFE_INTEGER, Number.MAX_SAFE_INTEGER),
};

/**
 * The contract's validator: `check(name, value)` is null when `value` is a valid `name` (a
 * definition of the schema: "ServerMessage", "StateMsg", "Session", …), else the first error,
 * with the path to the offending value. For a union of messages told apart by `type`
 * (ServerMessage, ClientMessage) the error is the one of the message that `type` names.
 */
export function contract(schemaText = readFileSync(SCHEMA_FILE, "utf8")) {
  const schema = JSON.parse(schemaText);
  const ajv = new Ajv({ strict: true, allowUnionTypes: true, formats: FORMATS });
  ajv.addSchema(schema, "api");
  const names = Object.keys(schema.definitions);
  const validators = new Map();
  const validator = (pointer) => {
    let v = validators.get(pointer);
    if (v === undefined) {
      v = ajv.getSchema(`api#${pointer}`);
      validators.set(pointer, v);
    }
    return v;
  };
  const firstError = (label, validate) => {
    const e = validate.errors?.[0];
    return e ? `${label}${e.instancePath || ""}: ${e.message}${e.params ? ` ${JSON.stringify(e.params)}` : ""}` : `${label}: invalid`;
  };
  /** The member of union `name` whose `type` is `value.type`: its pointer and name; undefined if none. */
  const member = (name, value) => {
    const def = schema.definitions[name];
    const key = def.anyOf ? "anyOf" : def.oneOf ? "oneOf" : null;
    if (key === null || typeof value !== "object" || value === null || typeof value.type !== "string") return null;
    for (const [i, branch] of def[key].entries()) {
      const ref = branch.$ref ?? branch.allOf?.[0]?.$ref;
      const target = ref ? schema.definitions[ref.replace("#/definitions/", "")] : branch;
      if (target?.properties?.type?.const === value.type) {
        return ref ? { pointer: ref.slice(1), label: ref.replace("#/definitions/", "") } : { pointer: `/definitions/${name}/${key}/${i}`, label: `${name}(${value.type})` };
      }
    }
    return undefined;
  };
  return {
    names,
    check(name, value) {
      if (!names.includes(name)) return `the contract has no message ${name}`;
      const validate = validator(`/definitions/${name}`);
      if (validate(value)) return null;
      const m = member(name, value);
      if (m === undefined) return `${name}: no message has the type ${JSON.stringify(value.type)}`;
      if (m === null) return firstError(name, validate);
      const one = validator(m.pointer);
      return one(value) ? firstError(name, validate) : firstError(m.label, one);
    },
  };
}
