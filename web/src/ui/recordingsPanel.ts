// Past recordings of this station (`GET /api/recordings`): when, how long, how big, which
// mission, where it landed and how far from the target. Each downloads (the MCAP file, for
// Foxglove or `stx export`) and, for operators, opens in a replay station of its own, in a new
// tab: the live station keeps flying while the debrief runs beside it.

import type * as Wire from "../generated/api";
import { ApiError, type Api } from "../lib/api";
import { fmtLatLon, label } from "../lib/format";
import { missPhrase } from "../lib/recovery";
import { isObj } from "../lib/parse";
import { withToken } from "../lib/token";
import { h, setText } from "./dom";
import { clockText } from "./replayBar";

/** `12.3 MB`. */
export function sizeText(bytes: number): string {
  if (bytes < 1e6) return `${(bytes / 1e3).toFixed(0)} kB`;
  return `${(bytes / 1e6).toFixed(bytes < 1e7 ? 1 : 0)} MB`;
}

/** `2026-11-25 14:03Z`. */
export function startText(ms: number | null): string {
  if (ms === null) return "—";
  return `${new Date(ms).toISOString().slice(0, 16).replace("T", " ")}Z`;
}

/** Where it came down and how far from the target, or the stage it ended in. */
export function landingText(r: Wire.RecordingSummary): string {
  if (r.landing !== null) {
    // The station's figure as measured at the landing, to 0.1 m as every page shows it.
    return `${fmtLatLon(r.landing.lat_deg, r.landing.lon_deg)} · ${missPhrase(r.landing.miss_m, r.landing.body)}`;
  }
  return r.last_stage === null ? "—" : `not landed (${label(r.last_stage)})`;
}

function parseList(v: unknown): Wire.RecordingsBody | null {
  if (!isObj(v) || !Array.isArray(v.recordings) || !Array.isArray(v.unreadable)) return null;
  return v as unknown as Wire.RecordingsBody;
}

export class RecordingsPanel {
  readonly root: HTMLElement;
  private readonly status: HTMLElement;
  private readonly body: HTMLElement;
  private readonly opened: HTMLElement;

  constructor(
    private readonly api: Api,
    private readonly token: string | null,
  ) {
    const refresh = h("button", { type: "button", "data-testid": "recordings-refresh", title: "read the recordings directory again" }, "Refresh");
    refresh.addEventListener("click", () => void this.load());
    this.status = h("span", { class: "recordings-status", "data-testid": "recordings-status" }, "");
    this.opened = h("div", { class: "recordings-opened", "data-testid": "recordings-opened", hidden: true });
    this.body = h("tbody", { "data-testid": "recordings-rows" });
    const head = h("thead", {}, h("tr", {}, ...["Start (UTC)", "Duration", "Size", "Mission", "Landing", ""].map((t) => h("th", {}, t))));
    this.root = h("div", { class: "recordings", "data-testid": "recordings" },
      h("div", { class: "recordings-bar" }, refresh, this.status), this.opened,
      h("table", { class: "recordings-table" }, head, this.body));
  }

  async load(): Promise<void> {
    setText(this.status, "reading…");
    let list: Wire.RecordingsBody | null;
    try {
      list = parseList(await this.api.get("/api/recordings"));
    } catch (e) {
      setText(this.status, e instanceof Error ? e.message : String(e));
      return;
    }
    if (list === null) {
      setText(this.status, "the station's answer is not a recordings list");
      return;
    }
    const where = list.directory === null ? "this station has no recordings directory" : list.directory;
    const bad = list.unreadable.length > 0 ? ` · ${list.unreadable.length} unreadable: ${list.unreadable.map((u) => `${u.name} (${u.reason})`).join("; ")}` : "";
    setText(this.status, `${list.recordings.length} recording${list.recordings.length === 1 ? "" : "s"} in ${where}${bad}`);
    this.body.replaceChildren(...list.recordings.map((r) => this.row(r)));
  }

  private row(r: Wire.RecordingSummary): HTMLElement {
    const path = `/api/recordings/${encodeURIComponent(r.name)}`;
    const download = h("a", { href: withToken(path, this.token), download: r.name, "data-testid": "recording-download" }, "Download");
    // Opening a replay starts a station: operators only (the page's role code disables it).
    const replay = h("button", { type: "button", "data-command": "replay", "data-testid": "recording-replay", title: "open in a replay station (new tab)" }, "Replay");
    replay.addEventListener("click", () => void this.openReplay(r.name, path));
    const state = r.recording_now ? " (recording now)" : r.complete ? "" : " (cut: readable to its last second)";
    return h("tr", { "data-testid": "recording-row", "data-name": r.name },
      h("td", { title: r.name }, startText(r.start_ms), h("small", {}, state)),
      h("td", { "data-testid": "recording-duration" }, clockText(r.duration_ms)),
      h("td", {}, sizeText(r.size_bytes)),
      h("td", { "data-testid": "recording-mission" }, r.mission ?? "—"),
      h("td", { "data-testid": "recording-landing" }, landingText(r)),
      h("td", { class: "actions" }, download, replay));
  }

  private async openReplay(name: string, path: string): Promise<void> {
    this.opened.hidden = false;
    setText(this.opened, `opening ${name}…`);
    try {
      const o = (await this.api.post(`${path}/replay`, {})) as Wire.ReplayOpened;
      const url = withToken(`${o.scheme}://${location.hostname}:${o.port}/`, this.token);
      const link = h("a", { href: url, target: "_blank", rel: "noopener", "data-testid": "recording-replay-link" }, `replay of ${name}`);
      this.opened.replaceChildren("Opened: ", link, " (a station of its own; it closes 10 minutes after its last page)");
      window.open(url, "_blank", "noopener");
    } catch (e) {
      setText(this.opened, `${name}: ${e instanceof ApiError ? e.reason : String(e)}`);
    }
  }
}
