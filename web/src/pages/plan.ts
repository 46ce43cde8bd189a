// The Plan page: a pre-flight plan from the launch site, the balloon's settings and their spread,
// and a forecast (or the ascent wind an earlier recording measured), computed by the station
// (`POST /api/plan`, the same plan as `stx plan`). The form starts from the station's own launch
// site, forecast and target (`GET /api/plan/defaults`); the result is the burst, deploy and
// landing points with their 1-σ ellipses on the station's map, the unsteered landings, the region
// steering likely reaches and the target's reachability, and with a recording the wind bands its
// ascent measured, each merged into the forecast or refused with the reason. Errors, the page's or the station's,
// are shown beside the form. A forecast file (GFS GRIB2 or a Wyoming sounding) sent to the
// station (`POST /api/plan/forecast`) becomes the forecast rows over the launch site; over it or
// the station's configured GFS file the launch window (`POST /api/plan/window`) plans every
// launch time and shows them as a strip, the best marked ★.

import "../styles/common.css";
import "../styles/plan.css";
import type * as Wire from "../generated/api";
import { Api, ApiError } from "../lib/api";
import { fmtLatLon } from "../lib/format";
import { parseSession } from "../lib/parse";
import { buildWindow, stripRows } from "../lib/launchWindow";
import { type PlanForm, buildRequest, forecastText, formOf, measuredLines } from "../lib/preflight";
import { resolveToken, searchWithoutToken } from "../lib/token";
import { h, setText } from "../ui/dom";
import { PreflightMap } from "../ui/preflightMap";

const token = resolveToken(location.search, sessionStorage);
if (new URLSearchParams(location.search).has("token")) history.replaceState(null, "", `${location.pathname}${searchWithoutToken(location.search)}`);
const api = new Api(token);

/** Each box: its field, label, unit (shown beside the label; the seed is a bare number) and what it takes. */
const BOXES: [Exclude<keyof PlanForm, "forecast" | "from_recording">, string, string | null, string][] = [
  ["launch_lat_deg", "Launch latitude", "° N", "degrees north"],
  ["launch_lon_deg", "Launch longitude", "° E", "degrees east"],
  ["launch_alt_msl_m", "Launch altitude", "m MSL", "m above sea level"],
  ["ascent_rate_mps", "Ascent rate", "m/s", "m/s, mean to burst"],
  ["ascent_rate_sigma_mps", "± ascent rate", "m/s, 1 σ", "1-σ, m/s"],
  ["burst_altitude_msl_m", "Burst altitude", "m MSL", "m above sea level"],
  ["burst_altitude_sigma_m", "± burst altitude", "m, 1 σ", "1-σ, m"],
  ["deploy_height_m", "Deploy height", "m above launch", "m above the launch site"],
  ["default_wind_sigma_mps", "Wind σ", "m/s", "m/s, for rows without a sigma"],
  ["runs", "Runs", "samples", "Monte Carlo samples"],
  ["seed", "Seed", null, "same seed, same plan"],
  ["target_lat_deg", "Target latitude", "° N", "degrees north; empty: none"],
  ["target_lon_deg", "Target longitude", "° E", "degrees east"],
];

const inputs = new Map<keyof PlanForm, HTMLInputElement | HTMLTextAreaElement | HTMLSelectElement>();
for (const [field, , , title] of BOXES) inputs.set(field, h("input", { type: "text", inputmode: "decimal", id: `plan-${field}`, "data-testid": `plan-in-${field}`, title }));
const forecastBox = h("textarea", { id: "plan-forecast", "data-testid": "plan-in-forecast", spellcheck: "false", title: "one row a line: alt_msl_m,speed_mps,from_deg[,sigma_mps]" });
inputs.set("forecast", forecastBox);
const recordingBox = h("select", { id: "plan-from_recording", "data-testid": "plan-in-from_recording" }, h("option", { value: "" }, "none: the forecast alone"));
inputs.set("from_recording", recordingBox);
const submit = h("button", { type: "submit", "data-testid": "plan-submit" }, "Plan");
const error = h("div", { class: "plan-error", role: "alert", "data-testid": "plan-error", hidden: true });
const status = h("div", { class: "small muted wide", role: "status", "data-testid": "plan-status" });

const fileBox = h("input", { type: "file", id: "plan-file", "data-testid": "plan-file", title: "a GFS GRIB2 file (pgrb2, or a NOMADS filter subset with UGRD, VGRD, HGT) or a University of Wyoming sounding (TEXT:LIST)" });
const fileRead = h("button", { type: "button", "data-testid": "plan-file-read" }, "Use file as forecast");
const fileStatus = h("div", { class: "small wide", role: "status", "data-testid": "plan-file-status" });
const windowFrom = h("input", { type: "text", id: "plan-window-from", "data-testid": "plan-window-from", placeholder: "2026-11-30T06:00:00Z", title: "first launch time, UTC (RFC 3339)" });
const windowTo = h("input", { type: "text", id: "plan-window-to", "data-testid": "plan-window-to", placeholder: "2026-12-03T06:00:00Z", title: "last launch time, UTC (RFC 3339)" });
const windowEvery = h("input", { type: "text", inputmode: "decimal", id: "plan-window-every", "data-testid": "plan-window-every", value: "1", title: "hours between launch times" });
const windowSource = h("select", { id: "plan-window-source", "data-testid": "plan-window-source" }, h("option", { value: "configured" }, "the station's GFS file"));
const windowSubmit = h("button", { type: "button", "data-testid": "plan-window-submit" }, "Launch window");
const windowStatus = h("div", { class: "small", role: "status", "data-testid": "plan-window-status" });
const strip = h("section", { class: "plan-strip", "data-testid": "plan-window", hidden: true });

const form = h("form", { class: "plan-form", "data-testid": "plan-form", novalidate: true });
for (const [field, label, unit] of BOXES) form.append(h("label", { for: `plan-${field}`, "data-unit": unit ?? "" }, label, unit === null ? "" : h("span", { class: "unit" }, ` (${unit})`)), inputs.get(field)!);
form.append(
  h("label", { for: "plan-forecast", class: "wide" }, "Forecast (alt_msl_m,speed_mps,from_deg[,sigma_mps]; from: where the wind blows from)"),
  forecastBox,
  h("label", { for: "plan-file" }, "Forecast file"),
  fileBox,
  h("div", { class: "wide" }, fileRead),
  fileStatus,
  h("label", { for: "plan-from_recording" }, "Measured ascent"),
  recordingBox,
  h("div", { class: "wide" }, submit),
  status,
  error,
  h("strong", { class: "wide" }, "Launch window (GFS; the plan above at every launch time)"),
  h("label", { for: "plan-window-from" }, "From", h("span", { class: "unit" }, " (UTC)")),
  windowFrom,
  h("label", { for: "plan-window-to" }, "To", h("span", { class: "unit" }, " (UTC)")),
  windowTo,
  h("label", { for: "plan-window-every" }, "Every", h("span", { class: "unit" }, " (h)")),
  windowEvery,
  h("label", { for: "plan-window-source" }, "Winds from"),
  windowSource,
  h("div", { class: "wide" }, windowSubmit),
  windowStatus,
);

const out = {
  burst: h("div", { class: "line", "data-testid": "plan-burst" }),
  deploy: h("div", { class: "line", "data-testid": "plan-deploy" }),
  landing: h("div", { class: "line", "data-testid": "plan-landing" }),
  round: h("div", { class: "line", "data-testid": "plan-round" }),
  reach: h("div", { class: "line", "data-testid": "plan-reach" }),
  target: h("div", { class: "line", "data-testid": "plan-target" }),
};
const measured = h("section", { class: "plan-lines", "data-testid": "plan-measured", hidden: true });
const result = h("section", { class: "plan-lines", "data-testid": "plan-result", hidden: true }, ...Object.values(out), measured);
const mapSlot = h("div", {});
const app = document.getElementById("app")!;
app.replaceChildren(
  h("header", {}, h("strong", {}, "STRAPLEX pre-flight plan"), h("a", { href: "index.html", class: "small" }, "live page")),
  h("main", { class: "plan-main" }, form, h("div", { class: "plan-result" }, strip, result, mapSlot)),
);

let map: PreflightMap | null = null;

const clock = (s: number): string => {
  const t = Math.max(0, Math.round(s));
  return `${Math.floor(t / 3600)}:${String(Math.floor(t / 60) % 60).padStart(2, "0")}:${String(t % 60).padStart(2, "0")}`;
};

function pointLine(name: string, p: Wire.PlannedPoint): string {
  const e = p.ellipse;
  const axis = (((e.major_axis_rad * 180) / Math.PI) % 180 + 180) % 180;
  return `${name}: ${fmtLatLon(p.lat_deg, p.lon_deg)}, ${p.alt_msl_m.toFixed(0)} m MSL · N ${p.north_m.toFixed(0)} m, E ${p.east_m.toFixed(0)} m of launch · T+${clock(p.time_s)} ±${p.time_sigma_s.toFixed(0)} s · 1σ ${e.semi_major_m.toFixed(0)} × ${e.semi_minor_m.toFixed(0)} m at ${axis.toFixed(0)}°`;
}

function showPlan(plan: Wire.PreflightReport): void {
  setText(out.burst, pointLine("Burst", plan.burst));
  setText(out.deploy, pointLine("Parafoil deploy", plan.deploy));
  setText(out.landing, pointLine("Landing, unsteered", plan.landing_unsteered));
  setText(out.round, pointLine("Landing, round chute only", plan.round_chute_landing));
  const pct = (p: number): string => `${(100 * p).toFixed(0)} %`;
  setText(out.reach, `Steering reaches ${plan.steered_reach_radius_m.toFixed(0)} m around the drifted air mass on average; the green region is reached in ${pct(plan.steered_region_probability)} of the samples or more, no point in more than ${pct(plan.steered_region_best_probability)} (${plan.landing_samples_lat_lon_deg.length} landings drawn)`);
  const t = plan.target;
  setText(out.target, t ? `Target ${fmtLatLon(t.lat_deg, t.lon_deg)}: reachable in ${(100 * t.reachable_probability).toFixed(0)} % of the samples, ${t.from_unsteered_landing_m.toFixed(0)} m from the unsteered landing` : "No target given");
  const m = plan.measured_ascent;
  measured.hidden = m === null;
  measured.replaceChildren(
    ...(m === null
      ? []
      : [
          h("div", { class: "line" }, `Measured ascent of ${m.recording}: ${m.bands.filter((b) => b.refused === null).length} of ${m.bands.length} bands merged into the forecast`),
          ...measuredLines(m).map((l) => h("div", { class: l.refused ? "line plan-refused" : "line", "data-testid": "plan-measured-band" }, l.text)),
        ]),
  );
  result.hidden = false;
  map?.show(plan);
}

function showError(text: string, field: keyof PlanForm | null): void {
  for (const [f, el] of inputs) el.setAttribute("aria-invalid", String(f === field));
  error.hidden = text === "";
  setText(error, text);
}

form.addEventListener("submit", (ev) => {
  ev.preventDefault();
  void plan();
});

async function plan(): Promise<void> {
  const built = buildRequest(formValues());
  if (!built.ok) {
    showError(built.error, built.field);
    return;
  }
  showError("", null);
  submit.disabled = true;
  setText(status, "computing…");
  const started = performance.now();
  try {
    const report = await api.post<Wire.PreflightReport>("/api/plan", built.body);
    showPlan(report);
    setText(status, `planned ${report.request.runs} samples in ${((performance.now() - started) / 1000).toFixed(1)} s`);
  } catch (e) {
    // The station's reason names the field; it is shown as given.
    showError(e instanceof ApiError ? `${e.status} ${e.error}: ${e.reason}` : String(e), null);
    setText(status, "");
  } finally {
    submit.disabled = false;
  }
}

/** The form's values, as typed. */
const formValues = (): PlanForm => Object.fromEntries([...inputs].map(([f, el]) => [f, el.value])) as unknown as PlanForm;

fileRead.addEventListener("click", () => void readFile());

/** Sends the chosen file to the station and takes its rows over the launch site as the forecast. */
async function readFile(): Promise<void> {
  const file = fileBox.files?.[0];
  if (!file) {
    setText(fileStatus, "choose a file first");
    return;
  }
  const q = new URLSearchParams({ lat: inputs.get("launch_lat_deg")!.value.trim(), lon: inputs.get("launch_lon_deg")!.value.trim() });
  const from = windowFrom.value.trim();
  if (from !== "") q.set("time", from);
  setText(fileStatus, `sending ${file.name} (${(file.size / 1e6).toFixed(1)} MB)…`);
  fileRead.disabled = true;
  try {
    const up = await api.upload<Wire.ForecastUploadReport>(`/api/plan/forecast?${q}`, file);
    forecastBox.value = forecastText(up.rows);
    windowSource.querySelector("option[data-upload]")?.remove();
    if (up.kind === "gfs") {
      windowSource.prepend(h("option", { value: String(up.id), "data-upload": "" }, `${file.name} (upload ${up.id})`));
      windowSource.value = String(up.id);
      if (from === "") windowFrom.value = up.valid_times[0] ?? "";
      if (windowTo.value.trim() === "") windowTo.value = up.valid_times[up.valid_times.length - 1] ?? "";
    }
    setText(fileStatus, up.kind === "gfs" ? `${file.name}: GFS run ${up.gfs_run}, the wind at ${up.at} over the launch site, ${up.rows.length} levels (forecast hours ${up.valid_times[0]} to ${up.valid_times[up.valid_times.length - 1]})` : `${file.name}: a sounding, ${up.rows.length} levels`);
  } catch (e) {
    setText(fileStatus, e instanceof ApiError ? `${e.status} ${e.error}: ${e.reason}` : String(e));
  } finally {
    fileRead.disabled = false;
  }
}

windowSubmit.addEventListener("click", () => void planWindow());

/** Plans every launch time of the window and shows the strip. */
async function planWindow(): Promise<void> {
  const built = buildRequest(formValues());
  if (!built.ok) {
    showError(built.error, built.field);
    return;
  }
  const source: Wire.WindowForecast = windowSource.value === "configured" ? "configured" : { upload: Number(windowSource.value) };
  const body = buildWindow(built.body.request, windowFrom.value, windowTo.value, windowEvery.value, source);
  if (!body.ok) {
    setText(windowStatus, body.error);
    return;
  }
  windowSubmit.disabled = true;
  setText(windowStatus, "computing…");
  const started = performance.now();
  try {
    const report = await api.post<Wire.WindowReport>("/api/plan/window", body.body);
    showStrip(report);
    setText(windowStatus, `${report.launches.length} launch times × ${report.request.runs} samples in ${((performance.now() - started) / 1000).toFixed(1)} s (GFS run ${report.gfs_run})`);
  } catch (e) {
    setText(windowStatus, e instanceof ApiError ? `${e.status} ${e.error}: ${e.reason}` : String(e));
  } finally {
    windowSubmit.disabled = false;
  }
}

function showStrip(report: Wire.WindowReport): void {
  strip.replaceChildren(
    h("div", { class: "line" }, "Launch times: the share of samples from which steering reaches the target (bar), the unsteered landing and the burst; ★ the best 3 (highest share, then the landing nearest the target)"),
    ...stripRows(report).map((r) => {
      const bar = h("span", { class: "plan-strip-bar" });
      // Through the CSSOM: the station's Content-Security-Policy refuses style attributes.
      bar.style.width = `${r.sharePct.toFixed(1)}%`;
      return h(
        "div",
        { class: r.best ? "plan-strip-row best" : "plan-strip-row", "data-testid": "window-row", "data-time": r.time, "data-rank": String(r.rank), "data-share": r.sharePct.toFixed(3), "data-best": String(r.best) },
        bar,
        h("span", { class: "plan-strip-text" }, r.text),
      );
    }),
  );
  strip.hidden = false;
}

async function start(): Promise<void> {
  try {
    const session = parseSession(await api.get("/api/session"));
    if (!session.ok) throw new Error(session.error);
    map = new PreflightMap(session.value.station, token);
    mapSlot.replaceChildren(map.root);
    const defaults = await api.get<Wire.PreflightDefaults>("/api/plan/defaults");
    const filled = formOf(defaults.request);
    for (const [f, el] of inputs) if (f !== "from_recording") el.value = filled[f];
    setText(status, `from the station: launch site${defaults.request.forecast.length ? ", forecast" : " (no forecast configured)"}${defaults.target_source ? `, target (${defaults.target_source})` : ""}; at most ${defaults.max_runs} runs`);
    const list = await api.get<Wire.RecordingsBody>("/api/recordings");
    for (const r of list.recordings) recordingBox.append(h("option", { value: r.name }, r.name));
  } catch (e) {
    showError(e instanceof ApiError ? `${e.status} ${e.error}: ${e.reason}` : `cannot start: ${String(e)}`, null);
  }
}

void start();
