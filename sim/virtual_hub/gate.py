"""Ctrl-C for the hub's main thread: raised in hub code while it runs, never in the hub's own loop.

MicroPython arms its interrupt character only while code executes (pyexec.c); a Ctrl-C that
arrives at the prompt is ordinary REPL input. The virtual hub runs hub code on the main thread and
reads the link on another, so the reader asks this gate to interrupt, and the gate raises the
exception in the main thread only between open() and close(). An interrupt that lands as the code
finishes is withdrawn at close(), so it can never surface in the hub's loop; one that arrives after
the code was requested but before it started is raised as it starts.

The exception is delivered with PyThreadState_SetAsyncExc, which (unlike a signal) can be taken
back, and reaches pure-Python loops and everything that returns to the interpreter; a long native
call (a MuJoCo step) finishes first, as a C function on the hub finishes before mp_handle_pending.
"""

import ctypes
import threading

_set_async_exc = ctypes.PYFUNCTYPE(ctypes.c_int, ctypes.c_ulong, ctypes.py_object)(
    ("PyThreadState_SetAsyncExc", ctypes.pythonapi)
)


class _Withdrawn(BaseException):
    """Stands in for an interrupt being withdrawn, and is taken by the gate itself (close())."""


class InterruptGate:
    """Interrupts for one thread (by default the main thread, where hub code runs)."""

    def __init__(self, thread_id=None):
        self._thread_id = thread_id if thread_id is not None else threading.main_thread().ident
        self._lock = threading.Lock()
        self._open = False
        self._pending = None
        self._waiters = []
        # Set while an interrupt is on its way, so hub code blocked in a wait (pacing the clock,
        # reading stdin) returns at once and the exception is raised.
        self.wakeup = threading.Event()

    def add_waiter(self, callback):
        """Call `callback()` on every delivered interrupt (to wake a condition variable)."""
        self._waiters.append(callback)

    @property
    def is_open(self):
        return self._open

    def open(self):
        """Hub code starts now (call from the hub code's thread); raises an interrupt already due."""
        with self._lock:
            self._open = True
            pending, self._pending = self._pending, None
        if pending is not None:
            raise pending()

    def close(self):
        """Hub code ended: no interrupt may reach this thread any more, including one in flight.

        The interrupt in flight is withdrawn by replacing it with one of our own and taking that
        here (a plain PyThreadState_SetAsyncExc(id, NULL) leaves the interpreter's "async
        exception pending" signal set for good, and CPython 3.11, while a profile function such as
        the simulator's Python-time charge is installed, then loops forever at the entry of the
        next Python function). Retries if the exception lands elsewhere inside this very call, so
        on return the thread is clean whatever the timing.
        """
        if threading.get_ident() != self._thread_id:
            raise RuntimeError("InterruptGate.close() is for the thread that runs the hub code")
        while True:
            try:
                with self._lock:
                    self._open = False
                    _set_async_exc(self._thread_id, _Withdrawn)
                    try:
                        while True:  # the check at this backward jump raises it
                            pass
                    except _Withdrawn:
                        pass
                    self.wakeup.clear()
                return
            except _Withdrawn:  # taken just outside the loop: the signal is consumed all the same
                with self._lock:
                    self.wakeup.clear()
                return
            except BaseException:  # the interrupt being withdrawn arrived first
                continue

    def discard_pending(self):
        """Forget an interrupt that arrived after close() for the code that just ended."""
        with self._lock:
            self._pending = None

    def interrupt(self, exc_type=KeyboardInterrupt):
        """Raise `exc_type` in the hub code now running, or as soon as the requested code starts."""
        with self._lock:
            if not self._open:
                self._pending = exc_type
                return
            _set_async_exc(self._thread_id, exc_type)
            self.wakeup.set()
        for callback in self._waiters:
            callback()
