import { describe, expect, it } from "vitest";
import { TracebackWatch, frameOf, type RuntimeError } from "../src/lib/traceback";

describe("tracebacks", () => {
  it("reads a frame's file and line", () => {
    expect(frameOf('  File "divide.py", line 3, in <module>')).toEqual({ file: "divide.py", line: 3 });
    expect(frameOf("12:00:00.000   File \"a.py\", line 12")).toEqual({ file: "a.py", line: 12 });
    expect(frameOf("print('line 3')")).toBeNull();
  });

  it("reports the innermost frame in the open program, with the exception's line", () => {
    const found: RuntimeError[] = [];
    let open = "main.py";
    const w = new TracebackWatch(() => open, (e) => found.push(e));
    for (const t of [
      "before",
      "Traceback (most recent call last):",
      '  File "main.py", line 9, in <module>',
      '  File "main.py", line 4, in turn',
      '  File "helpers.py", line 2, in go',
      "ValueError: bad turn",
      'File "main.py", line 1 — not inside a traceback',
    ])
      w.feed(t);
    expect(found).toEqual([{ file: "main.py", line: 4, message: "ValueError: bad turn" }]);
    open = "other.py";
    for (const t of ["Traceback (most recent call last):", '  File "main.py", line 2, in <module>', "ZeroDivisionError: division by zero"]) w.feed(t);
    expect(found.length).toBe(1);
  });
});
