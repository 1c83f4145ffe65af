import { describe, expect, it } from "vitest";
import { HubOutput } from "../src/lib/output";

const line = (line_no: number, text = `line ${line_no}`) => ({ line_no, text, hub_ms: 1000 + line_no, recv_ms: 2000 + line_no });
const texts = (o: HubOutput) => o.entries.map((e) => e.text);

describe("HubOutput", () => {
  it("keeps each run's lines once and in order", () => {
    const o = new HubOutput();
    o.startRun("r1", "run r1", 0);
    expect(o.append("r1", [line(1), line(2)])).toBeNull();
    expect(o.append("r1", [line(2), line(3)])).toBeNull();
    expect(texts(o)).toEqual(["run r1", "line 1", "line 2", "line 3"]);
  });

  it("holds lines after a hole until the store fills it", () => {
    const o = new HubOutput();
    o.append("r1", [line(1)]);
    const hole = o.append("r1", [line(4), line(5)]);
    expect(hole).toEqual({ run: "r1", after: 1, before: 4 });
    // More live lines while the fetch is out wait too.
    expect(o.append("r1", [line(6)])).toBeNull();
    expect(texts(o)).toEqual(["line 1"]);
    o.fill("r1", [line(2), line(3), line(4)]);
    expect(texts(o)).toEqual(["line 1", "line 2", "line 3", "line 4", "line 5", "line 6"]);
    expect(o.lastLine("r1")).toBe(6);
  });

  it("says how many lines are lost when the store no longer has them", () => {
    const o = new HubOutput();
    o.append("r1", [line(1)]);
    o.append("r1", [line(5)]);
    o.fill("r1", []);
    expect(texts(o)).toEqual(["line 1", "[3 lines lost: no longer held by the daemon]", "line 5"]);
    expect(o.entries[1].kind).toBe("error");
  });

  it("loads a run opened mid-way from the store", () => {
    const o = new HubOutput();
    const hole = o.append("r2", [line(50)]);
    expect(hole).toEqual({ run: "r2", after: 0, before: 50 });
    o.fill("r2", Array.from({ length: 50 }, (_, i) => line(i + 1)));
    expect(o.entries).toHaveLength(50);
    expect(o.entries.at(-1)?.text).toBe("line 50");
  });

  it("notifies subscribers with only the new entries, and trims to its limit", () => {
    const o = new HubOutput(3);
    const seen: string[][] = [];
    o.subscribe((entries) => seen.push(entries.map((e) => e.text)));
    o.append("r", [line(1), line(2)]);
    o.append("r", [line(3), line(4)]);
    expect(seen).toEqual([["line 1", "line 2"], ["line 3", "line 4"]]);
    expect(texts(o)).toEqual(["line 2", "line 3", "line 4"]);
    expect(o.trimmed).toBe(1);
  });

  it("downloads as text stamped with local time", () => {
    const o = new HubOutput();
    o.append("r", [line(1, "hello")]);
    expect(o.text()).toMatch(/^\d\d:\d\d:\d\d\.\d{3} {2}hello\n$/);
  });

  it("clears without forgetting where each run is", () => {
    const o = new HubOutput();
    o.append("r", [line(1), line(2)]);
    o.clear();
    o.append("r", [line(2), line(3)]);
    expect(texts(o)).toEqual(["line 3"]);
  });
});
