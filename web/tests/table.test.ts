import { describe, expect, it } from "vitest";
import { ConsoleModel } from "../src/lib/console.svelte";
import { batteryVolts, linkWords } from "../src/lib/format";

describe("the console at the table", () => {
  it("turns every control off while the event stream is lost, and back on when it returns", () => {
    const m = new ConsoleModel();
    m.me = { label: "local", role: "operator", via: "cookie" };
    expect(m.connectionLost).toBe(false); // the first connect is no loss
    expect(m.readOnlyReason).toBeNull();
    m.stream = "reconnecting";
    expect(m.connectionLost).toBe(true);
    expect(m.readOnlyReason).toMatch(/not reachable/);
    expect(m.uploadLockReason).toMatch(/not reachable/);
    m.stream = "refused";
    expect(m.readOnlyReason).toMatch(/signed out/);
    m.stream = "live";
    expect(m.readOnlyReason).toBeNull();
  });

  it("says a hub's link and battery where it reports them", () => {
    expect(linkWords(null)).toBeNull();
    expect(linkWords(-55)).toBe("strong");
    expect(linkWords(-75)).toBe("fair");
    expect(linkWords(-90)).toBe("weak");
    expect(batteryVolts({ battery_mv: 7412 })).toBe("7.41 V");
    expect(batteryVolts({})).toBeNull();
    expect(batteryVolts({ battery_mv: "7.4" })).toBeNull();
  });
});
