// Parses `state.stack` (the four bodies around the drone and their lines) for the 3-D view. A
// body or line that does not parse is left out rather than drawn in a wrong place; a stack
// without its drone is no stack (everything is placed from the drone).

import { isObj, num, oneOf, vec3, type Obj } from "./parseFields";
import type { Stack, StackBody, StackLine } from "./types";

const BODIES = { canopy: true, drone: true, capsule: true, transponder: true } as const satisfies Record<StackBody["body"], true>;
const SOURCES = { measured: true, rigging: true } as const satisfies Record<StackBody["source"], true>;
const LINES = { main_right: true, main_left: true, capsule: true, transponder: true } as const satisfies Record<StackLine["line"], true>;

function parseBody(o: Obj): StackBody | null {
  const body = oneOf(o, "body", BODIES);
  const source = oneOf(o, "source", SOURCES);
  const roll_deg = num(o, "roll_deg");
  const pitch_deg = num(o, "pitch_deg");
  const yaw_deg = num(o, "yaw_deg");
  const position_enu_m = vec3(o, "position_enu_m");
  const size_m = vec3(o, "size_m");
  if (body === null || source === null || roll_deg === null || pitch_deg === null || yaw_deg === null || position_enu_m === null || size_m === null) return null;
  return { body, roll_deg, pitch_deg, yaw_deg, position_enu_m, size_m, source, age_s: num(o, "age_s") };
}

function parseLine(o: Obj): StackLine | null {
  const line = oneOf(o, "line", LINES);
  const top_enu_m = vec3(o, "top_enu_m");
  const bottom_enu_m = vec3(o, "bottom_enu_m");
  return line === null || top_enu_m === null || bottom_enu_m === null ? null : { line, top_enu_m, bottom_enu_m };
}

const each = <T>(v: unknown, f: (o: Obj) => T | null): T[] => (Array.isArray(v) ? v.filter(isObj).map(f).filter((x): x is T => x !== null) : []);

export function parseStack(o: Obj): Stack | null {
  const bodies = each(o.bodies, parseBody);
  if (!bodies.some((b) => b.body === "drone")) return null;
  return { bodies, lines: each(o.lines, parseLine) };
}
