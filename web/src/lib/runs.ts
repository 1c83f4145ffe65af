/** The run history as the daemon keeps it: search, one run with its output, program and telemetry. */

import { api, query, type Run } from "./api";

const enc = encodeURIComponent;

export interface RunFilter {
  hub?: string;
  outcome?: string;
  q?: string;
  /** local dates, YYYY-MM-DD: runs started on or after `since`, before `until` */
  since?: string | null;
  until?: string | null;
  before?: string | null;
  limit?: number;
}

export interface RunDetail extends Run {
  source?: string | null;
  gaps?: { reason: string; since_ms: number; until_ms: number | null }[];
}

export async function searchRuns(f: RunFilter): Promise<Run[]> {
  return api.get<Run[]>(`/api/runs${query({ ...f })}`);
}

export async function getRun(id: string): Promise<RunDetail> {
  return api.get<RunDetail>(`/api/runs/${enc(id)}`);
}

export { fetchRunLines as runLines, fetchRunSamples as runSamples } from "./console.svelte";

/** Where a run's export lives; the browser downloads it with the session cookie. */
export function exportUrl(id: string, format: "text" | "json"): string {
  return `api/runs/${enc(id)}/export${query({ format })}`;
}
