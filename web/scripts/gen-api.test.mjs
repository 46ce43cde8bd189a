// The committed TypeScript of the API (src/generated/api.ts) is what the committed contract gives.
// (That the contract is what the daemon's Rust types give is checked by stx-station's tests.)
import { readFile } from "node:fs/promises";
import { expect, it } from "vitest";
import { apiTypes, SCHEMA_FILE, TYPES_FILE } from "./gen-api.mjs";

it("src/generated/api.ts is generated from src/generated/api.schema.json (else: npm run gen:api)", async () => {
  const fresh = await apiTypes(await readFile(SCHEMA_FILE, "utf8"));
  const committed = await readFile(TYPES_FILE, "utf8");
  expect(committed === fresh, "src/generated/api.ts is stale: run `npm run gen:api` and commit it").toBe(true);
});
