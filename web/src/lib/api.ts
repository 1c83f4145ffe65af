/**
 * The daemon's REST API as the page uses it: one `request` that turns the daemon's error shape
 * (`{"error", "message", "hint"}`) into an `ApiError`, so every page shows the same what/how-to-fix text,
 * and the typed calls the pages make. The cookie set by the token exchange authenticates every call.
 */

export type HubStatus = "offline" | "connecting" | "idle" | "running" | "busy" | "flashing";
export type RunOutcome = "finished" | "error" | "stopped" | "dropped" | "interrupted";
export type Role = "viewer" | "operator";

export interface Hub {
  hub_id: string;
  name: string;
  kind: string;
  address: string;
  status: HubStatus;
  rssi: number | null;
  last_seen_ms: number | null;
  firmware: string | null;
  capabilities: Record<string, unknown>;
  staged_program: string | null;
  run_id: string | null;
  run_started_ms: number | null;
  holder: { operation: string; who: string; since_ms: number } | null;
  /** why the last connect or operation failed, until the next one succeeds */
  last_error: string | null;
}

export interface Program {
  name: string;
  version: number;
  sha256: string;
  size: number;
  created_ms: number;
  who: string | null;
  source?: string;
}

export interface Run {
  run_id: string;
  hub_id: string;
  origin: string;
  program_name: string | null;
  program_sha256: string | null;
  slot: number | null;
  who: string | null;
  started_ms: number;
  ended_ms: number | null;
  outcome: RunOutcome | null;
  detail: string | null;
  line_count: number;
}

export interface OutputLine {
  line_no: number;
  text: string;
  hub_ms: number | null;
  recv_ms: number;
}

export interface TelemetrySample {
  name: string;
  value: number;
  hub_ms: number | null;
  recv_ms: number;
}

/** Competition mode as the daemon keeps it (`GET /api/competition`, and `competition` events). */
export interface Competition {
  on: boolean;
  match_s: number;
  /** when the match timer started, on the daemon's clock; null: not running */
  match_started_ms: number | null;
  changed_by: string | null;
  changed_ms: number | null;
  /** the daemon's clock when it answered (GET only; an event's `ts` says the same) */
  server_ms?: number;
}

export interface Me {
  label: string;
  role: Role;
  via: "cookie" | "bearer";
}

/** One failure as the daemon explains it; `status` 0 means the daemon could not be reached at all. */
export class ApiError extends Error {
  readonly status: number;
  readonly code: string;
  readonly hint: string | null;
  readonly detail: Record<string, unknown>;

  constructor(status: number, code: string, message: string, hint: string | null, detail: Record<string, unknown> = {}) {
    super(message);
    this.status = status;
    this.code = code;
    this.hint = hint;
    this.detail = detail;
  }
}

/** A daemon path ("/sim/runs/R/replay/") relative to the page, so a console behind a path prefix works too. */
export function pagePath(path: string): string {
  return path.replace(/^\//, "");
}

/** The base every URL is resolved against: the page's own folder, so a path prefix keeps working. */
function url(path: string): string {
  return new URL(pagePath(path), document.baseURI).toString();
}

export async function request<T>(method: string, path: string, body?: unknown, timeoutMs = 15000): Promise<T> {
  const controller = new AbortController();
  const timer = setTimeout(() => controller.abort(), timeoutMs);
  let response: Response;
  try {
    const raw = body instanceof Blob;
    response = await fetch(url(path), {
      method,
      credentials: "same-origin",
      headers: body === undefined ? {} : { "Content-Type": raw ? "application/octet-stream" : "application/json" },
      body: body === undefined ? undefined : raw ? body : JSON.stringify(body),
      signal: controller.signal,
    });
  } catch (err) {
    const timedOut = controller.signal.aborted;
    throw new ApiError(
      0,
      timedOut ? "timeout" : "unreachable",
      timedOut ? `The console did not answer ${method} ${path} within ${timeoutMs / 1000} s.` : "The console daemon cannot be reached.",
      "Check that `openbricks console` is still running, then retry.",
    );
  } finally {
    clearTimeout(timer);
  }
  if (response.status === 204) return undefined as T;
  const text = await response.text();
  let payload: unknown = null;
  try {
    payload = text ? JSON.parse(text) : null;
  } catch {
    payload = null;
  }
  if (!response.ok) throw toApiError(response.status, payload, text, `${method} ${path}`);
  return payload as T;
}

export function toApiError(status: number, payload: unknown, text = "", what = "the request"): ApiError {
  if (payload && typeof payload === "object" && "error" in payload) {
    const p = payload as Record<string, unknown>;
    return new ApiError(status, String(p.error), String(p.message ?? p.error), (p.hint as string) ?? null, p);
  }
  // FastAPI's own validation shape, should a route let one through.
  if (payload && typeof payload === "object" && "detail" in payload) {
    const detail = (payload as { detail: unknown }).detail;
    const message = typeof detail === "string" ? detail : JSON.stringify(detail);
    return new ApiError(status, "http_" + status, message, null);
  }
  // Not the daemon's JSON (a proxy's page, an older daemon): say what failed, not the page's markup.
  const plain = /^\s*</.test(text) ? "" : text.slice(0, 200);
  return new ApiError(status, "http_" + status, `${what} failed with HTTP ${status}${plain ? `: ${plain}` : ""}`, status === 404 ? "This daemon may be older than the page: is `openbricks console` up to date?" : null);
}

export const api = {
  get: <T>(path: string) => request<T>("GET", path),
  post: <T>(path: string, body?: unknown, timeoutMs?: number) => request<T>("POST", path, body ?? {}, timeoutMs),
  /** A file as the request body (application/octet-stream), e.g. a firmware image. */
  upload: <T>(path: string, file: Blob, timeoutMs = 120000) => request<T>("POST", path, file, timeoutMs),
  put: <T>(path: string, body?: unknown) => request<T>("PUT", path, body ?? {}),
  del: <T>(path: string) => request<T>("DELETE", path),
};

/** The absolute WebSocket URL for an API path, on the page's own origin. */
export function wsUrl(path: string): string {
  const u = new URL(url(path));
  u.protocol = u.protocol === "https:" ? "wss:" : "ws:";
  return u.toString();
}

export function query(params: Record<string, string | number | null | undefined>): string {
  const q = new URLSearchParams();
  for (const [k, v] of Object.entries(params)) if (v !== null && v !== undefined && v !== "") q.set(k, String(v));
  const s = q.toString();
  return s ? "?" + s : "";
}
