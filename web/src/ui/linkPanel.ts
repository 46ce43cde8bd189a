// Link quality: rate, loss, age of the last message, error counters (the station's and this
// page's own count of malformed WebSocket messages), each radio's own figures when the station
// holds more than one, and per-message ages in a details popover. Also the station's recording:
// a readout, and below it, while the disk refuses the recording, the problem, since when and the
// next try (then, once it resumes, when).

import { h, panel, readout, setText } from "./dom";
import { fmt, fmtDuration, fmtWallUtc } from "../lib/format";
import { messageAges, type StaleVerdict } from "../lib/staleness";
import type { MessageStats } from "../lib/parse";
import type { Link, Radio, Recording } from "../lib/types";

export class LinkPanel {
  readonly root: HTMLElement;
  private readonly rate: HTMLElement;
  private readonly loss: HTMLElement;
  private readonly age: HTMLElement;
  private readonly errors: HTMLElement;
  private readonly bad: HTMLElement;
  private readonly state: HTMLElement;
  private readonly rec: HTMLElement;
  private readonly recDetail: HTMLElement;
  private readonly agesBody: HTMLTableSectionElement;
  private readonly radiosTable: HTMLTableElement;
  private readonly radiosBody: HTMLTableSectionElement;

  constructor() {
    const r = readout("Rate", "link-rate");
    const l = readout("Loss", "link-loss");
    const a = readout("Last msg", "link-age", "age of the last message from the drone");
    const e = readout("CRC/parse/sig", "link-errors", "frames refused: CRC errors / parse errors / signature errors");
    const b = readout("Bad msgs", "link-bad-messages", "messages from the station this page could not read");
    const st = readout("Link", "link-state");
    const rec = readout("Recording", "recording-state", "the station's MCAP recording of this run");
    rec.root.classList.add("wide");
    [this.rate, this.loss, this.age, this.errors, this.bad, this.state, this.rec] = [r.value, l.value, a.value, e.value, b.value, st.value, rec.value];
    this.recDetail = h("div", { class: "rec-detail", "data-testid": "recording-problem", hidden: true });
    this.agesBody = h("tbody");
    const details = h("details", { class: "ages", "data-testid": "link-details" },
      h("summary", { "data-testid": "link-details-toggle" }, "Per-message ages"),
      h("table", { "data-testid": "link-ages-table" }, h("thead", {}, h("tr", {}, h("th", {}, "message"), h("th", {}, "age"))), this.agesBody));
    this.radiosBody = h("tbody");
    this.radiosTable = h("table", { class: "radios", "data-testid": "link-radios", hidden: true },
      h("thead", {}, h("tr", {}, ...["radio", "rate", "loss", "age", "copies"].map((c) => h("th", {}, c)))), this.radiosBody);
    this.root = panel("Link", "panel-link", h("div", { class: "ro-grid three" }, st.root, r.root, l.root, a.root, e.root, b.root, rec.root), this.recDetail, this.radiosTable, details);
  }

  update(link: Link | null, verdict: StaleVerdict, stats: MessageStats, receivedAtMs: number | null, nowMs: number, recording: Recording | null = null): void {
    this.showRecording(recording);
    setText(this.state, verdict.freshness === "fresh" ? "OK" : verdict.freshness === "stale" ? "STALE" : verdict.freshness === "disconnected" ? "DISCONNECTED" : "NO DATA");
    this.state.dataset.state = verdict.freshness;
    setText(this.rate, fmt(link?.rate_hz, "Hz"));
    setText(this.loss, fmt(link?.loss_percent, "%"));
    setText(this.age, fmt(verdict.age_s, "s", 1));
    setText(this.errors, link ? `${link.crc_errors ?? "—"} / ${link.parse_errors ?? "—"} / ${link.signature_errors ?? "—"}` : "—");
    setText(this.bad, `${stats.bad}${stats.lastError ? ` (last: ${stats.lastError})` : ""}`);
    this.bad.classList.toggle("warn", stats.bad > 0);
    this.showRadios(link?.radios ?? []);
    if (link === null || receivedAtMs === null) {
      this.agesBody.replaceChildren();
      return;
    }
    const rows = messageAges(link, receivedAtMs, nowMs).map((m) =>
      h("tr", { class: m.old ? "old" : "", "data-testid": `link-age-${m.name}`, title: m.limit_s === null ? "sent once, as an answer: its age is when the last one came" : `streamed: OLD after ${m.limit_s} s` },
        h("td", {}, m.name), h("td", {}, `${m.age_s.toFixed(1)} s${m.old ? " OLD" : m.limit_s === null ? " · answer" : ""}`)));
    this.agesBody.replaceChildren(...rows);
  }

  private showRecording(r: Recording | null): void {
    const text = recordingText(r);
    setText(this.rec, text.readout);
    if (r === null) delete this.rec.dataset.state;
    else this.rec.dataset.state = r.state;
    this.rec.classList.toggle("warn", text.warn);
    this.rec.title = text.title;
    setText(this.recDetail, text.detail);
    this.recDetail.hidden = text.detail === "";
    this.recDetail.classList.toggle("warn", r?.state === "failing");
  }

  /** One row per radio, only when there is a choice of radios: which one carries the commands
   *  (▲) and which has fallen silent. */
  private showRadios(radios: Radio[]): void {
    this.radiosTable.hidden = radios.length < 2;
    if (radios.length < 2) return;
    const rows = radios.map((r, i) =>
      h("tr", { class: r.stale ? "old" : "", "data-testid": `link-radio-${i + 1}`, title: r.address },
        h("td", {}, `${r.transmitting ? "▲ " : ""}${i + 1} ${r.address}`),
        h("td", {}, fmt(r.rate_hz, "Hz", 0)),
        h("td", {}, fmt(r.loss_percent, "%")),
        h("td", {}, `${fmt(r.age_s, "s", 1)}${r.stale ? " STALE" : ""}`),
        h("td", {}, r.duplicates === null ? "—" : String(r.duplicates))));
    this.radiosBody.replaceChildren(...rows);
  }
}

/** What the panel says of the recording. */
export interface RecordingText {
  /** REC with what was written, OFF, or FAILING (the station keeps flying either way). */
  readout: string;
  /** Below the readouts: while failing, the problem, since when and the next try; once it
   *  resumed, when and after how long; "" when there is nothing to say. */
  detail: string;
  /** Failing, or messages lost. */
  warn: boolean;
  /** The file and the last problem, on hover. */
  title: string;
}

export function recordingText(r: Recording | null): RecordingText {
  if (r === null) return { readout: "—", detail: "", warn: false, title: "" };
  const mb = r.bytes_written === null ? "—" : `${(r.bytes_written / 1e6).toFixed(1)} MB`;
  const lost = r.messages_lost ? `, ${r.messages_lost} lost` : "";
  const readout = r.state === "on" ? `REC ${mb}${lost}` : r.state === "off" ? "OFF" : `FAILING${lost}`;
  const problem = r.problem ?? "nothing is being written";
  // The readout's cell may be too narrow for the count: the line below says it too.
  const lostLine = r.messages_lost ? `; ${r.messages_lost} messages lost` : "";
  let detail = "";
  if (r.state === "failing") {
    // No `failing_since_ms`: the station never started writing (no directory) and does not retry.
    if (r.failing_since_ms === null) detail = `${problem}${lostLine}`;
    else {
      const tries = r.failed_tries ?? 0;
      const next = r.next_try_in_s === null ? "" : r.next_try_in_s <= 0 ? "; trying again now" : `; next try in ${fmtDuration(r.next_try_in_s)}`;
      detail = `${problem} — since ${fmtWallUtc(r.failing_since_ms)}${next} (${tries} ${tries === 1 ? "try" : "tries"} failed)${lostLine}`;
    }
  } else if (r.state === "on" && r.resumed_ms !== null) {
    detail = `Resumed ${fmtWallUtc(r.resumed_ms)} after failing ${fmtDuration(r.resumed_after_s)} (${problem})${lostLine}`;
  }
  return {
    readout,
    detail,
    warn: r.state === "failing" || (r.messages_lost ?? 0) > 0,
    title: [r.file, r.problem].filter((x) => x).join("\n"),
  };
}
