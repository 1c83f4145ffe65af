/**
 * The editor's completion and hover help for the hub runtime (the lookups live in completion.ts): added
 * as language data, so Python's own completions (keywords, names in the file) keep coming too.
 */

import { autocompletion, type Completion, type CompletionContext, type CompletionResult } from "@codemirror/autocomplete";
import { EditorState, type Extension } from "@codemirror/state";
import { EditorView, hoverTooltip } from "@codemirror/view";
import { completeAt, hoverAt, runtimeIndex, type Offer } from "./completion";

const TYPES: Record<Offer["kind"], string> = {
  class: "class",
  function: "function",
  method: "method",
  property: "property",
  constant: "constant",
  module: "namespace",
};

function helpBox(title: string, doc: string): HTMLElement {
  const box = document.createElement("div");
  box.className = "cm-runtime-help";
  const head = document.createElement("div");
  head.className = "cm-runtime-sig";
  head.textContent = title;
  box.append(head);
  if (doc) {
    const body = document.createElement("div");
    body.className = "cm-runtime-doc";
    body.textContent = doc;
    box.append(body);
  }
  return box;
}

async function runtimeCompletions(context: CompletionContext): Promise<CompletionResult | null> {
  const index = await runtimeIndex();
  if (!index) return null;
  const text = context.state.doc.toString();
  const found = completeAt(index, text, context.pos, context.explicit);
  if (!found || !found.offers.length) return null;
  const options: Completion[] = found.offers.map((o) => ({
    label: o.label,
    type: TYPES[o.kind],
    detail: o.kind === "method" || o.kind === "function" || o.kind === "class" ? o.signature : o.kind,
    info: () => helpBox(`${o.owner ? o.owner + "." : ""}${o.label}${o.kind === "property" ? "" : o.signature}`, o.doc),
    boost: o.kind === "method" || o.kind === "class" ? 1 : 0,
  }));
  return { from: found.from, options, validFor: /^\w*$/ };
}

const runtimeHover = hoverTooltip(async (view, pos) => {
  const index = await runtimeIndex();
  if (!index) return null;
  const hit = hoverAt(index, view.state.doc.toString(), pos);
  if (!hit) return null;
  return { pos: hit.from, end: hit.to, above: true, create: () => ({ dom: helpBox(hit.title, hit.doc) }) };
});

const helpTheme = EditorView.theme({
  ".cm-runtime-help": { padding: "4px 8px", maxWidth: "520px" },
  ".cm-runtime-sig": { fontFamily: "var(--mono)", color: "#e6edf3", whiteSpace: "pre-wrap" },
  ".cm-runtime-doc": { marginTop: "4px", color: "#9da7b3", whiteSpace: "pre-wrap" },
});

/** Completion (as you type, or Ctrl-Space) and hover help for the runtime's classes and methods. */
export function runtimeHelp(): Extension[] {
  return [
    autocompletion({ activateOnTyping: true, icons: true }),
    EditorState.languageData.of(() => [{ autocomplete: runtimeCompletions }]),
    runtimeHover,
    helpTheme,
  ];
}
