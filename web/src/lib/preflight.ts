// The Plan page's pure parts: the form's text to a `POST /api/plan` body (each number checked
// here so the person is told which box is wrong before anything is sent; the station checks the
// rules again and its reasons are shown as it gives them), the forecast table as the CSV of
// `stx plan` forecast files, the recording's measured wind bands as lines saying which were
// merged and which refused, and a 1-σ ellipse as a polygon for the map.

import type * as Wire from "../generated/api";

/** The form's boxes, as typed. Empty optional boxes take the station's defaults. */
export interface PlanForm {
  launch_lat_deg: string;
  launch_lon_deg: string;
  launch_alt_msl_m: string;
  ascent_rate_mps: string;
  ascent_rate_sigma_mps: string;
  burst_altitude_msl_m: string;
  burst_altitude_sigma_m: string;
  deploy_height_m: string;
  default_wind_sigma_mps: string;
  runs: string;
  seed: string;
  target_lat_deg: string;
  target_lon_deg: string;
  /** `alt_msl_m,speed_mps,from_deg[,sigma_mps]` per line (README, "Pre-flight planning"). */
  forecast: string;
  /** A recording's name, or "" for none. */
  from_recording: string;
}

export type Built = { ok: true; body: Wire.PreflightBody } | { ok: false; field: keyof PlanForm; error: string };

const CSV_COLUMNS = ["alt_msl_m", "speed_mps", "from_deg", "sigma_mps"];

/** The forecast rows of CSV text (header, blank and `#` lines skipped), or why not, by line. */
export function parseForecast(text: string): { ok: true; rows: Wire.ForecastRow[] } | { ok: false; error: string } {
  const rows: Wire.ForecastRow[] = [];
  const lines = text.split(/\r?\n/);
  for (const [i, raw] of lines.entries()) {
    const line = raw.trim();
    if (line === "" || line.startsWith("#") || line.startsWith("alt_msl_m")) continue;
    const cells = line.split(",").map((c) => c.trim());
    if (cells.length < 3 || cells.length > 4) return { ok: false, error: `forecast line ${i + 1}: expected alt_msl_m,speed_mps,from_deg[,sigma_mps], got ${cells.length} values` };
    const values = cells.map(Number);
    const bad = values.findIndex((v, k) => cells[k] === "" || !Number.isFinite(v));
    if (bad >= 0) return { ok: false, error: `forecast line ${i + 1}: ${CSV_COLUMNS[bad]} is not a number: "${cells[bad]}"` };
    const row: Wire.ForecastRow = { alt_msl_m: values[0]!, speed_mps: values[1]!, from_deg: values[2]! };
    if (values.length === 4) row.sigma_mps = values[3]!;
    rows.push(row);
  }
  if (rows.length === 0) return { ok: false, error: "forecast: at least one row (alt_msl_m,speed_mps,from_deg) is needed" };
  return { ok: true, rows };
}

/** The rows as the CSV the form shows, with its header. */
export function forecastText(rows: readonly Wire.ForecastRow[]): string {
  const hasSigma = rows.some((r) => r.sigma_mps !== undefined && r.sigma_mps !== null);
  const header = hasSigma ? CSV_COLUMNS.join(",") : CSV_COLUMNS.slice(0, 3).join(",");
  // A row without a sigma has three values (the planner's default applies to it).
  const line = (r: Wire.ForecastRow): string => [r.alt_msl_m, r.speed_mps, r.from_deg, ...(r.sigma_mps !== undefined && r.sigma_mps !== null ? [r.sigma_mps] : [])].join(",");
  return [header, ...rows.map(line)].join("\n");
}

/** The form's values from a request (the station's defaults, or a plan's request). */
export function formOf(r: Wire.PlanRequest, fromRecording = ""): PlanForm {
  const t = r.target_lat_lon_deg;
  return {
    launch_lat_deg: String(r.launch_lat_deg),
    launch_lon_deg: String(r.launch_lon_deg),
    launch_alt_msl_m: String(r.launch_alt_msl_m),
    ascent_rate_mps: String(r.ascent_rate_mps),
    ascent_rate_sigma_mps: String(r.ascent_rate_sigma_mps),
    burst_altitude_msl_m: String(r.burst_altitude_msl_m),
    burst_altitude_sigma_m: String(r.burst_altitude_sigma_m),
    deploy_height_m: String(r.deploy_height_m),
    default_wind_sigma_mps: String(r.default_wind_sigma_mps),
    runs: String(r.runs),
    seed: String(r.seed),
    target_lat_deg: t ? String(t[0]) : "",
    target_lon_deg: t ? String(t[1]) : "",
    forecast: forecastText(r.forecast),
    from_recording: fromRecording,
  };
}

type NumberField = Exclude<keyof PlanForm, "forecast" | "from_recording">;

/** The `POST /api/plan` body of the form, or the first box that is not a number. */
export function buildRequest(form: PlanForm): Built {
  const fail = (field: keyof PlanForm, error: string): Built => ({ ok: false, field, error });
  const num = (field: NumberField, required: boolean): number | null | string => {
    const text = form[field].trim();
    if (text === "") return required ? `${field} is required` : null;
    const v = Number(text);
    return Number.isFinite(v) ? v : `${field} is not a number: "${text}"`;
  };
  const request: Wire.PlanRequestInput = { launch_lat_deg: 0, launch_lon_deg: 0, forecast: [] };
  const optional: NumberField[] = ["launch_alt_msl_m", "ascent_rate_mps", "ascent_rate_sigma_mps", "burst_altitude_msl_m", "burst_altitude_sigma_m", "deploy_height_m", "default_wind_sigma_mps", "runs", "seed"];
  for (const field of ["launch_lat_deg", "launch_lon_deg", ...optional] as NumberField[]) {
    const v = num(field, field === "launch_lat_deg" || field === "launch_lon_deg");
    if (typeof v === "string") return fail(field, v);
    if (v === null) continue;
    if ((field === "runs" || field === "seed") && !(Number.isSafeInteger(v) && v >= 0)) return fail(field, `${field} must be a whole number ≥ 0, got ${v}`);
    (request as unknown as Record<string, number>)[field] = v;
  }
  const lat = num("target_lat_deg", false);
  const lon = num("target_lon_deg", false);
  if (typeof lat === "string") return fail("target_lat_deg", lat);
  if (typeof lon === "string") return fail("target_lon_deg", lon);
  if ((lat === null) !== (lon === null)) return fail(lat === null ? "target_lat_deg" : "target_lon_deg", "the target needs both latitude and longitude, or neither");
  request.target_lat_lon_deg = lat !== null && lon !== null ? [lat, lon] : null;
  const forecast = parseForecast(form.forecast);
  if (!forecast.ok) return fail("forecast", forecast.error);
  request.forecast = forecast.rows;
  const name = form.from_recording.trim();
  return { ok: true, body: { request, from_recording: name === "" ? null : name } };
}

const EARTH_RADIUS_M = 6_378_137;

/**
 * The outline of a 1-σ `ellipse` (axes in m, major axis in radians from north) around
 * `[lat, lon]`, as `n` points `[lat, lon]` (a local flat-earth step: the ellipses are
 * kilometres across, where the error of that is centimetres).
 */
export function ellipsePolygon(centre: [number, number], e: Wire.Ellipse, n = 48): [number, number][] {
  const [lat0, lon0] = centre;
  const phi = e.major_axis_rad;
  const u = [Math.cos(phi), Math.sin(phi)]; // major axis (north, east)
  const v = [-Math.sin(phi), Math.cos(phi)]; // minor axis
  const perLonM = EARTH_RADIUS_M * Math.cos((lat0 * Math.PI) / 180);
  const points: [number, number][] = [];
  for (let k = 0; k < n; k++) {
    const t = (2 * Math.PI * k) / n;
    const a = e.semi_major_m * Math.cos(t);
    const b = e.semi_minor_m * Math.sin(t);
    const north = a * u[0]! + b * v[0]!;
    const east = a * u[1]! + b * v[1]!;
    points.push([lat0 + (north / EARTH_RADIUS_M) * (180 / Math.PI), lon0 + (east / perLonM) * (180 / Math.PI)]);
  }
  return points;
}

/** One line per band a recording's ascent measured, lowest first: its altitudes, wind, 1-σ (the
 * larger component's) and whether the plan merged it or why it was refused. */
export function measuredLines(m: Wire.MeasuredAscentView): { text: string; refused: boolean }[] {
  return m.bands.map((b) => {
    const sigma = Math.max(b.sigma_north_mps, b.sigma_east_mps);
    const wind = `${b.alt_min_msl_m.toFixed(0)}–${b.alt_max_msl_m.toFixed(0)} m MSL: ${b.speed_mps.toFixed(1)} m/s from ${b.from_deg.toFixed(0)}°, 1σ ${sigma.toFixed(2)} m/s`;
    return b.refused === null ? { text: `${wind} · merged`, refused: false } : { text: `${wind} · refused: ${b.refused}`, refused: true };
  });
}
