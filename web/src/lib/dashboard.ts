/**
 * What the dashboard suggests when there is nothing to show yet: with no hubs, how to get one (a hub
 * turned on in Bluetooth range, one on USB, or virtual hubs with the simulator behind them); with hubs
 * but no run in the history, how to make the first one.
 */

export type NextStep =
  | { kind: "no-hubs"; ble: "scanning" | "off" | "unavailable"; bleDetail: string | null }
  | { kind: "no-runs" }
  | null;

/** `ble` is the daemon's Bluetooth scan state: "scanning", "starting", "off (--no-ble)" or "unavailable (why)…". */
export function nextStep(hubCount: number, hasRuns: boolean | null, ble: string | null): NextStep {
  if (hubCount === 0) {
    const state = (ble ?? "").trim();
    if (state.startsWith("scanning") || state.startsWith("starting")) return { kind: "no-hubs", ble: "scanning", bleDetail: null };
    if (state.startsWith("unavailable")) return { kind: "no-hubs", ble: "unavailable", bleDetail: state.slice("unavailable".length).trim() || null };
    return { kind: "no-hubs", ble: "off", bleDetail: null };
  }
  return hasRuns === false ? { kind: "no-runs" } : null;
}
