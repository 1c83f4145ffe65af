/**
 * The jobs the daemon keeps as history (flash, servo scans and re-IDs, seed sweeps: `GET /api/jobs`), as
 * the History page lists them. The stored list is read once per search; the jobs' live events then keep
 * it current (a running flash's progress, a job started elsewhere), so the list never waits for a reload.
 * Sim runs are runs: they are in the runs list (hub "sim"), not here.
 */

import { api, query } from "./api";
import type { Job } from "./console.svelte";

export type JobState = Job["state"];
export const JOB_STATES: JobState[] = ["queued", "running", "done", "failed", "cancelled"];

/** A job as `GET /api/jobs` answers it. */
export interface JobRecord {
  job_id: string;
  kind: string;
  label: string;
  batch: string | null;
  who: string;
  state: JobState;
  progress: number | null;
  message: string | null;
  params: Record<string, unknown>;
  result: Record<string, unknown> | null;
  steps: string[];
  created_ms: number;
  started_ms: number | null;
  ended_ms: number | null;
}

export interface JobFilter {
  kind?: string;
  state?: string;
  before?: string | null;
  limit?: number;
}

/** The kinds the History page offers to filter by, with their names on the page. */
export const JOB_KINDS: Record<string, string> = {
  flash: "Flash",
  servo_scan: "Servo scan",
  servo_set_id: "Servo re-ID",
  sim_sweep: "Sim sweep",
};

export function kindLabel(kind: string): string {
  return JOB_KINDS[kind] ?? kind;
}

export async function searchJobs(f: JobFilter): Promise<JobRecord[]> {
  return api.get<JobRecord[]>(`/api/jobs${query({ ...f })}`);
}

export async function getJob(id: string): Promise<JobRecord> {
  return api.get<JobRecord>(`/api/jobs/${encodeURIComponent(id)}`);
}

/** Sim runs announce themselves as jobs too, but they are runs, listed with the hubs' runs. */
const NOT_JOBS = new Set(["sim"]);

function matches(job: { kind: string; state: string }, f: JobFilter): boolean {
  return !NOT_JOBS.has(job.kind) && (!f.kind || job.kind === f.kind) && (!f.state || job.state === f.state);
}

/**
 * The stored list brought up to date with what the event stream said since: each listed job takes its live
 * state, progress and message; a job started after the list was read (a full record from a `job` event)
 * joins it when it matches the filter; a job whose state left the filter's drops out. Newest first, as
 * the daemon lists them (job ids sort by creation). `complete`: the stored list was not cut at a page, so
 * live jobs older than its last row may join too.
 */
export function withLive(listed: JobRecord[], live: Record<string, Job>, f: JobFilter, complete = true): JobRecord[] {
  const byId = new Map<string, JobRecord>();
  for (const row of listed) {
    const now = live[row.job_id];
    byId.set(row.job_id, now ? overlay(row, now) : row);
  }
  const oldest = listed.at(-1)?.job_id ?? "";
  for (const job of Object.values(live)) {
    if (byId.has(job.job_id) || !isRecord(job)) continue;
    if (!complete && job.job_id < oldest) continue;
    byId.set(job.job_id, overlay(job as unknown as JobRecord, job));
  }
  return [...byId.values()].filter((j) => matches(j, f)).sort((a, b) => (a.job_id < b.job_id ? 1 : a.job_id > b.job_id ? -1 : 0));
}

/** A live event's fields over the stored row (a `job_progress` event carries only some of them). */
function overlay(row: JobRecord, job: Job): JobRecord {
  const { updated_ms: _seen, ...fields } = job;
  const merged = { ...row } as Record<string, unknown>;
  for (const [key, value] of Object.entries(fields)) if (value !== undefined) merged[key] = value;
  return merged as unknown as JobRecord;
}

/** Whether a live job is a whole record (from a `job` event), not just a progress summary. */
function isRecord(job: Job): boolean {
  const j = job as unknown as Partial<JobRecord>;
  return typeof j.created_ms === "number" && typeof j.label === "string" && Array.isArray(j.steps);
}

/** What a finished job came to, in a line: its result's own words where it has them. */
export function jobOutcome(job: JobRecord): string {
  const r = job.result ?? {};
  if (job.state !== "done") return job.message ?? "";
  if (job.kind === "flash" && typeof r.hub_name === "string") return `named ${r.hub_name}${typeof r.firmware === "string" ? `, running ${r.firmware}` : ""}`;
  if (job.kind === "sim_sweep" && Array.isArray(r.rows)) {
    const s = (r.summary ?? {}) as { success_rate?: number | null; mean_score?: number | null };
    const parts = [`${r.rows.length} seeds`];
    if (typeof s.success_rate === "number") parts.push(`${Math.round(s.success_rate * 100)} % ran to the end`);
    if (typeof s.mean_score === "number") parts.push(`mean score ${s.mean_score}`);
    return parts.join(", ");
  }
  if (typeof r.message === "string") return r.message;
  return job.message ?? "done";
}
