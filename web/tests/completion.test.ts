import { describe, expect, it } from "vitest";
import { ApiIndex, classOf, completeAt, hoverAt, type RuntimeApi } from "../src/lib/completion";

const API: RuntimeApi = {
  version: "2.7.1",
  modules: [
    { name: "openbricks.interfaces", doc: "Interfaces.", symbols: [{ name: "Motor", kind: "class", signature: "()", doc: "A motor.", members: [{ name: "run", kind: "method", signature: "(speed)", doc: "Run." }, { name: "stop", kind: "method", signature: "()", doc: "Stop it." }], bases: [] }] },
    { name: "openbricks.robotics", doc: "Robotics.", symbols: [] },
    {
      name: "openbricks.robotics.drivebase",
      doc: "DriveBase.",
      symbols: [
        {
          name: "DriveBase",
          kind: "class",
          signature: "(left, right, wheel_diameter_mm, axle_track_mm, imu=None, drive='duty')",
          doc: "Two wheels.",
          members: [
            { name: "straight", kind: "method", signature: "(distance_mm, then='coast', wait=True)", doc: "Drive forward." },
            { name: "stop", kind: "method", signature: "(then='coast', wait=False)", doc: "Halt." },
          ],
          bases: ["Motor"],
        },
      ],
    },
    { name: "openbricks.tools", doc: "Tools.", symbols: [{ name: "wait", kind: "function", signature: "(ms)", doc: "Sleep." }] },
  ],
};
const index = new ApiIndex(API);
const at = (text: string, explicit = false) => completeAt(index, text, text.length, explicit);
const labels = (text: string, explicit = false) => at(text, explicit)?.offers.map((o) => o.label) ?? [];

describe("runtime completion", () => {
  it("offers a class's methods with their signatures, its own before what it inherits", () => {
    const found = at("DriveBase.st");
    expect(found?.from).toBe("DriveBase.".length);
    expect(found?.offers.map((o) => [o.label, o.owner, o.signature])).toEqual([
      ["straight", "DriveBase", "(distance_mm, then='coast', wait=True)"],
      ["stop", "DriveBase", "(then='coast', wait=False)"],
    ]);
    expect(labels("DriveBase.r")).toEqual(["run"]);
  });

  it("follows a name to the class it was made from", () => {
    const text = "from openbricks.robotics import DriveBase\nrobot = DriveBase(l, r, 56, 114)\nrobot.str";
    expect(classOf(index, text, "robot")).toBe("DriveBase");
    expect(labels(text)).toEqual(["straight"]);
    expect(labels("self.base = DriveBase(a, b, 1, 2)\nself.base.st")).toEqual(["straight", "stop"]);
  });

  it("offers every runtime method for a name of unknown class, and nothing in comments", () => {
    expect(at("thing.sto")?.offers.map((o) => o.owner)).toEqual(["Motor", "DriveBase"]);
    expect(at("# robot.st")).toBeNull();
    expect(at("x.")).toBeNull();
  });

  it("completes imports: module names, then a module's names", () => {
    expect(labels("from openbricks.rob")).toEqual(["openbricks.robotics", "openbricks.robotics.drivebase"]);
    expect(labels("from openbricks.robotics.drivebase import Dr")).toEqual(["DriveBase"]);
    expect(labels("from openbricks.robotics import ")).toEqual(["drivebase"]);
    expect(labels("from openbricks.tools import wait, ")).toEqual(["wait"]);
  });

  it("offers classes and functions by bare name after two letters", () => {
    expect(labels("Dr")).toEqual(["DriveBase"]);
    expect(at("w")).toBeNull();
    expect(labels("w", true)).toEqual(["wait"]);
  });
});

describe("runtime hover", () => {
  it("shows a method's class, signature and summary", () => {
    const text = "robot = DriveBase(l, r, 56, 114)\nrobot.straight(100)";
    const hit = hoverAt(index, text, text.indexOf("straight") + 3);
    expect(hit).toEqual({ from: text.indexOf("straight"), to: text.indexOf("(100"), title: "DriveBase.straight(distance_mm, then='coast', wait=True)", doc: "Drive forward." });
    expect(hoverAt(index, text, 2)).toBeNull();
    expect(hoverAt(index, text, text.indexOf("DriveBase") + 1)?.title).toBe("class DriveBase(left, right, wheel_diameter_mm, axle_track_mm, imu=None, drive='duty')");
  });
});
