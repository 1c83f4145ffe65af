/** How times and sizes read on the page: local time, short durations, RSSI. */

export function clock(ms: number): string {
  const s = Math.floor(ms / 1000);
  const m = Math.floor(s / 60);
  const h = Math.floor(m / 60);
  const p = (n: number) => String(n).padStart(2, "0");
  return h ? `${h}:${p(m % 60)}:${p(s % 60)}` : `${p(m)}:${p(s % 60)}`;
}

export function localTime(ms: number | null | undefined): string {
  if (ms === null || ms === undefined) return "—";
  return new Date(ms).toLocaleString(undefined, { year: "numeric", month: "2-digit", day: "2-digit", hour: "2-digit", minute: "2-digit", second: "2-digit" });
}

/** A local time, without the date when it is today's (for narrow lists). */
export function shortTime(ms: number, now = Date.now()): string {
  const d = new Date(ms);
  if (d.toDateString() !== new Date(now).toDateString()) return localTime(ms);
  return d.toLocaleTimeString(undefined, { hour: "2-digit", minute: "2-digit", second: "2-digit" });
}

export function duration(startMs: number, endMs: number | null, now = Date.now()): string {
  const ms = (endMs ?? now) - startMs;
  if (ms < 0) return "—";
  if (ms < 10000) return `${(ms / 1000).toFixed(1)} s`;
  return clock(ms);
}

export function rssiBars(rssi: number | null): number {
  if (rssi === null) return 0;
  if (rssi >= -60) return 4;
  if (rssi >= -70) return 3;
  if (rssi >= -80) return 2;
  return 1;
}

/** Offer text as a file download. */
export function download(name: string, text: string, type = "text/plain"): void {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = document.createElement("a");
  a.href = url;
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

/** Link quality in words from the RSSI the daemon reads (BLE hubs); null when the hub reports none. */
export function linkWords(rssi: number | null): string | null {
  if (rssi === null) return null;
  return ["weak", "weak", "fair", "good", "strong"][rssiBars(rssi)];
}

/**
 * A hub's supply voltage as the tile shows it (`battery_mv` in what the hub reports on connect), or null
 * when the hub does not measure it.
 */
export function batteryVolts(capabilities: Record<string, unknown> | null | undefined): string | null {
  const mv = capabilities?.battery_mv;
  if (typeof mv !== "number" || !Number.isFinite(mv) || mv <= 0) return null;
  return `${(mv / 1000).toFixed(2)} V`;
}
