"""The virtual hub's control socket: what a person standing at a hub could do, for a host.

A Unix socket in the hub's directory (`control.sock`; in a private temp directory when that path is
too long for a Unix socket, and always announced on start) takes one JSON object per line and answers
one per line:

    {"op": "click"}     press and release the program button (starts or stops the program)
    {"op": "press"}     hold the program button down ... {"op": "release"} let it go
    {"op": "status"}    name, pty, running, sim time, the robot's pose, REPL state

Answers are `{"ok": true, ...}` or `{"ok": false, "error": "..."}`. The REPL link stays the only
way to run code; this socket only does what the hub's hardware buttons do, plus read-only status.
"""

import json
import os
import socketserver
import tempfile
import threading

from .endpoint import CONTROL_SOCKET

MAX_LINE_BYTES = 4096
MAX_SOCKET_PATH_BYTES = 100  # AF_UNIX paths are capped near 108 bytes


class _Handler(socketserver.StreamRequestHandler):
    def handle(self):
        while True:
            line = self.rfile.readline(MAX_LINE_BYTES + 1)
            if not line:
                return
            reply = self.server.control.answer(line)
            self.wfile.write(json.dumps(reply).encode() + b"\n")


class _Server(socketserver.ThreadingMixIn, socketserver.UnixStreamServer):
    daemon_threads = True


class ControlServer:
    """Serves `hub` (a VirtualHub) on `path` from background threads."""

    def __init__(self, hub, path):
        self.hub = hub
        self.path = os.fspath(path)
        self._temp_dir = None
        if len(os.fsencode(self.path)) > MAX_SOCKET_PATH_BYTES:
            # A deep hub directory: the socket goes to a private temp dir (announced and in status).
            self._temp_dir = tempfile.mkdtemp(prefix="openbricks-vhub-")
            self.path = os.path.join(self._temp_dir, CONTROL_SOCKET)
        if os.path.exists(self.path):
            os.remove(self.path)  # left by a hub that was killed; the directory lock says it is ours now
        self._server = _Server(self.path, _Handler)
        self._server.control = self
        self._thread = threading.Thread(target=self._server.serve_forever, name="virtual-hub-control")
        self._thread.daemon = True

    def start(self):
        self._thread.start()
        return self

    def close(self):
        self._server.shutdown()
        self._server.server_close()
        try:
            os.remove(self.path)
            if self._temp_dir is not None:
                os.rmdir(self._temp_dir)
        except OSError:
            pass

    def answer(self, line):
        if len(line) > MAX_LINE_BYTES:
            return {"ok": False, "error": f"request longer than {MAX_LINE_BYTES} bytes"}
        try:
            request = json.loads(line)
            op = request["op"]
        except (ValueError, TypeError, KeyError):
            return {"ok": False, "error": 'send one JSON object per line, such as {"op": "status"}'}
        button = self.hub.world.button
        if op == "status":
            return {"ok": True, **self.hub.status()}
        if op == "click":
            button.click()
        elif op == "press":
            button.press()
        elif op == "release":
            button.release()
        else:
            return {"ok": False, "error": f"unknown op {op!r}: use click, press, release or status"}
        return {"ok": True, "button_clicks_pending": button.pending_clicks}
