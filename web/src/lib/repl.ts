/**
 * A hub's REPL through the console (`POST /api/hubs/{hub}/repl`): one entry is one operation on the hub,
 * so a refusal (the hub is busy with a run, the page is read-only) is shown in the transcript as the
 * answer to that entry, in the daemon's words.
 */

import { ApiError, api } from "./api";

export interface ReplEntry {
  hub: string;
  code: string;
  output: string;
  /** the hub's traceback, or why the console refused the entry */
  error: string | null;
  pending: boolean;
}

/** An entry may loop until stopped: the page waits this long before it gives up on the answer. */
const REPL_WAIT_MS = 11 * 60 * 1000;

export async function replEval(hubId: string, code: string): Promise<{ output: string; error: string | null }> {
  try {
    const r = await api.post<{ output: string; error: string | null }>(`/api/hubs/${encodeURIComponent(hubId)}/repl`, { code }, REPL_WAIT_MS);
    return { output: r.output, error: r.error };
  } catch (err) {
    if (err instanceof ApiError) return { output: "", error: err.hint ? `${err.message} (${err.hint})` : err.message };
    return { output: "", error: String(err) };
  }
}
