"""Fake servos behind a pseudo-terminal: the host tool opens the pty as its USB adapter's port."""

import os
import pty
import select
import threading

from fakes.scs_servo import FakeServo, ScsBus


class ServoRig:
    """Servos with the given ids on a bus reached through a pty; `echo` imitates adapters that hear
    their own transmission."""

    def __init__(self, ids, echo=False):
        self.bus = ScsBus()
        for servo_id in ids:
            self.bus.add(FakeServo(servo_id))
        self.echo = echo
        self._master, self._slave = pty.openpty()
        self.port = os.ttyname(self._slave)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def ids(self):
        return sorted(self.bus.servos)

    def _serve(self):
        while not self._stop.is_set():
            ready, _, _ = select.select([self._master], [], [], 0.05)
            if not ready:
                continue
            try:
                data = os.read(self._master, 4096)
            except OSError:
                return
            # The bus keeps a packet that arrives in pieces until its last byte is in.
            os.write(self._master, (data if self.echo else b"") + self.bus.handle(data))

    def close(self):
        self._stop.set()
        self._thread.join(timeout=2)
        os.close(self._master)
        os.close(self._slave)
