import { describe, expect, it } from "vitest";
import { paddedRange, timeRange, unitOf, unitsOf } from "../src/lib/plotscale";

describe("plot scales", () => {
  it("reads the unit from the series name", () => {
    expect(unitOf("x_mm").label).toBe("mm");
    expect(unitOf("heading_deg").label).toBe("deg");
    expect(unitOf("left_dps").label).toBe("deg/s");
    expect(unitOf("error").label).toBe("value");
  });

  it("gives one axis per unit, in the order the series come", () => {
    const names = ["x_mm", "y_mm", "heading_deg", "left_dps", "right_dps", "error"];
    expect(unitsOf(names).map((u) => u.label)).toEqual(["mm", "deg", "deg/s", "value"]);
  });

  it("gives a flat series room for several ticks", () => {
    expect(paddedRange(0, 0)).toEqual([-1, 1]);
    expect(paddedRange(200, 200)).toEqual([180, 220]);
    expect(paddedRange(null, null)).toEqual([-1, 1]);
    const [lo, hi] = paddedRange(0, 100);
    expect(lo).toBeLessThan(0);
    expect(hi).toBeGreaterThan(100);
  });

  it("spans the samples' time, a lone sample one second", () => {
    expect(timeRange(2, 5)).toEqual([2, 5]);
    expect(timeRange(3, 3)).toEqual([3, 4]);
  });
});
