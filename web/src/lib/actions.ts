/**
 * Every mutating thing the page can ask of the daemon, in one place: each call reports failure through
 * the daemon's own message and hint, and refuses up front (with the reason) when the role or competition
 * mode forbids it, so no control can mutate by a path the disabled-state logic does not know about.
 */

import { api, type Competition, type Hub } from "./api";
import { consoleModel as model } from "./console.svelte";
import { type StopAllResult, stopAllSummary } from "./words";

const enc = encodeURIComponent;

function refusedFor(kind: "mutate" | "upload"): boolean {
  const reason = kind === "upload" ? model.uploadLockReason : model.readOnlyReason;
  if (reason) model.notify("warn", reason);
  return reason !== null;
}

export async function stopAll(): Promise<void> {
  if (refusedFor("mutate")) return;
  try {
    const summary = stopAllSummary((await api.post<{ hubs: StopAllResult[] }>("/api/hubs/stop-all")).hubs);
    model.notify(summary.kind, summary.message);
  } catch (err) {
    model.fail(err, "STOP ALL");
  }
}

export async function stop(hubId: string): Promise<void> {
  if (refusedFor("mutate")) return;
  try {
    await api.post(`/api/hubs/${enc(hubId)}/stop`);
  } catch (err) {
    model.fail(err, `Stop ${hubName(hubId)}`);
  }
}

/** Identify, connect or disconnect one hub; the daemon's answer, or null when it was refused or failed. */
export async function hubAction(hubId: string, action: "identify" | "connect" | "disconnect"): Promise<Record<string, unknown> | null> {
  if (refusedFor("mutate")) return null;
  try {
    return (await api.post<Record<string, unknown>>(`/api/hubs/${enc(hubId)}/${action}`)) ?? {};
  } catch (err) {
    model.fail(err, `${action[0].toUpperCase()}${action.slice(1)} ${hubName(hubId)}`);
    return null;
  }
}

/** What to run: a stored program by name (the daemon records the exact version it ran). */
export interface RunRequest {
  program: string;
}

/**
 * What a hub's own Run button runs: the stored program of the name staged on it, or null with the reason.
 * (The daemon runs programs it is sent; a program staged by another tool has no stored copy to send.)
 */
export function rerunnable(hub: Hub, stored: Set<string> | null): { program: string } | { reason: string } {
  if (!hub.staged_program) return { reason: "Nothing staged: run a program on it from the editor first." };
  if (stored && !stored.has(hub.staged_program)) return { reason: `${hub.staged_program} is not stored in the console: open it in the editor.` };
  return { program: hub.staged_program };
}

/**
 * Run (or upload) on several hubs at once, each its own request so one busy hub does not hold back the
 * others; returns the hubs that accepted.
 */
export async function runOn(hubIds: string[], what: RunRequest, mode: "run" | "upload" = "run"): Promise<string[]> {
  if (refusedFor("upload")) return [];
  const results = await Promise.allSettled(hubIds.map((id) => api.post(`/api/hubs/${enc(id)}/${mode}`, { program: what.program })));
  const ok: string[] = [];
  results.forEach((r, i) => {
    if (r.status === "fulfilled") ok.push(hubIds[i]);
    else model.fail(r.reason, `${mode === "run" ? "Run" : "Upload"} on ${hubName(hubIds[i])}`);
  });
  if (ok.length && mode === "upload") model.notify("info", `Uploaded to ${ok.map(hubName).join(", ")}.`);
  return ok;
}

/** Each hub's Run button (and F5 on the dashboard): run the stored program staged on it. */
export async function runStaged(hubIds: string[]): Promise<void> {
  for (const id of hubIds) {
    const hub = model.hubs[id];
    if (!hub) continue;
    const what = rerunnable(hub, model.programNames);
    if ("reason" in what) model.notify("warn", `${hub.name}: ${what.reason}`);
    else void runOn([id], what);
  }
}

/**
 * Competition mode is the daemon's: it refuses uploads and new runs while a hub runs, for every page
 * and script alike. The page shows what the daemon answered, so a refused change leaves the switch as
 * it was.
 */
export async function changeCompetition(change: { on?: boolean; match_s?: number }): Promise<void> {
  if (refusedFor("mutate")) return;
  try {
    model.setCompetition(await api.put<Competition>("/api/competition", change));
  } catch (err) {
    model.fail(err, "Competition mode");
  }
}

export async function matchTimer(action: "start" | "reset"): Promise<void> {
  if (refusedFor("mutate")) return;
  try {
    model.setCompetition(await api.post<Competition>(`/api/competition/match/${action}`));
  } catch (err) {
    model.fail(err, action === "start" ? "Start match" : "Reset match");
  }
}

export function hubName(hubId: string): string {
  const h: Hub | undefined = model.hubs[hubId];
  return h ? h.name : hubId;
}
