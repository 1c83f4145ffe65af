import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import { DraftKeeper } from "../src/lib/drafts";

type Call = [string, string, number | null, boolean];

describe("draft keeper", () => {
  let calls: Call[];
  let fail: boolean;
  const send = async (name: string, source: string, base: number | null, keepalive: boolean) => {
    calls.push([name, source, base, keepalive]);
    if (fail) throw new Error("unreachable");
  };

  beforeEach(() => {
    vi.useFakeTimers();
    calls = [];
    fail = false;
  });
  afterEach(() => vi.useRealTimers());

  it("writes once, half a second after the last key, with the newest text", async () => {
    const k = new DraftKeeper(send);
    k.edited("a.py", "x", 1);
    await vi.advanceTimersByTimeAsync(300);
    k.edited("a.py", "xy", 1);
    await vi.advanceTimersByTimeAsync(300);
    expect(calls).toEqual([]);
    expect(k.unsaved).toBe(true);
    await vi.advanceTimersByTimeAsync(250);
    expect(calls).toEqual([["a.py", "xy", 1, false]]);
    expect(k.unsaved).toBe(false);
  });

  it("writes at once when the user leaves, and nothing for text the daemon already has", async () => {
    const k = new DraftKeeper(send);
    k.known("a.py", "stored");
    k.edited("a.py", "stored", 2);
    expect(k.unsaved).toBe(false);
    k.edited("a.py", "changed", 2);
    await k.flush(true);
    expect(calls).toEqual([["a.py", "changed", 2, true]]);
    await vi.advanceTimersByTimeAsync(1000);
    expect(calls.length).toBe(1);
  });

  it("switching programs sends the first one's text before the second's", async () => {
    const k = new DraftKeeper(send);
    k.edited("a.py", "one", null);
    k.edited("b.py", "two", 3);
    await vi.advanceTimersByTimeAsync(600);
    expect(calls.map((c) => c[0])).toEqual(["a.py", "b.py"]);
  });

  it("keeps a failed write pending and reports it; a save cancels what waits", async () => {
    const errors: string[] = [];
    const k = new DraftKeeper(send, (_e, name) => errors.push(name));
    fail = true;
    k.edited("a.py", "lost?", null);
    await vi.advanceTimersByTimeAsync(600);
    expect(errors).toEqual(["a.py"]);
    expect(k.unsaved).toBe(true);
    fail = false;
    await k.flush();
    expect(k.unsaved).toBe(false);
    k.edited("a.py", "more", null);
    k.cancel("b.py"); // another program's save leaves this one alone
    expect(k.unsaved).toBe(true);
    k.cancel("a.py");
    await vi.advanceTimersByTimeAsync(600);
    expect(calls.length).toBe(2);
    expect(k.unsaved).toBe(false);
  });
});
