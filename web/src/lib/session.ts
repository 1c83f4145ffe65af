/**
 * Starts the page's connection to the daemon: the state from REST, then the event stream, whose gaps,
 * resyncs and restarts all lead back to a refetch. A clock tick drives run timers and the match timer.
 *
 * A lost stream is retried quickly (at most a second apart), so a console that comes back is live on the
 * page within about a second; once it is back, everything is reloaded, since what changed meanwhile was
 * not seen. A console that answers but no longer knows this page's sign-in (restarted with a new token)
 * is said as such instead of retried forever.
 */

import { ApiError, api, query, wsUrl } from "./api";
import { consoleModel as model } from "./console.svelte";
import { EventStream, type StreamState } from "./events";

// The stream in frames of every event ready, one a display frame: ten hubs printing 100 lines a second
// each are a thousand messages a second, and the page pays for each message it is handed.
const BATCH_MS = 16;
/** Reconnect delays: short and capped small, the console is on this computer or this room's network. */
export const RECONNECT_MS = [200, 400, 700, 1000];

export function startSession(): () => void {
  let previous: StreamState = "connecting";
  let probing = false;
  const stream = new EventStream({
    url: (since, boot) => wsUrl(`/api/events${query({ since, boot, batch_ms: BATCH_MS })}`),
    backoffMs: RECONNECT_MS,
    handlers: {
      event: (e) => model.applyEvent(e),
      refetch: (r) => void model.refetch(r),
      notice: (m) => model.notify("info", m),
      state: (s, detail) => {
        const was = previous;
        previous = s;
        model.stream = s;
        model.streamDetail = detail ?? null;
        if (s === "refused") model.notify("error", `The console refused this page's session: ${detail}`, "Open the address the console printed when it started.");
        if (s === "live" && was === "reconnecting") void model.refetch();
        if (s === "reconnecting" && !probing) void probe();
      },
    },
  });

  /** While reconnecting: does the console answer, and does it still know us? */
  async function probe(): Promise<void> {
    probing = true;
    try {
      await api.get("/api/auth/me");
    } catch (err) {
      if (err instanceof ApiError && err.status === 401) {
        stream.stop();
        model.stream = "refused";
        model.streamDetail = "the console restarted with a new printed address";
      }
    } finally {
      probing = false;
    }
  }

  void model.refetch().then(() => stream.start());
  const tick = setInterval(() => (model.now = Date.now()), 250);
  return () => {
    stream.stop();
    clearInterval(tick);
  };
}
