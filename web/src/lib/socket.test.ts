import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import { LiveSocket, type SocketStatus, type WsLike } from "./socket";
import type { ServerMessage } from "./types";

class FakeWs implements WsLike {
  readyState = 0;
  onopen: WsLike["onopen"] = null;
  onclose: WsLike["onclose"] = null;
  onerror: WsLike["onerror"] = null;
  onmessage: WsLike["onmessage"] = null;
  sent: string[] = [];
  constructor(readonly url: string) {}
  send(d: string): void {
    this.sent.push(d);
  }
  close(): void {
    this.readyState = 3;
    this.onclose?.({ code: 1000, reason: "" });
  }
  open(): void {
    this.readyState = 1;
    this.onopen?.({});
  }
  drop(): void {
    this.readyState = 3;
    this.onclose?.({ code: 1006, reason: "" });
  }
}

describe("LiveSocket", () => {
  let made: FakeWs[];
  let statuses: SocketStatus[];
  let msgs: ServerMessage[];
  let sock: LiveSocket;

  beforeEach(() => {
    vi.useFakeTimers();
    made = [];
    statuses = [];
    msgs = [];
    sock = new LiveSocket({
      url: () => "ws://x/api/ws?token=op",
      create: (u) => {
        const w = new FakeWs(u);
        made.push(w);
        return w;
      },
      onMessage: (m) => msgs.push(m),
      onStatus: (s) => statuses.push(s),
      random: () => 0.5,
      now: () => 0,
    });
  });
  afterEach(() => vi.useRealTimers());

  it("reconnects with growing delays, and resets them after a success", () => {
    sock.start();
    made[0]!.drop();
    expect(statuses.at(-1)).toMatchObject({ kind: "waiting", attempt: 1, retryAtMs: 500 });
    vi.advanceTimersByTime(499);
    expect(made).toHaveLength(1);
    vi.advanceTimersByTime(1);
    expect(made).toHaveLength(2);
    made[1]!.drop();
    expect(statuses.at(-1)).toMatchObject({ kind: "waiting", attempt: 2, retryAtMs: 1000 });
    vi.advanceTimersByTime(1000);
    made[2]!.open();
    expect(statuses.at(-1)).toEqual({ kind: "open" });
    made[2]!.drop();
    expect(statuses.at(-1)).toMatchObject({ attempt: 1, retryAtMs: 500 });
  });

  it("decodes good frames, counts bad ones, never throws", () => {
    sock.start();
    made[0]!.open();
    for (const data of ['{"type":"pong"}', "garbage", '{"type":"state"}', 17]) made[0]!.onmessage?.({ data });
    expect(msgs).toEqual([{ type: "pong" }]);
    expect([sock.stats.received, sock.stats.bad]).toEqual([4, 3]);
  });

  /** A started socket whose open connection's sends go to `log` as `sent <frame>`. */
  function openRecording(log: string[], onMessage: (m: { type: string }) => void): FakeWs {
    sock = new LiveSocket({
      url: () => "ws://x/api/ws?token=op",
      create: (u) => {
        const w = new FakeWs(u);
        w.send = (d) => log.push(`sent ${d}`);
        made.push(w);
        return w;
      },
      onMessage,
      onStatus: () => {},
    });
    sock.start();
    made[0]!.open();
    return made[0]!;
  }
  const STATE = JSON.stringify({ type: "state", time_s: 1, link: { connected: false, stale: true, age_s: null, ages_s: {} }, mission: { stage: null, landing: null } });
  const ACK = 'sent {"type":"state_ack"}';

  it("acknowledges each state once handed to the page, and each unreadable frame, nothing else", () => {
    const order: string[] = [];
    const ws = openRecording(order, (m) => order.push(`page ${m.type}`));
    for (const data of [STATE, '{"type":"pong"}', "garbage", STATE]) ws.onmessage?.({ data });
    expect(order).toEqual(["page state", ACK, "page pong", ACK, "page state", ACK]);
    expect(ws.url).toBe("ws://x/api/ws?token=op&state_acks=true");
  });

  it("acknowledges a state whose handling threw", () => {
    const sent: string[] = [];
    const ws = openRecording(sent, () => {
      throw new Error("a panel failed");
    });
    expect(() => ws.onmessage?.({ data: STATE })).toThrow("a panel failed");
    expect(sent).toEqual([ACK]);
  });

  it("sends only while open; nothing is queued", () => {
    sock.start();
    expect(sock.send({ type: "ping" })).toBe(false);
    made[0]!.open();
    expect(sock.send({ type: "ping" })).toBe(true);
    expect(made[0]!.sent).toEqual(['{"type":"ping"}']);
  });

  it("stop() does not reconnect", () => {
    sock.start();
    sock.stop();
    vi.advanceTimersByTime(60_000);
    expect(made).toHaveLength(1);
  });
});
