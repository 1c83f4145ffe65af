import { describe, expect, it } from "vitest";
import { type Envelope, EventStream, type Refetch, type StreamSocket } from "../src/lib/events";

/** A socket the test drives by hand: what the daemon would send, when it would close. */
class HandSocket implements StreamSocket {
  onopen: ((ev: unknown) => void) | null = null;
  onmessage: ((ev: { data: unknown }) => void) | null = null;
  onclose: ((ev: { code: number; reason: string }) => void) | null = null;
  onerror: ((ev: unknown) => void) | null = null;
  sent: string[] = [];
  closed = false;
  constructor(readonly url: string) {}
  send(data: string) {
    this.sent.push(data);
  }
  close() {
    this.closed = true;
  }
  open() {
    this.onopen?.({});
  }
  push(e: Partial<Envelope>) {
    this.onmessage?.({ data: JSON.stringify({ hub: null, run: null, ts: 0, data: {}, ...e }) });
  }
  /** Several envelopes in one frame, as the daemon sends them when asked for `batch_ms`. */
  pushFrame(es: Partial<Envelope>[]) {
    this.onmessage?.({ data: JSON.stringify(es.map((e) => ({ hub: null, run: null, ts: 0, data: {}, ...e }))) });
  }
  drop(code = 1006) {
    this.onclose?.({ code, reason: "" });
  }
}

function harness() {
  const sockets: HandSocket[] = [];
  const events: Envelope[] = [];
  const refetches: Refetch[] = [];
  const notices: string[] = [];
  const states: string[] = [];
  const timers: (() => void)[] = [];
  const stream = new EventStream({
    url: (since, boot) => `ws://x/api/events${since === null ? "" : `?since=${since}&boot=${boot}`}`,
    open: (u) => {
      const s = new HandSocket(u);
      sockets.push(s);
      return s;
    },
    handlers: {
      event: (e) => events.push(e),
      refetch: (r) => refetches.push(r),
      notice: (m) => notices.push(m),
      state: (s) => states.push(s),
    },
    setTimer: (fn) => timers.push(fn),
    clearTimer: () => {},
  });
  const fire = () => timers.splice(0).forEach((t) => t());
  return { stream, sockets, events, refetches, notices, states, fire };
}

describe("EventStream", () => {
  it("delivers events in order and resumes after the last seq of its lifetime on reconnect", () => {
    const h = harness();
    h.stream.start();
    expect(h.sockets[0].url).toBe("ws://x/api/events");
    h.sockets[0].open();
    h.sockets[0].push({ seq: null as unknown as number, type: "hello", data: { boot: "B1", seq: 0, resume_from: 0 } });
    for (const seq of [1, 2, 3]) h.sockets[0].push({ seq, type: "output" });
    h.sockets[0].drop();
    expect(h.stream.state).toBe("reconnecting");
    h.fire();
    expect(h.sockets[1].url).toBe("ws://x/api/events?since=3&boot=B1");
    h.sockets[1].open();
    h.sockets[1].push({ seq: null as unknown as number, type: "hello", data: { boot: "B1", seq: 5, resume_from: 3 } });
    // A replay overlapping what we had is handled once only.
    for (const seq of [3, 4, 5]) h.sockets[1].push({ seq, type: "output" });
    expect(h.events.map((e) => e.seq)).toEqual([1, 2, 3, 4, 5]);
    expect(h.refetches).toEqual([]);
    expect(h.stream.state).toBe("live");
  });

  it("takes a frame of several envelopes one by one, in order, with overlaps and jumps judged inside it", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.sockets[0].pushFrame([{ seq: null as unknown as number, type: "hello", data: { boot: "B1", seq: 0, resume_from: 0 } }, { seq: 1, type: "hub" }, { seq: 2, type: "output" }]);
    h.sockets[0].pushFrame([{ seq: 2, type: "output" }, { seq: 3, type: "output" }, { seq: 6, type: "output" }]);
    expect(h.events.map((e) => e.seq)).toEqual([1, 2, 3, 6]);
    expect(h.refetches).toHaveLength(1);
    expect(h.refetches[0]).toMatchObject({ reason: "gap", from: 4, to: 5 });
    expect(h.stream.boot).toBe("B1");
    h.sockets[0].onmessage?.({ data: "[{not json" });
    expect(h.stream.malformed).toBe(1);
  });

  it("starts counting from the hello when it connects fresh", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.sockets[0].push({ seq: null as unknown as number, type: "hello", data: { boot: "B1", seq: 41, resume_from: 41 } });
    h.sockets[0].push({ seq: 42, type: "hub" });
    expect(h.refetches).toEqual([]);
    expect(h.stream.lastSeq).toBe(42);
  });

  it("turns a gap message into a refetch and resumes after the gap", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.sockets[0].push({ seq: 1, type: "output" });
    h.sockets[0].push({ seq: null as unknown as number, type: "gap", data: { from_seq: 2, to_seq: 39, reason: "not_saved", message: "not saved" } });
    h.sockets[0].push({ seq: 40, type: "output" });
    expect(h.refetches).toEqual([{ reason: "gap", message: "not saved", from: 2, to: 39, quiet: false }]);
    expect(h.events.map((e) => e.seq)).toEqual([1, 40]);
    expect(h.stream.lastSeq).toBe(40);
  });

  it("reloads quietly over events the daemon never keeps", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.sockets[0].push({ seq: 1, type: "hub" });
    h.sockets[0].push({ seq: null as unknown as number, type: "gap", data: { from_seq: 2, to_seq: 2, reason: "not_kept" } });
    expect(h.refetches[0].quiet).toBe(true);
  });

  it("never lets an unannounced jump in seq pass silently", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.sockets[0].push({ seq: 1, type: "output" });
    h.sockets[0].push({ seq: 5, type: "output" });
    expect(h.refetches).toHaveLength(1);
    expect(h.refetches[0]).toMatchObject({ reason: "gap", from: 2, to: 4 });
    expect(h.events.map((e) => e.seq)).toEqual([1, 5]);
  });

  it("says so on a resync and takes the catch-up that follows in order", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.sockets[0].push({ seq: 1, type: "output" });
    h.sockets[0].push({ seq: null as unknown as number, type: "resync", data: { from_seq: 2, to_seq: 900, reason: "fell behind" } });
    for (let seq = 2; seq <= 900; seq++) h.sockets[0].push({ seq, type: "output" });
    expect(h.notices).toHaveLength(1);
    expect(h.refetches).toEqual([]);
    expect(h.events).toHaveLength(900);
    expect(h.stream.resyncs).toBe(1);
  });

  it("notices a restarted daemon through its hello and resumes across lifetimes", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.sockets[0].push({ seq: null as unknown as number, type: "hello", data: { boot: "A", seq: 10, resume_from: 10 } });
    h.sockets[0].push({ seq: 11, type: "hub" });
    h.sockets[0].drop();
    h.fire();
    expect(h.sockets[1].url).toContain("since=11&boot=A");
    h.sockets[1].open();
    h.sockets[1].push({ seq: null as unknown as number, type: "hello", data: { boot: "B", seq: 20, resume_from: 11 } });
    h.sockets[1].push({ seq: 12, type: "hub" });
    expect(h.notices).toEqual(["The console daemon restarted; resuming from its store."]);
    expect(h.events.map((e) => e.seq)).toEqual([11, 12]);
    expect(h.stream.boot).toBe("B");
  });

  it("backs off between attempts and resets after a successful connect", () => {
    const delays: number[] = [];
    const sockets: HandSocket[] = [];
    const stream = new EventStream({
      url: () => "ws://x",
      open: (u) => {
        const s = new HandSocket(u);
        sockets.push(s);
        return s;
      },
      handlers: { event: () => {}, refetch: () => {} },
      backoffMs: [100, 200, 400],
      setTimer: (fn, ms) => {
        delays.push(ms);
        fn();
      },
    });
    stream.start();
    sockets[0].drop();
    sockets[1].drop();
    sockets[2].drop();
    sockets[3].drop();
    sockets[4].open();
    sockets[4].drop();
    expect(delays).toEqual([100, 200, 400, 400, 100]);
  });

  it("stops for good when the daemon refuses the token", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].drop(4401);
    h.fire();
    expect(h.sockets).toHaveLength(1);
    expect(h.stream.state).toBe("refused");
  });

  it("counts malformed messages without breaking the stream", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.sockets[0].onmessage?.({ data: "not json" });
    h.sockets[0].onmessage?.({ data: "{}" });
    h.sockets[0].onmessage?.({ data: JSON.stringify({ seq: "x", type: "hub" }) });
    h.sockets[0].push({ seq: 1, type: "hub" });
    expect(h.stream.malformed).toBe(3);
    expect(h.events).toHaveLength(1);
  });

  it("closes quietly on stop without reconnecting", () => {
    const h = harness();
    h.stream.start();
    h.sockets[0].open();
    h.stream.stop();
    expect(h.sockets[0].closed).toBe(true);
    h.fire();
    expect(h.sockets).toHaveLength(1);
    expect(h.stream.state).toBe("closed");
  });
});
