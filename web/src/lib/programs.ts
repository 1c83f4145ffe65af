/**
 * Programs as the daemon stores them, and the syntax check that runs before anything reaches a hub: the
 * daemon compiles on save and answers a syntax error with its line, which the editor marks inline.
 */

import { ApiError, api, type Program } from "./api";
import type { Problem } from "../components/CodeEditor.svelte";

const enc = encodeURIComponent;

export async function listPrograms(): Promise<Program[]> {
  const r = await api.get<Program[] | { programs: Program[] }>("/api/programs");
  return Array.isArray(r) ? r : r.programs;
}

export async function loadProgram(name: string): Promise<Program> {
  return api.get<Program>(`/api/programs/${enc(name)}`);
}

export async function saveProgram(name: string, source: string): Promise<Program> {
  return api.put<Program>(`/api/programs/${enc(name)}`, { source });
}

/** The editor marks for a refused save, or null when the refusal is not about the program's text. */
export function problemsOf(err: unknown): Problem[] | null {
  if (!(err instanceof ApiError) || !/syntax/i.test(err.code)) return null;
  const d = (err.detail.detail ?? err.detail) as Record<string, unknown>;
  const num = (v: unknown) => (typeof v === "number" ? v : typeof v === "string" && /^\d+$/.test(v) ? Number(v) : null);
  const line = num(d.line) ?? num(d.lineno) ?? num(/line (\d+)/.exec(err.message)?.[1]) ?? 1;
  const column = num(d.column) ?? num(d.col) ?? num(d.offset);
  const message = typeof d.msg === "string" ? d.msg : err.message;
  return [{ line, column, message }];
}

export const TEMPLATE = `# A new program: it runs on the hub (or the simulator) exactly as written.
from openbricks.tools import wait

for i in range(5):
    print("tick", i)
    wait(200)
`;
