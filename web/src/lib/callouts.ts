// What the station says aloud: from one `state` to the next (and from a command's outcome), the
// call-outs a mission operator wants to hear without looking — stage changes, final approach,
// the landing with its miss, link lost and back, a keep-out alarm, the replica disagreeing with
// the drone, a command the drone or the station refused. Pure: the caller keeps the memory and
// decides who hears what (voiceSettings.ts) and how (ui/voicePanel.ts).
//
// Every call-out is edge-triggered: said once on its transition, never on the steady state a
// 4 Hz stream repeats. The first state a page sees (a load, a replay's seek) is the baseline, not
// news: an operator opening the page mid-flight is not read the whole situation at once.

import { linkStale } from "./staleness";
import { phaseLabel } from "./recovery";
import type { CommandEntry } from "./commands";
import type { FlightStage, State } from "./types";

export const CALLOUT_CLASSES = ["stage", "approach", "landing", "link", "keep_out", "disagreement", "command"] as const;
export type CalloutClass = (typeof CALLOUT_CLASSES)[number];

/** How the settings name each class. */
export const CLASS_LABELS: Readonly<Record<CalloutClass, string>> = {
  stage: "Stage changes",
  approach: "Final approach",
  landing: "Landing and miss",
  link: "Link lost / back",
  keep_out: "Keep-out alarm",
  disagreement: "Replica disagreement",
  command: "Command refused",
};

export interface Callout {
  class: CalloutClass;
  text: string;
  /** Said while the stack flies, or of the landing that ends the flight: what "only while flying" keeps. */
  inFlight: boolean;
  /** Worth a tone before the words (something is wrong, not just happening). */
  alarm: boolean;
}

/**
 * The drone link is judged lost (or back) only once it has stayed so this long: a link that
 * flickers for a second between two packets is not news. On top of the station's own
 * `stale_after_s`.
 */
export const LINK_HOLD_S = 2;
/** At least this long between two link call-outs: a flapping link is reported as it ends up, not at every flap. */
export const LINK_MIN_GAP_S = 5;
/** A keep-out alarm that clears and comes back within this long (a prediction wandering on a zone's border) is not said again. */
export const KEEP_OUT_REPEAT_S = 60;
/** A new disagreement within this long of the last one said is not said again. */
export const DISAGREEMENT_REPEAT_S = 20;
/** Landed but the touchdown not measured this long after: say the landing without its miss. */
export const LANDING_MEASURE_WAIT_S = 10;

const FLIGHT_STAGES: readonly FlightStage[] = ["ascent", "round_chute", "parafoil_deploy", "parafoil"];

/** The stack is in the air (after launch, before the landing). */
export function isFlying(stage: FlightStage | null): boolean {
  return stage !== null && FLIGHT_STAGES.includes(stage);
}

/** Stage changes as the ear takes them; `landed` is the landing call-out's, with its miss. */
const STAGE_WORDS: Readonly<Record<Exclude<FlightStage, "landed">, string>> = {
  pre_launch: "On the pad",
  ascent: "Launched, ascending",
  round_chute: "Under the round chute",
  parafoil_deploy: "Parafoil deploying",
  parafoil: "Parafoil flying",
};

/** The drone link as the call-outs follow it. */
interface LinkMemory {
  /** As the last state had it. */
  stale: boolean;
  /** Page clock (ms) since which it has been so. */
  sinceMs: number;
  /** What it has held for `LINK_HOLD_S`. */
  settled: boolean;
  /** What was last said (or the baseline). */
  said: boolean;
  saidAtMs: number | null;
  /** It has been fresh at some point: "back" rather than "up". */
  everUp: boolean;
}

/** What the call-outs remember between states. */
export interface CalloutMemory {
  stage: FlightStage | null;
  phase: string | null;
  /** "Final approach" is due when the phase next becomes it (re-armed by a new pattern). */
  approachArmed: boolean;
  /**
   * The station's count of the drone's final approaches (`vehicle.final_approaches`) in the last
   * state; `null` while it is not known (no drone heard: the replica's phase is all there is).
   */
  finalApproaches: number | null;
  /** The measured landing was said (or was already there at the baseline). */
  landingSaid: boolean;
  /** The landing was said before its touchdown was measured. */
  landedSaid: boolean;
  /** Page clock when the stage became `landed`. */
  landedAtMs: number | null;
  link: LinkMemory;
  /** Keep-out alarms of the last state (`prediction|zone`). */
  keepOut: string[];
  /** When each keep-out alarm was last said, page clock ms. */
  keepOutSaidMs: Record<string, number>;
  /** Mission time the disagreement said (or seen at the baseline) began. */
  disagreementSince: number | null;
  disagreementSaidMs: number | null;
}

const stageOf = (s: State): FlightStage | null => s.mission.stage ?? s.vehicle?.stage ?? null;
const keepOutKeys = (s: State): string[] => s.keep_out_alarms.map((a) => `${a.prediction}|${a.zone}`);
const activeDisagreement = (s: State): number | null => {
  const d = s.guidance?.disagreement ?? null;
  // An episode without its start (a garbled field) still counts as one.
  return d !== null && !d.resolved ? (d.since_s ?? -1) : null;
};
/** Phases that start a pattern afresh: the next final approach is news again. */
const REARMING_PHASES: readonly string[] = ["idle", "approximation"];

/** The memory of a first state: everything in it taken as known. */
export function baseline(s: State, nowMs: number): CalloutMemory {
  const stale = linkStale(s.link);
  const phase = phaseLabel(s);
  const stage = stageOf(s);
  return {
    stage,
    phase,
    approachArmed: phase !== "final_approach" && phase !== "flare" && stage !== "landed",
    finalApproaches: s.vehicle?.final_approaches ?? null,
    landingSaid: s.mission.landing !== null,
    landedSaid: stage === "landed",
    landedAtMs: stage === "landed" ? nowMs : null,
    link: { stale, sinceMs: nowMs, settled: stale, said: stale, saidAtMs: null, everUp: !stale },
    keepOut: keepOutKeys(s),
    keepOutSaidMs: {},
    disagreementSince: activeDisagreement(s),
    disagreementSaidMs: null,
  };
}

/** "6 metres from the target", rounded for the ear. */
export function missWords(miss_m: number | null): string {
  if (miss_m === null) return "no target known";
  if (miss_m >= 999.5) return `${(miss_m / 1000).toFixed(1)} kilometres from the target`;
  const m = Math.round(miss_m);
  return `${m} ${m === 1 ? "metre" : "metres"} from the target`;
}

/**
 * The call-outs from the memory of the states before (`null`: this is the first) to `s`, and the
 * memory to keep. `nowMs` is the page's clock: the link's hold-off runs on it.
 */
export function stateCallouts(memory: CalloutMemory | null, s: State, nowMs: number): { memory: CalloutMemory; callouts: Callout[] } {
  if (memory === null) return { memory: baseline(s, nowMs), callouts: [] };
  const m: CalloutMemory = { ...memory, link: { ...memory.link }, keepOutSaidMs: { ...memory.keepOutSaidMs } };
  const out: Callout[] = [];
  const stage = stageOf(s) ?? m.stage; // an unknown stage is not a change
  // A call-out of the transition out of the flight (stage → landed) still belongs to the flight.
  const inFlight = isFlying(stage) || isFlying(m.stage);
  const say = (cls: CalloutClass, text: string, alarm = false, flying = inFlight): void => void out.push({ class: cls, text, inFlight: flying, alarm });

  // ---- stage
  if (stage !== m.stage && stage !== null) {
    // The first stage heard (a drone joining the link) is where it is, not a change.
    if (stage !== "landed" && m.stage !== null) say("stage", STAGE_WORDS[stage]);
    if (!isFlying(stage) && stage !== "landed") {
      // Back on the pad (a new mission): its landing and approach are ahead again.
      m.landingSaid = false;
      m.landedSaid = false;
      m.approachArmed = true;
    }
    m.landedAtMs = stage === "landed" ? nowMs : null;
    m.stage = stage;
  }

  // ---- final approach: from the station's count where it has one (a busy page is sent only the
  // newest state, and a short final approach can fall between two), else from the phase seen
  const phase = phaseLabel(s);
  const count = s.vehicle?.final_approaches ?? null;
  const begun = count !== null && m.finalApproaches !== null ? count > m.finalApproaches : phase === "final_approach" && phase !== m.phase;
  if (begun && m.approachArmed) {
    say("approach", "Final approach");
    m.approachArmed = false;
  }
  m.finalApproaches = count;
  if (phase !== null && phase !== m.phase) {
    if (REARMING_PHASES.includes(phase)) m.approachArmed = true;
    m.phase = phase;
  }

  // ---- landing: the station's one measured figure, else (not measured in time) without it
  const landing = s.mission.landing;
  if (landing !== null && !m.landingSaid) {
    say("landing", m.landedSaid ? `Touchdown measured: ${missWords(landing.miss_m)}` : `Landed, ${missWords(landing.miss_m)}`, false, true);
    m.landingSaid = true;
    m.landedSaid = true;
  } else if (landing === null && stage === "landed" && !m.landedSaid && m.landedAtMs !== null && nowMs - m.landedAtMs >= LANDING_MEASURE_WAIT_S * 1000) {
    say("landing", "Landed, touchdown not measured yet", false, true);
    m.landedSaid = true;
  }

  // ---- link: settled after a hold-off, said no more often than the minimum gap
  const stale = linkStale(s.link);
  if (stale !== m.link.stale) {
    m.link.stale = stale;
    m.link.sinceMs = nowMs;
  }
  if (nowMs - m.link.sinceMs >= LINK_HOLD_S * 1000) m.link.settled = m.link.stale;
  if (m.link.settled !== m.link.said && (m.link.saidAtMs === null || nowMs - m.link.saidAtMs >= LINK_MIN_GAP_S * 1000)) {
    say("link", m.link.settled ? "Link lost" : m.link.everUp ? "Link back" : "Link up", m.link.settled);
    m.link.said = m.link.settled;
    m.link.saidAtMs = nowMs;
  }
  if (!m.link.settled) m.link.everUp = true;

  // ---- keep-out alarms: each new one, unless it was said a moment ago
  const keys = keepOutKeys(s);
  for (const a of s.keep_out_alarms) {
    const key = `${a.prediction}|${a.zone}`;
    if (m.keepOut.includes(key)) continue;
    const last = m.keepOutSaidMs[key];
    if (last !== undefined && nowMs - last < KEEP_OUT_REPEAT_S * 1000) continue;
    say("keep_out", `Keep-out alarm: predicted ${a.prediction === "uncontrolled" ? "uncontrolled landing" : "landing"} in ${a.zone}`, true);
    m.keepOutSaidMs[key] = nowMs;
  }
  m.keepOut = keys;

  // ---- the station's guidance replica and the drone disagree: each new episode
  const since = activeDisagreement(s);
  if (since !== null && since !== m.disagreementSince) {
    const d = s.guidance?.disagreement;
    if (d && (m.disagreementSaidMs === null || nowMs - m.disagreementSaidMs >= DISAGREEMENT_REPEAT_S * 1000)) {
      say("disagreement", `Station and drone disagree on the ${d.what}`, true);
      m.disagreementSaidMs = nowMs;
    }
    m.disagreementSince = since;
  }
  return { memory: m, callouts: out };
}

/** How each refusal is said. */
const REFUSALS: Readonly<Partial<Record<CommandEntry["status"], string>>> = {
  denied: "denied",
  failed: "failed",
  unsupported: "not supported",
  timed_out: "timed out",
  rejected: "refused by the station",
};

/**
 * A command as the ear takes it: the page's label without its figures ("mode → manual" is
 * "mode to manual", "target → 38.53330, -7.88890, …" is "target").
 */
export function spokenCommand(label: string): string {
  const [what, to] = label.split("→").map((p) => p.trim().replace(/_/g, " "));
  if (to === undefined || /\d/.test(to)) return what ?? label;
  return `${what} to ${to}`;
}

/**
 * Remembers which commands were said, so that a refusal is said once however often its entry
 * changes. A refusal often overtakes the station's 202 to this page's own request: it first shows
 * as another operator's, named by the command alone ("set mode"). While one of this page's
 * requests is still unanswered such a refusal is held, so that the page's entry, with what was
 * asked ("mode to manual"), says it once the 202 merges them.
 */
export class CommandCallouts {
  private readonly said = new Set<string>();
  private held: CommandEntry[] = [];

  /** The call-outs after entry `e` changed; `entries` are all the page's (the tracker's). */
  take(e: CommandEntry, entries: readonly CommandEntry[], inFlight: boolean): Callout[] {
    const out: Callout[] = [];
    const awaiting = entries.some((x) => !x.foreign && x.status === "sending");
    if (e.foreign && awaiting && REFUSALS[e.status] !== undefined) {
      if (!this.held.includes(e)) this.held.push(e);
    } else {
      this.sayOnce(out, e, inFlight);
    }
    if (!awaiting) out.push(...this.release(inFlight));
    return out;
  }

  /** Refusals still held: to be said anyway when the page's request never comes back. */
  get holding(): boolean {
    return this.held.length > 0;
  }

  /** The held refusals not said since, said now. */
  release(inFlight: boolean): Callout[] {
    const out: Callout[] = [];
    for (const e of this.held.splice(0)) this.sayOnce(out, e, inFlight);
    return out;
  }

  private sayOnce(out: Callout[], e: CommandEntry, inFlight: boolean): void {
    const word = REFUSALS[e.status];
    if (word === undefined) return;
    const key = e.requestId ?? `page:${e.id}`;
    if (this.said.has(key)) return;
    this.said.add(key);
    out.push({ class: "command", text: `Command ${word}: ${spokenCommand(e.label)}`, inFlight, alarm: false });
  }
}
