/**
 * Programs as the daemon stores them, and the syntax check that runs before anything reaches a hub: the
 * daemon compiles on save and answers a syntax error with its line, which the editor marks inline.
 */

import { ApiError, api, type Program } from "./api";
import type { Problem } from "../components/CodeEditor.svelte";

const enc = encodeURIComponent;

export async function listPrograms(): Promise<Program[]> {
  return api.get<Program[]>("/api/programs");
}

export async function loadProgram(name: string): Promise<Program> {
  return api.get<Program>(`/api/programs/${enc(name)}`);
}

/** Store `source` as the newest version (unchanged text adds no version); refused with the reason if it
 * cannot run on a hub (syntax, size, binary). */
export async function saveProgram(name: string, source: string): Promise<{ program: Program; created: boolean }> {
  return api.put(`/api/programs/${enc(name)}`, { source });
}

/**
 * The editor marks for a refused save: the daemon names the line of a syntax error (or of a binary or
 * non-UTF-8 character) in the error's `detail`. Null when the refusal is not about a line of the text.
 */
export function problemsOf(err: unknown): Problem[] | null {
  if (!(err instanceof ApiError)) return null;
  const d = (err.detail.detail ?? {}) as Record<string, unknown>;
  if (typeof d.line !== "number" || d.line < 1) return null;
  const column = typeof d.column === "number" ? d.column : null;
  // "square.py, line 3: invalid syntax: x = (" → "invalid syntax: x = (" beside the line itself.
  const message = err.message.replace(/^.*?, line \d+: /, "");
  return [{ line: d.line, column, message }];
}

export const TEMPLATE = `# A new program: it runs on the hub (or the simulator) exactly as written.
from openbricks.tools import wait

for i in range(5):
    print("tick", i)
    wait(200)
`;

/** Every stored version of a program, newest first (text left out; `loadVersion` reads one). */
export async function listVersions(name: string): Promise<Program[]> {
  return api.get<Program[]>(`/api/programs/${enc(name)}/versions`);
}

export async function loadVersion(name: string, version: number): Promise<Program> {
  return api.get<Program>(`/api/programs/${enc(name)}/versions/${version}`);
}

/** An older version's text becomes the newest version again. */
export async function restoreVersion(name: string, version: number): Promise<{ program: Program; created: boolean }> {
  return api.post(`/api/programs/${enc(name)}/versions/${version}/restore`);
}

/** Refused with 409 `program_exists` when `newName` is taken. */
export async function renameProgram(name: string, newName: string): Promise<Program> {
  return api.post<Program>(`/api/programs/${enc(name)}/rename`, { new_name: newName });
}

export async function deleteProgram(name: string): Promise<void> {
  return api.del(`/api/programs/${enc(name)}`);
}

/** A file's text stored as a program: refused with 409 `program_exists` unless `replace`. */
export async function importProgram(name: string, source: string, replace = false): Promise<{ program: Program; created: boolean }> {
  return api.post(`/api/programs`, { name, source, replace });
}

/** The link that downloads a program's stored text as a .py file. */
export function downloadPath(name: string): string {
  return `api/programs/${enc(name)}/download`;
}
