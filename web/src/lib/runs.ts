/** The run history as the daemon keeps it: search, one run with its output, program and telemetry. */

import { api, type OutputLine, query, type Run, type TelemetrySample } from "./api";

const enc = encodeURIComponent;

export interface RunFilter {
  hub?: string;
  outcome?: string;
  q?: string;
  since_ms?: number | null;
  until_ms?: number | null;
  before?: string | null;
  limit?: number;
}

export interface RunDetail extends Run {
  source?: string | null;
  gaps?: { reason: string; since_ms: number; until_ms: number | null }[];
}

export async function searchRuns(f: RunFilter): Promise<Run[]> {
  const r = await api.get<Run[] | { runs: Run[] }>(`/api/runs${query({ ...f })}`);
  return Array.isArray(r) ? r : r.runs;
}

export async function getRun(id: string): Promise<RunDetail> {
  return api.get<RunDetail>(`/api/runs/${enc(id)}`);
}

export async function runLines(id: string): Promise<OutputLine[]> {
  const r = await api.get<OutputLine[] | { lines: OutputLine[] }>(`/api/runs/${enc(id)}/output`);
  return Array.isArray(r) ? r : r.lines;
}

export async function runSamples(id: string): Promise<TelemetrySample[]> {
  const r = await api.get<TelemetrySample[] | { samples: TelemetrySample[] }>(`/api/runs/${enc(id)}/telemetry`);
  return Array.isArray(r) ? r : r.samples;
}

/** Where a run's export lives; the browser downloads it with the session cookie. */
export function exportUrl(id: string, format: "text" | "json"): string {
  return `api/runs/${enc(id)}/export${query({ format })}`;
}
