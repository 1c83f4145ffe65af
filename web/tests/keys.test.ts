import { describe, expect, it } from "vitest";
import { actionFor, isTyping } from "../src/lib/keys";

const key = (k: string, mods: Partial<KeyboardEvent> = {}) => ({ key: k, ctrlKey: false, metaKey: false, altKey: false, shiftKey: false, ...mods });
const el = (tagName: string, extra: Record<string, unknown> = {}) => ({ tagName, closest: () => null, ...extra });

describe("console keys", () => {
  it("maps F5, F6, Esc and Ctrl-S", () => {
    expect(actionFor(key("F5"))).toBe("run");
    expect(actionFor(key("F6"))).toBe("stop");
    expect(actionFor(key("Escape"))).toBe("stopAll");
    expect(actionFor(key("s", { ctrlKey: true }))).toBe("save");
    expect(actionFor(key("S", { metaKey: true }))).toBe("save");
  });

  it("leaves other keys (and a hard reload) to the browser", () => {
    expect(actionFor(key("s"))).toBeNull();
    expect(actionFor(key("F5", { ctrlKey: true }))).toBeNull();
    expect(actionFor(key("a", { ctrlKey: true }))).toBeNull();
    expect(actionFor(key("."))).toBeNull();
  });

  it("keeps Esc for whatever is being typed in, and Ctrl+. stops all there", () => {
    for (const t of [el("TEXTAREA"), el("SELECT"), el("INPUT"), el("input", { type: "search" }), el("DIV", { isContentEditable: true })]) {
      expect(actionFor(key("Escape"), t)).toBeNull();
      expect(actionFor(key(".", { ctrlKey: true }), t)).toBe("stopAll");
      expect(actionFor(key(".", { metaKey: true }), t)).toBe("stopAll");
    }
    // Inside the code editor or a dialog: found by the nearest ancestor.
    const inEditor = el("DIV", { closest: (s: string) => (s.includes(".cm-editor") ? {} : null) });
    expect(isTyping(inEditor)).toBe(true);
    expect(actionFor(key("Escape"), inEditor)).toBeNull();
  });

  it("stops all on Esc where nothing is typed: the page, a button, a checkbox", () => {
    for (const t of [null, el("BODY"), el("BUTTON"), el("INPUT", { type: "checkbox" })]) expect(actionFor(key("Escape"), t)).toBe("stopAll");
    // A modified Esc (Shift+Esc is the browser's task manager) is never STOP ALL.
    expect(actionFor(key("Escape", { shiftKey: true }))).toBeNull();
  });
});
