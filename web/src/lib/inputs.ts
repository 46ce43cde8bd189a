// Validation of what operators type, before anything is sent: a command with a typo in it must
// not leave the page. Each returns the value or a message naming the field.

export type Checked<T> = { ok: true; value: T } | { ok: false; error: string };

export function parseNumber(text: string, field: string, min: number, max: number): Checked<number> {
  const t = text.trim().replace(",", ".");
  if (t === "") return { ok: false, error: `${field}: required` };
  const v = Number(t);
  if (!Number.isFinite(v)) return { ok: false, error: `${field}: not a number` };
  if (v < min || v > max) return { ok: false, error: `${field}: must be within ${min}…${max}` };
  return { ok: true, value: v };
}

export const parseLat = (t: string, field = "latitude"): Checked<number> => parseNumber(t, `${field} (°)`, -90, 90);
export const parseLon = (t: string, field = "longitude"): Checked<number> => parseNumber(t, `${field} (°)`, -180, 180);
export const parseDeg = (t: string, field: string): Checked<number> => parseNumber(t, `${field} (°)`, -360, 360);
export const parseAlt = (t: string, field = "altitude MSL"): Checked<number> => parseNumber(t, `${field} (m)`, -500, 9000);

/** Collects several checks; the first error wins. */
export function all<T extends readonly Checked<unknown>[]>(...checks: T): { ok: true; values: { [K in keyof T]: T[K] extends Checked<infer V> ? V : never } } | { ok: false; error: string } {
  for (const c of checks) if (!c.ok) return { ok: false, error: c.error };
  return { ok: true, values: checks.map((c) => (c as { ok: true; value: unknown }).value) as never };
}
