// What the station shares beyond its pages (`GET /api/sharing`): the read-only MAVLink forwards
// for other ground stations and the chase cars' broadcast. Parsed leniently like the rest of the
// wire (a forward without a name is dropped, a missing count is 0), and put into the sentences
// the Go/no-go tab shows.

import { isObj, num, str, type Obj } from "./parseFields";
import type { ChaseView, ForwardView, SharingBody } from "../generated/api";

export type { ChaseView, ForwardView, SharingBody as Sharing };

const count = (o: Obj, k: string): number => Math.max(0, Math.round(num(o, k) ?? 0));

export function parseSharing(v: unknown): SharingBody {
  if (!isObj(v)) return { forwards: [], chase: null };
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
  return { forwards, chase };
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
