/**
 * What a hub's log view holds and draws, without the DOM: its lines (parsed once for ANSI colours as they
 * arrive), wrapped at the pane's width in columns the way a terminal wraps, and any window of rows as
 * HTML. The view draws only the rows on screen, so ten busy hubs cost what their visible rows cost,
 * not what they print: a terminal emulator redrew every cell of every row on each write, which took most
 * of the page's main thread with ten hubs streaming.
 */

import { PLAIN, type Run, type Style, parseLine, runHtml as span } from "./ansi";
import type { Entry } from "./output";
import { stamp } from "./output";
import { frameOf } from "./traceback";

interface Line {
  id: number;
  entry: Entry;
  runs: Run[];
  /** columns of the text (without the time stamp) */
  width: number;
}

/** A search hit: the line's id, and where in its text (columns, time stamp excluded). */
export interface Match {
  id: number;
  col: number;
  len: number;
}

const KIND_STYLE: Record<Entry["kind"], Style | null> = {
  out: null,
  note: { ...PLAIN, fg: 6 },
  error: { ...PLAIN, fg: 1 },
};
const STAMP_STYLE: Style = { ...PLAIN, fg: 8 };
const STAMP_COLS = 13; // "hh:mm:ss.mmm "

export class LogLines {
  private lines: Line[] = [];
  /** cum[i]: rows above lines[i], counted from an arbitrary origin (so dropping lines costs nothing). */
  private cum: number[] = [0];
  private nextId = 0;
  private style: Style = PLAIN;
  private cols = 80;

  constructor(
    readonly capacity = 10000,
    readonly timestamps = false,
    /** Traceback frames (`File "a.py", line 3`) drawn as links carrying their file and line. */
    readonly linkFrames = false,
  ) {}

  get rowCount(): number {
    return this.cum[this.cum.length - 1] - this.cum[0];
  }

  get lineCount(): number {
    return this.lines.length;
  }

  /** Append entries; returns how many rows were dropped from the top to stay within `capacity`. */
  add(entries: Entry[]): number {
    for (const entry of entries) {
      const kindStyle = KIND_STYLE[entry.kind];
      let runs: Run[];
      if (entry.kind === "out") {
        const parsed = parseLine(entry.text, this.style);
        runs = parsed.runs;
        this.style = parsed.end;
      } else {
        runs = parseLine(entry.text, kindStyle ?? PLAIN).runs; // a note starts and ends in its own colour
      }
      const width = runs.reduce((n, r) => n + r.text.length, 0);
      const line: Line = { id: this.nextId++, entry, runs, width };
      this.lines.push(line);
      this.cum.push(this.cum[this.cum.length - 1] + this.rowsOf(line));
    }
    const over = this.lines.length - this.capacity;
    if (over <= 0) return 0;
    const dropped = this.cum[over] - this.cum[0];
    this.lines.splice(0, over);
    this.cum.splice(0, over);
    return dropped;
  }

  clear(): void {
    this.lines = [];
    this.cum = [0];
    this.style = PLAIN;
  }

  /** Wrap at `cols` columns from now on (the pane was resized). */
  setCols(cols: number): void {
    cols = Math.max(8, Math.floor(cols));
    if (cols === this.cols) return;
    this.cols = cols;
    const cum = [0];
    for (const line of this.lines) cum.push(cum[cum.length - 1] + this.rowsOf(line));
    this.cum = cum;
  }

  private rowsOf(line: Line): number {
    return Math.max(1, Math.ceil(((this.timestamps ? STAMP_COLS : 0) + line.width) / this.cols));
  }

  /** The index of the line that row `row` (0: the top row) belongs to. */
  private lineAt(row: number): number {
    const target = this.cum[0] + row;
    let lo = 0;
    let hi = this.lines.length - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (this.cum[mid] <= target) lo = mid;
      else hi = mid - 1;
    }
    return lo;
  }

  /** The row a line (by id) starts on, or null when it is no longer held. */
  rowOfLine(id: number): number | null {
    const i = id - (this.lines[0]?.id ?? 0);
    return i >= 0 && i < this.lines.length ? this.cum[i] - this.cum[0] : null;
  }

  /** HTML for `count` rows from row `first`: one `<div class="r">` per row, `mark` highlighted. */
  render(first: number, count: number, mark: Match | null = null): string {
    const total = this.rowCount;
    if (!this.lines.length || first >= total) return "";
    let html = "";
    let i = this.lineAt(Math.max(0, first));
    let sub = this.cum[0] + first - this.cum[i];
    for (let row = first; row < Math.min(total, first + count); row++) {
      const line = this.lines[i];
      const frame = this.linkFrames ? frameOf(line.entry.text) : null;
      const attrs = frame ? ` class="r at" data-file="${escapeAttr(frame.file)}" data-line="${frame.line}" title="Show line ${frame.line} in the editor"` : ` class="r"`;
      html += `<div${attrs}>${this.rowHtml(line, sub, mark && mark.id === line.id ? mark : null)}</div>`;
      sub += 1;
      if (this.cum[0] + row + 1 >= this.cum[i + 1]) {
        i += 1;
        sub = 0;
      }
    }
    return html;
  }

  private rowHtml(line: Line, sub: number, mark: Match | null): string {
    const from = sub * this.cols;
    const to = from + this.cols;
    const prefix = this.timestamps ? STAMP_COLS : 0;
    let html = "";
    if (prefix && from < prefix) html += span(`${stamp(line.entry.ms)} `.slice(from, Math.min(to, prefix)), STAMP_STYLE, false);
    let col = prefix;
    for (const run of line.runs) {
      const end = col + run.text.length;
      const a = Math.max(from, col);
      const b = Math.min(to, end);
      if (a < b) {
        if (mark) {
          // Split the run where the highlighted match starts and ends.
          const m0 = prefix + mark.col;
          const m1 = m0 + mark.len;
          for (const [x, y, marked] of [
            [a, Math.min(b, Math.max(a, m0)), false],
            [Math.max(a, m0), Math.min(b, m1), true],
            [Math.max(a, Math.min(b, m1)), b, false],
          ] as [number, number, boolean][]) {
            if (x < y) html += span(run.text.slice(x - col, y - col), run.style, marked);
          }
        } else html += span(run.text.slice(a - col, b - col), run.style, false);
      }
      col = end;
      if (col >= to) break;
    }
    return html;
  }

  /**
   * The next (or previous) occurrence of `needle`, case-insensitive, after (before) `from`; from the
   * last line backwards when `from` is null. Null when there is none.
   */
  find(needle: string, from: Match | null, forward: boolean): Match | null {
    if (!needle || !this.lines.length) return null;
    const want = needle.toLowerCase();
    const base = this.lines[0].id;
    const n = this.lines.length;
    let i = from ? Math.min(n - 1, Math.max(0, from.id - base)) : forward ? 0 : n - 1;
    for (let step = 0; step <= n; step++) {
      const text = this.lines[i].runs.map((r) => r.text).join("").toLowerCase();
      let col: number;
      if (forward) col = text.indexOf(want, from && this.lines[i].id === from.id ? from.col + 1 : 0);
      else {
        const before = from && this.lines[i].id === from.id ? from.col - 1 : text.length;
        col = before < 0 ? -1 : text.lastIndexOf(want, before);
      }
      if (col >= 0 && !(from && this.lines[i].id === from.id && col === from.col)) return { id: this.lines[i].id, col, len: needle.length };
      from = null;
      i = forward ? (i + 1) % n : (i - 1 + n) % n;
    }
    return null;
  }
}

function escapeAttr(text: string): string {
  return text.replace(/&/g, "&amp;").replace(/"/g, "&quot;").replace(/</g, "&lt;");
}
