// What the guidance replica's spiral has learned of the canopy in flight (`guidance.learned`), as
// the live page's Flight data panel shows it: a small table under the measured airspeed, sink
// and heading rate, in percent of the polar guidance was given. Guidance plans every spiral with
// these scales, so the operator must see at a glance when the canopy flies far from its polar,
// and how much flight that belief rests on.
//
// The table keeps one shape (a heading row and two rows) whatever there is to say: the left
// column must hold every panel down to Link at 1440×900, and a block that grew when the replica
// started flying would push Link out of view mid-flight.

import type { Learned, N } from "./types";

/** Farther than this from nominal, in percent, a scale is marked. */
export const OFF_NOMINAL_PERCENT = 15;

export interface LearnedCell {
  text: string;
  /** Columns and rows the cell spans (1 when absent). */
  cols?: number;
  rows?: number;
  /** Far from nominal: drawn as a warning. */
  off?: boolean;
  title?: string;
}

export interface LearnedTable {
  head: LearnedCell[];
  /** Two rows, airspeed then sink, each starting with its label. */
  rows: [LearnedCell[], LearnedCell[]];
}

/** The settings the wire sends (released, half, full); they stand in when it sends none. */
const NOMINAL_BRAKES = [0, 0.5, 1];

const brakeName = (b: N): string => (b === null ? "?" : b === 0.5 ? "½" : String(Number(b.toFixed(2))));

/** Seconds of flight, to 0.1 s below 10 s: the turn's first figure often rests on a fraction of one. */
const seconds = (s: number): string => `${s < 10 ? s.toFixed(1) : s.toFixed(0)} s`;

/** The seconds behind a scale, or null while there are none: until then the scale is the polar's own. */
const learnedFor = (s: N): number | null => (s !== null && s > 0 ? s : null);

/**
 * A scale as a percent of nominal, marked when it is more than `OFF_NOMINAL_PERCENT` away; its
 * 1-σ, when known, in the title (the cell itself has no room for it in the left column).
 */
function scaleCell(v: N, what: string, sigma: N = null): LearnedCell {
  if (v === null) return { text: "—", title: `${what}: not received` };
  // Judged on the percent shown, so that the mark and the figure agree ("85 %" is not "more than 15 % off").
  const percent = Math.round(v * 100);
  const off = Math.abs(percent - 100) > OFF_NOMINAL_PERCENT;
  const doubt = sigma === null ? "" : ` ± ${(sigma * 100).toFixed(1)} % (1σ)`;
  // Colour is never the only carrier of meaning: an off-nominal value also carries a "!".
  return { text: `${percent} %${off ? "!" : ""}`, off, title: `${what}: ${(v * 100).toFixed(1)} % of nominal${doubt}${off ? `, more than ${OFF_NOMINAL_PERCENT} % off` : ""}` };
}

/** The table for `learned`; `null` (the replica is not flying its spiral) gives the same shape, saying so. */
export function learnedTable(l: Learned | null): LearnedTable {
  const brakes: N[] = l?.brake ?? NOMINAL_BRAKES;
  const glideS = learnedFor(l?.learned_s ?? null);
  const turnS = learnedFor(l?.turn_learned_s ?? null);
  const head: LearnedCell[] = [
    {
      // After the landing the values stay for the debrief, marked as the flight's last ones.
      text: l !== null && l.flying === false ? "at landing" : glideS === null ? "learned" : `learned ${seconds(glideS)}`,
      title: `${l !== null && l.flying === false ? `as last learned before the landing${glideS === null ? "" : `, from ${seconds(glideS)} of straight, settled flight`}: ` : ""}what the guidance replica's spiral has learned of the canopy in flight, in percent of the polar guidance was given: airspeed and sink rate at each brake setting, from this many seconds of straight, settled flight`,
    },
    ...brakes.map((b, i) => ({ text: i === 0 ? `brakes ${brakeName(b)}` : brakeName(b) })),
    { text: turnS === null ? "turn" : `turn ${seconds(turnS)}`, title: "turn rate flown over the polar's for the same main-line commands, from this many seconds of turning" },
  ];
  const airspeed: LearnedCell = { text: "airspeed" };
  const sink: LearnedCell = { text: "sink" };
  if (l === null) return { head, rows: [[airspeed, { text: "— guidance replica not flying", cols: brakes.length + 1, rows: 2 }], [sink]] };
  const turn: LearnedCell = turnS === null ? { text: "not yet", rows: 2, title: "turn rate: not learned yet, the polar's" } : { ...scaleCell(l.turn_scale, "turn rate", l.turn_sigma ?? null), rows: 2 };
  if (glideS === null) {
    const notYet = { text: "not learned yet", cols: brakes.length, rows: 2, title: "airspeed and sink rate: the polar's, until the spiral has flown straight and settled" };
    return { head, rows: [[airspeed, notYet, turn], [sink]] };
  }
  const at = (scales: N[] | null, what: string, sigma: N): LearnedCell[] => brakes.map((b, i) => scaleCell(scales?.[i] ?? null, `${what} at brakes ${brakeName(b)}`, sigma));
  return { head, rows: [[airspeed, ...at(l.airspeed_scale, "airspeed", l.airspeed_sigma ?? null), turn], [sink, ...at(l.sink_scale, "sink rate", l.sink_sigma ?? null)]] };
}
