/**
 * Runtime errors tied to the code: a hub's traceback names the program's own file and line
 * (`File "square.py", line 3, in <module>`), which the editor marks and a click in the output jumps to.
 */

export interface Frame {
  file: string;
  line: number;
}

export interface RuntimeError extends Frame {
  /** the exception's own line, e.g. "ZeroDivisionError: division by zero" */
  message: string;
}

const FRAME = /File "([^"]+)", line (\d+)/;

/** The file and line a traceback line points at, or null for any other line. */
export function frameOf(text: string): Frame | null {
  const m = FRAME.exec(text);
  return m ? { file: m[1], line: Number(m[2]) } : null;
}

/**
 * Reads output lines as they come and reports each finished traceback's innermost frame in `file`
 * (the program open in the editor; frames in its modules or the runtime are not its lines).
 */
export class TracebackWatch {
  private frame: Frame | null = null;
  private inside = false;

  constructor(
    private readonly file: () => string | null,
    private readonly found: (error: RuntimeError) => void,
  ) {}

  feed(text: string): void {
    if (/^Traceback \(most recent call last\):/.test(text)) {
      this.inside = true;
      this.frame = null;
      return;
    }
    if (!this.inside) return;
    const f = frameOf(text);
    if (f) {
      if (f.file === this.file()) this.frame = f;
      return;
    }
    if (/^\s/.test(text)) return; // the quoted source line under a frame
    this.inside = false;
    if (this.frame) this.found({ ...this.frame, message: text.trim() });
    this.frame = null;
  }
}
