/**
 * The editor's unsaved text, kept in the console's store as it is typed, so a page switch, a reload or a
 * closed laptop never loses an edit: the daemon holds one draft per program name until Save makes a
 * version of it (which clears it). The keeper writes half a second after the last key, at once when the
 * user leaves the program or the page, and says whether something typed has not reached the daemon yet
 * (the page then asks before it unloads).
 */

import { ApiError, api } from "./api";

const enc = encodeURIComponent;

export interface Draft {
  name: string;
  source: string;
  /** the stored version the edit started from; null for a program never saved */
  base_version: number | null;
  who: string | null;
  updated_ms: number;
}

export type DraftInfo = Omit<Draft, "source">;

/** The program's draft, or null when it has none. */
export async function loadDraft(name: string): Promise<Draft | null> {
  try {
    return await api.get<Draft>(`/api/programs/${enc(name)}/draft`);
  } catch (err) {
    if (err instanceof ApiError && err.status === 404) return null;
    throw err;
  }
}

export async function listDrafts(): Promise<DraftInfo[]> {
  return api.get<DraftInfo[]>("/api/drafts");
}

export async function putDraft(name: string, source: string, baseVersion: number | null, keepalive = false): Promise<void> {
  const path = `/api/programs/${enc(name)}/draft`;
  const body = { source, base_version: baseVersion };
  if (!keepalive) {
    await api.put(path, body);
    return;
  }
  // Leaving the page: a request the browser finishes after the page is gone.
  const r = await fetch(new URL(path.slice(1), document.baseURI), {
    method: "PUT",
    credentials: "same-origin",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(body),
    keepalive: true,
  });
  if (!r.ok) throw new ApiError(r.status, `http_${r.status}`, `Keeping the draft of ${name} failed with HTTP ${r.status}`, null);
}

export async function discardDraft(name: string): Promise<void> {
  return api.del(`/api/programs/${enc(name)}/draft`);
}

export const DRAFT_DELAY_MS = 500;

interface Pending {
  name: string;
  source: string;
  base: number | null;
}

type Send = (name: string, source: string, base: number | null, keepalive: boolean) => Promise<void>;

/** Debounced draft writes for one editor; at most one write in flight, the newest text always last. */
export class DraftKeeper {
  private pending: Pending | null = null;
  private timer: ReturnType<typeof setTimeout> | null = null;
  private inFlight: Promise<void> | null = null;
  /** The last text the daemon confirmed, per name (nothing to write when it is unchanged). */
  private confirmed = new Map<string, string>();

  constructor(
    private readonly send: Send = putDraft,
    private readonly onError: (err: unknown, name: string) => void = () => {},
    private readonly delayMs = DRAFT_DELAY_MS,
  ) {}

  /** True while typed text has not reached the daemon (waiting for the pause, or on its way). */
  get unsaved(): boolean {
    return this.pending !== null || this.inFlight !== null;
  }

  /** True while typed text waits for the pause in typing (not yet sent). */
  get waiting(): boolean {
    return this.pending !== null;
  }

  /** `source` is what the daemon already has for `name` (the stored version, or the restored draft). */
  known(name: string, source: string): void {
    this.confirmed.set(name, source);
  }

  /** The editor's text changed: write it after a pause in typing. */
  edited(name: string, source: string, base: number | null): void {
    if (this.pending && this.pending.name !== name) void this.flush();
    if (this.confirmed.get(name) === source && !this.inFlight) {
      this.cancel();
      return;
    }
    this.pending = { name, source, base };
    if (this.timer) clearTimeout(this.timer);
    this.timer = setTimeout(() => void this.flush(), this.delayMs);
  }

  /** Write what waits now (leaving the program or the page); `keepalive` outlives an unloading page. */
  async flush(keepalive = false): Promise<void> {
    if (this.timer) clearTimeout(this.timer);
    this.timer = null;
    const p = this.pending;
    if (!p) return this.inFlight ?? undefined;
    this.pending = null;
    const before = this.inFlight;
    const write = (async () => {
      if (before) await before.catch(() => {});
      try {
        await this.send(p.name, p.source, p.base, keepalive);
        this.confirmed.set(p.name, p.source);
      } catch (err) {
        if (!this.pending) this.pending = p; // still not kept: the next edit or flush tries again
        this.onError(err, p.name);
      }
    })();
    this.inFlight = write;
    try {
      await write;
    } finally {
      if (this.inFlight === write) this.inFlight = null;
    }
  }

  /** Resolves when no write is on its way (before a save, so no late draft outlives it). */
  async idle(): Promise<void> {
    while (this.inFlight) await this.inFlight.catch(() => {});
  }

  /** Forget what waits (the program was saved: the daemon cleared its draft). */
  cancel(name?: string): void {
    if (name !== undefined && this.pending && this.pending.name !== name) return;
    if (this.timer) clearTimeout(this.timer);
    this.timer = null;
    this.pending = null;
  }
}
