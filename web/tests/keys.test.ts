import { describe, expect, it } from "vitest";
import { actionFor } from "../src/lib/keys";

const key = (k: string, mods: Partial<KeyboardEvent> = {}) => ({ key: k, ctrlKey: false, metaKey: false, altKey: false, shiftKey: false, ...mods });

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
  });
});
