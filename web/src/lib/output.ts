/**
 * One hub's output as the page keeps it: runs in order, each run's lines in `line_no` order, exactly once.
 *
 * Lines arrive from the event stream, possibly with holes (the page opened mid-run, a reconnect past the
 * daemon's replay ring, a resync). A hole is never papered over: lines after it wait while the missing ones
 * are fetched from the run store, and what the store no longer has becomes a visible note. Terminals read
 * committed entries through `subscribe` and never re-render the whole log.
 */

import type { OutputLine } from "./api";

export type EntryKind = "out" | "note" | "error";

export interface Entry {
  kind: EntryKind;
  run: string | null;
  line_no: number | null;
  text: string;
  /** epoch ms: the hub's clock when known, else the daemon's receive time, else the page's */
  ms: number;
}

export interface Hole {
  run: string;
  /** the missing lines are those with after < line_no < before (before null: up to whatever exists) */
  after: number;
  before: number | null;
}

type Listener = (entries: Entry[], cleared: boolean) => void;

export class HubOutput {
  readonly entries: Entry[] = [];
  private readonly last = new Map<string, number>();
  private readonly waiting = new Map<string, OutputLine[]>();
  private readonly listeners = new Set<Listener>();
  /** Lines dropped from the front when the log passed `limit` (the run store still has them). */
  trimmed = 0;

  constructor(readonly limit = 20000) {}

  subscribe(fn: Listener): () => void {
    this.listeners.add(fn);
    return () => this.listeners.delete(fn);
  }

  /** The highest line number committed for `run` (0: none yet). */
  lastLine(run: string): number {
    return this.last.get(run) ?? 0;
  }

  hasRun(run: string): boolean {
    return this.last.has(run) || this.waiting.has(run);
  }

  /** A run began: its header, and its line count starts at zero. */
  startRun(run: string, title: string, ms: number): void {
    if (this.last.has(run)) return;
    this.last.set(run, 0);
    this.commit([{ kind: "note", run, line_no: null, text: title, ms }]);
  }

  note(text: string, run: string | null = null, kind: EntryKind = "note", ms = Date.now()): void {
    this.commit([{ kind, run, line_no: null, text, ms }]);
  }

  /**
   * Live lines of `run`. Returns the hole to fetch from the store when they do not follow what is
   * committed; the lines after it wait for `fill`.
   */
  append(run: string, lines: OutputLine[]): Hole | null {
    const waiting = this.waiting.get(run);
    if (waiting) {
      for (const l of lines) if (l.line_no > this.lastLine(run)) waiting.push(l);
      return null; // a fetch for this run is already out
    }
    const fresh: Entry[] = [];
    let next = this.lastLine(run) + 1;
    for (let i = 0; i < lines.length; i++) {
      const l = lines[i];
      if (l.line_no < next) continue; // already have it (replay overlap)
      if (l.line_no > next) {
        this.last.set(run, next - 1);
        this.commit(fresh);
        this.waiting.set(run, lines.slice(i));
        return { run, after: next - 1, before: l.line_no };
      }
      fresh.push(toEntry(run, l));
      next += 1;
    }
    this.last.set(run, next - 1);
    this.commit(fresh);
    return null;
  }

  /**
   * Lines of `run` fetched from the store for a hole (or a whole run opened mid-way). Lines the store no
   * longer has become one note saying how many are gone; then the waiting live lines follow in order.
   */
  fill(run: string, stored: OutputLine[]): void {
    const waiting = this.waiting.get(run) ?? [];
    this.waiting.delete(run);
    const all = [...stored, ...waiting].sort((a, b) => a.line_no - b.line_no);
    const out: Entry[] = [];
    let next = this.lastLine(run) + 1;
    for (const l of all) {
      if (l.line_no < next) continue;
      if (l.line_no > next) {
        const n = l.line_no - next;
        out.push({ kind: "error", run, line_no: null, text: `[${n} line${n === 1 ? "" : "s"} lost: no longer held by the daemon]`, ms: l.hub_ms ?? l.recv_ms });
      }
      out.push(toEntry(run, l));
      next = l.line_no + 1;
    }
    this.last.set(run, next - 1);
    this.commit(out);
  }

  clear(): void {
    this.entries.length = 0;
    this.trimmed = 0;
    for (const fn of this.listeners) fn([], true);
  }

  /** The log as a text file: local time, then the line. */
  text(): string {
    return this.entries.map((e) => `${stamp(e.ms)}  ${e.text}`).join("\n") + (this.entries.length ? "\n" : "");
  }

  private commit(entries: Entry[]): void {
    if (!entries.length) return;
    for (const e of entries) this.entries.push(e);
    const over = this.entries.length - this.limit;
    if (over > 0) {
      this.entries.splice(0, over);
      this.trimmed += over;
    }
    for (const fn of this.listeners) fn(entries, false);
  }
}

function toEntry(run: string, l: OutputLine): Entry {
  return { kind: "out", run, line_no: l.line_no, text: l.text, ms: l.hub_ms ?? l.recv_ms ?? Date.now() };
}

/** Local wall-clock time with milliseconds, the way every log line on the page is stamped. */
export function stamp(ms: number): string {
  const d = new Date(ms);
  const p = (n: number, w = 2) => String(n).padStart(w, "0");
  return `${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}.${p(d.getMilliseconds(), 3)}`;
}
