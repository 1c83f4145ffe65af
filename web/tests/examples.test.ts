import { describe, expect, it } from "vitest";
import { firstView, groupExamples, type Example } from "../src/lib/examples";

const ex = (id: string, group: string, group_title: string): Example => ({ id, title: id, group, group_title, summary: "", file: `${id}.py` });

describe("groupExamples", () => {
  it("keeps the daemon's order of groups and of examples within each", () => {
    const groups = groupExamples([
      ex("first_robot", "drive_base", "Drive base"),
      ex("drivebase_square", "drive_base", "Drive base"),
      ex("color_array", "sensors", "Sensors"),
      ex("qtr_line_follow", "line_following", "Line following"),
      ex("full_robot", "competition", "Competition"),
    ]);
    expect(groups.map((g) => g.title)).toEqual(["Drive base", "Sensors", "Line following", "Competition"]);
    expect(groups[0].examples.map((e) => e.id)).toEqual(["first_robot", "drivebase_square"]);
  });

  it("gives no groups for no examples", () => {
    expect(groupExamples([])).toEqual([]);
  });
});

describe("firstView", () => {
  it("shows a first-time visitor (no programs) the examples, and a team its programs", () => {
    expect(firstView(0, null)).toBe("examples");
    expect(firstView(3, null)).toBe("programs");
  });

  it("follows the address when it asks for one", () => {
    expect(firstView(3, "examples")).toBe("examples");
    expect(firstView(0, "programs")).toBe("programs");
    expect(firstView(0, "bogus")).toBe("examples");
  });
});
