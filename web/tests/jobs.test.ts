import { describe, expect, it } from "vitest";
import { ConsoleModel } from "../src/lib/console.svelte";
import type { Envelope } from "../src/lib/events";
import { type JobRecord, jobOutcome, withLive } from "../src/lib/jobs";

const record = (id: string, extra: Partial<JobRecord> = {}): JobRecord => ({
  job_id: id,
  kind: "flash",
  label: `/dev/ttyUSB${id}`,
  batch: null,
  who: "local",
  state: "done",
  progress: 100,
  message: "done",
  params: { port: `/dev/ttyUSB${id}` },
  result: { hub_name: "RobotA", firmware: "openbricks 2.8.0" },
  steps: ["write the firmware"],
  created_ms: 1000,
  started_ms: 1000,
  ended_ms: 2000,
  ...extra,
});

let seq = 0;
const ev = (type: string, data: object): Envelope => ({ seq: ++seq, type, hub: null, run: null, ts: 5000 + seq, data: data as Record<string, unknown> });

describe("jobs in the history", () => {
  it("keeps the stored list current from the job events: progress, the end, and jobs started since", () => {
    const m = new ConsoleModel();
    const listed = [record("02", { state: "running", progress: 10, message: "write the firmware", result: null, ended_ms: null }), record("01")];
    // A progress event carries only a summary; the job's end carries the whole record.
    m.applyEvent(ev("job_progress", { job_id: "02", kind: "flash", label: "/dev/ttyUSB02", batch: null, state: "running", progress: 55 }));
    let shown = withLive(listed, m.jobs, {});
    expect(shown.map((j) => [j.job_id, j.state, j.progress])).toEqual([
      ["02", "running", 55],
      ["01", "done", 100],
    ]);
    expect(shown[0].params).toEqual({ port: "/dev/ttyUSB02" }); // what the summary lacks stays as stored

    m.applyEvent(ev("job", record("03", { kind: "servo_scan", label: "SimHub-1", state: "running", result: null, progress: null })));
    m.applyEvent(ev("job", record("02", { state: "failed", message: "no answer from the bootloader", result: null })));
    shown = withLive(listed, m.jobs, {});
    expect(shown.map((j) => [j.job_id, j.state])).toEqual([
      ["03", "running"],
      ["02", "failed"],
      ["01", "done"],
    ]);
    expect(jobOutcome(shown[1])).toBe("no answer from the bootloader");
    // Filters hold for live jobs too: one that left the state asked for drops out, a new one of another kind stays out.
    expect(withLive(listed, m.jobs, { state: "running" }).map((j) => j.job_id)).toEqual(["03"]);
    expect(withLive(listed, m.jobs, { kind: "flash" }).map((j) => j.job_id)).toEqual(["02", "01"]);
  });

  it("leaves sim runs to the runs list and older live jobs to the next page", () => {
    const m = new ConsoleModel();
    m.applyEvent(ev("job", { job: { ...record("05"), kind: "sim" } }));
    m.applyEvent(ev("job", record("00")));
    const listed = [record("04"), record("03")];
    expect(withLive(listed, m.jobs, {}, false).map((j) => j.job_id)).toEqual(["04", "03"]);
    expect(withLive(listed, m.jobs, {}, true).map((j) => j.job_id)).toEqual(["04", "03", "00"]);
  });

  it("says in a line what each kind of job came to", () => {
    expect(jobOutcome(record("01"))).toBe("named RobotA, running openbricks 2.8.0");
    const sweep = record("02", {
      kind: "sim_sweep",
      result: { rows: [{ seed: 1 }, { seed: 2 }], summary: { success_rate: 0.5, mean_score: 12.5 } },
    });
    expect(jobOutcome(sweep)).toBe("2 seeds, 50 % ran to the end, mean score 12.5");
    const scan = record("03", { kind: "servo_scan", result: { ids: [1, 2], message: "servo ids on SimHub-1's servo bus: 1, 2" } });
    expect(jobOutcome(scan)).toBe("servo ids on SimHub-1's servo bus: 1, 2");
    expect(jobOutcome(record("04", { state: "cancelled", message: "cancelled: the console was shut down while it ran" }))).toMatch(/shut down/);
  });
});
