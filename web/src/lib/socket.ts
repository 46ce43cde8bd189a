// The live WebSocket, reconnecting with backoff. It decodes every frame (parse.ts), counts bad
// ones, hands good messages to the page, and acknowledges each state once handled. The socket
// factory and timers are injectable so the reconnect logic can be tested without a network.

import { backoffMs } from "./backoff";
import { decodeMessage, MessageStats } from "./parse";
import type { ClientMessage, ServerMessage } from "./types";

export type SocketStatus =
  | { kind: "connecting"; attempt: number }
  | { kind: "open" }
  | { kind: "waiting"; attempt: number; retryAtMs: number; reason: string };

export interface WsLike {
  readyState: number;
  onopen: ((ev: unknown) => void) | null;
  onclose: ((ev: { code: number; reason: string }) => void) | null;
  onerror: ((ev: unknown) => void) | null;
  onmessage: ((ev: { data: unknown }) => void) | null;
  send(data: string): void;
  close(): void;
}

export interface LiveSocketDeps {
  url: () => string;
  create?: (url: string) => WsLike;
  onMessage: (m: ServerMessage) => void;
  onStatus: (s: SocketStatus) => void;
  now?: () => number;
  random?: () => number;
}

const OPEN = 1;

export class LiveSocket {
  readonly stats = new MessageStats();
  private ws: WsLike | null = null;
  private attempt = 0;
  private retry: ReturnType<typeof setTimeout> | null = null;
  private stopped = false;

  constructor(private readonly deps: LiveSocketDeps) {}

  get open(): boolean {
    return this.ws !== null && this.ws.readyState === OPEN;
  }

  start(): void {
    this.stopped = false;
    this.connect();
  }

  stop(): void {
    this.stopped = true;
    if (this.retry !== null) clearTimeout(this.retry);
    this.ws?.close();
    this.ws = null;
  }

  /** Drops a socket that went silent (half-open TCP); the close handler schedules the retry. */
  kick(): void {
    this.ws?.close();
  }

  /** Sends a client message; false if the socket is not open (nothing queued: stale stick input is worse than none). */
  send(m: ClientMessage): boolean {
    if (!this.open || this.ws === null) return false;
    try {
      this.ws.send(JSON.stringify(m));
      return true;
    } catch {
      return false;
    }
  }

  private connect(): void {
    this.deps.onStatus({ kind: "connecting", attempt: this.attempt });
    const create = this.deps.create ?? ((u: string) => new WebSocket(u) as unknown as WsLike);
    let ws: WsLike;
    try {
      // It says so as it connects: the station then holds states for it from the first.
      const url = this.deps.url();
      ws = create(`${url}${url.includes("?") ? "&" : "?"}state_acks=true`);
    } catch (e) {
      this.scheduleRetry(e instanceof Error ? e.message : "cannot open");
      return;
    }
    this.ws = ws;
    ws.onopen = () => {
      this.attempt = 0;
      this.deps.onStatus({ kind: "open" });
    };
    ws.onmessage = (ev) => {
      const d = decodeMessage(ev.data);
      this.stats.record(d);
      try {
        if (d.ok) this.deps.onMessage(d.msg);
      } finally {
        // Handled: the station sends the next state only then (API.md, `state_ack`), so a busy
        // page is sent the newest state instead of a backlog. A frame that could not be read
        // may have been a state: acknowledged too, or the station would wait for it. In
        // `finally`: a state whose handling threw is done with too, and an acknowledgement
        // lost for good would narrow the page's flow for the rest of the connection.
        if (!d.ok || d.msg.type === "state") this.send({ type: "state_ack" });
      }
    };
    ws.onerror = () => {
      // onclose follows with the code; nothing to do here but not let the error escape.
    };
    ws.onclose = (ev) => {
      if (this.ws !== ws) return;
      this.ws = null;
      if (!this.stopped) this.scheduleRetry(ev.reason || `closed (code ${ev.code})`);
    };
  }

  private scheduleRetry(reason: string): void {
    const delay = backoffMs(this.attempt, this.deps.random);
    const now = (this.deps.now ?? Date.now)();
    this.deps.onStatus({ kind: "waiting", attempt: this.attempt + 1, retryAtMs: now + delay, reason });
    this.attempt += 1;
    this.retry = setTimeout(() => {
      this.retry = null;
      if (!this.stopped) this.connect();
    }, delay);
  }
}
