// The call-outs: each class said once on its transition and never on the steady state, the link's
// hold-off against flapping, the first state a baseline; and who hears them (voiceSettings.ts).
import { describe, expect, it } from "vitest";
import { CALLOUT_CLASSES, CommandCallouts, KEEP_OUT_REPEAT_S, LANDING_MEASURE_WAIT_S, LINK_HOLD_S, LINK_MIN_GAP_S, missWords, spokenCommand, stateCallouts, type Callout, type CalloutMemory } from "./callouts";
import { CommandTracker, type CommandEntry } from "./commands";
import { decodeMessage } from "./parse";
import { audible, defaultSettings, parseSettings } from "./voiceSettings";
import type { CommandResult, FlightStage, GuidancePhase, State } from "./types";

interface Over {
  stage?: FlightStage;
  phase?: GuidancePhase;
  /** The station's count of the drone's final approaches; absent as from a station without it. */
  finals?: number;
  stale?: boolean;
  miss_m?: number | null;
  alarms?: { prediction: "planned" | "uncontrolled"; zone: string }[];
  disagreement?: { since_s: number; resolved: boolean } | null;
}

/** A state as the page reads it off the wire. */
function state(o: Over = {}): State {
  const landing = o.miss_m === undefined ? null : { body: "drone", miss_m: o.miss_m, position: { lat_deg: 38.5, lon_deg: -7.9, alt_msl_m: 245 }, target: null, time_s: 600 };
  const d = o.disagreement ? { what: "phase", replica: "branch3", drone: "branch2", for_s: 1, adopted: false, ...o.disagreement } : null;
  const msg = decodeMessage(JSON.stringify({
    type: "state", time_s: 1,
    link: { connected: true, stale: o.stale ?? false, age_s: o.stale ? 5 : 0.1, ages_s: {} },
    vehicle: { stage: o.stage ?? "parafoil", phase: o.phase ?? "branch2", final_approaches: o.finals },
    guidance: { mode: "spiral_landing", phase: o.phase ?? "branch2", disagreement: d },
    keep_out_alarms: (o.alarms ?? []).map((a) => ({ ...a, since_s: 500 })),
    mission: { stage: o.stage ?? "parafoil", landing },
  }));
  if (!msg.ok || msg.msg.type !== "state") throw new Error("bad fixture");
  return msg.msg;
}

/** Feeds states one per `stepMs` of page time; every call-out made, with when. */
function run(states: State[], stepMs = 250, t0 = 0): { said: (Callout & { at: number })[]; memory: CalloutMemory | null } {
  let memory: CalloutMemory | null = null;
  const said: (Callout & { at: number })[] = [];
  states.forEach((s, i) => {
    const r = stateCallouts(memory, s, t0 + i * stepMs);
    memory = r.memory;
    for (const c of r.callouts) said.push({ ...c, at: t0 + i * stepMs });
  });
  return { said, memory };
}
const repeat = (n: number, s: State): State[] => Array.from({ length: n }, () => s);
const texts = (cs: Callout[]) => cs.map((c) => c.text);

describe("the baseline", () => {
  it("a first state says nothing, whatever it holds (a page opened mid-flight, a replay's seek)", () => {
    const busy = state({ stage: "landed", phase: "final_approach", stale: true, miss_m: 6, alarms: [{ prediction: "planned", zone: "Pond" }], disagreement: { since_s: 3, resolved: false } });
    expect(run(repeat(20, busy)).said).toEqual([]);
  });
});

describe("stage", () => {
  it("each change said once, in the ear's words; the steady state is silent", () => {
    const seq = [...repeat(5, state({ stage: "pre_launch" })), ...repeat(5, state({ stage: "ascent" })), ...repeat(5, state({ stage: "round_chute" })), ...repeat(5, state({ stage: "parafoil_deploy" })), ...repeat(5, state({ stage: "parafoil" }))];
    const said = run(seq).said.filter((c) => c.class === "stage");
    expect(texts(said)).toEqual(["Launched, ascending", "Under the round chute", "Parafoil deploying", "Parafoil flying"]);
  });
  it("the first stage heard (the drone joins a page already open) is not a change", () => {
    const noDrone = decodeMessage(JSON.stringify({ type: "state", time_s: 1, link: { connected: false, stale: true, age_s: null, ages_s: {} }, mission: { stage: null, landing: null } }));
    if (!noDrone.ok || noDrone.msg.type !== "state") throw new Error("bad fixture");
    const said = run([noDrone.msg, noDrone.msg, state({ stage: "pre_launch" }), state({ stage: "pre_launch" }), state({ stage: "ascent" })]).said.filter((c) => c.class === "stage");
    expect(texts(said)).toEqual(["Launched, ascending"]);
  });
  it("landed is the landing's call-out, not a stage change", () => {
    const said = run([state({ stage: "parafoil" }), state({ stage: "landed" }), state({ stage: "landed", miss_m: 6.4 })]).said;
    expect(said.map((c) => [c.class, c.text])).toEqual([["landing", "Landed, 6 metres from the target"]]);
  });
});

describe("final approach", () => {
  it("said once when the phase becomes it, not again while it flaps with the leg before", () => {
    const phases: GuidancePhase[] = ["branch3", "branch4", "final_approach", "final_approach", "branch4", "final_approach", "flare"];
    const said = run(phases.map((phase) => state({ phase }))).said;
    expect(texts(said)).toEqual(["Final approach"]);
  });
  it("a new pattern (back to approximation) makes the next final approach news again", () => {
    const phases: GuidancePhase[] = ["branch4", "final_approach", "approximation", "branch1", "final_approach"];
    expect(texts(run(phases.map((phase) => state({ phase }))).said)).toEqual(["Final approach", "Final approach"]);
  });
  it("one that fell between two states the page was sent is said from the station's count", () => {
    const states = [state({ phase: "branch4", finals: 0 }), state({ phase: "branch4", finals: 0 }), state({ phase: "flare", finals: 1 })];
    expect(texts(run(states).said)).toEqual(["Final approach"]);
  });
  it("by the count too, once while it flaps with the leg before, and again after a new pattern", () => {
    const seen: [GuidancePhase, number][] = [["branch4", 0], ["final_approach", 1], ["branch4", 1], ["final_approach", 2], ["approximation", 2], ["branch4", 3]];
    const said = run(seen.map(([phase, finals]) => state({ phase, finals }))).said;
    expect(texts(said)).toEqual(["Final approach", "Final approach"]);
  });
  it("a page opened during the final approach does not say it", () => {
    expect(run([state({ phase: "final_approach" }), state({ phase: "final_approach" }), state({ phase: "flare" })]).said).toEqual([]);
  });
});

describe("landing", () => {
  it("the station's miss, rounded for the ear, once", () => {
    const seq = [state({ stage: "parafoil", phase: "flare" }), state({ stage: "landed" }), ...repeat(10, state({ stage: "landed", miss_m: 12.6 }))];
    expect(texts(run(seq).said)).toEqual(["Landed, 13 metres from the target"]);
  });
  it("missWords: metres, one metre, kilometres, no target", () => {
    expect(missWords(0.6)).toBe("1 metre from the target");
    expect(missWords(6.2)).toBe("6 metres from the target");
    expect(missWords(999.4)).toBe("999 metres from the target");
    expect(missWords(1234)).toBe("1.2 kilometres from the target");
    expect(missWords(null)).toBe("no target known");
  });
  it("not measured in time: said without the miss, then the miss once it is measured", () => {
    const wait = Math.ceil((LANDING_MEASURE_WAIT_S * 1000) / 250);
    const seq = [state({ stage: "parafoil" }), ...repeat(wait + 2, state({ stage: "landed" })), state({ stage: "landed", miss_m: 3 }), state({ stage: "landed", miss_m: 3 })];
    expect(texts(run(seq).said)).toEqual(["Landed, touchdown not measured yet", "Touchdown measured: 3 metres from the target"]);
  });
  it("a new mission (back on the pad) lands again with its own call-out", () => {
    const seq = [state({ stage: "parafoil" }), state({ stage: "landed", miss_m: 5 }), state({ stage: "pre_launch" }), state({ stage: "ascent" }), state({ stage: "parafoil" }), state({ stage: "landed", miss_m: 9 })];
    expect(texts(run(seq).said.filter((c) => c.class === "landing"))).toEqual(["Landed, 5 metres from the target", "Landed, 9 metres from the target"]);
  });
});

describe("link", () => {
  it("lost after the hold-off, back after it, each once", () => {
    const hold = (LINK_HOLD_S * 1000) / 250;
    const gap = (LINK_MIN_GAP_S * 1000) / 250;
    const seq = [...repeat(4, state()), ...repeat(gap + 4, state({ stale: true })), ...repeat(gap + 4, state())];
    const { said } = run(seq);
    expect(said.map((c) => [c.text, c.at, c.alarm])).toEqual([
      ["Link lost", (4 + hold) * 250, true],
      ["Link back", (4 + gap + 4 + hold) * 250, false],
    ]);
  });
  it("a link that flickers shorter than the hold-off says nothing", () => {
    const seq = [];
    for (let i = 0; i < 20; i++) seq.push(state({ stale: true }), state({ stale: true }), state(), state());
    expect(run([state(), ...seq]).said).toEqual([]);
  });
  it("a link that flaps slower than the hold-off is said no more often than the minimum gap, and as it ends up", () => {
    // 3 s stale, 3 s fresh, 3 s stale… for a minute, then fresh.
    const seq = [state()];
    for (let i = 0; i < 10; i++) seq.push(...repeat(12, state({ stale: true })), ...repeat(12, state()));
    seq.push(...repeat(40, state()));
    const { said } = run(seq);
    for (let i = 1; i < said.length; i++) expect(said[i]!.at - said[i - 1]!.at).toBeGreaterThanOrEqual(LINK_MIN_GAP_S * 1000);
    expect(said.length).toBeLessThan(20);
    expect(said[said.length - 1]!.text).toBe("Link back");
  });
  it("first contact is 'Link up', not 'back'", () => {
    const seq = [...repeat(3, state({ stale: true })), ...repeat(20, state())];
    expect(texts(run(seq).said)).toEqual(["Link up"]);
  });
});

describe("keep-out alarm", () => {
  const pond = { prediction: "uncontrolled" as const, zone: "Road N114 corridor" };
  it("said when a prediction enters a zone, once while it stays there", () => {
    const said = run([state(), ...repeat(10, state({ alarms: [pond] }))]).said;
    expect(said.map((c) => [c.class, c.text, c.alarm])).toEqual([["keep_out", "Keep-out alarm: predicted uncontrolled landing in Road N114 corridor", true]]);
  });
  it("the planned landing is 'predicted landing'; each prediction and zone its own alarm", () => {
    const both = [pond, { prediction: "planned" as const, zone: "Pond" }];
    expect(texts(run([state({ alarms: [pond] }), state({ alarms: both }), state({ alarms: both })]).said)).toEqual(["Keep-out alarm: predicted landing in Pond"]);
  });
  it("an alarm that clears and comes back at once (a prediction on the zone's border) is not said again; much later it is", () => {
    const flap = [state(), state({ alarms: [pond] }), state(), state({ alarms: [pond] }), state(), state({ alarms: [pond] })];
    expect(run(flap).said).toHaveLength(1);
    const later = [state(), state({ alarms: [pond] }), ...repeat((KEEP_OUT_REPEAT_S * 1000) / 250, state()), state({ alarms: [pond] })];
    expect(run(later).said).toHaveLength(2);
  });
});

describe("replica disagreement", () => {
  it("said when it begins, not while it lasts nor when it resolves", () => {
    const seq = [state(), ...repeat(8, state({ disagreement: { since_s: 100, resolved: false } })), ...repeat(4, state({ disagreement: { since_s: 100, resolved: true } })), state()];
    expect(run(seq).said.map((c) => [c.class, c.text, c.alarm])).toEqual([["disagreement", "Station and drone disagree on the phase", true]]);
  });
  it("a new episode right after is not said again; one well after is", () => {
    const a = state({ disagreement: { since_s: 100, resolved: false } });
    const b = state({ disagreement: { since_s: 103, resolved: false } });
    expect(run([state(), a, state(), b]).said).toHaveLength(1);
    expect(run([state(), a, ...repeat(100, state()), b]).said).toHaveLength(2);
  });
});

describe("command refused", () => {
  const result = (over: Partial<CommandResult>): CommandResult => ({ type: "command_result", request_id: "r1", command: "set_mode", outcome: "in_progress", attempts: 1, detail: "", value: null, ...over });
  /** The call-outs of a tracker's changes, as the page wires them. */
  const wired = () => {
    const said: Callout[] = [];
    const calls = new CommandCallouts();
    const t: CommandTracker = new CommandTracker((e: CommandEntry) => said.push(...calls.take(e, t.entries, true)));
    return { t, said };
  };
  it("denied by the drone: said once, with the command in words", () => {
    const { t, said } = wired();
    const id = t.begin("set_mode", "mode → manual", 0);
    t.accepted(id, "r1", 1);
    t.result(result({ outcome: "in_progress" }), 2);
    t.result(result({ outcome: "denied", detail: "no fresh sticks" }), 3);
    t.result(result({ outcome: "denied" }), 4);
    expect(said.map((c) => [c.class, c.text])).toEqual([["command", "Command denied: mode to manual"]]);
  });
  it("accepted says nothing", () => {
    const { t, said } = wired();
    const id = t.begin("set_mode", "mode → heading", 0);
    t.accepted(id, "r1", 1);
    t.result(result({ outcome: "accepted" }), 2);
    expect(said).toEqual([]);
  });
  it("a refusal that overtook the 202 is said once, with what the page asked, when the 202 merges it", () => {
    const { t, said } = wired();
    const id = t.begin("set_mode", "mode → manual", 0);
    t.result(result({ request_id: "r7", outcome: "denied" }), 1);
    expect(said).toEqual([]);
    t.accepted(id, "r7", 2);
    expect(texts(said)).toEqual(["Command denied: mode to manual"]);
  });
  it("held for a request of this page that turns out to be another, it is said by its name", () => {
    const { t, said } = wired();
    const id = t.begin("set_mode", "mode → manual", 0);
    t.result(result({ request_id: "theirs", command: "set_target", outcome: "denied" }), 1);
    t.accepted(id, "mine", 2);
    expect(texts(said)).toEqual(["Command denied: set target"]);
  });
  it("held while the page's request hangs, released on demand (the page's timer)", () => {
    const calls = new CommandCallouts();
    const t = new CommandTracker();
    t.begin("set_mode", "mode → manual", 0);
    const theirs = t.result(result({ request_id: "x", outcome: "denied" }), 1);
    expect(calls.take(theirs, t.entries, true)).toEqual([]);
    expect(calls.holding).toBe(true);
    expect(texts(calls.release(true))).toEqual(["Command denied: set mode"]);
    expect(calls.release(true)).toEqual([]);
  });
  it("failed, timed out, not supported, refused by the station; another operator's by its name", () => {
    const { t, said } = wired();
    t.result(result({ request_id: "a", command: "set_param", outcome: "failed" }), 0);
    t.result(result({ request_id: "b", command: "set_target", outcome: "timed_out" }), 0);
    t.result(result({ request_id: "c", command: "set_plan", outcome: "unsupported" }), 0);
    t.rejected(t.begin("set_mode", "mode → heading", 0), "403", 1);
    expect(texts(said)).toEqual(["Command failed: set param", "Command timed out: set target", "Command not supported: set plan", "Command refused by the station: mode to heading"]);
  });
  it("figures are not read out", () => {
    expect(spokenCommand("target → 38.53330, -7.88890, approach into wind")).toBe("target");
    expect(spokenCommand("param GN_HK1 → 0.0125")).toBe("param GN HK1");
    expect(spokenCommand("CUTDOWN")).toBe("CUTDOWN");
  });
});

describe("who hears", () => {
  const flying: Callout = { class: "stage", text: "Parafoil flying", inFlight: true, alarm: false };
  const onPad: Callout = { class: "link", text: "Link up", inFlight: false, alarm: false };
  it("by default everything, on the pad too", () => {
    expect(audible(flying, defaultSettings())).toBe(true);
    expect(audible(onPad, defaultSettings())).toBe(true);
  });
  it("mute all silences every class", () => {
    const s = { ...defaultSettings(), muted: true };
    for (const c of CALLOUT_CLASSES) expect(audible({ ...flying, class: c }, s)).toBe(false);
  });
  it("a class muted is silent, the others not", () => {
    const s = defaultSettings();
    s.classes.stage = false;
    expect(audible(flying, s)).toBe(false);
    expect(audible({ ...flying, class: "approach" }, s)).toBe(true);
  });
  it("only while flying: the pad and the ground after the landing are quiet, the landing itself is said", () => {
    const s = { ...defaultSettings(), onlyWhileFlying: true };
    expect(audible(onPad, s)).toBe(false);
    expect(audible(flying, s)).toBe(true);
    // In the states: the landing is in flight; the link lost on the ground after it is not.
    const seq = [state({ stage: "parafoil" }), state({ stage: "landed", miss_m: 4 }), ...repeat(40, state({ stage: "landed", miss_m: 4, stale: true }))];
    expect(run(seq).said.map((c) => [c.text, audible(c, s)])).toEqual([["Landed, 4 metres from the target", true], ["Link lost", false]]);
    // On the pad: the first contact and the launch.
    const pad = [state({ stage: "pre_launch", stale: true }), ...repeat(12, state({ stage: "pre_launch" })), state({ stage: "ascent" })];
    expect(run(pad).said.map((c) => [c.text, audible(c, s)])).toEqual([["Link up", false], ["Launched, ascending", true]]);
  });
  it("settings read back from storage; garbled or partial entries fall back to the defaults", () => {
    const s = defaultSettings();
    s.muted = true;
    s.classes.keep_out = false;
    expect(parseSettings(JSON.stringify(s))).toEqual(s);
    expect(parseSettings("{not json")).toEqual(defaultSettings());
    expect(parseSettings(null)).toEqual(defaultSettings());
    expect(parseSettings(JSON.stringify({ onlyWhileFlying: true, classes: { link: false, bogus: false, stage: "no" } }))).toEqual({ ...defaultSettings(), onlyWhileFlying: true, classes: { ...defaultSettings().classes, link: false } });
  });
});
