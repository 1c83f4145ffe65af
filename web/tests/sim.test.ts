import { describe, expect, it } from "vitest";
import { runLike, scoreText } from "../src/lib/sim";

describe("runLike", () => {
  it("runs one seed again as the sweep ran it, at real time, leaving out what a sim run does not take", () => {
    const params = { program: "square.py", version: 3, world: "wro", chassis: null, seed: 0, limit_ms: 30000, memory_mb: 1024, seeds: [1, 2], workers: 2, dask: null, hub_dir: null };
    expect(runLike(params, 2)).toEqual({ program: "square.py", version: 3, world: "wro", seed: 2, speed: 1, limit_ms: 30000, memory_mb: 1024 });
  });

  it("asks for the newest version when the sweep did not record one", () => {
    expect(runLike({ program: "old.py", world: "empty" }, 7)).toEqual({ program: "old.py", world: "empty", seed: 7, speed: 1 });
  });

  it("runs a sim run again from its record", () => {
    const run = { run_id: "R", program_name: "line.py", world: "line_track", chassis: "st3032", seed: 4, limit_ms: 60000, memory_mb: 1024, speed: null };
    expect(runLike(run, run.seed)).toEqual({ program: "line.py", world: "line_track", chassis: "st3032", seed: 4, speed: 1, limit_ms: 60000, memory_mb: 1024 });
  });
});

describe("scoreText", () => {
  it("puts each measure in a line, rounded, and a dash for no score", () => {
    expect(scoreText({ points: 40, progress: 0.93456, zones: ["red", "blue"] })).toBe('points 40, progress 0.93, zones ["red","blue"]');
    expect(scoreText(null)).toBe("—");
  });
});
