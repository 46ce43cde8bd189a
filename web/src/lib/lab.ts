// The Lab page's logic without the DOM: the vehicle editor's edits (only fields changed from
// the seed's value are sent; text that is no number is refused here, the rest by the station's
// own validation), a job's progress as a fraction and a label, the eigenvalue plot's geometry
// (the complex plane scaled to the points), how an outcome reads, a comparison's recording
// picker and error table, and an identification's parameter list, result table, correlation
// matrix and the fitted values as edits of the vehicle form.

import type * as Wire from "../generated/api";
import { fmtDuration } from "./format";

export type VehicleField = Wire.VehicleField;
export type LabStatus = Wire.LabStatusBody;
/** A comparison's result (the contract inlines each kind of result in `LabResult`). */
export type CompareResult = Extract<Wire.LabResult, { kind: "compare" }>;
/** An identification's result. */
export type IdentifyResult = Extract<Wire.LabResult, { kind: "identify" }>;

/** The edits of a vehicle form: `values` by field name as typed; fields equal to their seed value are left out. */
export function vehicleEdits(fields: readonly VehicleField[], values: ReadonlyMap<string, string>): { edits: Record<string, number>; errors: Record<string, string> } {
  const edits: Record<string, number> = {};
  const errors: Record<string, string> = {};
  for (const f of fields) {
    const text = values.get(f.name);
    if (text === undefined || text.trim() === "") continue;
    const v = Number(text.trim());
    if (!Number.isFinite(v)) {
      errors[f.name] = "not a number";
      continue;
    }
    if (v !== f.seed) edits[f.name] = v;
  }
  return { edits, errors };
}

/** What a job counts its progress in. */
const UNITS: Readonly<Record<string, string>> = { monte_carlo: "runs", compare: "samples", identify: "iterations" };

/** A running job's progress: fraction 0…1 (null when the job cannot tell) and a label. */
export function progressOf(job: Wire.LabJobView): { fraction: number | null; label: string } {
  const secs = `${job.elapsed_s.toFixed(0)} s`;
  const cancelling = job.cancelling ? ", cancelling…" : "";
  if (job.total <= 0) return { fraction: null, label: `${job.kind} running, ${secs}${cancelling}` };
  const fraction = Math.min(1, Math.max(0, job.done / job.total));
  const unit = UNITS[job.kind] ?? "steps";
  return { fraction, label: `${job.done}/${job.total} ${unit}, ${secs}${cancelling}` };
}

/** How an outcome reads in one line. */
export function outcomeLine(o: Wire.LabOutcomeView): string {
  const head = `job ${o.id} (${o.kind}, ${o.started_by}): ${o.outcome.replace("_", " ")} after ${o.elapsed_s.toFixed(1)} s`;
  return o.reason ? `${head} — ${o.reason}` : head;
}

export interface Box {
  width: number;
  height: number;
  margin: number;
}

/** Maps complex points onto a box: x = real part, y = imaginary part (up), both axes through their zero, equal scales. */
export function complexPlane(points: readonly (readonly [number, number])[], box: Box): { x: (re: number) => number; y: (im: number) => number; reMin: number; reMax: number; imMax: number } {
  let reMin = -1;
  let reMax = 0.5;
  let imMax = 1;
  for (const [re, im] of points) {
    if (!Number.isFinite(re) || !Number.isFinite(im)) continue;
    reMin = Math.min(reMin, re);
    reMax = Math.max(reMax, re);
    imMax = Math.max(imMax, Math.abs(im));
  }
  const w = box.width - 2 * box.margin;
  const h = box.height - 2 * box.margin;
  const scale = Math.min(w / (reMax - reMin), h / (2 * imMax));
  const x0 = box.margin + (w - scale * (reMax - reMin)) / 2 - scale * reMin;
  const y0 = box.height / 2;
  return { x: (re) => x0 + scale * re, y: (im) => y0 - scale * im, reMin, reMax, imMax };
}

/** A Monte Carlo figure in metres, or "–" (a failed run makes the maximum infinite, sent as null). */
export function metres(v: number | null | undefined): string {
  return v === null || v === undefined || !Number.isFinite(v) ? "–" : `${v.toFixed(1)} m`;
}

/** A recording in the compare picker: its file name, when and how long, what of. */
export function recordingOption(r: Wire.RecordingSummary): { value: string; label: string } {
  const when = r.start_ms === null ? null : `${new Date(r.start_ms).toISOString().slice(0, 16).replace("T", " ")} UTC`;
  const about = [when, fmtDuration(r.duration_ms / 1000), r.mission].filter((p) => p !== null && p !== "").join(", ");
  return { value: r.name, label: `${r.name} — ${about}${r.recording_now ? " (recording now)" : ""}` };
}

/** What each channel of a comparison is, for its plot's title and the error table. */
export const COMPARE_CHANNELS: Readonly<Record<string, string>> = {
  north_m: "north",
  east_m: "east",
  height_m: "height (MSL)",
  roll_deg: "roll",
  pitch_deg: "pitch",
  yaw_deg: "yaw",
  airspeed_mps: "airspeed",
  sink_mps: "sink rate",
  turn_rate_deg_s: "turn rate",
};

/** Decimals an error figure is shown with, by unit: centimetres and tenths of a degree say nothing more. */
const DIGITS: Readonly<Record<string, number>> = { m: 1, deg: 1, "m/s": 2, "deg/s": 1 };

/** A figure with its unit, or "–" when it is no finite number. */
export function figure(v: number | null | undefined, unit: string): string {
  if (v === null || v === undefined || !Number.isFinite(v)) return "–";
  const n = v.toFixed(DIGITS[unit] ?? 2);
  return unit === "" ? n : `${n} ${unit}`;
}

/** The error table of a comparison: channel, unit, RMS, largest and mean error (model − recorded, with units), samples. */
export function compareRows(r: { channels: readonly Wire.CompareChannel[] }): [string, string, string, string, string, string][] {
  return r.channels.map((c) => [COMPARE_CHANNELS[c.name] ?? c.name, c.unit, figure(c.rms, c.unit), figure(c.max_abs, c.unit), figure(c.bias, c.unit), String(c.count)]);
}

/** The parameters to identify as typed ("cl_alpha, cd0"): names split at commas or spaces. None
 *  or one listed twice is refused here; whether a name is known is the station's to say (its
 *  refusal lists the names it knows). */
export function identifyParams(text: string): { params: string[] } | { error: string } {
  const params = text.split(/[\s,]+/).filter((p) => p !== "");
  if (params.length === 0) return { error: "name at least one parameter to fit, e.g. cl_alpha, cd0" };
  const twice = params.find((p, i) => params.slice(0, i).some((q) => q.toLowerCase() === p.toLowerCase()));
  return twice === undefined ? { params } : { error: `${twice} is listed twice` };
}

/** A coefficient with four significant figures (they span 1e-4 to 10), or "–". */
function sig(v: number | null | undefined, digits = 4): string {
  return v === null || v === undefined || !Number.isFinite(v) ? "–" : String(Number(v.toPrecision(digits)));
}

/** The table of an identification: parameter, before, fitted, ± standard error, 95 % interval,
 *  change from before in per cent. A parameter the flight does not determine has "–" where its
 *  standard error and interval would be. */
export function identifyRows(r: Pick<IdentifyResult, "params">): [string, string, string, string, string, string][] {
  return r.params.map((p) => {
    const interval = p.interval95_low === null || p.interval95_high === null ? "not determined" : `${sig(p.interval95_low)} … ${sig(p.interval95_high)}`;
    const change = p.nominal === 0 ? "–" : `${(100 * (p.fitted / p.nominal - 1)).toFixed(1)} %`;
    return [p.name, sig(p.nominal), sig(p.fitted), p.std_error === null ? "–" : `± ${sig(p.std_error, 2)}`, interval, change];
  });
}

/** The correlation matrix as text with two decimals, or null when the flight does not tell the parameters apart. */
export function correlationCells(r: Pick<IdentifyResult, "correlation">): string[][] | null {
  return r.correlation === null ? null : r.correlation.map((row) => row.map((c) => (Number.isFinite(c) ? c.toFixed(2) : "–")));
}

/** The fitted values as edits of the vehicle form: each coefficient goes to the form's field of
 *  that name in the canopy's aerodynamics or brake terms. A parameter with no such field (the rigging angle
 *  turns several geometry vectors) is listed apart: it reaches a vehicle only through the fitted file. */
export function fittedEdits(r: Pick<IdentifyResult, "params">, fields: readonly VehicleField[]): { edits: Record<string, number>; apart: string[] } {
  const edits: Record<string, number> = {};
  const apart: string[] = [];
  for (const p of r.params) {
    const field = fields.find((f) => f.name === `canopy.aero.${p.name}` || f.name === `canopy.brakes.${p.name}`);
    if (field === undefined || !Number.isFinite(p.fitted)) apart.push(p.name);
    else edits[field.name] = p.fitted;
  }
  return { edits, apart };
}

/** Which part of its recording a comparison flew: a mission's parafoil stage, or all of it. */
export function comparedPart(r: Pick<CompareResult, "parafoil_stage_s" | "recorded_s">): string {
  const p = r.parafoil_stage_s;
  return p === null ? "the whole recording" : `its parafoil stage, ${p[0].toFixed(1)} … ${p[1].toFixed(1)} s of ${r.recorded_s.toFixed(1)} s recorded`;
}

/** The window of a recording to compare or identify over, as typed in its two boxes (seconds
 *  from the flight's first sample; a blank box leaves that end open). Whether the flight
 *  reaches it is the station's to say. */
export function recordingWindow(fromText: string, toText: string): { from_s?: number; to_s?: number } | { error: string } {
  const out: { from_s?: number; to_s?: number } = {};
  for (const [key, text] of [["from_s", fromText], ["to_s", toText]] as const) {
    if (text.trim() === "") continue;
    const v = Number(text.trim());
    if (!Number.isFinite(v) || v < 0) return { error: `${key === "from_s" ? "from" : "to"}: ${JSON.stringify(text)} is not a number of seconds ≥ 0` };
    out[key] = v;
  }
  if (out.from_s !== undefined && out.to_s !== undefined && out.to_s <= out.from_s) return { error: `to (${out.to_s} s) must be after from (${out.from_s} s)` };
  return out;
}
