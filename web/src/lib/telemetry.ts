/**
 * Telemetry of one run: named series of (time, value) from `plot(name, value)` on the hub (or the
 * simulator's pose and speeds), kept as uPlot's column arrays so a plot redraws without copying.
 */

import type { TelemetrySample } from "./api";

export class RunTelemetry {
  /** series name → [times in s since the first sample, values] */
  readonly series = new Map<string, { t: number[]; v: number[] }>();
  private t0: number | null = null;
  private readonly listeners = new Set<() => void>();
  /** Live samples waiting while the stored ones are read (null: none are being read). */
  private held: TelemetrySample[] | null = null;
  version = 0;

  constructor(readonly limit = 20000) {}

  /** A run opened while under way: its stored samples are being read; live ones wait for them. */
  hold(): void {
    this.held ??= [];
  }

  /**
   * The stored samples, then the live ones (held, or taken before the hold) the store did not have yet,
   * each once and in order.
   */
  release(stored: TelemetrySample[]): void {
    const live = [...this.taken(), ...(this.held ?? [])];
    this.held = null;
    this.series.clear();
    this.t0 = null;
    const last = new Map<string, number>();
    for (const s of stored) last.set(s.name, Math.max(last.get(s.name) ?? -Infinity, s.hub_ms ?? s.recv_ms));
    this.add([...stored, ...live.filter((s) => (s.hub_ms ?? s.recv_ms) > (last.get(s.name) ?? -Infinity))]);
  }

  /** What this holds, as samples again (times to the millisecond they came with). */
  private taken(): TelemetrySample[] {
    const out: TelemetrySample[] = [];
    for (const [name, col] of this.series) {
      for (let i = 0; i < col.t.length; i++) {
        const ms = Math.round((this.t0 ?? 0) + col.t[i] * 1000);
        out.push({ name, value: col.v[i], hub_ms: ms, recv_ms: ms });
      }
    }
    return out.sort((a, b) => a.recv_ms - b.recv_ms);
  }

  add(samples: TelemetrySample[]): void {
    if (this.held) {
      this.held.push(...samples);
      return;
    }
    if (!samples.length) return;
    for (const s of samples) {
      const ms = s.hub_ms ?? s.recv_ms;
      if (this.t0 === null) this.t0 = ms;
      let col = this.series.get(s.name);
      if (!col) {
        col = { t: [], v: [] };
        this.series.set(s.name, col);
      }
      col.t.push((ms - this.t0) / 1000);
      col.v.push(s.value);
      if (col.t.length > this.limit) {
        col.t.splice(0, col.t.length - this.limit);
        col.v.splice(0, col.v.length - this.limit);
      }
    }
    this.version += 1;
    for (const fn of this.listeners) fn();
  }

  names(): string[] {
    return [...this.series.keys()].sort();
  }

  subscribe(fn: () => void): () => void {
    this.listeners.add(fn);
    return () => this.listeners.delete(fn);
  }

  /** Every series as CSV rows `name,t_s,value`, for download. */
  csv(): string {
    const rows = ["name,t_s,value"];
    for (const name of this.names()) {
      const col = this.series.get(name)!;
      for (let i = 0; i < col.t.length; i++) rows.push(`${name},${col.t[i].toFixed(3)},${col.v[i]}`);
    }
    return rows.join("\n") + "\n";
  }
}
