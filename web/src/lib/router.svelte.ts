/**
 * Pages live in the URL's hash (`#/editor`), so the daemon serves one static `index.html` and a reload or a
 * shared link opens the same page; query parameters after the page name carry what it shows (`#/history?run=ID`).
 */

export const PAGES = [
  { id: "dashboard", label: "Dashboard", key: "1" },
  { id: "editor", label: "Editor", key: "2" },
  { id: "output", label: "Output", key: "3" },
  { id: "history", label: "History", key: "4" },
  { id: "telemetry", label: "Telemetry", key: "5" },
  { id: "sim", label: "Simulator", key: "6" },
  { id: "flash", label: "Flash", key: "7" },
  { id: "servo", label: "Servo-ID", key: "8" },
  { id: "audit", label: "Audit", key: "9" },
  { id: "share", label: "Share", key: "0" },
] as const;

export type PageId = (typeof PAGES)[number]["id"];

function parse(hash: string): { page: PageId; params: URLSearchParams } {
  const [path, q] = hash.replace(/^#\/?/, "").split("?");
  const page = (PAGES.find((p) => p.id === path)?.id ?? "dashboard") as PageId;
  return { page, params: new URLSearchParams(q ?? "") };
}

class Router {
  page = $state<PageId>("dashboard");
  params = $state(new URLSearchParams());

  constructor() {
    if (typeof window === "undefined") return;
    const apply = () => {
      const r = parse(window.location.hash);
      this.page = r.page;
      this.params = r.params;
    };
    apply();
    window.addEventListener("hashchange", apply);
  }

  go(page: PageId, params: Record<string, string> = {}): void {
    const q = new URLSearchParams(params).toString();
    window.location.hash = `#/${page}${q ? "?" + q : ""}`;
  }
}

export const router = new Router();
