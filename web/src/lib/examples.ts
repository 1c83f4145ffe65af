/**
 * The examples the console ships (the manual's programs), grouped as the manual's chapters are. Opening
 * one asks the daemon for a copy in the stored programs, so the team edits its own program and the
 * example stays as shipped for the next person.
 */

import { api, type Program } from "./api";

export interface Example {
  id: string;
  title: string;
  group: string;
  group_title: string;
  summary: string;
  file: string;
}

export interface ExampleGroup {
  group: string;
  title: string;
  examples: Example[];
}

export async function listExamples(): Promise<Example[]> {
  return api.get<Example[]>("/api/examples");
}

/** Store a copy of the example as a new program (numbered when its name is taken); returns it. */
export async function openExample(id: string): Promise<Program> {
  const r = await api.post<{ example: string; program: Program }>(`/api/examples/${encodeURIComponent(id)}/open`);
  return r.program;
}

/** The daemon's order kept: groups in the order they first appear, each with its examples in order. */
export function groupExamples(list: Example[]): ExampleGroup[] {
  const groups = new Map<string, ExampleGroup>();
  for (const e of list) {
    let g = groups.get(e.group);
    if (!g) groups.set(e.group, (g = { group: e.group, title: e.group_title, examples: [] }));
    g.examples.push(e);
  }
  return [...groups.values()];
}

/**
 * What the Editor shows first: the examples for a visitor with no stored programs (nothing of theirs to
 * open yet), the programs otherwise, unless the page's address asks for one or the other.
 */
export function firstView(programCount: number, asked: string | null): "examples" | "programs" {
  if (asked === "examples" || asked === "programs") return asked;
  return programCount === 0 ? "examples" : "programs";
}
