"""The one pacer: simulated time held to the wall clock at a speed, with pause, and a chance per frame
for someone watching to look at the world.

A program run advances simulated time itself (its sleeps, bus transfers and Python calls move the
SimClock), so nothing outside can step the physics; pacing rides along instead. The Pacer is a timer
on the simulation's own clock: every time it fires, the physics has just reached that instant, so it
hands `on_frame` (the 3D viewer) a look and then holds the program's thread until the wall clock has
caught up with simulated time at the chosen speed (or for as long as the run is paused). The
physics between two firings still runs as one native call, so pacing costs a few microseconds per
frame, not per step.

It paces `sim run --speed`, the viewer (whose page changes speed and pauses mid-run) and a virtual
hub (real time at its prompt, its own speed while a program runs). Unpaced headless runs have no
pacer at all: nothing then depends on the wall clock, and a job gives the same result every time.

Paced, the timer fires about `frame_hz` times per wall-clock second: at 0.25x every 4 ms of
simulated time, at 8x every 133 ms. As fast as possible, it fires every few tens of simulated ms
(so a pause or a new speed lands promptly) and hands over a frame only when a frame period of wall
time has passed. Time the program spent not advancing the clock (a hub waiting at its prompt) is not
made up later: behind by more than MAX_LAG_S, pacing starts over from the present.
"""

from __future__ import annotations

import threading
import time

DEFAULT_FRAME_HZ = 60
# Behind the wall clock by more than this (a slow machine at 8x), the pacer stops trying to catch up
# rather than racing through the backlog once the machine has time again.
MAX_LAG_S = 0.1
# As fast as possible: bounds on the simulated time between firings. The upper bound is how late a
# pause or a new speed can land, in simulated time; frames are still handed over only ~frame_hz times
# a second.
_MIN_FREE_RUN_MS = 5
_MAX_FREE_RUN_MS = 50
# A firing this close to a frame period after the last frame still makes one (paced firings jitter).
_FRAME_SLACK = 0.8


class Pacer:
    """Holds simulated time to the wall clock; hands `on_frame()` a look ~frame_hz times a second.

    speed is a real-time factor (1.0 = real time) or None (as fast as possible). `speed` and
    `paused` may be changed from any thread; a change takes effect at once, even mid-wait.
    `on_behind(seconds)` hears of the wall time the simulation could not keep up with, whenever
    pacing gives up on it and starts over from the present.
    While `wakeup` (an Event) is set nothing is held back: an interrupt is on its way to the
    program; call nudge() when it is set to cut a wait short.
    """

    def __init__(
        self,
        clock,
        on_frame=None,
        speed: float | None = 1.0,
        frame_hz: float = DEFAULT_FRAME_HZ,
        wakeup: threading.Event | None = None,
        on_behind=None,
    ):
        if frame_hz <= 0:
            raise ValueError(f"frame_hz must be positive, not {frame_hz!r}")
        self._clock = clock
        self._on_frame = on_frame
        self._wakeup = wakeup
        self._on_behind = on_behind
        self._frame_hz = float(frame_hz)
        self._speed = _checked_speed(speed)
        self._paused = False
        self._running = False
        self._handle = None
        self._changed = threading.Event()  # set on any control change: wakes a waiting pacer
        self._anchor = None  # (wall_s, sim_us): real-time pacing is measured from here
        self._last_frame_s = None  # wall time of the latest on_frame()
        self._last_tick = None  # (wall_s, sim_us) at the latest firing, for the free-running rate
        self._rate_from = None  # ... and at the one before it

    # --- controls (any thread) ----------------------------------------------------------------

    @property
    def speed(self) -> float | None:
        return self._speed

    @speed.setter
    def speed(self, value: float | None) -> None:
        self._speed = _checked_speed(value)
        self._anchor = None  # pace the new speed from now, not from the start of the run
        self._changed.set()

    @property
    def paused(self) -> bool:
        return self._paused

    @paused.setter
    def paused(self, value: bool) -> None:
        self._paused = bool(value)
        self._anchor = None
        self._changed.set()

    def start(self) -> None:
        """Begin pacing from the clock's current instant."""
        if self._running:
            return
        self._running = True
        self._anchor = None
        self._last_tick = self._rate_from = self._last_frame_s = None
        self._schedule()

    def nudge(self) -> None:
        """Wake a held program at once (any thread); pacing goes on from the present."""
        self._anchor = None
        self._changed.set()

    def stop(self) -> None:
        """Stop holding time back (any thread): a paused or waiting run goes on at once."""
        self._running = False
        handle, self._handle = self._handle, None
        if handle is not None:
            handle.cancel()
        self._changed.set()

    # --- on the simulation's thread -------------------------------------------------------------

    def _schedule(self) -> None:
        self._handle = self._clock.schedule(self._tick, self._next_delay_ms() * 1000)

    def _tick(self) -> None:
        if not self._running:
            return
        now = time.perf_counter()
        previous, self._last_tick = self._last_tick, (now, self._clock.now_us())
        try:
            if self._on_frame is not None and (
                self._last_frame_s is None or now - self._last_frame_s >= _FRAME_SLACK / self._frame_hz
            ):
                self._last_frame_s = now
                self._on_frame()
            self._hold()
        finally:
            # An interrupt raised in the program's thread while it is held here (a host's Ctrl-C
            # reaching a virtual hub) goes on to the program, but pacing must outlive it: a pacer
            # that stopped rescheduling would leave the hub running flat out from then on.
            if self._running:
                self._rate_from = previous
                self._schedule()

    def _hold(self) -> None:
        """Wait while paused, or until the wall clock catches up with simulated time."""
        while self._running:
            self._changed.clear()  # cleared before the state is read: a change after this still wakes us
            if self._wakeup is not None and self._wakeup.is_set():
                self._anchor = None
                return
            if self._paused:
                self._changed.wait()
                continue
            speed = self._speed
            if speed is None:
                return
            now = time.perf_counter()
            sim_us = self._clock.now_us()
            anchor = self._anchor
            if anchor is None:
                self._anchor = (now, sim_us)
                return
            due = anchor[0] + (sim_us - anchor[1]) / 1e6 / speed
            if now - due > MAX_LAG_S:
                self._anchor = (now, sim_us)
                if self._on_behind is not None:
                    self._on_behind(now - due)
                return
            if due <= now:
                return
            self._changed.wait(due - now)
            if not self._changed.is_set():
                return

    def _next_delay_ms(self) -> int:
        """Simulated ms until the next frame: about one wall-clock frame at the current speed."""
        speed = self._speed
        if speed is not None:
            return max(1, round(speed * 1000.0 / self._frame_hz))
        # The rate between the last two firings (a pause or a slower speed in between only makes the
        # next interval short; the one after is right again).
        earlier, last = self._rate_from, self._last_tick
        if earlier is None or last is None:
            return _MIN_FREE_RUN_MS
        wall_s = last[0] - earlier[0]
        sim_ms = (last[1] - earlier[1]) / 1000.0
        if wall_s <= 0 or sim_ms <= 0:
            return _MIN_FREE_RUN_MS
        rate = sim_ms / wall_s  # simulated ms per wall-clock second
        return int(min(_MAX_FREE_RUN_MS, max(_MIN_FREE_RUN_MS, rate / self._frame_hz)))


def _checked_speed(speed):
    if speed is None:
        return None
    speed = float(speed)
    if not speed > 0:
        raise ValueError(
            f"speed must be a positive real-time factor or None (as fast as possible), not {speed}"
        )
    return speed
