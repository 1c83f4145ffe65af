/** The simulator as the daemon serves it: its worlds, its runs (each a job with a 3D view and a replay). */

import { api, query } from "./api";
import { storedZip } from "./zip";
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
  chassis: string | null;
  limit_ms: number;
  memory_mb: number;
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

export interface UploadedWorld {
  name: string;
  description: string;
  uploaded: boolean;
}

/** Upload a world: one zip as it is, or a world file and its mat zipped here. */
export async function uploadWorld(files: File[]): Promise<UploadedWorld> {
  const zip =
    files.length === 1 && files[0].name.toLowerCase().endsWith(".zip")
      ? files[0]
      : new Blob([storedZip(await Promise.all(files.map(async (f) => ({ name: f.name, data: new Uint8Array(await f.arrayBuffer()) }))))]);
  return api.upload<UploadedWorld>("/api/sim/worlds", zip);
}

export async function getSimRun(runId: string): Promise<SimRun> {
  return api.get<SimRun>(`/api/sim/runs/${encodeURIComponent(runId)}`);
}

export async function listSimRuns(limit = 20): Promise<SimRun[]> {
  return api.get<SimRun[]>(`/api/sim/runs${query({ limit })}`);
}

/** What starts a sim run: a stored program, and the defaults unless given. */
export interface SimRunRequest {
  program: string;
  version?: number;
  world?: string;
  chassis?: string | null;
  seed?: number;
  speed?: number | null;
  limit_ms?: number;
  memory_mb?: number;
}

/** Start a stored program in the simulator. */
export async function startSimRun(body: SimRunRequest): Promise<SimRun> {
  return api.post<SimRun>("/api/sim/runs", body);
}

/**
 * A run like an earlier one, with `seed`: from a sweep's params or a sim run's record, the same program
 * (and version, when it was recorded), world, chassis and limits, at real time to watch.
 */
export function runLike(p: Record<string, unknown>, seed: number): SimRunRequest {
  const body: SimRunRequest = { program: String(p.program ?? p.program_name), seed, speed: 1 };
  if (typeof p.version === "number") body.version = p.version;
  if (typeof p.world === "string") body.world = p.world;
  if (typeof p.chassis === "string") body.chassis = p.chassis;
  if (typeof p.limit_ms === "number") body.limit_ms = p.limit_ms;
  if (typeof p.memory_mb === "number") body.memory_mb = p.memory_mb;
  return body;
}

export async function setSpeed(runId: string, speed: number | null): Promise<SimRun> {
  return api.post<SimRun>(`/api/sim/runs/${encodeURIComponent(runId)}/speed`, { speed });
}

/** A run's score in a line: each measure with its value ("points 40, progress 0.93"), "—" for none. */
export function scoreText(score: Record<string, unknown> | null | undefined): string {
  if (!score) return "—";
  return Object.entries(score)
    .map(([k, v]) => `${k} ${typeof v === "number" ? Math.round(v * 100) / 100 : JSON.stringify(v)}`)
    .join(", ");
}
