/**
 * The client side of the daemon's one event WebSocket.
 *
 * The daemon numbers every event with `seq`, strictly increasing for its lifetime. A client that reconnects
 * asks to resume after the last `seq` it handled and the daemon replays what it missed; if some of it is
 * gone the daemon says so with a `gap` event, and a client that fell too far behind gets a `resync`. This
 * module keeps that bookkeeping in one place so the pages only see: events in order and exactly once, and
 * a `refetch` call whenever what they show may be incomplete (a gap). Messages meant for this client alone
 * (`hello`, `gap`, `resync`, replies) carry `"seq": null` and never move the resume point except a gap's
 * end. Nothing is dropped silently.
 */

export interface Envelope {
  seq: number;
  type: string;
  hub: string | null;
  run: string | null;
  ts: number;
  data: Record<string, unknown>;
}

/** The part of the browser's WebSocket this client uses (tests pass their own). */
export interface StreamSocket {
  onopen: ((ev: unknown) => void) | null;
  onmessage: ((ev: { data: unknown }) => void) | null;
  onclose: ((ev: { code: number; reason: string }) => void) | null;
  onerror: ((ev: unknown) => void) | null;
  send(data: string): void;
  close(code?: number, reason?: string): void;
}

export type StreamState = "connecting" | "live" | "reconnecting" | "refused" | "closed";

/** Why what the page shows may be incomplete; the page reloads it from the REST API. */
export interface Refetch {
  reason: "gap";
  message: string;
  /** For a gap: the first and last missing seq, when known. */
  from?: number;
  to?: number;
  /** nothing the page shows was lost (only events the daemon never keeps): reload without a warning */
  quiet?: boolean;
}

export interface StreamHandlers {
  event(e: Envelope): void;
  refetch(r: Refetch): void;
  /** Something the user may want to know that needs no action (a resync, a daemon restart). */
  notice?(message: string): void;
  /** Other messages for this client (replies to commands). */
  control?(e: Envelope): void;
  state?(s: StreamState, detail?: string): void;
}

export interface StreamOptions {
  /** The WebSocket URL to open, resuming after `since` (null: from now) of daemon lifetime `boot`. */
  url(since: number | null, boot: string | null): string;
  open?: (url: string) => StreamSocket;
  handlers: StreamHandlers;
  /** Reconnect delays in ms, the last one repeated. */
  backoffMs?: number[];
  /** Close codes after which reconnecting cannot help (auth refused): the stream stops and says why. */
  fatalCodes?: number[];
  setTimer?: (fn: () => void, ms: number) => unknown;
  clearTimer?: (t: unknown) => void;
}

const DEFAULT_BACKOFF = [250, 500, 1000, 2000, 5000];

export class EventStream {
  /** The last seq handled; a reconnect resumes after it. */
  lastSeq: number | null = null;
  /** The daemon instance the seqs belong to (from its `hello`), to notice a restart. */
  boot: string | null = null;
  state: StreamState = "closed";
  reconnects = 0;
  resyncs = 0;
  malformed = 0;

  private socket: StreamSocket | null = null;
  private attempt = 0;
  private timer: unknown = null;
  private stopped = true;

  constructor(private readonly opts: StreamOptions) {}

  start(): void {
    if (!this.stopped) return;
    this.stopped = false;
    this.connect();
  }

  stop(): void {
    this.stopped = true;
    if (this.timer !== null) (this.opts.clearTimer ?? clearTimeout)(this.timer as ReturnType<typeof setTimeout>);
    this.timer = null;
    const s = this.socket;
    this.socket = null;
    if (s) {
      s.onclose = null;
      s.close(1000, "page closed");
    }
    this.setState("closed");
  }

  /** Send a command over the stream (subscriptions, pings); false when not connected. */
  send(message: Record<string, unknown>): boolean {
    if (!this.socket || this.state !== "live") return false;
    this.socket.send(JSON.stringify(message));
    return true;
  }

  private connect(): void {
    const open = this.opts.open ?? ((u: string) => new WebSocket(u) as unknown as StreamSocket);
    this.setState(this.reconnects === 0 && this.lastSeq === null ? "connecting" : "reconnecting");
    const socket = open(this.opts.url(this.lastSeq, this.boot));
    this.socket = socket;
    socket.onopen = () => {
      if (this.socket !== socket) return;
      this.attempt = 0;
      this.setState("live");
    };
    socket.onmessage = (ev) => {
      if (this.socket !== socket) return;
      this.receive(ev.data);
    };
    socket.onerror = () => {
      /* the close that follows schedules the retry */
    };
    socket.onclose = (ev) => {
      if (this.socket !== socket) return;
      this.socket = null;
      if (this.stopped) return;
      if ((this.opts.fatalCodes ?? [4401, 4403, 1008]).includes(ev.code)) {
        this.stopped = true;
        this.setState("refused", ev.reason || `closed with code ${ev.code}`);
        return;
      }
      this.scheduleReconnect();
    };
  }

  private scheduleReconnect(): void {
    const delays = this.opts.backoffMs ?? DEFAULT_BACKOFF;
    const delay = delays[Math.min(this.attempt, delays.length - 1)];
    this.attempt += 1;
    this.reconnects += 1;
    this.setState("reconnecting");
    this.timer = (this.opts.setTimer ?? setTimeout)(() => {
      this.timer = null;
      if (!this.stopped) this.connect();
    }, delay);
  }

  /**
   * One frame off the wire: an envelope, or (asked for with `batch_ms`) an array of them in order. Each
   * is parsed, ordered, deduplicated and dispatched. Public for tests and benchmarks.
   */
  receive(raw: unknown): void {
    let parsed: unknown;
    try {
      parsed = typeof raw === "string" ? JSON.parse(raw) : raw;
    } catch {
      this.malformed += 1;
      return;
    }
    if (Array.isArray(parsed)) for (const e of parsed) this.handle(e as Envelope);
    else this.handle(parsed as Envelope);
  }

  private handle(e: Envelope): void {
    if (!e || typeof e !== "object" || typeof e.type !== "string") {
      this.malformed += 1;
      return;
    }
    if (e.seq === null || e.seq === undefined) {
      this.control(e);
      return;
    }
    if (typeof e.seq !== "number") {
      this.malformed += 1;
      return;
    }
    if (this.lastSeq !== null && e.seq <= this.lastSeq) return; // replay overlapping what we had
    if (this.lastSeq !== null && e.seq > this.lastSeq + 1) {
      // Seqs are contiguous: a jump the daemon did not announce with a gap is still a gap.
      this.refetch({
        reason: "gap",
        message: `Events ${this.lastSeq + 1}–${e.seq - 1} were not received; reloading.`,
        from: this.lastSeq + 1,
        to: e.seq - 1,
      });
    }
    this.lastSeq = e.seq;
    this.dispatch(e);
  }

  /** Messages for this client only, outside the numbered stream (`"seq": null`). */
  private control(e: Envelope): void {
    const d = e.data ?? {};
    switch (e.type) {
      case "hello": {
        const boot = typeof d.boot === "string" ? d.boot : null;
        if (this.boot !== null && boot !== null && boot !== this.boot) this.opts.handlers.notice?.("The console daemon restarted; resuming from its store.");
        this.boot = boot;
        const from = typeof d.resume_from === "number" ? d.resume_from : typeof d.seq === "number" ? d.seq : null;
        if (this.lastSeq === null && from !== null) this.lastSeq = from;
        break;
      }
      case "gap": {
        const to = typeof d.to_seq === "number" ? d.to_seq : null;
        if (to !== null) this.lastSeq = Math.max(this.lastSeq ?? to, to);
        this.refetch({
          reason: "gap",
          message: String(d.message ?? d.reason ?? "Some events are no longer available; reloading from the store."),
          from: typeof d.from_seq === "number" ? d.from_seq : undefined,
          to: to ?? undefined,
          // Events the daemon never keeps (progress ticks) are no loss worth a warning.
          quiet: d.reason === "not_kept",
        });
        break;
      }
      case "resync":
        // The daemon catches this client up from its ring and store right after; events follow in order.
        this.resyncs += 1;
        this.opts.handlers.notice?.(String(d.message ?? "This page fell behind the live stream; catching up from the store."));
        break;
      default:
        this.opts.handlers.control?.(e);
    }
  }

  private dispatch(e: Envelope): void {
    try {
      this.opts.handlers.event(e);
    } catch (err) {
      console.error("event handler failed", e.type, err);
    }
  }

  private refetch(r: Refetch): void {
    try {
      this.opts.handlers.refetch(r);
    } catch (err) {
      console.error("refetch handler failed", err);
    }
  }

  private setState(s: StreamState, detail?: string): void {
    this.state = s;
    this.opts.handlers.state?.(s, detail);
  }
}
