// The Lab page: edit the vehicle (units and the seed's values beside each field, checked by the
// station with the model's own rules), run a scenario, a Monte Carlo batch, the stability
// analysis or a tuning run in the station's background, compare a recording of the station
// with the model (recorded and modelled side by side per channel, with the error table) or fit
// chosen coefficients to it (table with intervals, correlation matrix, the fitted values into
// the form or as a file), follow its progress (cancel a batch, a comparison or a fit), and see
// the plots; save a vehicle or gains file, send tuned gains to the drone after a confirmation;
// fly the simulated drone's mission again with the vehicle as edited or fitted (`--sim` only).
// Operators run and save; viewers see the results only (the station refuses them anyway).
// The status is polled: twice a second while a job runs, every 3 s otherwise.

import "../styles/common.css";
import "../styles/lab.css";
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { Api, ApiError } from "../lib/api";
import { complexPlane, identifyParams, metres, outcomeLine, progressOf, recordingOption, recordingWindow, vehicleEdits } from "../lib/lab";
import { isObj } from "../lib/parse";
import { resolveToken, searchWithoutToken, withToken } from "../lib/token";
import type * as Wire from "../generated/api";
import { h, s, setText } from "../ui/dom";
import { compareView } from "../ui/labCompare";
import { identifyView } from "../ui/labIdentify";
import { applyRole } from "../ui/role";

const SCENARIOS = ["uncontrolled", "spiral-exit", "spiral-landing", "vertical", "localizer", "stratospheric"];
const CONTROLLERS = ["heading", "course", "localizer", "vertical"];

const token = resolveToken(location.search, sessionStorage);
if (new URLSearchParams(location.search).has("token")) history.replaceState(null, "", `${location.pathname}${searchWithoutToken(location.search)}`);
const api = new Api(token);

let operator = false;
let fields: Wire.VehicleField[] = [];
const typed = new Map<string, string>();
let shownResult = -1;
let lastGains: Record<string, number> | null = null;

const num = (id: string, value: string, min: string, max: string, step = "any") =>
  h("input", { type: "number", "data-testid": id, value, min, max, step });

const el = {
  role: h("span", { "data-testid": "lab-role" }),
  vehicleRows: h("tbody"),
  vehicleMsg: h("div", { "data-testid": "vehicle-msg", role: "status" }),
  vehicleName: h("input", { type: "text", "data-testid": "vehicle-name", placeholder: "file name" }),
  rehearse: h("button", { type: "button", "data-testid": "vehicle-rehearse", "data-role": "operator" }, "Rehearse with this vehicle"),
  rehearsal: h("div", { "data-testid": "rehearsal-status", class: "note", role: "status" }),
  kind: h("select", { "data-testid": "job-kind" }, ...["scenario", "monte_carlo", "stability", "tune"].map((k) => h("option", { value: k }, k.replace("_", " ")))),
  scenario: h("select", { "data-testid": "job-scenario" }, ...SCENARIOS.map((n) => h("option", { value: n }, n))),
  runs: num("mc-runs", "20", "1", "500", "1"),
  seed: num("mc-seed", "1", "0", "1000000000", "1"),
  wind: num("mc-wind", "4", "0", "15"),
  releaseAlt: num("mc-altitude", "600", "50", "3000"),
  trimAlt: num("trim-altitude", "100", "-5000", "86000"),
  // Tuning flies 14-DOF steps from its trim: at 100 m they reach the ground, so it has its own height.
  tuneAlt: num("tune-altitude", "600", "-5000", "86000"),
  controller: h("select", { "data-testid": "tune-controller" }, ...CONTROLLERS.map((n) => h("option", { value: n }, n))),
  start: h("button", { type: "button", "data-testid": "job-start", "data-role": "operator" }, "Run"),
  cancel: h("button", { type: "button", "data-testid": "job-cancel", "data-role": "operator" }, "Cancel"),
  recording: h("select", { "data-testid": "compare-recording", class: "recording-picker" }),
  recordingsRefresh: h("button", { type: "button", "data-testid": "compare-refresh" }, "Refresh"),
  compare: h("button", { type: "button", "data-testid": "compare-start", "data-role": "operator" }, "Compare"),
  windowFrom: h("input", { type: "number", "data-testid": "window-from", min: "0", step: "any", placeholder: "start" }),
  windowTo: h("input", { type: "number", "data-testid": "window-to", min: "0", step: "any", placeholder: "end" }),
  identifyParams: h("input", { type: "text", "data-testid": "identify-params", value: "cl_alpha, cd0", class: "params-input", "aria-label": "parameters to fit" }),
  identify: h("button", { type: "button", "data-testid": "identify-start", "data-role": "operator" }, "Identify"),
  progress: h("progress", { "data-testid": "job-progress", max: "1" }),
  progressLabel: h("div", { "data-testid": "job-progress-label", role: "status" }),
  jobMsg: h("div", { "data-testid": "job-msg", class: "error", role: "alert" }),
  outcome: h("div", { "data-testid": "job-outcome" }),
  results: h("div", { class: "plots", "data-testid": "lab-results" }),
};

function jobBody(): Wire.LabJobBody {
  const edits = vehicleEdits(fields, typed).edits;
  const n = (i: HTMLInputElement) => Number(i.value);
  switch (el.kind.value) {
    case "monte_carlo":
      return { kind: "monte_carlo", runs: n(el.runs), seed: n(el.seed), wind_max_mps: n(el.wind), altitude_m: n(el.releaseAlt) };
    case "stability":
      return { kind: "stability", altitude_m: n(el.trimAlt), vehicle: edits };
    case "tune":
      return { kind: "tune", controller: el.controller.value, altitude_m: n(el.tuneAlt) };
    default:
      return { kind: "scenario", scenario: el.scenario.value, vehicle: edits };
  }
}

/** Shows why a request was refused. */
function showError(e: unknown, where: HTMLElement): void {
  if (e instanceof ApiError) setText(where, `${e.error}: ${e.reason}`);
  else setText(where, String(e));
}

/** The vehicle field a refusal names: its reason starts with the field's dotted name. */
function fieldOf(e: ApiError): string | null {
  const head = e.reason.split(": ")[0] ?? "";
  return fields.some((f) => f.name === head) ? head : null;
}

function vehicleTable(): void {
  el.vehicleRows.replaceChildren(
    ...fields.map((f) => {
      const input = h("input", { type: "text", "data-testid": `vehicle-${f.name}`, value: String(f.seed), "data-role": "operator" });
      input.addEventListener("input", () => typed.set(f.name, input.value));
      // The rule a value breaks goes under its name: a fifth column widened the table out of its panel.
      return h("tr", { "data-field": f.name },
        h("td", { class: "vehicle-name" }, f.name, h("div", { class: "field-error", "data-testid": `vehicle-error-${f.name}` })),
        h("td", {}, input), h("td", {}, f.unit), h("td", { class: "note" }, String(f.seed)));
    }),
  );
}

function vehicleRequest(): { vehicle: Record<string, number> } | null {
  const { edits, errors } = vehicleEdits(fields, typed);
  const bad = Object.entries(errors)[0];
  if (bad !== undefined) {
    setText(el.vehicleMsg, `${bad[0]}: ${bad[1]}`);
    return null;
  }
  return { vehicle: edits };
}

async function checkVehicle(): Promise<void> {
  const body = vehicleRequest();
  if (!body) return;
  setText(el.vehicleMsg, "");
  if ((await post(api, "/api/lab/vehicle/check", body, el.vehicleMsg)) !== null) setText(el.vehicleMsg, `valid (${Object.keys(body.vehicle).length} changed from the seed)`);
}

async function saveVehicle(): Promise<void> {
  const body = vehicleRequest();
  if (!body) return;
  const saved = await post(api, "/api/lab/vehicle/save", { ...body, name: el.vehicleName.value }, el.vehicleMsg);
  if (isObj(saved) && typeof saved.path === "string") setText(el.vehicleMsg, `saved ${saved.path}`);
}

/** The simulated drone flies its mission again from the start with the vehicle as edited (or
 * as fitted, once a fit's values are in the form) as its truth. */
async function rehearse(): Promise<void> {
  const body = vehicleRequest();
  if (!body) return;
  setText(el.vehicleMsg, "");
  const r = await post(api, "/api/lab/rehearse", body, el.vehicleMsg);
  if (isObj(r) && typeof r.mission === "string") {
    setText(el.vehicleMsg, `the simulated drone flies ${r.mission} again from its start with this vehicle (${Object.keys(body.vehicle).length} changed from the seed)`);
    void poll();
  }
}

/** What the simulated drone flies, as the Lab last set it. */
function rehearsalLine(st: Wire.LabStatusBody): string {
  if (!st.rehearse) return "this station flies no simulated drone to rehearse with (stx serve --sim)";
  const r = st.rehearsal;
  if (!r) return "the simulated drone flies the vehicle it was started with";
  const changed = Object.entries(r.vehicle).map(([k, v]) => `${k} ${v}`).join(", ");
  return `the simulated drone flies ${r.mission} with ${changed === "" ? "the seed's vehicle" : changed} (restarted by ${r.started_by})`;
}

/** POSTs; a refusal is shown in `where` and, naming a vehicle field, on its row. */
async function post(a: Api, path: string, body: unknown, where: HTMLElement): Promise<unknown> {
  for (const row of el.vehicleRows.querySelectorAll("tr.invalid")) row.classList.remove("invalid");
  for (const cell of el.vehicleRows.querySelectorAll(".field-error")) cell.textContent = "";
  try {
    return await a.post(path, body);
  } catch (e) {
    showError(e, where);
    const field = e instanceof ApiError ? fieldOf(e) : null;
    if (e instanceof ApiError && field !== null) {
      const row = el.vehicleRows.querySelector<HTMLElement>(`tr[data-field="${CSS.escape(field)}"]`);
      if (row) {
        row.classList.add("invalid");
        const cell = row.querySelector(".field-error");
        if (cell) cell.textContent = e.reason.slice(field.length + 2);
      }
    }
    return null;
  }
}

async function start(): Promise<void> {
  setText(el.jobMsg, "");
  const r = await post(api, "/api/lab/jobs", jobBody(), el.jobMsg);
  if (r !== null) void poll();
}

/** Fills the recording picker from the station's recordings directory, keeping the choice. */
async function loadRecordings(): Promise<void> {
  try {
    const list = await api.get<Wire.RecordingsBody>("/api/recordings");
    // The choice as it is when the list arrives: one made while the list was on its way is kept
    // (read before the request, it was lost, and Compare flew another recording).
    const chosen = el.recording.value;
    const options = list.recordings.map(recordingOption).map((o) => h("option", { value: o.value }, o.label));
    if (options.length === 0) options.push(h("option", { value: "", disabled: true }, list.directory === null ? "this station keeps no recordings" : "no recordings yet"));
    el.recording.replaceChildren(...options);
    if (list.recordings.some((r) => r.name === chosen)) el.recording.value = chosen;
  } catch (e) {
    showError(e, el.jobMsg);
  }
}

/** The window typed for compare and identify, or null after saying what is wrong with it. */
function windowAsked(): { from_s?: number; to_s?: number } | null {
  const w = recordingWindow(el.windowFrom.value, el.windowTo.value);
  if ("error" in w) {
    setText(el.jobMsg, `window: ${w.error}`);
    return null;
  }
  return w;
}

async function compare(): Promise<void> {
  setText(el.jobMsg, "");
  if (el.recording.value === "") {
    setText(el.jobMsg, "choose a recording to compare");
    return;
  }
  const span = windowAsked();
  if (span === null) return;
  const body: Wire.LabJobBody = { kind: "compare", recording: el.recording.value, vehicle: vehicleEdits(fields, typed).edits, ...span };
  const r = await post(api, "/api/lab/jobs", body, el.jobMsg);
  if (r !== null) void poll();
}

async function identify(): Promise<void> {
  setText(el.jobMsg, "");
  if (el.recording.value === "") {
    setText(el.jobMsg, "choose a recording to identify from");
    return;
  }
  const asked = identifyParams(el.identifyParams.value);
  if ("error" in asked) {
    setText(el.jobMsg, `parameters: ${asked.error}`);
    return;
  }
  const span = windowAsked();
  if (span === null) return;
  const body: Wire.LabJobBody = { kind: "identify", recording: el.recording.value, params: asked.params, vehicle: vehicleEdits(fields, typed).edits, ...span };
  const r = await post(api, "/api/lab/jobs", body, el.jobMsg);
  if (r !== null) void poll();
}

/** Puts values into the vehicle form as if typed there. */
function fillVehicle(edits: Record<string, number>): void {
  for (const [name, value] of Object.entries(edits)) {
    typed.set(name, String(value));
    const input = el.vehicleRows.querySelector<HTMLInputElement>(`input[data-testid="vehicle-${CSS.escape(name)}"]`);
    if (input) input.value = String(value);
  }
}

async function cancel(): Promise<void> {
  try {
    await api.post("/api/lab/cancel", {});
  } catch (e) {
    showError(e, el.jobMsg);
  }
  void poll();
}

function timeChart(title: string, x: number[], series: { label: string; data: number[]; color: string }[], testid: string): HTMLElement {
  const box = h("div", { "data-testid": testid }, h("h2", {}, title));
  const width = Math.max(320, Math.min(900, (el.results.clientWidth || 700) - 20));
  const opts: uPlot.Options = {
    width,
    height: 180,
    scales: { x: { time: false } },
    series: [{ label: "t s" }, ...series.map((s) => ({ label: s.label, stroke: s.color }))],
  };
  new uPlot(opts, [x, ...series.map((s) => s.data)], box);
  return box;
}

function svgPlot(testid: string, title: string, points: [number, number][], seed: [number, number][], xLabel: string, yLabel: string): HTMLElement {
  const box = { width: 420, height: 260, margin: 24 };
  const p = complexPlane([...points, ...seed], box);
  const svg = s("svg", { width: box.width, height: box.height, "data-testid": testid });
  svg.append(s("line", { x1: 0, x2: box.width, y1: p.y(0), y2: p.y(0), stroke: "#999" }));
  svg.append(s("line", { x1: p.x(0), x2: p.x(0), y1: 0, y2: box.height, stroke: "#999" }));
  for (const [re, im] of seed) svg.append(s("circle", { cx: p.x(re), cy: p.y(im), r: 5, fill: "none", stroke: "#c05800", class: "seed-point" }));
  for (const [re, im] of points) if (Number.isFinite(re) && Number.isFinite(im)) svg.append(s("circle", { cx: p.x(re), cy: p.y(im), r: 3, fill: "#0b2f8a", class: "point" }));
  svg.append(s("text", { x: box.width - 4, y: p.y(0) - 4, "text-anchor": "end", "font-size": 11 }, xLabel));
  svg.append(s("text", { x: p.x(0) + 4, y: 12, "font-size": 11 }, yLabel));
  return h("div", {}, h("h2", {}, title), svg);
}

function table(testid: string, rows: [string, string, string?][]): HTMLElement {
  return h("table", { "data-testid": testid }, h("tr", {}, h("th", {}, ""), h("th", {}, "stx"), h("th", {}, "seed")), ...rows.map(([k, v, seed]) => h("tr", {}, h("td", {}, k), h("td", {}, v), h("td", { class: "note" }, seed ?? ""))));
}

/** A tuning run's result (the contract inlines each kind of result in `LabResult`). */
type TuneResult = Extract<Wire.LabResult, { kind: "tune" }>;

/** A step cost, or "–" where the 14-DOF step failed. */
const cost = (c: number | null): string => (c === null ? "–" : c.toFixed(3));

function gainsPanel(t: TuneResult): HTMLElement {
  const gains: Record<string, number> = {};
  for (const [k, v] of Object.entries(t.gains)) if (v !== undefined) gains[k] = v;
  lastGains = gains;
  const name = h("input", { type: "text", "data-testid": "gains-name", placeholder: "file name", "data-role": "operator" });
  const msg = h("div", { "data-testid": "gains-msg", role: "status" });
  const save = h("button", { type: "button", "data-testid": "gains-save", "data-role": "operator" }, "Save gains file");
  const send = h("button", { type: "button", "data-testid": "gains-send", "data-role": "operator" }, "Send gains to the drone…");
  const confirm = h("button", { type: "button", "data-testid": "gains-confirm", "data-role": "operator", hidden: true }, "Confirm: set these parameters on the drone");
  save.addEventListener("click", async () => {
    const r = await post(api, "/api/lab/gains/save", { gains: lastGains, name: name.value }, msg);
    if (isObj(r) && typeof r.path === "string") setText(msg, `saved ${r.path}`);
  });
  send.addEventListener("click", () => {
    confirm.hidden = false;
    setText(msg, `${Object.keys(gains).length} parameters will change the drone's guidance in flight.`);
  });
  confirm.addEventListener("click", async () => {
    confirm.hidden = true;
    const r = await post(api, "/api/lab/gains/send", { gains: lastGains, confirm: true }, msg);
    if (isObj(r) && Array.isArray(r.request_ids)) setText(msg, `sent: ${r.request_ids.length} parameter requests (see the dashboard's command list)`);
  });
  const rows = Object.entries(gains).map(([k, v]) => [k, v.toPrecision(4)] as [string, string]);
  const panel = h("div", { "data-testid": "tune-result" }, h("h2", {}, `Tuned ${t.controller}: cost ${cost(t.cost_before)} → ${cost(t.cost_tuned)} (seed's gains ${cost(t.cost_seed)})`), table("tune-gains", rows), h("div", { class: "row" }, name, save, send, confirm), msg);
  applyRole(panel, operator);
  return panel;
}

function showResult(r: Wire.LabResult): void {
  const parts: HTMLElement[] = [];
  if (r.kind === "scenario") {
    parts.push(timeChart(`Height above release — ${r.scenario}`, r.time_s, [{ label: "height m", data: r.height_m, color: "#0b2f8a" }], "plot-height"));
    parts.push(timeChart("Attitude", r.time_s, [{ label: "roll °", data: r.roll_deg, color: "#0b2f8a" }, { label: "pitch °", data: r.pitch_deg, color: "#c05800" }, { label: "yaw °", data: r.yaw_deg, color: "#006400" }], "plot-attitude"));
    parts.push(timeChart("Airspeed, sink rate", r.time_s, [{ label: "airspeed m/s", data: r.airspeed_mps, color: "#0b2f8a" }, { label: "sink m/s", data: r.sink_mps, color: "#c05800" }], "plot-speeds"));
    parts.push(timeChart("Position", r.time_s, [{ label: "north m", data: r.north_m, color: "#0b2f8a" }, { label: "east m", data: r.east_m, color: "#c000c0" }], "plot-position"));
  } else if (r.kind === "monte_carlo") {
    parts.push(
      h("div", { "data-testid": "mc-result" }, h("h2", {}, `Monte Carlo: ${r.runs_flown} of ${r.runs_asked} runs flown, ${r.failed_runs} failed`),
        table("mc-stats", [
          ["miss median", metres(r.miss_median_m)],
          ["miss p95", metres(r.miss_p95_m)],
          ["miss max", metres(r.miss_max_m)],
          ["into the wind", `${(100 * r.into_wind_fraction).toFixed(0)} %`],
          ["payload touchdown vertical speed (median)", `${r.touchdown_vertical_speed_median_mps.toFixed(2)} m/s`],
        ])),
    );
    parts.push(svgPlot("mc-landings", "Landings from the target (long along the upwind direction, right across it)", r.landings_long_right_m.map(([l, rr]) => [rr, l]), [], "right m", "long m"));
  } else if (r.kind === "stability") {
    parts.push(svgPlot("eigen-plot", "Eigenvalues (● stx, ○ seed §6.2.1)", r.eigenvalues, r.seed_eigenvalues, "Re 1/s", "Im 1/s"));
    parts.push(table("stability-ranks", [
      ["trim airspeed", `${r.airspeed_mps.toFixed(2)} m/s`],
      ["trim sink rate", `${r.sink_rate_mps.toFixed(2)} m/s`, "3.1"],
      ["glide ratio", r.glide_ratio.toFixed(2), "≈2"],
      ["zero eigenvalues", String(r.zero_eigenvalues), String(r.seed_zero_eigenvalues)],
      ["controllability rank", String(r.controllability_rank), String(r.seed_controllability_rank)],
      ["observability rank", String(r.observability_rank), String(r.seed_observability_rank)],
    ]));
    for (const w of r.warnings) parts.push(h("div", { class: "note" }, `warning: ${w}`));
  } else if (r.kind === "tune") {
    parts.push(gainsPanel(r));
  } else if (r.kind === "compare") {
    const columns = (el.results.clientWidth || 700) >= 900 ? 3 : 2;
    parts.push(...compareView(r, Math.max(260, Math.floor((el.results.clientWidth || 700) / columns) - 16)));
  } else if (r.kind === "identify") {
    parts.push(...identifyView(r, fields, fillVehicle));
  }
  el.results.replaceChildren(...parts);
}

let timer: ReturnType<typeof setTimeout> | null = null;

async function poll(): Promise<void> {
  if (timer !== null) clearTimeout(timer);
  let status: Wire.LabStatusBody | null = null;
  try {
    status = await api.get<Wire.LabStatusBody>("/api/lab");
  } catch (e) {
    showError(e, el.jobMsg);
  }
  if (status) render(status);
  timer = setTimeout(() => void poll(), status?.job ? 500 : 3000);
}

function render(st: Wire.LabStatusBody): void {
  if (!st.available) setText(el.jobMsg, "this station runs no Lab");
  const job = st.job;
  el.start.disabled = !operator || job !== null || !st.available;
  el.cancel.disabled = !operator || job === null;
  el.compare.disabled = el.start.disabled;
  el.identify.disabled = el.start.disabled;
  el.rehearse.disabled = !operator || !st.rehearse;
  setText(el.rehearsal, rehearsalLine(st));
  if (job) {
    const p = progressOf(job);
    if (p.fraction === null) el.progress.removeAttribute("value");
    else el.progress.value = p.fraction;
    setText(el.progressLabel, p.label);
  } else {
    el.progress.value = 0;
    setText(el.progressLabel, "idle");
  }
  const last = st.last;
  setText(el.outcome, last ? outcomeLine(last) : "no job yet");
  if (last && last.id !== shownResult) {
    shownResult = last.id;
    if (last.result) showResult(last.result);
    else el.results.replaceChildren();
  }
}

async function main(): Promise<void> {
  const app = document.getElementById("app");
  if (!app) return;
  const session = await api.get<Wire.Session>("/api/session").catch((e: unknown) => {
    app.replaceChildren(h("p", { class: "error" }, e instanceof ApiError ? e.message : String(e)));
    return null;
  });
  if (!session) return;
  operator = session.role === "operator";
  setText(el.role, `${session.name} (${session.role}${operator ? "" : ": results only"})`);
  fields = (await api.get<Wire.VehicleFieldsBody>("/api/lab/vehicle")).fields;
  vehicleTable();
  const check = h("button", { type: "button", "data-testid": "vehicle-check" }, "Check");
  const save = h("button", { type: "button", "data-testid": "vehicle-save", "data-role": "operator" }, "Save vehicle file");
  check.addEventListener("click", () => void checkVehicle());
  save.addEventListener("click", () => void saveVehicle());
  el.rehearse.addEventListener("click", () => void rehearse());
  el.start.addEventListener("click", () => void start());
  el.cancel.addEventListener("click", () => void cancel());
  el.compare.addEventListener("click", () => void compare());
  el.identify.addEventListener("click", () => void identify());
  el.recordingsRefresh.addEventListener("click", () => void loadRecordings());
  const dashboard = h("a", { href: withToken("index.html", token), "data-testid": "dashboard-link" }, "Dashboard");
  const page = h("div", {},
    h("header", {}, h("strong", {}, "stx — Lab"), el.role, dashboard),
    h("main", {},
      h("div", {},
        h("section", {}, h("h2", {}, "Vehicle (seed: STRAPLEX, config/vehicle/straplex.toml)"),
          h("table", { class: "vehicle-table" }, h("thead", {}, h("tr", {}, h("th", {}, "parameter"), h("th", {}, "value"), h("th", {}, "unit"), h("th", {}, "seed"))), el.vehicleRows),
          h("div", { class: "row" }, check, el.vehicleName, save, el.rehearse), el.vehicleMsg, el.rehearsal),
        h("section", {}, h("h2", {}, "Run"),
          h("div", { class: "row" }, h("label", {}, "job ", el.kind)),
          h("div", { class: "row" }, h("label", {}, "scenario ", el.scenario)),
          h("div", { class: "row" }, h("label", {}, "runs ", el.runs), h("label", {}, "seed ", el.seed), h("label", {}, "wind max m/s ", el.wind), h("label", {}, "release height m ", el.releaseAlt)),
          h("div", { class: "row" }, h("label", {}, "trim altitude m ", el.trimAlt)),
          h("div", { class: "row" }, h("label", {}, "controller ", el.controller), h("label", {}, "tune at m ", el.tuneAlt)),
          h("div", { class: "row" }, el.start, el.cancel),
          h("h2", {}, "A recorded flight: compare with the model, identify coefficients"),
          h("div", { class: "row" }, h("label", { class: "recording-label" }, "recording ", el.recording), el.recordingsRefresh),
          h("div", { class: "row" }, h("label", {}, "from s ", el.windowFrom), h("label", {}, "to s ", el.windowTo)),
          h("div", { class: "row note" }, "its parafoil stage (a mission's ascent, round chute and canopy inflation left out), or the window typed, in s from its start; flown from its first recorded state with its servo commands and wind estimate, by the vehicle as edited above"),
          h("div", { class: "row" }, el.compare),
          h("div", { class: "row" }, h("label", {}, "parameters ", el.identifyParams), el.identify),
          h("div", { class: "row note" }, "fits the named coefficients of the vehicle as edited to the recording by least squares (names as in the vehicle file: cl_alpha, cd0, cn_da, …; rigging_deg for the rigging angle)"),
          el.progress, el.progressLabel, el.jobMsg, el.outcome)),
      h("section", {}, h("h2", {}, "Results"), el.results)));
  app.replaceChildren(page);
  applyRole(page, operator);
  await loadRecordings();
  await poll();
}

void main();
