// What the station shares beyond its pages (`GET /api/sharing`): the read-only MAVLink forwards
// for other ground stations, the chase cars' broadcast and the SondeHub-Amateur upload. Parsed leniently like the rest of the
// wire (a forward without a name is dropped, a missing count is 0), and put into the sentences
// the Go/no-go tab shows.

import { bool, isObj, num, str, type Obj } from "./parseFields";
import type { ChaseCarView, ChaseView, ForwardView, RelayShare, SharingBody, SondehubNote, SondehubView } from "../generated/api";

export type { ChaseView, ForwardView, RelayShare, SharingBody as Sharing, SondehubView };

const count = (o: Obj, k: string): number => Math.max(0, Math.round(num(o, k) ?? 0));

function notes(v: unknown): SondehubNote[] {
  if (!Array.isArray(v)) return [];
  return v.filter(isObj).flatMap((n) => {
    const text = str(n, "text");
    return text === null ? [] : [{ wall_ms: count(n, "wall_ms"), text }];
  });
}

function parseChaseCar(v: unknown): ChaseCarView | null {
  if (!isObj(v)) return null;
  const callsign = str(v, "callsign");
  const p = Array.isArray(v.position) ? v.position : [];
  const [lat, lon, alt] = p;
  if (callsign === null || typeof lat !== "number" || typeof lon !== "number" || typeof alt !== "number") return null;
  return { callsign, position: [lat, lon, alt], uploaded_wall_ms: num(v, "uploaded_wall_ms") };
}

/** The SondeHub part: `null` when it is off or has no callsigns. */
export function parseSondehub(v: unknown): SondehubView | null {
  if (!isObj(v)) return null;
  const uploader = str(v, "uploader_callsign");
  const payload = str(v, "payload_callsign");
  if (uploader === null || payload === null) return null;
  return {
    url: str(v, "url") ?? "?", uploader_callsign: uploader, payload_callsign: payload, period_s: num(v, "period_s") ?? 0,
    made: count(v, "made"), sent: count(v, "sent"), historical: count(v, "historical"), refused: count(v, "refused"),
    queued: count(v, "queued"), queue_max: count(v, "queue_max"), dropped: count(v, "dropped"), restored: count(v, "restored"),
    on_disk: bool(v, "on_disk") ?? false, last_upload_wall_ms: num(v, "last_upload_wall_ms"), last_result: str(v, "last_result"),
    failing: bool(v, "failing") ?? false, retry_wall_ms: num(v, "retry_wall_ms"), errors: notes(v.errors), warnings: notes(v.warnings),
    station_uploaded_wall_ms: num(v, "station_uploaded_wall_ms"), chase_car: parseChaseCar(v.chase_car),
  };
}

export function parseSharing(v: unknown): SharingBody {
  if (!isObj(v)) return { forwards: [], chase: null, sondehub: null, relays: [] };
  const forwards: ForwardView[] = [];
  for (const f of Array.isArray(v.forwards) ? v.forwards : []) {
    if (!isObj(f)) continue;
    const name = str(f, "name");
    const address = str(f, "address");
    if (name === null || address === null) continue;
    const may = Array.isArray(f.may_send_to_drone) ? f.may_send_to_drone.filter((x): x is number => Number.isInteger(x)) : [];
    forwards.push({
      name, address, may_send_to_drone: may,
      out_passed: count(f, "out_passed"), out_filtered: count(f, "out_filtered"), out_dropped: count(f, "out_dropped"),
      in_passed: count(f, "in_passed"), in_refused: count(f, "in_refused"),
    });
  }
  let chase: ChaseView | null = null;
  const c = isObj(v.chase) ? v.chase : null;
  const callsign = c ? str(c, "callsign") : null;
  if (c && callsign !== null) {
    chase = {
      callsign, landing_callsign: str(c, "landing_callsign") ?? `${callsign}_LANDING`, to: str(c, "to") ?? "?",
      period_s: num(c, "period_s") ?? 0, sent: count(c, "sent"), last_sent_wall_ms: num(c, "last_sent_wall_ms"), error: str(c, "error"),
    };
  }
  return { forwards, chase, sondehub: parseSondehub(v.sondehub), relays: parseRelays(v.relays) };
}

function parseRelays(v: unknown): RelayShare[] {
  if (!Array.isArray(v)) return [];
  return v.filter(isObj).flatMap((r) => {
    const name = str(r, "name");
    return name === null ? [] : [{ id: count(r, "id"), name, connected_s: num(r, "connected_s") ?? 0, viewers: count(r, "viewers") }];
  });
}

/** The public relays' audience in one line. */
export function relaysLine(relays: readonly RelayShare[]): string {
  if (relays.length === 0) return "no public relay connected (stx relay --upstream …)";
  const pages = relays.reduce((n, r) => n + r.viewers, 0);
  const each = relays.map((r) => `${r.name} #${r.id}: ${r.viewers}`).join(", ");
  return `${pages} public page${pages === 1 ? "" : "s"} through ${relays.length} relay${relays.length === 1 ? "" : "s"} (${each})`;
}

/** What a watcher on `f` may do to the drone, in words. */
export function forwardRights(f: ForwardView): string {
  return f.may_send_to_drone.length === 0 ? "read-only" : `may send the drone message ids ${f.may_send_to_drone.join(", ")}`;
}

/** One line on the forward's traffic. */
export function forwardCounts(f: ForwardView): string {
  const lost = f.out_dropped > 0 ? `, ${f.out_dropped} lost (it fell behind)` : "";
  return `${f.out_passed} frames sent, ${f.out_filtered} filtered${lost}; from it: ${f.in_passed} passed, ${f.in_refused} kept from the drone`;
}

/** The chase broadcast in one line; `now_ms` for the age of the last datagram. */
export function chaseLine(c: ChaseView | null, nowMs: number): string {
  if (c === null) return "chase broadcast off (no [chase] in the station's config)";
  const head = `${c.callsign} and ${c.landing_callsign} to ${c.to} every ${c.period_s} s`;
  if (c.error !== null) return `${head}: FAILING (${c.error})`;
  if (c.last_sent_wall_ms === null) return `${head}: nothing sent yet (no GPS fix)`;
  const age = Math.max(0, Math.round((nowMs - c.last_sent_wall_ms) / 1000));
  return `${head}: ${c.sent} datagrams sent, the last ${age} s ago`;
}

const ago = (nowMs: number, thenMs: number): string => `${Math.max(0, Math.round((nowMs - thenMs) / 1000))} s ago`;

/** The SondeHub upload in one line: where, whether it works, the last upload. */
export function sondehubLine(s: SondehubView | null, nowMs: number): string {
  if (s === null) return "SondeHub upload off (no [sondehub] in the station's config)";
  const head = `${s.payload_callsign} by ${s.uploader_callsign} to ${s.url} every ${s.period_s} s`;
  const last = s.last_upload_wall_ms === null ? "nothing uploaded yet" : `last upload ${ago(nowMs, s.last_upload_wall_ms)}`;
  if (s.failing) {
    const retry = s.retry_wall_ms === null ? "" : `, next try in ${Math.max(0, Math.round((s.retry_wall_ms - nowMs) / 1000))} s`;
    return `${head}: FAILING (${s.last_result ?? "no answer"}${retry}); ${last}`;
  }
  return `${head}: ${last}${s.last_result === null ? "" : ` (${s.last_result})`}`;
}

/** The upload's counts in one line. */
export function sondehubCounts(s: SondehubView): string {
  const parts = [`${s.sent} points taken`, `${s.queued} queued${s.on_disk ? " on disk" : " in memory"} (of ${s.queue_max})`];
  if (s.historical > 0) parts.push(`${s.historical} as historical`);
  if (s.refused > 0) parts.push(`${s.refused} refused by the server`);
  if (s.dropped > 0) parts.push(`${s.dropped} DROPPED (queue full)`);
  if (s.restored > 0) parts.push(`${s.restored} restored at start`);
  return parts.join(", ");
}

/** The station's and the chase car's positions on the map, in words. */
export function sondehubListeners(s: SondehubView, nowMs: number): string {
  const station = s.station_uploaded_wall_ms === null ? "station position not uploaded" : `station position uploaded ${ago(nowMs, s.station_uploaded_wall_ms)}`;
  const c = s.chase_car;
  if (c === null) return `${station}; no chase car (the recovery page shares its phone's position)`;
  const car = c.uploaded_wall_ms === null ? "waiting to upload" : `uploaded ${ago(nowMs, c.uploaded_wall_ms)}`;
  return `${station}; chase car ${c.callsign} at ${c.position[0].toFixed(5)}, ${c.position[1].toFixed(5)} ${car}`;
}
