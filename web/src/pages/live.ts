// The live page: the operators' replacement of "STX center". This module wires the pieces:
// session and token, the WebSocket, the panels, commands and their outcomes, staleness. The
// logic lives in ../lib (tested); the panels in ../ui.

import "../styles/common.css";
import "../styles/live.css";
import { Api, ApiError, type CommandBodies, type CommandPath } from "../lib/api";
import { CommandTracker, type CommandEntry } from "../lib/commands";
import { fmt, fmtMissionTime, label } from "../lib/format";
import { parseAscentWind, parseKeepOut, parseParams, parseSession, isObj } from "../lib/parse";
import { LiveSocket, type SocketStatus } from "../lib/socket";
import { landingBadge, phaseLabel } from "../lib/recovery";
import { replicaAlarm } from "../lib/replica";
import { SeekEpoch } from "../lib/replaySeek";
import { judgeStaleness, type StaleVerdict } from "../lib/staleness";
import { resolveToken, searchWithoutToken, withToken } from "../lib/token";
import type { EventMsg, Level, Session, State, TrackPoint } from "../lib/types";
import { AttitudeIndicator, Compass } from "../ui/attitude";
import { CommandList } from "../ui/commandList";
import { GuidanceInputs, ModeButtons, TargetEditor, type SendCommand } from "../ui/controls";
import { CutdownButton } from "../ui/cutdownButton";
import { h, panel, setText } from "../ui/dom";
import { EventLog } from "../ui/eventLog";
import { Actuators, FlightData } from "../ui/flightData";
import { JoystickPanel } from "../ui/joystickPanel";
import { LinkPanel } from "../ui/linkPanel";
import { RecordingsPanel } from "../ui/recordingsPanel";
import { ReplayBar } from "../ui/replayBar";
import { MapView } from "../ui/map";
import { ParamEditor } from "../ui/paramEditor";
import { PickGroup } from "../ui/pick";
import { PlanEditor } from "../ui/planEditor";
import { Plots } from "../ui/plots";
import { applyRole, OPERATOR_REQUIRED, REPLAY_HAS_NO_DRONE } from "../ui/role";
import { tabs } from "../ui/tabs";
import { View3D } from "../ui/view3d";
import { VoicePanel } from "../ui/voicePanel";
import { WindPanel } from "../ui/windPanel";
import { ReadinessPanel } from "../ui/readinessPanel";
import { SharingPanel } from "../ui/sharingPanel";
import { parseSharing } from "../lib/sharing";
import { parseSurfaceWind } from "../lib/surfaceWind";

const app = document.getElementById("app")!;
const token = resolveToken(location.search, sessionStorage);
if (new URLSearchParams(location.search).has("token")) history.replaceState(null, "", `${location.pathname}${searchWithoutToken(location.search)}${location.hash}`);
const api = new Api(token);

/** Seconds without any state before a silent socket is dropped and reopened. */
const SILENT_SOCKET_S = 6;
/** Live track points closer than this in time are not added (the history comes at ~1 Hz). */
const TRACK_EVERY_S = 1;

void start();

async function start(): Promise<void> {
  let attempt = 0;
  for (;;) {
    try {
      const s = parseSession(await api.get("/api/session"));
      if (!s.ok) throw new ApiError(200, "bad_session", s.error);
      build(s.value);
      return;
    } catch (e) {
      if (e instanceof ApiError && e.status === 401) {
        fatal("Not authorised", `The station refused this page's token (${e.reason}). Open the page with ?token=YOUR_TOKEN in the address.`);
        return;
      }
      attempt += 1;
      fatal("Station unreachable", `${e instanceof Error ? e.message : String(e)} — retrying (attempt ${attempt})…`);
      await new Promise((r) => setTimeout(r, Math.min(10_000, 500 * 2 ** attempt)));
    }
  }
}

function fatal(title: string, text: string): void {
  app.replaceChildren(h("div", { class: "fatal", role: "alert", "data-testid": "fatal" }, h("h1", {}, title), h("p", {}, text)));
}

function build(session: Session): void {
  let role = session.role;
  let latest: State | null = null;
  let receivedAtMs: number | null = null;
  let socketStatus: SocketStatus = { kind: "connecting", attempt: 0 };
  let verdict: StaleVerdict = judgeStaleness({ socketOpen: false, link: null, receivedAtMs: null, nowMs: Date.now() });
  let track: TrackPoint[] = [];
  /** A replay's seek shown: after a seek the track, plots and log start over, one timeline. */
  const seeks = new SeekEpoch();
  const station = session.station;

  // ---- panels
  const map = new MapView(station, token, (zones) => api.put("/api/keep-out", zones));
  const picks = new PickGroup((p) => map.setPicker(p));
  const attitude = new AttitudeIndicator();
  const compass = new Compass();
  const flight = new FlightData();
  const actuators = new Actuators();
  const wind = new WindPanel(station.origin.alt_msl_m, {
    set: async (body) => parseSurfaceWind(await api.post("/api/surface_wind", body)),
    clear: async () => parseSurfaceWind(await api.delete("/api/surface_wind")),
  });
  const readiness = new ReadinessPanel(async (id, ticked) => {
    await api.post(`/api/readiness/${encodeURIComponent(id)}`, { ticked });
  });
  const sharing = new SharingPanel();
  const link = new LinkPanel();
  const replayBar = new ReplayBar(async (body) => {
    try {
      await api.post("/api/replay", body);
    } catch (e) {
      localEvent("warning", `replay: ${e instanceof Error ? e.message : String(e)}`);
    }
  });
  const plots = new Plots();
  const view3d = new View3D(station.origin);
  const events = new EventLog();
  const recordings = new RecordingsPanel(api, token);
  const voice = new VoicePanel();
  const commandList = new CommandList();
  const tracker = new CommandTracker((e) => onCommand(e));

  const localEvent = (level: Level, text: string): void =>
    events.add({ type: "event", time_s: latest?.time_s ?? null, mission_time_s: latest?.mission_time_s ?? null, wall_ms: Date.now(), level, source: "page", text });

  const runCommand = <P extends CommandPath>(command: string, text: string, path: P, body: CommandBodies[P]): number => {
    const id = tracker.begin(command, text, Date.now());
    api.command(path, body).then(
      (rid) => tracker.accepted(id, rid, Date.now()),
      (e: unknown) => {
        const reason = e instanceof Error ? e.message : String(e);
        tracker.rejected(id, reason, Date.now());
        localEvent("warning", `${text}: rejected — ${reason}`);
      },
    );
    return id;
  };
  const send: SendCommand = (command, text, path, body) => void runCommand(command, text, path, body);

  const modes = new ModeButtons(station.modes.length > 0 ? station.modes : ["uncontrolled", "manual", "heading", "course", "localizer", "spiral_landing"], send);
  const target = new TargetEditor(send, picks, map);
  const guidanceInputs = new GuidanceInputs(send, picks, map);
  const plan = new PlanEditor(send, picks, map);
  const params = new ParamEditor((name, value) => runCommand("set_param", `param ${name} → ${value}`, `/api/params/${encodeURIComponent(name)}`, { value }));
  // Ascent bands pushed over the WebSocket (`loadAscentWind`): a push that arrives
  // while the request is out is newer than its answer, which must then not replace it (a slow
  // answer did, and the first band vanished from the panel until the next one came).
  let ascentPushes = 0;
  const socket = new LiveSocket({
    url: () => withToken(`${location.protocol === "https:" ? "wss:" : "ws:"}//${location.host}/api/ws`, token),
    onMessage: (m) => {
      switch (m.type) {
        case "hello":
          role = m.session.role;
          applyRoleEverywhere();
          // `ascent_wind` comes only when the bands change: (re)connected, the page reads them.
          loadAscentWind();
          loadKeepOut();
          break;
        case "state":
          onState(m);
          break;
        case "history":
          onHistory(m.track, m.events, m.states, m.replay_epoch);
          break;
        case "event":
          events.add(m);
          break;
        case "command_result":
          tracker.result(m, Date.now());
          break;
        case "params":
          params.setParams(m.params, m.complete);
          break;
        case "ascent_wind":
          ascentPushes += 1;
          wind.setAscent(m);
          break;
        case "keep_out":
          map.setZones(m);
          view3d.setZones(m);
          break;
        case "lagged":
          // The station dropped messages for this page: say so rather than show a silent gap.
          localEvent("warning", `this page fell behind: ${m.missed ?? "some"} events, command results or parameter tables were not received (reload to re-read them)`);
          break;
        default:
          break;
      }
    },
    onStatus: (s) => {
      socketStatus = s;
      joystick.setSocketOpen(s.kind === "open");
      refresh();
    },
  });
  const joystick = new JoystickPanel((m) => socket.send(m));
  const cutdown = new CutdownButton({
    arm: async () => {
      localEvent("warning", `cutdown: armed by ${session.name} (hold completed) at ${new Date().toISOString().slice(11, 19)}Z`);
      const r = await api.post("/api/cutdown/arm", {});
      if (!isObj(r) || typeof r.arm_id !== "string") throw new Error("no arm_id in the station's answer");
      return { arm_id: r.arm_id };
    },
    confirm: async (armId) => {
      const id = tracker.begin("cutdown", "CUTDOWN", Date.now());
      try {
        const rid = await api.command("/api/cutdown/confirm", { arm_id: armId });
        tracker.accepted(id, rid, Date.now());
        localEvent("warning", `cutdown: confirmed by ${session.name} at ${new Date().toISOString().slice(11, 19)}Z (request ${rid})`);
        return { request_id: rid };
      } catch (e) {
        tracker.rejected(id, e instanceof Error ? e.message : String(e), Date.now());
        throw e;
      }
    },
  });

  // ---- layout
  const clock = h("span", { class: "clock", "data-testid": "mission-clock" });
  const conn = h("span", { class: "badge", "data-testid": "conn-status" });
  const roleBadge = h("span", { class: "badge", "data-testid": "role-badge" });
  const hdrMode = h("span", { class: "badge", "data-testid": "hdr-mode" });
  const hdrStage = h("span", { class: "badge", "data-testid": "hdr-stage" });
  const hdrPhase = h("span", { class: "badge", "data-testid": "hdr-phase" });
  const hdrLink = h("span", { class: "badge", "data-testid": "hdr-link", title: "drone link: message rate, share lost, age of the last message" });
  const hdrLanding = h("span", { class: "badge", "data-testid": "hdr-landing" });
  const hdrReplica = h("span", { class: "badge alarm", "data-testid": "hdr-replica", role: "alert", hidden: true, title: "the station's guidance replica and the drone disagree" });
  const kml = h("a", { href: withToken("/kml", token), "data-testid": "kml-link", class: "linkbtn", title: "open in Google Earth: a network link that refreshes every 2 s" }, "KML");
  // The recovery page opens in a new tab, which does not share this tab's sessionStorage: the
  // token goes in its address (the page takes it out of the address bar at once, as this one does).
  const lab = h("a", { href: withToken("lab.html", token), target: "_blank", rel: "noopener", "data-testid": "lab-link", class: "linkbtn", title: "scenarios, Monte Carlo, stability, tuning (new tab)" }, "Lab");
  const recovery = h("a", { href: withToken("recovery.html", token), target: "_blank", rel: "noopener", "data-testid": "recovery-link", class: "linkbtn", title: "the recovery team's page for phones (new tab)" }, "Recovery");
  const planLink = h("a", { href: withToken("plan.html", token), target: "_blank", rel: "noopener", "data-testid": "plan-link", class: "linkbtn", title: "pre-flight plan: burst, deploy and landing regions from a forecast (new tab)" }, "Plan");
  const header = h("header", { class: "top" },
    h("strong", { class: "station" }, station.name), clock, conn, roleBadge,
    h("span", { class: "hdr-group" }, h("small", {}, "mode "), hdrMode, h("small", {}, " stage "), hdrStage, h("small", {}, " phase "), hdrPhase),
    hdrLink, hdrLanding, hdrReplica, readiness.badge, h("span", { class: "spacer" }), voice.quick, kml, recovery, planLink, lab);
  const banner = h("div", { class: "banner", role: "alert", "data-testid": "banner", hidden: true });
  const viewerNote = h("div", { class: "viewer-note", "data-testid": "viewer-note" }, `Viewer: you can watch everything; commanding needs the operator role (${OPERATOR_REQUIRED}).`);

  const instruments = panel("Attitude · heading", "panel-attitude", h("div", { class: "insts" }, attitude.root, compass.root));
  const left = h("aside", { class: "col left vd" }, instruments, flight.root, actuators.root, wind.root, link.root);
  const bottom = tabs("views", [
    { id: "plots", label: "Plots", content: plots.root, onShow: () => plots.layout() },
    { id: "3d", label: "3-D view", content: view3d.root, onShow: () => view3d.layout() },
    { id: "events", label: "Event log", content: events.root },
    { id: "recordings", label: "Recordings", content: recordings.root, onShow: () => void recordings.load() },
    { id: "voice", label: "Voice", content: voice.root },
  ]);
  const centre = h("section", { class: "col centre" }, h("div", { class: "map-wrap vd" }, map.root), map.legend.root, bottom.root);
  // Modes and the joystick first: in manual flight both must be in view without scrolling.
  const commandTab = h("div", {}, modes.root, joystick.root, target.root, guidanceInputs.root);
  const right = tabs("control", [
    { id: "command", label: "Command", content: commandTab },
    { id: "plan", label: "Plan", content: plan.root },
    { id: "params", label: "Parameters", content: params.root },
    { id: "readiness", label: "Go/no-go", content: h("div", {}, readiness.root, sharing.root) },
  ]);
  const rightCol = h("aside", { class: "col right" }, viewerNote, right.root, commandList.root, cutdown.root);
  app.replaceChildren(header, replayBar.root, banner, h("main", { class: "grid" }, left, centre, rightCol));
  map.invalidate();
  plots.layout();
  new ResizeObserver(() => {
    map.invalidate();
    plots.layout();
    view3d.layout();
  }).observe(centre);

  // Controls made later (parameter rows, plan items read from the drone) follow the role too:
  // a viewer's, and a replay's, are off from the moment they appear.
  new MutationObserver((records) => {
    const added = records.some((r) => Array.from(r.addedNodes).some((n) => n instanceof HTMLElement && (n.matches("[data-command]") || n.querySelector("[data-command]") !== null)));
    if (added) applyRoleEverywhere();
  }).observe(app, { childList: true, subtree: true });

  // ---- behaviour
  function applyRoleEverywhere(): void {
    // A replay has no drone to command: every command control is off, for everyone.
    const operator = role === "operator" && !station.replay;
    applyRole(document, operator, station.replay ? REPLAY_HAS_NO_DRONE : OPERATOR_REQUIRED);
    joystick.setRole(operator);
    setText(roleBadge, `${station.replay ? "REPLAY" : operator ? "OPERATOR" : "VIEWER"} ${session.name}`);
    if (station.replay) setText(viewerNote, "Replay of a recording: there is no drone to command; pause, seek and speed are in the bar above.");
    roleBadge.dataset.role = role;
  }

  function onCommand(e: CommandEntry): void {
    commandList.update(e, tracker.entries);
    params.onCommand(e);
    voice.onCommand(e, tracker.entries);
  }

  function onState(s: State): void {
    const seek = seeks.state(s.replay?.epoch ?? null);
    if (seek === "drop") return; // built before the seek now shown
    if (seek === "restart") startOver();
    latest = s;
    replayBar.update(s.replay);
    voice.onState(s, Date.now());
    receivedAtMs = Date.now();
    plots.push(s);
    const e = s.estimate;
    if (!s.link.stale && e?.lat_deg != null && e.lon_deg != null) {
      const last = track[track.length - 1];
      if (last === undefined || s.time_s - last.time_s >= TRACK_EVERY_S) {
        const p = { time_s: s.time_s, mission_time_s: s.mission_time_s, lat_deg: e.lat_deg, lon_deg: e.lon_deg, alt_msl_m: e.alt_msl_m };
        if (last !== undefined && s.time_s < last.time_s) track = []; // mission clock restarted
        track.push(p);
        if (track.length > 20_000) track = track.slice(-18_000);
        map.setTrack(track);
        view3d.addPoint(p);
      }
    }
    render();
  }

  function onHistory(t: TrackPoint[], ev: EventMsg[], states: State[], epoch: number | null): void {
    if (!seeks.history(epoch)) return; // of a seek already left
    track = t.slice();
    map.setTrack(track);
    view3d.setTrack(track);
    events.reset(ev);
    plots.reset(states, latest !== null && seeks.shows(latest.replay?.epoch ?? null) ? latest : null);
  }

  /** A replay jumped: what the page drew belongs to another moment (the history of the new one follows). */
  function startOver(): void {
    track = [];
    map.setTrack(track);
    view3d.setTrack(track);
    events.reset([]);
    plots.reset([], null);
    voice.restart();
  }

  function render(): void {
    refresh();
    const s = latest;
    if (s === null) return;
    const e = s.estimate;
    attitude.update(s.vehicle?.attitude?.roll_deg ?? null, s.vehicle?.attitude?.pitch_deg ?? null);
    compass.update(e?.heading_deg ?? s.vehicle?.attitude?.yaw_deg ?? null, e?.course_deg ?? null, e?.wind_from_deg ?? null);
    flight.update(s);
    actuators.update(s);
    wind.update(s);
    readiness.update(s.readiness);
    map.update(s, verdict.stale);
    view3d.update(s);
    modes.update(s);
    target.update(s);
    plan.update(s);
    cutdown.update(s.mission.cutdown_armed_until_s, s.time_s);
    joystick.setVehicleMode(s.vehicle?.mode ?? null);
    // The mission's clock (the drone's), at any rehearsal speed; the station's only before the drone is heard.
    setText(clock, fmtMissionTime(s.mission_time_s));
    clock.title = "mission time: the drone's clock (T+ since its start)";
    const d = s.guidance?.disagreement ?? null;
    hdrReplica.hidden = d === null;
    if (d !== null) {
      setText(hdrReplica, replicaAlarm(d));
      hdrReplica.dataset.state = d.resolved ? "resolved" : "active";
    }
    setText(hdrMode, label(s.vehicle?.mode ?? s.guidance?.mode));
    setText(hdrStage, label(s.mission.stage ?? s.vehicle?.stage));
    setText(hdrPhase, label(phaseLabel(s)));
  }

  /** Staleness and connection state: runs on every state and on a timer (ages grow in silence). */
  function refresh(): void {
    const now = Date.now();
    verdict = judgeStaleness({ socketOpen: socket.open, link: latest?.link ?? null, receivedAtMs, nowMs: now });
    document.body.classList.toggle("stale", verdict.stale);
    document.body.dataset.freshness = verdict.freshness;
    link.update(latest?.link ?? null, verdict, socket.stats, receivedAtMs, now, latest?.recording ?? null);
    const st = socketStatus;
    const connText = st.kind === "open" ? "CONNECTED" : st.kind === "connecting" ? "CONNECTING…" : `DISCONNECTED — retry in ${Math.max(0, (st.retryAtMs - now) / 1000).toFixed(0)} s`;
    setText(conn, connText);
    conn.dataset.state = st.kind;
    setText(hdrLink, latest ? `${fmt(latest.link.rate_hz, "Hz", 0)} · ${fmt(latest.link.loss_percent, "%")} lost · ${fmt(verdict.age_s, "s")} old` : "link —");
    hdrLink.dataset.state = verdict.freshness;
    // Derived from the vehicle's data: shown stale with them (ages grow in silence, hence here).
    const lb = landingBadge(latest, verdict.stale, verdict.age_s);
    setText(hdrLanding, lb.text);
    hdrLanding.dataset.state = lb.state;
    for (const b of [hdrMode, hdrStage, hdrPhase]) b.classList.toggle("stale", verdict.stale);
    if (st.kind !== "open") {
      banner.hidden = false;
      banner.dataset.kind = "disconnected";
      setText(banner, `DISCONNECTED from the station${st.kind === "waiting" ? ` (${st.reason}); reconnecting in ${Math.max(0, (st.retryAtMs - now) / 1000).toFixed(0)} s, attempt ${st.attempt}` : " — connecting…"}. Values shown are the last received and are NOT current.`);
    } else if (verdict.stale) {
      banner.hidden = false;
      banner.dataset.kind = "stale";
      setText(banner, `STALE — ${verdict.reasons.join("; ")}. Vehicle values are old and greyed; they are NOT current.`);
    } else {
      banner.hidden = true;
      banner.dataset.kind = "none";
    }
    if (socket.open && receivedAtMs !== null && now - receivedAtMs > SILENT_SOCKET_S * 1000) {
      receivedAtMs = now - SILENT_SOCKET_S * 1000; // one kick per silence, not one per tick
      socket.kick();
    }
  }

  function loadKeepOut(): void {
    api.get("/api/keep-out").then(
      (r) => {
        const k = isObj(r) ? parseKeepOut(r) : null;
        if (!k?.ok) return;
        map.setZones(k.value);
        view3d.setZones(k.value);
        if (k.value.load_error) localEvent("error", `keep-out zones NOT loaded: ${k.value.load_error}`);
      },
      (e: unknown) => localEvent("warning", `keep-out zones not loaded: ${e instanceof Error ? e.message : String(e)}`),
    );
  }

  function loadAscentWind(): void {
    const pushesBefore = ascentPushes;
    api.get("/api/ascent_wind").then(
      (r) => {
        const a = isObj(r) ? parseAscentWind(r) : null;
        if (a?.ok && ascentPushes === pushesBefore) wind.setAscent(a.value);
      },
      (e: unknown) => localEvent("warning", `ascent winds not loaded: ${e instanceof Error ? e.message : String(e)}`),
    );
  }

  // What is shared changes slowly (counts, the chase broadcast's last datagram): every 3 s.
  function loadSharing(): void {
    api.get("/api/sharing").then(
      (r) => sharing.update(parseSharing(r), Date.now()),
      (e: unknown) => sharing.failed(e instanceof Error ? e.message : String(e)),
    );
  }

  applyRoleEverywhere();
  setInterval(refresh, 250);
  loadSharing();
  setInterval(loadSharing, 3000);
  socket.start();
  api.get("/api/params").then(
    (r) => {
      const p = isObj(r) ? parseParams(r) : null;
      if (p?.ok) params.setParams(p.value.params, p.value.complete);
    },
    (e: unknown) => localEvent("warning", `parameters not loaded: ${e instanceof Error ? e.message : String(e)}`),
  );
}
