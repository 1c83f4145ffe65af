/**
 * The console's keys: F5 run, F6 stop, Esc STOP ALL, Ctrl-S save. The page on screen supplies what run and
 * save mean there (the editor runs its program; elsewhere run starts the selected hubs' staged programs);
 * Esc always means STOP ALL, wherever the focus is, because it is the safety key.
 */

export type KeyAction = "run" | "stop" | "stopAll" | "save";

const handlers = new Map<KeyAction, () => void>();
const fallback = new Map<KeyAction, () => void>();

/** The current page's handler for an action; returns the function that removes it. */
export function onKey(action: KeyAction, fn: () => void): () => void {
  handlers.set(action, fn);
  return () => {
    if (handlers.get(action) === fn) handlers.delete(action);
  };
}

/** What an action does when the page on screen gives it no meaning of its own. */
export function defaultKey(action: KeyAction, fn: () => void): void {
  fallback.set(action, fn);
}

export function actionFor(e: Pick<KeyboardEvent, "key" | "ctrlKey" | "metaKey" | "altKey" | "shiftKey">): KeyAction | null {
  if (e.key === "Escape") return "stopAll";
  if (e.key === "F5" && !e.ctrlKey && !e.metaKey) return "run";
  if (e.key === "F6") return "stop";
  if ((e.ctrlKey || e.metaKey) && !e.altKey && e.key.toLowerCase() === "s") return "save";
  return null;
}

export function handleKey(e: KeyboardEvent): void {
  const action = actionFor(e);
  if (!action) return;
  const fn = handlers.get(action) ?? fallback.get(action);
  if (!fn) return;
  e.preventDefault();
  fn();
}
