/**
 * The console's keys: F5 run, F6 stop, Esc STOP ALL, Ctrl-S save. The page on screen supplies what run and
 * save mean there (the editor runs its program; elsewhere run starts the selected hubs' staged programs).
 *
 * Esc is STOP ALL only while nobody is typing: in a text field, a list box, the code editor or a dialog it
 * keeps its usual meaning (close the search box, the completion list, the dialog), so a student closing a
 * search never stops every robot of the team. There, and anywhere else, Ctrl+. (Cmd+. on a Mac, the
 * "cancel" chord) is STOP ALL: a key nobody presses by accident while typing.
 */

export type KeyAction = "run" | "stop" | "stopAll" | "save";

/** The chord that stops all hubs wherever the focus is, as the page names it. */
export const STOP_ALL_CHORD = "Ctrl+.";

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

/** The part of a focused element this module looks at (tests pass plain objects). */
export interface FocusTarget {
  tagName?: string;
  type?: string;
  isContentEditable?: boolean;
  closest?: (selector: string) => unknown;
}

// Inputs that take no typing: Esc on them is still STOP ALL.
const NOT_TYPED = new Set(["checkbox", "radio", "button", "submit", "reset", "range", "color", "file", "image"]);

/** Whether Esc belongs to what has the focus: a text field, textarea, select, the code editor or a dialog. */
export function isTyping(target: FocusTarget | null | undefined): boolean {
  if (!target || typeof target.tagName !== "string") return false;
  const tag = target.tagName.toLowerCase();
  if (tag === "textarea" || tag === "select") return true;
  if (tag === "input") return !NOT_TYPED.has((target.type ?? "text").toLowerCase());
  if (target.isContentEditable) return true;
  return Boolean(target.closest?.(".cm-editor, [contenteditable=''], [contenteditable='true'], dialog[open], [role='dialog']"));
}

type KeyLike = Pick<KeyboardEvent, "key" | "ctrlKey" | "metaKey" | "altKey" | "shiftKey">;

export function actionFor(e: KeyLike, target: FocusTarget | null = null): KeyAction | null {
  if (e.key === "Escape") return e.ctrlKey || e.metaKey || e.altKey || e.shiftKey || isTyping(target) ? null : "stopAll";
  if (e.key === "." && (e.ctrlKey || e.metaKey) && !e.altKey) return "stopAll";
  if (e.key === "F5" && !e.ctrlKey && !e.metaKey) return "run";
  if (e.key === "F6") return "stop";
  if ((e.ctrlKey || e.metaKey) && !e.altKey && e.key.toLowerCase() === "s") return "save";
  return null;
}

export function handleKey(e: KeyboardEvent): void {
  const action = actionFor(e, e.target as FocusTarget | null);
  if (!action) return;
  const fn = handlers.get(action) ?? fallback.get(action);
  if (!fn) return;
  e.preventDefault();
  fn();
}
