import { describe, expect, it } from "vitest";
import { PLAIN, linesHtml, parseLine, styleAttrs, xterm256 } from "../src/lib/ansi";
import { LogLines } from "../src/lib/logview";
import type { Entry } from "../src/lib/output";

const out = (text: string, ms = 0): Entry => ({ kind: "out", run: "R", line_no: null, text, ms });
/** The rows' text as a person reads it (tags dropped, entities decoded). */
const rows = (html: string) =>
  [...html.matchAll(/<div class="r">(.*?)<\/div>/g)].map((m) => m[1].replace(/<[^>]+>/g, "").replace(/&lt;/g, "<").replace(/&gt;/g, ">").replace(/&amp;/g, "&"));

describe("ANSI colours", () => {
  it("turns SGR sequences into styled runs and drops other control sequences", () => {
    const { runs, end } = parseLine("ok \x1b[1;31mFAIL\x1b[0m done\x1b[2K\x1b[3A\x1b]0;title\x07!");
    expect(runs.map((r) => r.text)).toEqual(["ok ", "FAIL", " done!"]);
    expect(runs[1].style).toMatchObject({ fg: 1, bold: true });
    expect(styleAttrs(runs[1].style!).cls).toBe("f9 bo"); // bold brightens red, as terminals do
    expect(runs[0].style).toBeNull();
    expect(end).toEqual(PLAIN);
  });

  it("carries a colour to the next line until it is reset, and knows 256 and true colours", () => {
    const first = parseLine("\x1b[32mgreen starts");
    const second = parseLine("still green\x1b[39m plain", first.end);
    expect(second.runs[0]).toMatchObject({ text: "still green", style: { fg: 2 } });
    expect(second.runs[1]).toEqual({ text: " plain", style: null });
    const rich = parseLine("\x1b[38;5;208ma\x1b[48;2;16;32;255mb");
    expect(styleAttrs(rich.runs[0].style!).css).toBe(`color:${xterm256(208)};`);
    expect(styleAttrs(rich.runs[1].style!).css).toContain("background:#1020ff;");
  });

  it("renders stored lines as HTML with their colours carried from line to line, markup escaped", () => {
    expect(linesHtml(["\x1b[31m<red>", "still & red\x1b[0m", "plain"])).toEqual([
      '<span class="f1">&lt;red&gt;</span>',
      '<span class="f1">still &amp; red</span>',
      "plain",
    ]);
  });

  it("expands tabs to the next multiple of eight columns", () => {
    expect(parseLine("a\tb\x1b[31m\tc").runs.map((r) => r.text).join("")).toBe("a       b       c");
  });
});

describe("LogLines", () => {
  it("wraps lines at the view's width, as a terminal does, and draws any window of rows", () => {
    const log = new LogLines(100);
    log.setCols(10);
    log.add([out("0123456789abcdef"), out("short"), out("")]);
    expect(log.rowCount).toBe(4);
    expect(rows(log.render(0, 10))).toEqual(["0123456789", "abcdef", "short", ""]);
    expect(rows(log.render(1, 2))).toEqual(["abcdef", "short"]);
    log.setCols(20);
    expect(rows(log.render(0, 10))).toEqual(["0123456789abcdef", "short", ""]);
  });

  it("keeps colours across a wrap, escapes markup, colours notes and errors, and stamps when asked", () => {
    const log = new LogLines(100, true);
    log.setCols(30);
    log.add([{ kind: "note", run: "R", line_no: null, text: "▶ started", ms: 0 }, out("<b>&\x1b[31mred text that wraps</b>")]);
    const html = log.render(0, 10);
    expect(html).toContain('<span class="f6">▶ started</span>');
    expect(html).not.toContain("<b>");
    const text = rows(html);
    expect(text[0]).toMatch(/^\d\d:\d\d:\d\d\.\d{3} ▶ started$/);
    expect(text.slice(1).join("")).toMatch(/<b>&red text that wraps<\/b>$/);
    expect(text.length).toBe(3);
    expect(text.every((t) => t.length <= 30)).toBe(true);
    expect(html.match(/class="f1"/g)?.length).toBeGreaterThan(1); // both rows of the wrapped line are red
  });

  it("holds at most its capacity, saying how many rows went from the top", () => {
    const log = new LogLines(3);
    log.setCols(8);
    expect(log.add([out("aaaaaaaaaaaa"), out("b"), out("c")])).toBe(0);
    expect(log.add([out("d")])).toBe(2); // the two rows of the first line
    expect(rows(log.render(0, 9))).toEqual(["b", "c", "d"]);
  });

  it("finds text forwards and backwards, wrapping around, and highlights the match", () => {
    const log = new LogLines(100);
    log.setCols(80);
    log.add([out("alpha stall"), out("beta"), out("gamma STALL stall")]);
    const first = log.find("stall", null, true)!;
    expect(first).toMatchObject({ col: 6 });
    const second = log.find("stall", first, true)!;
    const third = log.find("stall", second, true)!;
    expect([second.col, third.col]).toEqual([6, 12]);
    expect(log.rowOfLine(second.id)).toBe(2);
    expect(log.find("stall", third, true)).toEqual(first); // round again
    expect(log.find("stall", first, false)).toEqual(third);
    expect(log.find("nowhere", null, true)).toBeNull();
    expect(log.render(2, 1, second)).toContain('<span class="mk">STALL</span>');
  });
});
