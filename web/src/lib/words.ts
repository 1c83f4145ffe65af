/**
 * What the page says, in words a student at the table understands. The daemon's messages are written for
 * scripts and the CLI too (they name the HTTP call to make, they stamp times in UTC); the page shows the
 * same facts without the plumbing: no HTTP verbs or paths, local times, an action for each audit row.
 */

import type { ApiError } from "./api";

const HTTP_REF = /\s*\((?:GET|POST|PUT|PATCH|DELETE)\s+[^)]*\)/g;
const ISO_TIME = /\b\d{4}-\d{2}-\d{2}T\d{2}:\d{2}(?::\d{2}(?:\.\d+)?)?(?:Z|[+-]\d{2}:?\d{2})?/g;

function localClock(iso: string): string {
  const t = Date.parse(iso);
  return Number.isNaN(t) ? iso : new Date(t).toLocaleTimeString(undefined, { hour: "2-digit", minute: "2-digit", second: "2-digit" });
}

/** A daemon message without HTTP calls in brackets, its UTC times as this computer's clock time. */
export function plain(text: string): string {
  return text.replace(HTTP_REF, "").replace(ISO_TIME, (m) => localClock(m)).replace(/\s+([,.;)])/g, "$1");
}

/** A failed call as the page says it: what went wrong and what to do, both in plain words. */
export function plainError(err: Pick<ApiError, "message" | "hint" | "code">): { message: string; hint: string | null } {
  if (err.code === "unreachable" || err.code === "timeout") return { message: "The console did not answer.", hint: "Check that the console is still running (the window where it was started), then try again." };
  return { message: plain(err.message), hint: err.hint ? plain(err.hint) : null };
}

/** The Bluetooth scan's state (the daemon's "scanning", "off (--no-ble)", "unavailable (Error: …)…") as the pill says it. */
export function bluetoothWords(ble: string | null): { text: string; title: string } | null {
  if (!ble) return null;
  const s = ble.trim();
  if (s.startsWith("scanning")) return { text: "Bluetooth: looking for hubs", title: "The console is scanning for Bluetooth hubs." };
  if (s.startsWith("starting") || s.startsWith("not started")) return { text: "Bluetooth: starting", title: "The console is starting its Bluetooth scan." };
  if (s.startsWith("off")) return { text: "Bluetooth: off", title: "The console was started without Bluetooth (--no-ble). USB and virtual hubs work." };
  if (s.startsWith("unavailable"))
    return {
      text: "Bluetooth: not available on this computer",
      title: "This computer has no Bluetooth the console can use (no adapter, or it is turned off). USB and virtual hubs work without it.",
    };
  return { text: `Bluetooth: ${plain(s)}`, title: "The console's Bluetooth scan" };
}

/** One hub's answer to STOP ALL (POST /api/hubs/stop-all). */
export interface StopAllResult {
  hub: string;
  name: string;
  stopped: boolean;
  detail?: string | null;
}

// The daemon's word for an idle hub (server/daemon/hubs/actor.py NOTHING_RUNNING), and for one not linked.
const NOTHING_RUNNING = /^(no program|nothing) was running/;
const NOT_LINKED = new Set(["offline", "connecting", "flashing"]);

/**
 * What STOP ALL says afterwards. A hub with nothing to stop is a success: STOP ALL asks for every hub to
 * be still, and it is. A hub the console holds no link to is said plainly (it may run on its own), and
 * only a hub that did not confirm its stop is an error.
 */
export function stopAllSummary(results: StopAllResult[]): { kind: "info" | "warn" | "error"; message: string } {
  const stopped = results.filter((r) => r.stopped).map((r) => r.name);
  const unlinked = results.filter((r) => !r.stopped && NOT_LINKED.has(r.detail ?? "")).map((r) => r.name);
  const failed = results.filter((r) => !r.stopped && !NOT_LINKED.has(r.detail ?? "") && !NOTHING_RUNNING.test(r.detail ?? ""));
  const parts: string[] = [];
  if (stopped.length) parts.push(`Stopped ${stopped.join(", ")}.`);
  if (failed.length) parts.push(`Could not stop ${failed.map((f) => `${f.name} (${plain(f.detail ?? "no answer")})`).join(", ")}: stop it by hand.`);
  if (unlinked.length) parts.push(`${unlinked.join(", ")} ${unlinked.length > 1 ? "are" : "is"} not connected: stop ${unlinked.length > 1 ? "them" : "it"} on the hub if it is moving.`);
  if (!parts.length) parts.push(results.length ? "All hubs are stopped (nothing was running)." : "No hubs to stop.");
  return { kind: failed.length ? "error" : unlinked.length ? "warn" : "info", message: parts.join(" ") };
}

function verb(method: string, path: string, program: string | null = null): string | null {
  const m = method.toUpperCase();
  const p = path.replace(/\/+$/, "");
  const rules: [string, RegExp, (g: string[]) => string][] = [
    ["POST", /^\/api\/hubs\/stop-all$/, () => "Stopped all hubs"],
    ["POST", /^\/api\/hubs\/([^/]+)\/run$/, (g) => `Ran ${program ?? "a program"} on ${g[0]}`],
    ["POST", /^\/api\/hubs\/([^/]+)\/upload$/, (g) => `Uploaded ${program ?? "a program"} to ${g[0]}`],
    ["POST", /^\/api\/hubs\/([^/]+)\/stop$/, (g) => `Stopped ${g[0]}`],
    ["POST", /^\/api\/hubs\/([^/]+)\/identify$/, (g) => `Identified ${g[0]} (blinked its light)`],
    ["POST", /^\/api\/hubs\/([^/]+)\/connect$/, (g) => `Connected ${g[0]}`],
    ["POST", /^\/api\/hubs\/([^/]+)\/disconnect$/, (g) => `Disconnected ${g[0]}`],
    ["POST", /^\/api\/hubs\/([^/]+)\/repl$/, (g) => `Typed at ${g[0]}'s prompt`],
    ["PUT", /^\/api\/programs\/([^/]+)$/, (g) => `Saved ${g[0]}`],
    ["DELETE", /^\/api\/programs\/([^/]+)$/, (g) => `Deleted ${g[0]}`],
    ["POST", /^\/api\/programs\/([^/]+)\/rename$/, (g) => `Renamed ${g[0]}`],
    ["POST", /^\/api\/programs\/([^/]+)\/versions\/(\d+)\/restore$/, (g) => `Restored version ${g[1]} of ${g[0]}`],
    ["POST", /^\/api\/examples\/([^/]+)\/open$/, (g) => `Opened the example ${g[0]}`],
    ["POST", /^\/api\/sim\/runs$/, () => "Started a simulator run"],
    ["POST", /^\/api\/sim\/runs\/([^/]+)\/stop$/, () => "Stopped a simulator run"],
    ["POST", /^\/api\/sim\/runs\/([^/]+)\/pause$/, () => "Paused a simulator run"],
    ["POST", /^\/api\/sim\/runs\/([^/]+)\/resume$/, () => "Resumed a simulator run"],
    ["POST", /^\/api\/sim\/runs\/([^/]+)\/speed$/, () => "Changed a simulator run's speed"],
    ["POST", /^\/api\/sim\/sweeps$/, () => "Started a simulator sweep"],
    ["POST", /^\/api\/flash\/firmware$/, () => "Uploaded a firmware image"],
    ["POST", /^\/api\/flash$/, () => "Started flashing"],
    ["POST", /^\/api\/servos\/scan$/, () => "Scanned for servos"],
    ["POST", /^\/api\/servos\/set-id$/, () => "Changed a servo's id"],
    ["POST", /^\/api\/jobs\/([^/]+)\/stop$/, () => "Cancelled a job"],
    ["POST", /^\/api\/auth\/tokens$/, () => "Made a sign-in link"],
    ["DELETE", /^\/api\/auth\/tokens\/([^/]+)$/, (g) => `Revoked the sign-in link ${g[0]}`],
    ["PUT", /^\/api\/competition$/, () => "Changed competition mode"],
    ["POST", /^\/api\/competition\/match\/start$/, () => "Started the match timer"],
    ["POST", /^\/api\/competition\/match\/reset$/, () => "Reset the match timer"],
  ];
  for (const [want, re, say] of rules) {
    const found = m === want ? re.exec(p) : null;
    if (found) return say(found.slice(1).map((x) => safeDecode(x)));
  }
  return null;
}

function safeDecode(s: string): string {
  try {
    return decodeURIComponent(s);
  } catch {
    return s;
  }
}

const JOB_KINDS: Record<string, string> = { flash: "Flash", sim: "Simulator run", sweep: "Simulator sweep", servo_scan: "Servo scan", servo: "Servo job" };

/**
 * An audit row's action ("POST /api/hubs/virtual:SimHub-1/identify", or a job's "flash /dev/ttyUSB0") as
 * a sentence; `hubName` turns a hub id into the name on its tile, `program` names what a run or upload
 * sent (the audit keeps the request, not its body: the page finds it in the run history).
 */
export function auditWords(action: string, hubName: (idOrName: string) => string = (x) => x, program: string | null = null): string {
  const [method, ...rest] = action.trim().split(/\s+/);
  const path = rest.join(" ");
  if (/^(GET|POST|PUT|PATCH|DELETE)$/i.test(method) && path.startsWith("/")) {
    const hub = /^\/api\/hubs\/([^/]+)\//.exec(path);
    const said = verb(method, hub && hub[1] !== "stop-all" ? path.replace(hub[1], encodeURIComponent(hubName(safeDecode(hub[1])))) : path, program);
    return said ?? `Changed something (${method.toUpperCase()} ${path})`;
  }
  // A job's end: its kind and label.
  const kind = JOB_KINDS[method] ?? method;
  return path ? `${kind}: ${path}` : kind;
}

/** An audit row's HTTP status (or, for a job's row, how the job ended) as its result. */
export function auditResult(status: number, action = ""): string {
  const job = !/^(GET|POST|PUT|PATCH|DELETE)\s/i.test(action.trim());
  if (job) return status < 300 ? "done" : status === 503 ? "cancelled" : "failed";
  if (status === 202) return "started";
  if (status < 300) return "done";
  if (status === 401 || status === 403) return "refused (no permission)";
  if (status === 409) return "refused (busy or locked)";
  if (status === 422 || status === 400) return "refused (bad input)";
  return "failed";
}

/** The hub an audit row's request addressed (by id or name, as the path has it), for finding its run. */
export function auditHub(action: string): string | null {
  const m = /^POST\s+\/api\/hubs\/([^/]+)\/(run|upload)$/i.exec(action.trim());
  return m ? safeDecode(m[1]) : null;
}

/**
 * The program a run request started: the run on that hub that began last before the request was
 * recorded (the audit entry is written as the request ends, a moment after its run starts).
 */
export function programOfRun(
  row: { ts_ms: number; action: string },
  runs: { hub_id: string; started_ms: number; program_name: string | null }[],
  hubIdOf: (idOrName: string) => string,
): string | null {
  const ref = auditHub(row.action);
  if (ref === null || !/\/run$/.test(row.action.trim())) return null;
  const hub = hubIdOf(ref);
  let best: { started_ms: number; program_name: string | null } | null = null;
  for (const r of runs) {
    if (r.hub_id !== hub || r.started_ms > row.ts_ms || row.ts_ms - r.started_ms > 10000) continue;
    if (!best || r.started_ms > best.started_ms) best = r;
  }
  return best?.program_name ?? null;
}
