/**
 * Completion and hover help for the hub runtime's API, from what the daemon reads out of the installed
 * `openbricks` package (`GET /api/runtime/api`): one source, so a method added to the runtime shows up
 * here without anyone keeping a list. Python has no types to go on, so a name's class is guessed the way
 * a reader would: `robot = DriveBase(...)` makes `robot.` a DriveBase; a name with no such line is
 * offered every runtime method that matches, each labelled with its class.
 */

import { api } from "./api";

export interface ApiSymbol {
  name: string;
  kind: "class" | "function" | "method" | "property" | "constant";
  signature: string;
  doc: string;
  members?: ApiSymbol[];
  bases?: string[];
}

export interface ApiModule {
  name: string;
  doc: string;
  symbols: ApiSymbol[];
}

export interface RuntimeApi {
  version: string;
  modules: ApiModule[];
}

/** One name offered: what is typed, what it is, its signature and where it comes from. */
export interface Offer {
  label: string;
  kind: ApiSymbol["kind"] | "module";
  signature: string;
  doc: string;
  /** the class or module it belongs to */
  owner: string;
}

export interface Completions {
  from: number;
  offers: Offer[];
}

export interface Hover {
  from: number;
  to: number;
  title: string;
  doc: string;
}

const IDENT = /[A-Za-z_]\w*$/;

/** The runtime's API indexed for lookups by class, by module and by bare name. */
export class ApiIndex {
  readonly modules = new Map<string, ApiModule>();
  readonly classes = new Map<string, { symbol: ApiSymbol; module: string }>();
  readonly globals = new Map<string, { symbol: ApiSymbol; module: string }>();

  constructor(readonly api: RuntimeApi) {
    for (const m of api.modules) {
      this.modules.set(m.name, m);
      for (const s of m.symbols) {
        if (!this.globals.has(s.name)) this.globals.set(s.name, { symbol: s, module: m.name });
        if (s.kind === "class" && !this.classes.has(s.name)) this.classes.set(s.name, { symbol: s, module: m.name });
      }
    }
  }

  /** A class's members with the ones it inherits from runtime classes (its own win). */
  membersOf(className: string, seen = new Set<string>()): { member: ApiSymbol; owner: string }[] {
    const found = this.classes.get(className);
    if (!found || seen.has(className)) return [];
    seen.add(className);
    const own = (found.symbol.members ?? []).map((member) => ({ member, owner: className }));
    const names = new Set(own.map((o) => o.member.name));
    const inherited = (found.symbol.bases ?? []).flatMap((b) => this.membersOf(b, seen)).filter((o) => !names.has(o.member.name) && names.add(o.member.name));
    return [...own, ...inherited];
  }

  /** Every method and property of every runtime class, for a name whose class is not known. */
  allMembers(): { member: ApiSymbol; owner: string }[] {
    return [...this.classes.keys()].flatMap((c) => (this.classes.get(c)!.symbol.members ?? []).map((member) => ({ member, owner: c })));
  }
}

/** The class `name` holds in `text`: from its last `name = Class(...)` (or `self.name = ...`) before `upTo`. */
export function classOf(index: ApiIndex, text: string, name: string, upTo = text.length): string | null {
  if (index.classes.has(name)) return name;
  const escaped = name.replace(/[.*+?^${}()|[\]\\]/g, "\\$&");
  const assign = new RegExp(`(?:^|[^\\w.])${escaped}\\s*(?::[^=\\n]*)?=\\s*([A-Za-z_]\\w*)\\s*\\(`, "gm");
  let last: string | null = null;
  for (const m of text.slice(0, upTo).matchAll(assign)) if (index.classes.has(m[1])) last = m[1];
  return last;
}

function offer(symbol: ApiSymbol, owner: string): Offer {
  return { label: symbol.name, kind: symbol.kind, signature: symbol.signature, doc: symbol.doc, owner };
}

function startsWith(label: string, prefix: string): boolean {
  return label.toLowerCase().startsWith(prefix.toLowerCase());
}

/** What to offer at `pos` in `text`, or null where the runtime has nothing to say. */
export function completeAt(index: ApiIndex, text: string, pos: number, explicit = false): Completions | null {
  const lineStart = text.lastIndexOf("\n", pos - 1) + 1;
  const line = text.slice(lineStart, pos);
  if (/#/.test(line.replace(/(["'])(?:\\.|(?!\1).)*\1/g, ""))) return null; // in a comment

  // `from openbricks.robotics import Dri`: the module's names.
  const fromImport = /^\s*from\s+([\w.]+)\s+import\s+(?:.*,\s*)?(\w*)$/.exec(line);
  if (fromImport) {
    const module = index.modules.get(fromImport[1]);
    if (!module) return null;
    const prefix = fromImport[2];
    const subs = [...index.modules.keys()]
      .filter((n) => n.startsWith(module.name + ".") && !n.slice(module.name.length + 1).includes("."))
      .map((n): Offer => ({ label: n.slice(module.name.length + 1), kind: "module", signature: "", doc: index.modules.get(n)!.doc, owner: module.name }));
    const offers = [...module.symbols.map((s) => offer(s, module.name)), ...subs].filter((o) => startsWith(o.label, prefix));
    return { from: pos - prefix.length, offers };
  }
  // `import openbricks.rob` / `from openbricks.dr`: module names.
  const moduleName = /^\s*(?:from|import)\s+([\w.]*)$/.exec(line);
  if (moduleName) {
    const typed = moduleName[1];
    const offers = [...index.modules.values()].filter((m) => m.name.startsWith(typed)).map((m): Offer => ({ label: m.name, kind: "module", signature: "", doc: m.doc, owner: "" }));
    return { from: pos - typed.length, offers };
  }
  // `robot.str` / `DriveBase.st`: the members of the class the name holds.
  const dotted = /([A-Za-z_][\w]*(?:\.[A-Za-z_]\w*)*)\.(\w*)$/.exec(line);
  if (dotted) {
    const owner = dotted[1];
    const prefix = dotted[2];
    const from = pos - prefix.length;
    const module = index.modules.get(owner);
    if (module) return { from, offers: module.symbols.map((s) => offer(s, module.name)).filter((o) => startsWith(o.label, prefix)) };
    const last = owner.split(".").pop()!;
    const cls = classOf(index, text, owner === last ? last : owner, lineStart) ?? classOf(index, text, last, lineStart);
    const members = cls ? index.membersOf(cls) : prefix || explicit ? index.allMembers() : [];
    const offers = members.filter((m) => startsWith(m.member.name, prefix)).map((m) => offer(m.member, m.owner));
    return offers.length ? { from, offers } : null;
  }
  // A bare name: the runtime's classes and functions (after two letters, or when asked with Ctrl-Space).
  const word = IDENT.exec(line);
  const prefix = word ? word[0] : "";
  if (!explicit && prefix.length < 2) return null;
  const offers = [...index.globals.values()]
    .filter((g) => (g.symbol.kind === "class" || g.symbol.kind === "function") && startsWith(g.symbol.name, prefix))
    .map((g) => offer(g.symbol, g.module));
  return offers.length ? { from: pos - prefix.length, offers } : null;
}

/** The signature and summary of the runtime name under `pos`, or null. */
export function hoverAt(index: ApiIndex, text: string, pos: number): Hover | null {
  let from = pos;
  let to = pos;
  while (from > 0 && /\w/.test(text[from - 1])) from--;
  while (to < text.length && /\w/.test(text[to])) to++;
  if (from === to) return null;
  const name = text.slice(from, to);
  const lineStart = text.lastIndexOf("\n", from - 1) + 1;
  const before = text.slice(lineStart, from);
  const owner = /([A-Za-z_]\w*)\.$/.exec(before);
  if (owner) {
    const cls = classOf(index, text, owner[1], lineStart);
    const candidates = cls ? index.membersOf(cls) : index.allMembers();
    const hit = candidates.find((m) => m.member.name === name);
    if (!hit) return null;
    const sig = hit.member.kind === "method" ? hit.member.signature : "";
    return { from, to, title: `${hit.owner}.${name}${sig}`, doc: hit.member.doc };
  }
  const g = index.globals.get(name);
  if (!g || g.symbol.kind === "constant") return null;
  return { from, to, title: `${g.symbol.kind === "class" ? "class " : ""}${name}${g.symbol.signature}`, doc: [g.symbol.doc, `(${g.module})`].filter(Boolean).join(" ") };
}

let loading: Promise<ApiIndex | null> | null = null;

/** The runtime's API from the daemon, fetched once; null (and tried again next time) if it failed. */
export function runtimeIndex(): Promise<ApiIndex | null> {
  loading ??= api.get<RuntimeApi>("/api/runtime/api").then(
    (r) => new ApiIndex(r),
    () => {
      loading = null;
      return null;
    },
  );
  return loading;
}
