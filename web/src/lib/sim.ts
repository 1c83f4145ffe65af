/** The simulator as the daemon serves it: its worlds, its runs (each a job with a 3D view and a replay). */

import { api, query } from "./api";
import type { Job } from "./console.svelte";

/** A sim run as `GET /api/sim/runs` answers it (the fields the page shows). */
export interface SimRun {
  run_id: string;
  job_id: string;
  kind: "sim";
  state: Job["state"];
  label: string | null;
  message: string | null;
  program_name: string | null;
  world: string;
  seed: number;
  speed: number | null;
  started_ms: number;
  ended_ms: number | null;
  exit: string | null;
  score: Record<string, unknown> | null;
  error: string | null;
  live: boolean;
  paused: boolean;
  replay_url: string | null;
  recording_url: string | null;
}

/** Real-time factors offered for a run (null: as fast as the computer can). */
export const SPEEDS: (number | null)[] = [0.25, 0.5, 1, 2, 4, 8, null];

export function speedLabel(speed: number | null): string {
  return speed === null ? "max" : `${speed}×`;
}

export async function listWorlds(): Promise<string[]> {
  return (await api.get<{ name: string }[]>("/api/sim/worlds")).map((w) => w.name);
}

export async function listSimRuns(limit = 20): Promise<SimRun[]> {
  return api.get<SimRun[]>(`/api/sim/runs${query({ limit })}`);
}

/** Start a stored program in the simulator (the world's defaults unless given). */
export async function startSimRun(body: { program: string; world?: string; seed?: number; speed?: number | null }): Promise<SimRun> {
  return api.post<SimRun>("/api/sim/runs", body);
}

export async function setSpeed(runId: string, speed: number | null): Promise<SimRun> {
  return api.post<SimRun>(`/api/sim/runs/${encodeURIComponent(runId)}/speed`, { speed });
}

/** A daemon path as the page links it: relative, so a console behind a path prefix works too. */
export function relative(url: string): string {
  return url.replace(/^\//, "");
}
