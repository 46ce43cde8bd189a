#!/usr/bin/env node
// Voice and sound (issue 32, item 2) in a real browser: a whole short mission, pad to landing,
// flown by `stx drone` beside `stx serve` at 10× (a lower burst and deployment than mission-short,
// so it lasts under 7 minutes of mission time), its link cut during the ascent, a keep-out zone put
// under the predicted landing, a manual-mode request the drone denies. Three pages listen at once,
// the browser's `speechSynthesis` replaced by a recorder of every utterance:
//  A. an operator with the defaults (everything said): each stage change once, "Final approach"
//     once, "Landed, N metres from the target" with the station's own miss, link up / lost / back
//     when the station's link really went stale and fresh, the keep-out alarm, the command denied,
//     a tone before each alarm, and nothing twice;
//  B. a viewer with stage call-outs off and "only while flying" on, set in the Voice tab and kept
//     over a reload: exactly A's in-flight call-outs without the stage changes (nothing on the pad,
//     nothing on the ground after the landing);
//  C. a viewer on a phone with "mute all": nothing at all, and the header's quick mute says so.
// And a browser without speech synthesis says so in the tab. What A should have heard is worked
// out here from the states A's socket received (on the page's clock, as the utterances: a busy
// page may run seconds behind the station), not from the page's code.
//
// Usage: node tests/browser/voice.mjs [path/to/stx]   (default target/release/stx)
// Env: CHROMIUM (default /usr/bin/chromium), VOICE_SPEED (default 10: the station sends a state
// after each burst of telemetry, so at 20× three dashboards on two cores fall behind).

import { mkdtemp, readFile, writeFile } from "node:fs/promises";
import { tmpdir } from "node:os";
import { join } from "node:path";
import {
  OPERATOR, VIEWER, root, out, sleep, check, newContext, startStation, freeUdpPort, apiOf, run, text, attr, watchErrors, runFlights, registerRest, configWithZoneCopy, fromNorthEast, settled,
} from "./harness.mjs";

registerRest("PUT", /^\/api\/keep-out$/, "KeepOutBody", "KeepOutMsg");

const SPEED = Number(process.env.VOICE_SPEED ?? 10);
/** Link down during the ascent, in mission seconds (launch at 60 s, burst at about 200 s). */
const DROP = [80, 140];
/** The zone put under the landing: not a name of the shipped sample's (it has a "Road N114 corridor"). */
const ZONE = "Voice test field";
/** How the test expects each stage change to be said (landed is the landing's call-out). */
const STAGE_WORDS = { pre_launch: "On the pad", ascent: "Launched, ascending", round_chute: "Under the round chute", parafoil_deploy: "Parafoil deploying", parafoil: "Parafoil flying" };
const ALARM = /^(Link lost|Keep-out alarm|Station and drone disagree)/;

/**
 * mission-short with a burst at 950 m and the parafoil at 500 m above the site, the target where
 * it reaches with a final approach of some 40 s (landing at about 380 s).
 */
async function scenario() {
  const src = await readFile(join(root, "config/scenarios/mission-short.toml"), "utf8");
  let toml = src;
  for (const [re, line] of [
    [/^name = .*$/m, 'name = "voice"'],
    [/^launch_delay_s = .*$/m, "launch_delay_s = 60.0"],
    [/^burst_altitude_msl_m = .*$/m, "burst_altitude_msl_m = 950.0"],
    [/^deploy_height_m = .*$/m, "deploy_height_m = 500.0"],
    [/^target_ne_m = .*$/m, "target_ne_m = [100.0, 800.0]"],
  ]) {
    if (!re.test(toml)) throw new Error(`mission-short.toml has no line ${re} to change`);
    toml = toml.replace(re, line);
  }
  const file = join(await mkdtemp(join(tmpdir(), "stx-browser-voice-")), "voice.toml");
  await writeFile(file, toml);
  return file;
}

/** Every utterance the page made and every state it received, on its own clock. */
function recordSpeech() {
  window.__spoken = [];
  window.__states = [];
  window.__oscillators = 0;
  const Native = window.WebSocket;
  window.WebSocket = class extends Native {
    constructor(...args) {
      super(...args);
      // Before the page's own handler: a state is recorded before anything it makes is said.
      this.addEventListener("message", (e) => {
        try {
          const m = JSON.parse(e.data);
          if (m.type === "state") window.__states.push({ at: Date.now(), stage: m.mission?.stage ?? m.vehicle?.stage ?? null, phase: m.vehicle?.phase ?? m.guidance?.phase ?? null, finals: m.vehicle?.final_approaches ?? null, stale: m.link?.stale === true || m.link?.connected === false });
        } catch {}
      });
    }
  };
  const synth = {
    speak: (u) => window.__spoken.push({ text: u.text, at: Date.now() }),
    cancel() {}, pause() {}, resume() {},
    getVoices: () => [],
    speaking: false, pending: false, paused: false, onvoiceschanged: null,
    addEventListener() {}, removeEventListener() {}, dispatchEvent: () => true,
  };
  Object.defineProperty(window, "speechSynthesis", { value: synth, configurable: true });
  if (typeof window.SpeechSynthesisUtterance !== "function") {
    window.SpeechSynthesisUtterance = class { constructor(text) { this.text = text; } };
  }
  // The alarm tone: each beep is an oscillator.
  const make = AudioContext.prototype.createOscillator;
  AudioContext.prototype.createOscillator = function () {
    window.__oscillators += 1;
    return make.call(this);
  };
}

async function listener(label, token, viewport, mobile = false) {
  const ctx = await newContext(label, { viewport, ...(mobile ? { isMobile: true, hasTouch: true } : {}) });
  await ctx.addInitScript(recordSpeech);
  const page = await ctx.newPage();
  watchErrors(page, label);
  return { ctx, page };
}
const connected = (page) => page.waitForFunction(() => document.querySelector('[data-testid="conn-status"]')?.textContent === "CONNECTED", null, { timeout: 15000 });
const spoken = (page) => page.evaluate(() => window.__spoken.slice());

async function flight() {
  const port = await freeUdpPort();
  const copy = await configWithZoneCopy();
  const { base } = await startStation(["--config", copy.file, "--link", `udpin:127.0.0.1:${port}`]);
  const api = apiOf(base);

  // ---------------------------------------------------------------- a browser that cannot speak
  const mute = await newContext("no speech", { viewport: { width: 1440, height: 900 } });
  await mute.addInitScript(() => {
    delete window.speechSynthesis;
    delete Window.prototype.speechSynthesis;
  });
  const mpage = await mute.newPage();
  watchErrors(mpage, "no speech");
  await mpage.goto(`${base}/?token=${VIEWER}`);
  await connected(mpage);
  await mpage.click('[data-testid="tab-voice"]');
  const noSpeech = { state: await attr(mpage, "voice-status", "data-state"), text: await text(mpage, "voice-status") };
  check("voice: a browser without speech synthesis says so in the Voice tab (and the page works on)", noSpeech.state === "unavailable" && /cannot speak/.test(noSpeech.text), `${noSpeech.state}: "${noSpeech.text}"`);
  await mute.close();

  // ---------------------------------------------------------------- A: an operator, the defaults
  const A = await listener("voice A", OPERATOR, { width: 1440, height: 900 });
  await A.page.goto(`${base}/?token=${OPERATOR}`);
  await connected(A.page);
  const before = await attr(A.page, "voice-status", "data-state");
  await A.page.click('[data-testid="tab-voice"]');
  const after = await attr(A.page, "voice-status", "data-state");
  await A.page.click('[data-testid="voice-test"]');
  const test = await spoken(A.page);
  // The quick mute adds no line to the header at 1440×900.
  const header = await A.page.evaluate(() => {
    const hdr = document.querySelector("header.top");
    const quick = document.querySelector('[data-testid="voice-quick"]');
    const shown = hdr.getBoundingClientRect().height;
    quick.hidden = true;
    const without = hdr.getBoundingClientRect().height;
    quick.hidden = false;
    const q = quick.getBoundingClientRect();
    return { shown, without, inside: q.width > 0 && q.bottom <= hdr.getBoundingClientRect().bottom };
  });
  check("1440×900: the header's quick mute takes no line of its own", header.inside && header.shown === header.without, JSON.stringify(header));
  check("voice: silent until the first click on the page (the browser's rule, said in the tab), then speaking; Test voice speaks",
    before === "waiting_for_gesture" && after === "ready" && test.length === 1 && /^Voice check/.test(test[0].text), `before the click ${before}, after ${after}; said ${JSON.stringify(test.map((u) => u.text))}`);

  // ---------------------------------------------------------------- B: stage off, only while flying, kept over a reload
  const B = await listener("voice B", VIEWER, { width: 1440, height: 900 });
  await B.page.goto(`${base}/?token=${VIEWER}`);
  await connected(B.page);
  await B.page.click('[data-testid="tab-voice"]');
  await B.page.click('[data-testid="voice-class-stage"]');
  await B.page.click('[data-testid="voice-only-flying"]');
  await B.page.reload();
  await connected(B.page);
  await B.page.click('[data-testid="tab-voice"]');
  const kept = await B.page.evaluate(() => ({
    stage: document.querySelector('[data-testid="voice-class-stage"]').checked,
    approach: document.querySelector('[data-testid="voice-class-approach"]').checked,
    flying: document.querySelector('[data-testid="voice-only-flying"]').checked,
    muted: document.querySelector('[data-testid="voice-mute-all"]').checked,
  }));
  check("voice: settings made in the Voice tab are kept over a reload (stage off, only while flying on, the rest as they were)", !kept.stage && kept.approach && kept.flying && !kept.muted, JSON.stringify(kept));

  // ---------------------------------------------------------------- C: a phone, mute all
  const C = await listener("voice C", VIEWER, { width: 390, height: 844 }, true);
  await C.page.goto(`${base}/?token=${VIEWER}`);
  await connected(C.page);
  await C.page.click('[data-testid="tab-voice"]');
  await C.page.click('[data-testid="voice-mute-all"]');
  const quickC = { text: await text(C.page, "voice-quick"), state: await attr(C.page, "voice-quick", "data-state") };
  check("voice: mute all in the tab shows in the header's quick mute", quickC.state === "muted" && /MUTED/.test(quickC.text), `${quickC.state}: "${quickC.text}"`);

  // ---------------------------------------------------------------- the mission
  const file = await scenario();
  const drone = run(["drone", "--connect", `udpout:127.0.0.1:${port}`, "--scenario", file, "--speed", String(SPEED), "--link-drop", `${DROP[0]}:${DROP[1]}`, "--linger", "3", "--summary-json"], "stx drone");
  let droneDone = false;
  drone.proc.once("exit", () => (droneDone = true));
  console.log(`voice: station at ${base}, drone at ${SPEED}× real time, link down ${DROP[0]}–${DROP[1]} s of mission time`);
  const polls = [];
  let zonePut = null;
  let commanded = false;
  const t0 = Date.now();
  const deadline = t0 + (420 / SPEED) * 1000 + 40_000;
  for (;;) {
    const s = (await api("/api/state")).body;
    const p = { at: Date.now(), stage: s?.mission?.stage ?? null, stale: s?.link?.stale ?? null, landing: s?.mission?.landing ?? null, alarms: (s?.keep_out_alarms ?? []).map((a) => `${a.prediction}|${a.zone}`), uncontrolled: s?.prediction?.uncontrolled ?? null };
    polls.push(p);
    // Under the parafoil: a zone around where the stack would land uncontrolled, once that
    // prediction has settled.
    const u = s?.prediction?.uncontrolled;
    const underCanopy = polls.filter((q) => q.stage === "parafoil").map((q) => ({ at: q.at, point: q.uncontrolled }));
    if (zonePut === null && p.stage === "parafoil" && settled(underCanopy)) {
      const zones = (await api("/api/keep-out")).body.zones;
      const ring = [[-250, -250], [-250, 250], [250, 250], [250, -250], [-250, -250]].map(([n, e]) => fromNorthEast(u, n, e)).map((q) => [q.lon_deg, q.lat_deg]);
      // Ours alone: a landing inside a shipped zone too is reported under that zone's name only.
      // Timed when sent: the station raises the alarm as it takes the zone, and the page can
      // say it before the PUT's answer is back here.
      const sentAt = Date.now();
      const put = await api("/api/keep-out", OPERATOR, { method: "PUT", body: JSON.stringify({ ...zones, features: [{ type: "Feature", properties: { name: ZONE }, geometry: { type: "Polygon", coordinates: [ring] } }] }) });
      zonePut = { at: sentAt, status: put.status };
    }
    // The link back after its cut: the operator asks for manual without sticks, which the drone denies.
    if (!commanded && polls.some((q) => q.stale === true && q.stage === "ascent") && p.stale === false && p.stage !== "pre_launch") {
      commanded = true;
      await A.page.click('[data-testid="mode-manual"]');
    }
    // Done once the pages have caught up with the drone landed and gone quiet (A's last word
    // is the link lost after its landing; B has said the landing).
    if (droneDone) {
      const [sa, sb] = [await spoken(A.page), await spoken(B.page)];
      const at = sa.find((u) => /^Landed/.test(u.text))?.at;
      if (at !== undefined && sa.some((u) => u.at > at && u.text === "Link lost") && sb.some((u) => /^Landed/.test(u.text))) break;
    }
    if (Date.now() > deadline) break;
    await sleep(200);
  }
  const landing = polls.find((q) => q.landing !== null)?.landing ?? null;
  const truth = JSON.parse(drone.out.trim().split("\n").pop() || "null");
  check("voice: the drone flew the mission to a landing, every stage in turn, its link cut during the ascent", truth?.landed === true && landing !== null && truth.stages.map((s) => s.stage).join(" ") === "pre_launch ascent round_chute parafoil_deploy parafoil landed",
    `${truth?.stages?.map((s) => `${s.stage} ${s.start_s.toFixed(0)} s`).join(", ")}; station's landing ${landing ? `${landing.miss_m?.toFixed(1)} m from the target` : "none"}; ${((Date.now() - t0) / 1000).toFixed(0)} s`);

  const a = await spoken(A.page);
  const b = await spoken(B.page);
  const c = await spoken(C.page);
  const states = await A.page.evaluate(() => window.__states);
  await writeFile(join(out, "voice-utterances.json"), JSON.stringify({ a, b, c, polls, states }, null, 1));
  const said = (re) => a.filter((u) => re.test(u.text));
  const texts = (us) => us.map((u) => u.text);

  // ---------------------------------------------------------------- A: what it heard
  // Stage changes: one per change in the states A received, in the test's words.
  const changes = [];
  for (let i = 1; i < states.length; i++) {
    const [x, y] = [states[i - 1].stage, states[i].stage];
    if (x !== null && y !== null && x !== y && y !== "landed") changes.push(STAGE_WORDS[y]);
  }
  const stageSaid = texts(a).filter((t) => Object.values(STAGE_WORDS).includes(t));
  check("A: each stage change said once, as the states came (launch, round chute, parafoil)", stageSaid.join(" | ") === changes.join(" | ") && ["Launched, ascending", "Under the round chute", "Parafoil flying"].every((w) => stageSaid.includes(w)),
    `said: ${stageSaid.join(" | ")}; changes received: ${changes.join(" | ")}`);
  const finals = said(/^Final approach$/);
  // The page is sent the newest state when it is ready: a short final approach may show only in
  // the station's count of them.
  const reached = states.find((s, i) => s.phase === "final_approach" || (i > 0 && s.finals !== null && states[i - 1].finals !== null && s.finals > states[i - 1].finals));
  check("A: 'Final approach' said once, when the drone's phase became it (or the station's count of them grew)", finals.length === 1 && reached !== undefined && finals[0].at >= reached.at && finals[0].at - reached.at < 1000, `${finals.length} time(s); the phase first received ${reached ? `${((reached.at - t0) / 1000).toFixed(1)} s` : "never"}, said at ${finals.map((u) => ((u.at - t0) / 1000).toFixed(1)).join(", ")} s`);
  const landed = said(/^Landed/);
  const metres = Number(/^Landed, (\d+) metres? from the target$/.exec(landed[0]?.text ?? "")?.[1]);
  check("A: the landing said once with the station's miss (to the metre)", landed.length === 1 && landing?.miss_m != null && Math.abs(metres - landing.miss_m) <= 0.51,
    `${JSON.stringify(texts(landed))}; the station's mission.landing: ${landing?.miss_m} m`);
  // The link: up at first contact, lost during the cut, back once fresh, lost when the landed
  // drone goes quiet; lost and back in turn (a loaded machine may add an outage of its own: it
  // is said too, if the station had it stale, and never twice the same).
  const linkSaid = said(/^Link /);
  const staleFrom = states.find((q) => q.stage === "ascent" && q.stale === true);
  const freshAgain = staleFrom && states.find((q) => q.at > staleFrom.at && q.stale === false);
  const cutLost = linkSaid.find((u) => u.text === "Link lost" && u.at >= staleFrom?.at && u.at <= freshAgain?.at);
  const cutBack = cutLost && linkSaid.find((u) => u.at > cutLost.at);
  const landedAt = landed[0]?.at ?? Infinity;
  const last = linkSaid[linkSaid.length - 1];
  const alternate = linkSaid.every((u, i) => (i === 0 ? u.text === "Link up" : u.text === (i % 2 === 1 ? "Link lost" : "Link back")));
  const lostWhenStale = linkSaid.filter((u) => u.text === "Link lost").every((u) => states.some((q) => q.stale === true && q.at <= u.at && q.at >= u.at - 5000));
  check("A: link up, lost during the cut (after the station saw it stale), back after it came back, lost when the landed drone went quiet — in turn, never twice the same",
    alternate && lostWhenStale && cutLost !== undefined && cutBack?.text === "Link back" && cutBack.at >= freshAgain.at && cutBack.at < landedAt && last?.text === "Link lost" && last.at > landedAt,
    `${linkSaid.map((u) => `${u.text} at ${((u.at - t0) / 1000).toFixed(1)} s`).join(", ")}; the page's states stale from ${staleFrom ? ((staleFrom.at - t0) / 1000).toFixed(1) : "?"} s to ${freshAgain ? ((freshAgain.at - t0) / 1000).toFixed(1) : "?"} s`);
  const alarmsRaised = new Set(polls.flatMap((q) => q.alarms));
  const keepOut = said(/^Keep-out alarm/);
  const ours = keepOut.filter((u) => u.text.endsWith(`in ${ZONE}`));
  check("A: the keep-out alarm said when the station raised it for the zone put under the landing, each alarm once",
    zonePut?.status === 200 && [...alarmsRaised].some((k) => k.endsWith(`|${ZONE}`)) && ours.length >= 1 && ours.every((u) => u.at > zonePut.at) && new Set(texts(keepOut)).size === keepOut.length,
    `zone put → ${zonePut?.status}; station's alarms ${[...alarmsRaised].join(", ") || "none"}; said ${JSON.stringify(texts(keepOut))}`);
  const denied = said(/^Command /);
  const status = await attr(A.page, "command-item", "data-status");
  check("A: the manual mode the drone denied is said once", commanded && status === "denied" && texts(denied).join() === "Command denied: mode to manual", `the page's entry: ${status}; said ${JSON.stringify(texts(denied))}`);
  const oscillators = await A.page.evaluate(() => window.__oscillators);
  const alarms = a.filter((u) => ALARM.test(u.text)).length;
  check("A: a two-beep tone before each alarm (link lost, keep-out), none before the rest", alarms >= 3 && oscillators === 2 * alarms, `${oscillators} beeps for ${alarms} alarms`);
  const repeats = a.filter((u, i) => i > 0 && u.text === a[i - 1].text);
  check("A: nothing said twice in a row (4 Hz states are no news)", repeats.length === 0 && a.length >= 12, `${a.length} utterances; repeated: ${JSON.stringify(texts(repeats))}`);

  // ---------------------------------------------------------------- B and C
  const launchAt = said(/^Launched/)[0]?.at ?? Infinity;
  // The same call-outs, whatever order two pages' timing gives them; a viewer names another's
  // command by the command alone ("set mode" rather than "mode to manual").
  const same = (x, y) => {
    const norm = (us) => texts(us).map((t) => t.replace(/^(Command [^:]+):.*$/, "$1")).sort().join(" | ");
    return norm(x) === norm(y);
  };
  const inFlight = a.filter((u) => u.at >= launchAt && u.at <= landedAt && !Object.values(STAGE_WORDS).includes(u.text));
  check("B (stage off, only while flying): A's in-flight call-outs without the stage changes — nothing on the pad or on the ground after",
    same(b, inFlight) && texts(b).includes("Final approach") && texts(b).some((t) => /^Landed/.test(t)) && !texts(b).includes("Link up"),
    `B: ${texts(b).join(" | ")}`);
  const cBeeps = await C.page.evaluate(() => window.__oscillators);
  check("C (mute all): nothing said, no tone, while A said everything", c.length === 0 && cBeeps === 0 && a.length >= 12, `C: ${JSON.stringify(texts(c))}, ${cBeeps} beeps`);
  const cList = await C.page.locator('[data-testid="voice-said-item"][data-heard="false"]').count();
  check("C: the muted call-outs are still written in the Voice tab", cList >= 8, `${cList} listed as not heard`);

  // ---------------------------------------------------------------- the tab and the header, at 1440×900 and on a phone
  await A.page.screenshot({ path: join(out, "voice-panel.png") });
  await A.page.click('[data-testid="voice-quick"]');
  const quickA = { box: await A.page.locator('[data-testid="voice-mute-all"]').isChecked(), stored: await A.page.evaluate(() => JSON.parse(localStorage.getItem("stx.voice") ?? "{}").muted) };
  check("the header's quick mute is the tab's mute all, kept in the browser", quickA.box && quickA.stored === true, JSON.stringify(quickA));
  const phone = await C.page.evaluate(() => ({ scrollW: document.documentElement.scrollWidth, panelW: document.querySelector('[data-testid="panel-voice"]').getBoundingClientRect().width }));
  check("phone (390 px): the Voice tab fits, no sideways scrolling", phone.scrollW <= 390 && phone.panelW > 300, `page ${phone.scrollW} px wide, tab ${phone.panelW.toFixed(0)} px`);
  await C.page.locator('[data-testid="panel-voice"]').scrollIntoViewIfNeeded();
  await C.page.screenshot({ path: join(out, "voice-phone.png") });
  await A.ctx.close();
  await B.ctx.close();
  await C.ctx.close();
}

await runFlights(flight, ["ServerMessage:hello", "ServerMessage:state", "ServerMessage:command_result", "StateMsg", "KeepOutMsg", "KeepOutBody", "ModeBody", "CommandAccepted", "Session"]);
