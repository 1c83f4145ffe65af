/**
 * Starts the page's connection to the daemon: the state from REST, then the event stream, whose gaps,
 * resyncs and restarts all lead back to a refetch. A clock tick drives run timers and the match timer.
 */

import { query, wsUrl } from "./api";
import { consoleModel as model } from "./console.svelte";
import { EventStream } from "./events";

// The stream in frames of every event ready, one a display frame: ten hubs printing 100 lines a second
// each are a thousand messages a second, and the page pays for each message it is handed.
const BATCH_MS = 16;

export function startSession(): () => void {
  const stream = new EventStream({
    url: (since, boot) => wsUrl(`/api/events${query({ since, boot, batch_ms: BATCH_MS })}`),
    handlers: {
      event: (e) => model.applyEvent(e),
      refetch: (r) => void model.refetch(r),
      notice: (m) => model.notify("info", m),
      state: (s, detail) => {
        model.stream = s;
        model.streamDetail = detail ?? null;
        if (s === "refused") model.notify("error", `The console refused this page's session: ${detail}`, "Open the URL with the token that `openbricks console` printed.");
      },
    },
  });
  void model.refetch().then(() => stream.start());
  const tick = setInterval(() => (model.now = Date.now()), 250);
  return () => {
    stream.stop();
    clearInterval(tick);
  };
}
