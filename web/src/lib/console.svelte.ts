/**
 * The page's one live model of the daemon: hubs, who we are, the event stream's health, each hub's output
 * and each run's telemetry. Pages read it; only `applyEvent` and the refetch paths write it, so what a page
 * shows always comes from the daemon (REST for the state, the event stream for changes).
 */

import { SvelteSet } from "svelte/reactivity";
import { ApiError, api, type Competition, type Hub, type Me, type OutputLine, type RunOutcome, type TelemetrySample, query } from "./api";
import type { Envelope, Refetch, StreamState } from "./events";
import { HubOutput } from "./output";
import { RunTelemetry } from "./telemetry";
import { plainError } from "./words";

export interface Notice {
  id: number;
  kind: "info" | "error" | "warn";
  message: string;
  hint?: string | null;
}

export interface RunInfo {
  run_id: string;
  hub_id: string | null;
  program_name: string | null;
  started_ms: number;
  ended_ms: number | null;
  outcome: RunOutcome | null;
}

/** A daemon job (sim run, sweep, flash, servo scan) as its events describe it. */
export interface Job {
  job_id: string;
  kind: string;
  state: "queued" | "running" | "done" | "failed" | "cancelled";
  progress: number | null;
  label?: string | null;
  message?: string | null;
  result?: Record<string, unknown> | null;
  updated_ms: number;
}

let noticeIds = 0;
const KEPT_RUN_OUTPUTS = 8;

export class ConsoleModel {
  me = $state<Me | null>(null);
  hubs = $state<Record<string, Hub>>({});
  selected = new SvelteSet<string>();
  stream = $state<StreamState>("connecting");
  streamDetail = $state<string | null>(null);
  notices = $state<Notice[]>([]);
  /** Runs seen on the stream, newest last (the History page reads the store; this feeds the live pages). */
  runs = $state<Record<string, RunInfo>>({});
  lastOutcome = $state<Record<string, RunOutcome>>({});
  /** Whether the history holds any run at all (null until loaded): the dashboard's first-run hint. */
  hasRuns = $state<boolean | null>(null);
  jobs = $state<Record<string, Job>>({});
  /** Names of the programs the daemon stores (null until loaded). */
  programNames = $state<Set<string> | null>(null);
  /** The Bluetooth scan's state as the daemon reports it (scanning, unavailable and why, off). */
  ble = $state<string | null>(null);
  /** Bumped whenever a refetch reloaded the state, so pages showing stored data reload too. */
  generation = $state(0);
  /** Competition mode, as the daemon keeps it; `matchStartedMs` is on this computer's clock. */
  competition = $state({ on: false, matchSeconds: 150, matchStartedMs: null as number | null });
  now = $state(Date.now());
  /** The daemon's API paths (from its OpenAPI schema): pages whose API is missing say so. */
  apiPaths = $state<Set<string> | null>(null);

  readonly outputs = new Map<string, HubOutput>();
  /** Single runs' output, for a page that shows one run (the Simulator's), the newest few kept. */
  readonly runOutputs = new Map<string, HubOutput>();
  readonly telemetry = new Map<string, RunTelemetry>();
  /** Runs whose stored telemetry was read (or is being read) into `telemetry`. */
  private readonly telemetryRead = new Set<string>();

  hubList = $derived(Object.values(this.hubs).sort((a, b) => a.name.localeCompare(b.name) || a.hub_id.localeCompare(b.hub_id)));
  anyRunning = $derived(Object.values(this.hubs).some((h) => h.status === "running"));

  constructor(private readonly fetchLines = fetchRunLines) {}

  /**
   * Whether the event stream is lost: what the page shows is the last it heard, and nothing it sends
   * would be seen through. The first connect ("connecting") is not a loss.
   */
  connectionLost = $derived(this.stream === "reconnecting" || this.stream === "refused");

  /** Why a mutating control is disabled right now, or null when it may be used. */
  readOnlyReason = $derived(
    this.connectionLost
      ? this.stream === "refused"
        ? "This page is signed out of the console: open the address the console printed."
        : "The console is not reachable: waiting for it to come back."
      : this.me === null
      ? "Waiting for the console to say who you are."
      : this.me.role === "viewer"
        ? "Viewer role: read-only. Open the console with an operator token to change anything."
        : null,
  );

  /** Uploads, new runs, flashing and servo re-ID are refused in competition mode while a run is on. */
  uploadLockReason = $derived(
    this.readOnlyReason ??
      (this.competition.on && this.anyRunning ? "Competition mode: uploads, runs, flashing and servo re-ID are locked while a run is on." : null),
  );

  /** Whether the daemon serves `path` (as written in its OpenAPI schema, e.g. "/api/sim/runs"). */
  hasApi(path: string): boolean {
    return this.apiPaths?.has(path) ?? false;
  }

  output(hubId: string): HubOutput {
    let o = this.outputs.get(hubId);
    if (!o) {
      o = new HubOutput();
      this.outputs.set(hubId, o);
    }
    return o;
  }

  /**
   * A run's telemetry as it arrives. `stored`: for a run this page did not see start, what the daemon
   * kept is read once, and the live samples join after it.
   */
  runTelemetry(runId: string, stored = false): RunTelemetry {
    let t = this.telemetry.get(runId);
    if (!t) {
      t = new RunTelemetry();
      this.telemetry.set(runId, t);
    }
    if (stored && !this.runs[runId] && !this.telemetryRead.has(runId)) {
      this.telemetryRead.add(runId);
      const reading = t;
      reading.hold();
      fetchRunSamples(runId).then(
        (samples) => reading.release(samples),
        (err) => {
          reading.release([]);
          this.fail(err, "Loading the run's telemetry");
        },
      );
    }
    return t;
  }

  /** One run's output alone: what the daemon stored of it, then its live lines, in order and once. */
  runOutput(runId: string): HubOutput {
    let o = this.runOutputs.get(runId);
    if (!o) {
      o = new HubOutput();
      this.runOutputs.set(runId, o);
      for (const old of this.runOutputs.keys()) {
        if (this.runOutputs.size <= KEPT_RUN_OUTPUTS) break;
        this.runOutputs.delete(old);
      }
      void this.fillHole(o, runId, 0);
    }
    return o;
  }

  notify(kind: Notice["kind"], message: string, hint?: string | null): void {
    const id = ++noticeIds;
    this.notices = [...this.notices.slice(-4), { id, kind, message, hint }];
    setTimeout(() => this.dismiss(id), kind === "error" ? 12000 : 5000);
  }

  dismiss(id: number): void {
    this.notices = this.notices.filter((n) => n.id !== id);
  }

  /** Show a failed call the way the daemon explained it. */
  fail(err: unknown, what: string): void {
    // Unreachable while the stream is not live: the banner says it (or will, as the stream's retry fails);
    // no toast per failed call on top of it.
    if (err instanceof ApiError && err.status === 0 && this.stream !== "live") return;
    if (err instanceof ApiError) {
      const said = plainError(err);
      this.notify("error", `${what}: ${said.message}`, said.hint);
    } else this.notify("error", `${what}: ${String(err)}`);
  }

  setHubs(list: Hub[]): void {
    const next: Record<string, Hub> = {};
    for (const h of list) next[h.hub_id] = h;
    this.hubs = next;
    for (const id of [...this.selected]) if (!next[id]) this.selected.delete(id);
  }

  /** Reload everything the stream may have missed. */
  async refetch(r?: Refetch): Promise<void> {
    if (r && !r.quiet) this.notify("warn", r.message);
    const [me, hubs] = await Promise.allSettled([
      api.get<Me>("/api/auth/me"),
      api.get<{ hubs: Hub[]; ble: string }>("/api/hubs"),
    ]);
    if (me.status === "fulfilled") this.me = me.value;
    else this.fail(me.reason, "Signing in");
    if (hubs.status === "fulfilled") {
      this.setHubs(hubs.value.hubs);
      this.ble = hubs.value.ble;
    } else this.fail(hubs.reason, "Loading the hubs");
    try {
      const [programs, recent] = await Promise.all([
        api.get<{ name: string }[]>("/api/programs"),
        api.get<{ hub_id: string; outcome: RunOutcome | null }[]>("/api/runs?limit=200"),
      ]);
      this.programNames = new Set(programs.map((p) => p.name));
      // Each hub's last outcome: runs come newest first.
      const last: Record<string, RunOutcome> = {};
      for (const r of recent) if (r.outcome && !(r.hub_id in last)) last[r.hub_id] = r.outcome;
      this.lastOutcome = { ...last, ...this.lastOutcome };
      this.hasRuns = recent.length > 0 || Object.keys(this.runs).length > 0;
    } catch (err) {
      this.fail(err, "Loading programs and recent runs");
    }
    try {
      this.setCompetition(await api.get<Competition>("/api/competition"));
    } catch (err) {
      // A daemon older than competition mode (404) has none to lock with: the page's switch stays off.
      if (!(err instanceof ApiError && err.status === 404)) this.fail(err, "Loading competition mode");
    }
    if (this.apiPaths === null) {
      try {
        const schema = await api.get<{ paths: Record<string, unknown> }>("/openapi.json");
        this.apiPaths = new Set(Object.keys(schema.paths ?? {}));
      } catch {
        this.apiPaths = new Set();
      }
    }
    // Each open run's output is brought up to date from the store.
    for (const [hubId, out] of this.outputs) {
      const hub = this.hubs[hubId];
      if (hub?.run_id && out.hasRun(hub.run_id)) void this.fillHole(out, hub.run_id, out.lastLine(hub.run_id));
    }
    for (const [run, out] of this.runOutputs) void this.fillHole(out, run, out.lastLine(run));
    this.generation += 1;
  }

  applyEvent(e: Envelope): void {
    const d = e.data ?? {};
    switch (e.type) {
      case "hub":
      case "hub_changed":
      case "hub_status": {
        const hub = ((d as { hub?: Hub }).hub ?? d) as Hub;
        if (hub.hub_id) this.hubs[hub.hub_id] = { ...this.hubs[hub.hub_id], ...hub };
        break;
      }
      case "hub_removed":
        if (e.hub) delete this.hubs[e.hub];
        break;
      case "run_started": {
        const run = e.run ?? (d.run_id as string);
        const hubId = e.hub ?? (d.hub_id as string) ?? null;
        const info: RunInfo = {
          run_id: run,
          hub_id: hubId,
          program_name: (d.program_name as string) ?? null,
          started_ms: (d.started_ms as number) ?? e.ts,
          ended_ms: null,
          outcome: null,
        };
        this.runs[run] = info;
        this.hasRuns = true;
        if (hubId) {
          const label = info.program_name ? `▶ ${info.program_name}` : "▶ run";
          this.output(hubId).startRun(run, `${label} started (${(d.origin as string) ?? "daemon"})`, info.started_ms);
        }
        break;
      }
      case "output":
      case "run_output": {
        const hubId = e.hub;
        const run = e.run;
        if (!hubId || !run) break;
        const lines = (d.lines as OutputLine[]) ?? [d as unknown as OutputLine];
        for (const out of [this.output(hubId), this.runOutputs.get(run)]) {
          const hole = out?.append(run, lines);
          if (out && hole) void this.fillHole(out, run, hole.after);
        }
        break;
      }
      case "telemetry":
      case "run_telemetry": {
        if (!e.run) break;
        const samples = (d.samples as TelemetrySample[]) ?? [d as unknown as TelemetrySample];
        this.runTelemetry(e.run).add(samples);
        break;
      }
      case "run_gap":
        if (e.hub) this.output(e.hub).note(`[link dropped: ${(d.reason as string) ?? "output may be missing"}]`, e.run, "error");
        break;
      case "run_ended": {
        const run = e.run ?? (d.run_id as string);
        const outcome = d.outcome as RunOutcome;
        if (this.runs[run]) {
          this.runs[run].ended_ms = (d.ended_ms as number) ?? e.ts;
          this.runs[run].outcome = outcome;
        }
        const hubId = e.hub ?? this.runs[run]?.hub_id;
        // A detail that only repeats the outcome ("stopped: stopped") says nothing more.
        const detail = d.detail && d.detail !== outcome ? `: ${d.detail as string}` : "";
        const kind = outcome === "error" || outcome === "dropped" ? "error" : "note";
        if (hubId) {
          this.lastOutcome[hubId] = outcome;
          this.output(hubId).note(`■ ${outcome}${detail}`, run, kind);
        }
        this.runOutputs.get(run)?.note(`■ ${outcome}${detail}`, run, kind);
        break;
      }
      case "program": {
        const name = d.name as string | undefined;
        if (name && this.programNames) {
          const next = new Set(this.programNames);
          if (d.action === "deleted") next.delete(name);
          else next.add(name);
          if (d.action === "renamed") next.delete(d.old_name as string);
          this.programNames = next;
        }
        break;
      }
      case "competition":
        this.setCompetition(d as unknown as Competition, e.ts);
        break;
      case "job":
      case "job_progress":
      case "job_changed": {
        const job = ((d as { job?: Job }).job ?? d) as Job;
        if (job.job_id) this.jobs[job.job_id] = { ...this.jobs[job.job_id], ...job, updated_ms: e.ts };
        break;
      }
      default:
        break;
    }
  }

  private async fillHole(out: HubOutput, run: string, after: number): Promise<void> {
    try {
      out.fill(run, await this.fetchLines(run, after));
    } catch (err) {
      out.fill(run, []);
      this.fail(err, "Loading missed output");
    }
  }

  /**
   * Take competition mode from the daemon. Its match start is on the daemon's clock, `serverMs` the
   * daemon's clock now (an answer's `server_ms`, an event's `ts`): the timer runs on this computer's
   * clock from the same instant, so a page on another computer shows the same time left.
   */
  setCompetition(c: Competition, serverMs = c.server_ms ?? Date.now()): void {
    this.competition = {
      on: c.on,
      matchSeconds: c.match_s,
      matchStartedMs: c.match_started_ms === null ? null : c.match_started_ms + (Date.now() - serverMs),
    };
  }
}

/** A run's stored telemetry samples. */
export async function fetchRunSamples(run: string): Promise<TelemetrySample[]> {
  return api.get<TelemetrySample[]>(`/api/runs/${encodeURIComponent(run)}/telemetry`);
}

/** Every stored line of `run` after line `after`, page by page. */
export async function fetchRunLines(run: string, after = 0): Promise<OutputLine[]> {
  const all: OutputLine[] = [];
  for (;;) {
    const page = await api.get<{ lines: OutputLine[]; next_after: number; more: boolean }>(
      `/api/runs/${encodeURIComponent(run)}/output${query({ after, limit: 5000 })}`,
    );
    all.push(...page.lines);
    if (!page.more || page.next_after <= after) return all;
    after = page.next_after;
  }
}

export const consoleModel = new ConsoleModel();
