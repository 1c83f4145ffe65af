import { describe, expect, it } from "vitest";
import { auditResult, auditWords, bluetoothWords, plain, plainError, programOfRun, stopAllSummary } from "../src/lib/words";

describe("words a student understands", () => {
  it("drops HTTP calls and UTC stamps from the daemon's messages", () => {
    const said = plain("SimHub-1 is busy: run by local since 2026-11-29T04:03:12+00:00");
    expect(said).not.toMatch(/2026-11-29T/);
    expect(said).toMatch(/^SimHub-1 is busy: run by local since \d{2}.\d{2}.\d{2}/);
    expect(plain("wait for it to end, or stop it first (POST .../stop), then retry")).toBe("wait for it to end, or stop it first, then retry");
    expect(plainError({ code: "unreachable", message: "x", hint: null }).message).toBe("The console did not answer.");
  });

  it("says what Bluetooth is doing without the exception", () => {
    const pill = bluetoothWords("unavailable (FileNotFoundError: [Errno 2] No such file or directory); virtual and USB hubs work without it");
    expect(pill?.text).toBe("Bluetooth: not available on this computer");
    expect(JSON.stringify(pill)).not.toMatch(/Errno|FileNotFound/);
    expect(bluetoothWords("off (--no-ble)")?.text).toBe("Bluetooth: off");
    expect(bluetoothWords("scanning")?.text).toMatch(/looking/);
    expect(bluetoothWords(null)).toBeNull();
  });

  it("calls a STOP ALL with nothing running a success", () => {
    const idle = [
      { hub: "a", name: "SimHub-1", stopped: false, detail: "no program was running" },
      { hub: "b", name: "SimHub-2", stopped: false, detail: "no program was running" },
    ];
    expect(stopAllSummary(idle)).toEqual({ kind: "info", message: "All hubs are stopped (nothing was running)." });
    expect(stopAllSummary([{ ...idle[0], stopped: true, detail: "run stopped" }, idle[1]])).toEqual({ kind: "info", message: "Stopped SimHub-1." });
    expect(stopAllSummary([{ ...idle[0], detail: "offline" }]).kind).toBe("warn");
    const failed = stopAllSummary([{ ...idle[0], detail: "run did not end within 3 s of Ctrl-C" }]);
    expect(failed.kind).toBe("error");
    expect(failed.message).toMatch(/Could not stop SimHub-1/);
  });

  it("reads audit rows as actions", () => {
    const names = (id: string) => (id === "virtual:SimHub-1" ? "SimHub-1" : id);
    expect(auditWords("POST /api/hubs/stop-all", names)).toBe("Stopped all hubs");
    expect(auditWords("POST /api/hubs/virtual:SimHub-1/identify", names)).toBe("Identified SimHub-1 (blinked its light)");
    expect(auditWords("POST /api/hubs/virtual%3ASimHub-1/run", names)).toBe("Ran a program on SimHub-1");
    expect(auditWords("PUT /api/programs/square.py")).toBe("Saved square.py");
    expect(auditWords("flash /dev/ttyUSB0")).toBe("Flash: /dev/ttyUSB0");
    expect(auditResult(202, "POST /api/flash")).toBe("started");
    expect(auditResult(500, "flash /dev/ttyUSB0")).toBe("failed");
    expect(auditResult(403, "POST /api/hubs/stop-all")).toMatch(/refused/);
    expect(auditResult(200, "POST /api/hubs/stop-all")).toBe("done");
  });
});

describe("an audit row's program", () => {
  it("is the run that started on that hub just before the request was recorded", () => {
    const runs = [
      { hub_id: "virtual:SimHub-1", started_ms: 1000, program_name: "old.py" },
      { hub_id: "virtual:SimHub-1", started_ms: 50_000, program_name: "square.py" },
      { hub_id: "virtual:SimHub-2", started_ms: 50_010, program_name: "other.py" },
    ];
    const idOf = (ref: string) => (ref.startsWith("virtual:") ? ref : `virtual:${ref}`);
    const row = { ts_ms: 50_200, action: "POST /api/hubs/SimHub-1/run" };
    expect(programOfRun(row, runs, idOf)).toBe("square.py");
    expect(auditWords(row.action, (x) => x, programOfRun(row, runs, idOf))).toBe("Ran square.py on SimHub-1");
    expect(programOfRun({ ts_ms: 90_000, action: row.action }, runs, idOf)).toBeNull(); // too long after
    expect(programOfRun({ ts_ms: 50_200, action: "POST /api/hubs/stop-all" }, runs, idOf)).toBeNull();
  });
});
