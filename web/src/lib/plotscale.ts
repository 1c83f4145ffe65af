/**
 * How the telemetry plots scale: one y axis per unit, read from a series' name the way the runtime and
 * the simulator name them (`x_mm`, `heading_deg`, `left_dps`), and ranges with room for several ticks
 * even when a series holds one value (a robot driving straight plots y_mm = 0 throughout, which uPlot
 * alone draws as an axis with the single tick "0").
 */

export interface Unit {
  /** the uPlot scale key */
  key: string;
  /** the axis label */
  label: string;
}

const SUFFIXES: [string, Unit][] = [
  ["_mm", { key: "mm", label: "mm" }],
  ["_deg", { key: "deg", label: "deg" }],
  ["_dps", { key: "dps", label: "deg/s" }],
  ["_degs", { key: "dps", label: "deg/s" }],
  ["_ms", { key: "ms", label: "ms" }],
  ["_pct", { key: "pct", label: "%" }],
  ["_v", { key: "v", label: "V" }],
];
const PLAIN: Unit = { key: "value", label: "value" };

export function unitOf(name: string): Unit {
  const lower = name.toLowerCase();
  for (const [suffix, unit] of SUFFIXES) if (lower.endsWith(suffix)) return unit;
  return PLAIN;
}

/** The distinct units of `names`, in order of first appearance: one axis each. */
export function unitsOf(names: string[]): Unit[] {
  const seen = new Map<string, Unit>();
  for (const n of names) {
    const u = unitOf(n);
    if (!seen.has(u.key)) seen.set(u.key, u);
  }
  return [...seen.values()];
}

/**
 * A range around [min, max] with a little margin; a flat series (or none) gets a span of its own size
 * (at least 1), centred on its value, so the axis shows several ticks.
 */
export function paddedRange(min: number | null, max: number | null): [number, number] {
  if (min == null || max == null || !Number.isFinite(min) || !Number.isFinite(max)) return [-1, 1];
  const span = max - min;
  if (span <= 0) {
    const half = Math.max(1, Math.abs(min) * 0.1);
    return [min - half, max + half];
  }
  const pad = span * 0.05;
  return [min - pad, max + pad];
}

/** The time axis: exactly the samples' span, or one second from a lone sample's time. */
export function timeRange(min: number | null, max: number | null): [number, number] {
  if (min == null || max == null || !Number.isFinite(min) || !Number.isFinite(max)) return [0, 1];
  return max > min ? [min, max] : [min, min + 1];
}
