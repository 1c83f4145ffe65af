/**
 * ANSI colours in a hub's output, as a terminal shows them: SGR sequences (`ESC[...m`: the 16 colours,
 * 256-colour and true-colour, bold, dim, italic, underline, inverse) become styled runs of text; the
 * other control sequences a program may print (cursor moves, erases, titles) are dropped, since a log
 * view keeps lines, not a screen. The style carries from line to line until reset, as in a terminal.
 */

export interface Style {
  fg: number | string | null; // 0-255 palette index, or "#rrggbb"
  bg: number | string | null;
  bold: boolean;
  dim: boolean;
  italic: boolean;
  underline: boolean;
  inverse: boolean;
}

export interface Run {
  text: string;
  style: Style | null; // null: the default style
}

export const PLAIN: Style = Object.freeze({ fg: null, bg: null, bold: false, dim: false, italic: false, underline: false, inverse: false });

// CSI (ESC [ params final), OSC (ESC ] ... BEL or ESC \), other two-byte escapes, and lone control characters.
// eslint-disable-next-line no-control-regex
const ESCAPES = /\x1b\[([0-9:;?<=>]*)([ -/]*[@-~])|\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)?|\x1b[@-Z\\-_]|[\x00-\x08\x0b-\x1f\x7f]/g;

function isPlain(s: Style): boolean {
  return s.fg === null && s.bg === null && !s.bold && !s.dim && !s.italic && !s.underline && !s.inverse;
}

/** Apply one SGR parameter list to `s` (a copy is made by the caller). */
function applySgr(s: Style, params: string): Style {
  const p = params === "" ? [0] : params.split(/[;:]/).map((x) => (x === "" ? 0 : Number(x)));
  const next = { ...s };
  for (let i = 0; i < p.length; i++) {
    const c = p[i];
    if (c === 0) Object.assign(next, PLAIN);
    else if (c === 1) next.bold = true;
    else if (c === 2) next.dim = true;
    else if (c === 3) next.italic = true;
    else if (c === 4) next.underline = true;
    else if (c === 7) next.inverse = true;
    else if (c === 22) next.bold = next.dim = false;
    else if (c === 23) next.italic = false;
    else if (c === 24) next.underline = false;
    else if (c === 27) next.inverse = false;
    else if (c >= 30 && c <= 37) next.fg = c - 30;
    else if (c === 39) next.fg = null;
    else if (c >= 40 && c <= 47) next.bg = c - 40;
    else if (c === 49) next.bg = null;
    else if (c >= 90 && c <= 97) next.fg = c - 90 + 8;
    else if (c >= 100 && c <= 107) next.bg = c - 100 + 8;
    else if (c === 38 || c === 48) {
      let colour: number | string | null = null;
      if (p[i + 1] === 5 && i + 2 < p.length) {
        colour = Math.max(0, Math.min(255, p[i + 2]));
        i += 2;
      } else if (p[i + 1] === 2 && i + 4 < p.length) {
        const hex = (n: number) => Math.max(0, Math.min(255, n | 0)).toString(16).padStart(2, "0");
        colour = `#${hex(p[i + 2])}${hex(p[i + 3])}${hex(p[i + 4])}`;
        i += 4;
      } else break; // malformed: ignore the rest, as terminals do
      if (c === 38) next.fg = colour;
      else next.bg = colour;
    }
  }
  return next;
}

/**
 * Split one line into styled runs, starting in style `start`; returns the runs and the style the line
 * ends in (the next line's start). Tabs become spaces to the next multiple of eight columns.
 */
export function parseLine(line: string, start: Style = PLAIN): { runs: Run[]; end: Style } {
  const runs: Run[] = [];
  let style = start;
  let col = 0;
  let last = 0;
  const push = (raw: string) => {
    if (!raw) return;
    let text = raw;
    if (text.includes("\t")) {
      let out = "";
      for (const ch of text) {
        if (ch === "\t") {
          const n = 8 - ((col + out.length) % 8);
          out += " ".repeat(n);
        } else out += ch;
      }
      text = out;
    }
    col += text.length;
    const prev = runs.at(-1);
    const s = isPlain(style) ? null : style;
    if (prev && prev.style === s) prev.text += text;
    else runs.push({ text, style: s });
  };
  if (!line.includes("\x1b") && !/[\x00-\x08\x0b-\x1f\x7f]/.test(line)) {
    push(line);
    return { runs, end: style };
  }
  ESCAPES.lastIndex = 0;
  for (let m = ESCAPES.exec(line); m; m = ESCAPES.exec(line)) {
    push(line.slice(last, m.index));
    last = m.index + m[0].length;
    if (m[2] === "m" && !m[1].startsWith("?")) style = applySgr(style, m[1]);
  }
  push(line.slice(last));
  return { runs, end: style };
}

/** The CSS for a style: palette colours as classes (themed in CSS), others inline. */
export function styleAttrs(s: Style): { cls: string; css: string } {
  let fg = s.fg;
  let bg = s.bg;
  if (s.inverse) [fg, bg] = [bg ?? "default-bg", fg ?? "default-fg"];
  if (s.bold && typeof fg === "number" && fg < 8) fg += 8; // bold brightens, as in most terminals
  const cls: string[] = [];
  let css = "";
  if (typeof fg === "number" && fg < 16) cls.push(`f${fg}`);
  else if (fg === "default-fg") cls.push("fi");
  else if (fg !== null) css += `color:${typeof fg === "number" ? xterm256(fg) : fg};`;
  if (typeof bg === "number" && bg < 16) cls.push(`b${bg}`);
  else if (bg === "default-bg") cls.push("bi");
  else if (bg !== null) css += `background:${typeof bg === "number" ? xterm256(bg) : bg};`;
  if (s.bold) cls.push("bo");
  if (s.dim) cls.push("di");
  if (s.italic) cls.push("it");
  if (s.underline) cls.push("un");
  return { cls: cls.join(" "), css };
}

function escape(text: string): string {
  return /[&<>]/.test(text) ? text.replace(/&/g, "&amp;").replace(/</g, "&lt;").replace(/>/g, "&gt;") : text;
}

/**
 * One run of text as HTML, for an element of class `ansi` (app.css holds the palette); `mark` highlights
 * it (a search match). The text is escaped, and styles are built from numbers only.
 */
export function runHtml(text: string, style: Style | null, mark = false): string {
  const { cls, css } = style ? styleAttrs(style) : { cls: "", css: "" };
  const classes = mark ? (cls ? `${cls} mk` : "mk") : cls;
  if (!classes && !css) return escape(text);
  return `<span${classes ? ` class="${classes}"` : ""}${css ? ` style="${css}"` : ""}>${escape(text)}</span>`;
}

/** Lines of output as HTML, each line's colours carrying to the next as in a terminal. */
export function linesHtml(lines: string[]): string[] {
  let style = PLAIN;
  return lines.map((line) => {
    const parsed = parseLine(line, style);
    style = parsed.end;
    return parsed.runs.map((r) => runHtml(r.text, r.style)).join("");
  });
}

/** The xterm 256-colour palette's colours 16-255 (a 6x6x6 cube, then 24 greys). */
export function xterm256(n: number): string {
  const hex = (v: number) => v.toString(16).padStart(2, "0");
  if (n >= 232) {
    const g = 8 + (n - 232) * 10;
    return `#${hex(g)}${hex(g)}${hex(g)}`;
  }
  const i = n - 16;
  const level = (v: number) => (v === 0 ? 0 : 55 + v * 40);
  return `#${hex(level(Math.floor(i / 36)))}${hex(level(Math.floor(i / 6) % 6))}${hex(level(i % 6))}`;
}
