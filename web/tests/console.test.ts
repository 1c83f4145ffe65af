import { describe, expect, it } from "vitest";
import type { Hub, OutputLine } from "../src/lib/api";
import { ConsoleModel } from "../src/lib/console.svelte";
import type { Envelope } from "../src/lib/events";
import { RunTelemetry } from "../src/lib/telemetry";

const hub = (id: string, extra: Partial<Hub> = {}): Hub => ({
  hub_id: id,
  name: id.toUpperCase(),
  kind: "virtual",
  address: id,
  status: "idle",
  rssi: null,
  last_seen_ms: null,
  firmware: "openbricks 2.7.1",
  capabilities: {},
  staged_program: null,
  run_id: null,
  run_started_ms: null,
  holder: null,
  last_error: null,
  ...extra,
});

let seq = 0;
const ev = (type: string, hubId: string | null, run: string | null, data: object): Envelope => ({
  seq: ++seq,
  type,
  hub: hubId,
  run,
  ts: 1000 + seq,
  data: data as Record<string, unknown>,
});
const line = (n: number) => ({ line_no: n, text: `l${n}`, hub_ms: n, recv_ms: n });
const settle = () => new Promise((r) => setTimeout(r, 0));

describe("ConsoleModel", () => {
  it("follows hub events and lists hubs by name", () => {
    const m = new ConsoleModel();
    m.applyEvent(ev("hub", "b", null, hub("b")));
    m.applyEvent(ev("hub", "a", null, hub("a")));
    m.applyEvent(ev("hub", "b", "R1", hub("b", { status: "running", run_id: "R1", run_started_ms: 5 })));
    expect(m.hubList.map((h) => h.name)).toEqual(["A", "B"]);
    expect(m.hubs.b.status).toBe("running");
    expect(m.anyRunning).toBe(true);
  });

  it("keeps two hubs' outputs apart and records each run's outcome", () => {
    const m = new ConsoleModel();
    m.applyEvent(ev("run_started", "a", "RA", { run_id: "RA", hub_id: "a", program_name: "p.py", origin: "daemon", started_ms: 1 }));
    m.applyEvent(ev("run_started", "b", "RB", { run_id: "RB", hub_id: "b", program_name: "p.py", origin: "daemon", started_ms: 1 }));
    m.applyEvent(ev("output", "a", "RA", { lines: [line(1), line(2)] }));
    m.applyEvent(ev("output", "b", "RB", { lines: [line(1)] }));
    m.applyEvent(ev("run_ended", "a", "RA", { run_id: "RA", outcome: "finished", detail: null, ended_ms: 9 }));
    const text = (id: string) => m.output(id).entries.map((e) => e.text);
    expect(text("a")).toEqual(["▶ p.py started (daemon)", "l1", "l2", "■ finished"]);
    expect(text("b")).toEqual(["▶ p.py started (daemon)", "l1"]);
    expect(m.lastOutcome).toEqual({ a: "finished" });
    expect(m.runs.RA.outcome).toBe("finished");
  });

  it("fills a hole in a run's output from the store before showing what follows", async () => {
    const asked: [string, number][] = [];
    const m = new ConsoleModel(async (run: string, after = 0) => {
      asked.push([run, after]);
      return [line(2), line(3)] as OutputLine[];
    });
    m.applyEvent(ev("output", "a", "R", { lines: [line(1)] }));
    m.applyEvent(ev("output", "a", "R", { lines: [line(4)] }));
    await settle();
    expect(asked).toEqual([["R", 1]]);
    expect(m.output("a").entries.map((e) => e.text)).toEqual(["l1", "l2", "l3", "l4"]);
  });

  it("shows one run's output alone: what the store has, then its live lines, each once", async () => {
    let answer: (lines: OutputLine[]) => void = () => {};
    const m = new ConsoleModel((run: string, after = 0) => {
      expect([run, after]).toEqual(["S", 0]);
      return new Promise<OutputLine[]>((resolve) => (answer = resolve));
    });
    const out = m.runOutput("S");
    // Live lines arrive while the store is still being read; one of them the store also has.
    m.applyEvent(ev("output", "sim", "S", { lines: [line(3), line(4)] }));
    m.applyEvent(ev("output", "sim", "OTHER", { lines: [line(1)] }));
    answer([line(1), line(2), line(3)] as OutputLine[]);
    await settle();
    await settle();
    m.applyEvent(ev("run_ended", "sim", "S", { run_id: "S", outcome: "finished", detail: null, ended_ms: 9 }));
    expect(out.entries.map((e) => e.text)).toEqual(["l1", "l2", "l3", "l4", "■ finished"]);
    expect(m.runOutput("S")).toBe(out);
  });

  it("keeps telemetry per run", () => {
    const m = new ConsoleModel();
    m.applyEvent(ev("telemetry", "a", "R", { samples: [{ name: "speed", value: 1, hub_ms: 1000, recv_ms: 1000 }, { name: "speed", value: 2, hub_ms: 1500, recv_ms: 1500 }] }));
    const t = m.runTelemetry("R");
    expect(t.names()).toEqual(["speed"]);
    expect(t.series.get("speed")).toEqual({ t: [0, 0.5], v: [1, 2] });
  });

  it("disables mutation for a viewer and locks uploads in competition mode while a run is on", () => {
    const m = new ConsoleModel();
    expect(m.readOnlyReason).toMatch(/Waiting/);
    m.me = { label: "coach", role: "viewer", via: "cookie" };
    expect(m.readOnlyReason).toMatch(/Viewer role/);
    m.me = { label: "local", role: "operator", via: "cookie" };
    expect(m.readOnlyReason).toBeNull();
    m.competition.on = true;
    expect(m.uploadLockReason).toBeNull();
    m.applyEvent(ev("hub", "a", "R", hub("a", { status: "running" })));
    expect(m.uploadLockReason).toMatch(/Competition mode/);
    expect(m.readOnlyReason).toBeNull(); // stopping stays possible
  });

  it("takes competition mode from the daemon and runs its match timer on this computer's clock", () => {
    const m = new ConsoleModel();
    const before = Date.now();
    // The daemon's clock is 60 s ahead of ours; its match started 10 s before it published the event.
    const daemonNow = before + 60000;
    m.applyEvent({ ...ev("competition", null, null, { on: true, match_s: 120, match_started_ms: daemonNow - 10000, changed_by: "local", changed_ms: daemonNow }), ts: daemonNow });
    expect(m.competition.on).toBe(true);
    expect(m.competition.matchSeconds).toBe(120);
    const elapsed = Date.now() - (m.competition.matchStartedMs as number);
    expect(elapsed).toBeGreaterThanOrEqual(10000);
    expect(elapsed).toBeLessThan(10000 + 1000);
    m.setCompetition({ on: false, match_s: 120, match_started_ms: null, changed_by: "local", changed_ms: 1, server_ms: 5 });
    expect(m.competition).toEqual({ on: false, matchSeconds: 120, matchStartedMs: null });
  });
});

describe("RunTelemetry", () => {
  it("puts stored samples before the live ones that arrived while they were read, each once", () => {
    const t = new RunTelemetry();
    const s = (ms: number, value: number) => ({ name: "x_mm", value, hub_ms: ms, recv_ms: ms });
    t.hold();
    t.add([s(2000, 2), s(2500, 3)]); // live, while the store is read
    expect(t.names()).toEqual([]);
    t.release([s(1000, 0), s(1500, 1), s(2000, 2)]); // the store has caught up with one of them
    expect(t.series.get("x_mm")).toEqual({ t: [0, 0.5, 1, 1.5], v: [0, 1, 2, 3] });
    t.add([s(3000, 4)]);
    expect(t.series.get("x_mm")?.v).toEqual([0, 1, 2, 3, 4]);
  });

  it("puts stored samples before live ones it took before it knew the run was under way", () => {
    const t = new RunTelemetry();
    const s = (ms: number, value: number) => ({ name: "x_mm", value, hub_ms: ms, recv_ms: ms });
    t.add([s(2000, 2)]);
    t.hold();
    t.add([s(2500, 3)]);
    t.release([s(1000, 0), s(1500, 1), s(2000, 2)]);
    expect(t.series.get("x_mm")).toEqual({ t: [0, 0.5, 1, 1.5], v: [0, 1, 2, 3] });
  });
});
