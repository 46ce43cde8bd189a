// The Lab page's logic without the DOM: the vehicle editor's edits (only fields changed from
// the seed's value are sent; text that is no number is refused here, the rest by the station's
// own validation), a job's progress as a fraction and a label, the eigenvalue plot's geometry
// (the complex plane scaled to the points), and how an outcome reads.

import type * as Wire from "../generated/api";

export type VehicleField = Wire.VehicleField;
export type LabStatus = Wire.LabStatusBody;

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

/** A running job's progress: fraction 0…1 (null when the job cannot tell) and a label. */
export function progressOf(job: Wire.LabJobView): { fraction: number | null; label: string } {
  const secs = `${job.elapsed_s.toFixed(0)} s`;
  const cancelling = job.cancelling ? ", cancelling…" : "";
  if (job.total <= 0) return { fraction: null, label: `${job.kind} running, ${secs}${cancelling}` };
  const fraction = Math.min(1, Math.max(0, job.done / job.total));
  const unit = job.kind === "monte_carlo" ? "runs" : "steps";
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
