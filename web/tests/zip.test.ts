import { describe, expect, it } from "vitest";
import { crc32, storedZip } from "../src/lib/zip";

describe("storedZip", () => {
  it("computes the zip CRC-32", () => {
    expect(crc32(new TextEncoder().encode("123456789"))).toBe(0xcbf43926);
  });

  it("writes local headers, the central directory and the end record for each file", () => {
    const files = [
      { name: "table.toml", data: new TextEncoder().encode('mat = "mat.png"\n') },
      { name: "mat.png", data: new Uint8Array([137, 80, 78, 71]) },
    ];
    const zip = storedZip(files);
    const view = new DataView(zip.buffer);
    expect(view.getUint32(0, true)).toBe(0x04034b50);
    const end = zip.length - 22;
    expect(view.getUint32(end, true)).toBe(0x06054b50);
    expect(view.getUint16(end + 10, true)).toBe(2);
    const centralAt = view.getUint32(end + 16, true);
    expect(view.getUint32(centralAt, true)).toBe(0x02014b50);
    expect(new TextDecoder().decode(zip.slice(30, 40))).toBe("table.toml");
  });
});
