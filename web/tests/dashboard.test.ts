import { describe, expect, it } from "vitest";
import { nextStep } from "../src/lib/dashboard";

describe("nextStep", () => {
  it("with no hubs, says how to get one, by the state of the Bluetooth scan", () => {
    expect(nextStep(0, null, "scanning")).toEqual({ kind: "no-hubs", ble: "scanning", bleDetail: null });
    expect(nextStep(0, true, "off (--no-ble)")).toEqual({ kind: "no-hubs", ble: "off", bleDetail: null });
    expect(nextStep(0, false, "unavailable (BleakError: no adapter); virtual and USB hubs work without it")).toEqual({
      kind: "no-hubs",
      ble: "unavailable",
      bleDetail: "(BleakError: no adapter); virtual and USB hubs work without it",
    });
    expect(nextStep(0, null, null)?.kind).toBe("no-hubs");
  });

  it("with hubs and an empty history, points at the first run; otherwise nothing", () => {
    expect(nextStep(2, false, "scanning")).toEqual({ kind: "no-runs" });
    expect(nextStep(2, true, "scanning")).toBeNull();
    expect(nextStep(2, null, "scanning")).toBeNull(); // not loaded yet: no hint that may be wrong
  });
});
