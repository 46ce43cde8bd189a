// The Lab's identification of vehicle parameters from a recording, drawn: what was fitted and
// how well (iterations, why it stopped, residual RMS before and after in multiples of the
// sensor noise), the table of parameters (before, fitted, standard error, 95 % interval), the
// correlation matrix shaded by strength (two strongly correlated coefficients are what a flight
// cannot tell apart), and the ways to keep the result: into the vehicle form (then Check, Save,
// or fly it in a scenario or a comparison) or as the fitted vehicle file.

import { correlationCells, fittedEdits, identifyRows, type IdentifyResult, type VehicleField } from "../lib/lab";
import { h } from "./dom";

/** Fills the vehicle form with these edits (field name → value). */
export type ApplyEdits = (edits: Record<string, number>) => void;

function correlationTable(r: IdentifyResult): HTMLElement {
  const cells = correlationCells(r);
  if (cells === null) return h("div", { class: "note", "data-testid": "identify-correlation" }, "no correlation matrix: the flight does not tell these parameters apart");
  const names = r.params.map((p) => p.name);
  const header = h("tr", {}, h("th", {}, ""), ...names.map((n) => h("th", {}, n)));
  const rows = cells.map((row, i) =>
    h("tr", {}, h("th", {}, names[i] ?? ""), ...row.map((text, j) => {
      const c = r.correlation?.[i]?.[j] ?? 0;
      const shade = i === j || !Number.isFinite(c) ? "" : `background: rgba(192, 88, 0, ${(0.6 * Math.abs(c)).toFixed(2)})`;
      return h("td", { style: shade }, text);
    })),
  );
  return h("table", { "data-testid": "identify-correlation", class: "correlation" }, h("caption", {}, "correlation of the estimates"), header, ...rows);
}

/** The parts of the Lab's results for an identification; `apply` fills the vehicle form. */
export function identifyView(r: IdentifyResult, fields: readonly VehicleField[], apply: ApplyEdits): HTMLElement[] {
  const vehicle = r.vehicle_changes.length === 0 ? "the seed's vehicle" : `the vehicle with ${r.vehicle_changes.join(", ")}`;
  const head = h("h2", { "data-testid": "identify-summary" },
    `${r.recording}: ${r.params.length} parameter${r.params.length === 1 ? "" : "s"} fitted from ${vehicle} in ${r.iterations} iterations (${r.stop}); residual RMS ${r.residual_rms_before.toFixed(2)} → ${r.residual_rms_after.toFixed(2)} × sensor noise`);
  const header = h("tr", {}, ...["parameter", "before", "fitted", "standard error", "95 % interval", "change"].map((t) => h("th", {}, t)));
  const rows = identifyRows(r).map((cells) => h("tr", { "data-param": cells[0] }, ...cells.map((t) => h("td", {}, t))));
  const table = h("table", { "data-testid": "identify-params" }, header, ...rows);

  const { edits, apart } = fittedEdits(r, fields);
  const msg = h("div", { "data-testid": "identify-msg", role: "status" });
  const use = h("button", { type: "button", "data-testid": "identify-apply", "data-role": "operator", disabled: Object.keys(edits).length === 0 }, "Put the fitted values into the vehicle form");
  use.addEventListener("click", () => {
    apply(edits);
    const left = apart.length === 0 ? "" : `; ${apart.join(", ")} only in the fitted file`;
    msg.textContent = `${Object.keys(edits).length} fitted value${Object.keys(edits).length === 1 ? "" : "s"} in the form (Check, then Save or fly it)${left}`;
  });
  const file = URL.createObjectURL(new Blob([r.vehicle_toml], { type: "application/toml" }));
  const download = h("a", { href: file, download: `identified-${r.recording.replace(/\.[^.]*$/, "")}.toml`, "data-testid": "identify-download" }, "Download the fitted vehicle file");
  const toml = h("details", {}, h("summary", {}, "fitted vehicle file"), h("pre", { "data-testid": "identify-toml" }, r.vehicle_toml));
  return [h("div", { "data-testid": "identify-result" }, head, table, correlationTable(r), h("div", { class: "row" }, use, download), msg, toml)];
}
