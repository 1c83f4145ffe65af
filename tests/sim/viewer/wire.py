"""A stand-in for the browser: a websocket client that speaks viser's wire format.

It connects the way the page does (subprotocol `viser-v<version>`, else the server refuses), decodes
every window the server sends into plain message dicts with their numpy arrays filled in, keeps
them with their arrival time, and can press buttons and pick dropdown values as a person would.
The tests judge the viewer by what reaches this client, which is what reaches a browser.
"""

from __future__ import annotations

import threading
import time

import msgspec.msgpack
import numpy as np
import viser
import zstandard
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect


class WireClient:
    def __init__(self, port: int, host: str = "127.0.0.1"):
        self._socket = connect(
            f"ws://{host}:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None
        )
        self._decompressor = zstandard.ZstdDecompressor()
        self._lock = threading.Lock()
        self.received: list[tuple[float, dict]] = []  # (perf_counter at arrival, message)
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        # A page reports its camera as soon as it has drawn; viser counts it connected from then on
        # (before that, its button presses go nowhere).
        self._send(
            {
                "type": "ViewerCameraMessage",
                "wxyz": (1.0, 0.0, 0.0, 0.0),
                "position": (0.0, -1.0, 1.0),
                "fov": 1.3,
                "near": 0.01,
                "far": 1000.0,
                "image_height": 720,
                "image_width": 1280,
                "look_at": (0.0, 0.0, 0.0),
                "up_direction": (0.0, 0.0, 1.0),
            }
        )

    def close(self) -> None:
        self._socket.close()
        self._reader.join(timeout=2.0)

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()

    # --- what arrived --------------------------------------------------------------------------

    def messages(self, type_name: str | None = None, since: float = 0.0) -> list[tuple[float, dict]]:
        with self._lock:
            return [
                (t, m)
                for t, m in self.received
                if t >= since and (type_name is None or m["type"] == type_name)
            ]

    def wait_for(self, predicate, timeout_s: float = 10.0, what: str = "a message"):
        """The first message satisfying predicate(message), waiting up to timeout_s for it."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            for _, message in self.messages():
                if predicate(message):
                    return message
            time.sleep(0.02)
        raise AssertionError(f"no {what} reached the client within {timeout_s} s")

    def gui(self, label: str, type_name: str | None = None) -> dict:
        """The GUI component labelled `label` now (labels change: Pause becomes Resume), as its
        creation message with every later update of its props applied."""

        def current():
            components = {}
            for _, message in self.messages():
                kind = message["type"]
                if kind.startswith("Gui") and kind.endswith("Message") and "props" in message:
                    components[message["uuid"]] = {**message, "props": dict(message["props"])}
                elif kind == "GuiUpdateMessage" and message["uuid"] in components:
                    components[message["uuid"]]["props"].update(message["updates"])
            return [
                c
                for c in components.values()
                if c["props"].get("label") == label and (type_name is None or c["type"] == type_name)
            ]

        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:
            found = current()
            if found:
                return found[-1]
            time.sleep(0.02)
        raise AssertionError(f"no GUI element labelled {label!r} reached the client")

    def gui_content(self, uuid: str) -> str | None:
        """The latest text of a markdown or html component: at creation, then after each update
        (viser carries markdown as its `_markdown` prop, html as `content`)."""
        content = None
        for _, message in self.messages():
            if message.get("uuid") != uuid:
                continue
            props = message.get("props") or message.get("updates") or {}
            for key in ("content", "_markdown"):
                if key in props:
                    content = props[key]
        return content

    def status_lines(self) -> list[str]:
        """Every status line the Run panel showed, in order (markdown updates only)."""
        return [
            m["updates"]["_markdown"]
            for _, m in self.messages("GuiUpdateMessage")
            if "_markdown" in m["updates"] and "simulated" in m["updates"]["_markdown"]
        ]

    # --- acting as a person ----------------------------------------------------------------------

    def click(self, label: str) -> None:
        button = self.gui(label, "GuiButtonMessage")
        self._send({"type": "GuiUpdateMessage", "uuid": button["uuid"], "updates": {"value": True}})

    def choose(self, label: str, value: str) -> None:
        dropdown = self.gui(label, "GuiDropdownMessage")
        assert value in dropdown["props"]["options"], dropdown["props"]["options"]
        self._send({"type": "GuiUpdateMessage", "uuid": dropdown["uuid"], "updates": {"value": value}})

    # --- internals ---------------------------------------------------------------------------------

    def _send(self, message: dict) -> None:
        self._socket.send(msgspec.msgpack.encode(message))

    def _read(self) -> None:
        try:
            for raw in self._socket:
                arrived = time.perf_counter()
                messages = self._decode(raw)
                with self._lock:
                    self.received.extend((arrived, m) for m in messages)
        except ConnectionClosed:
            pass

    def _decode(self, raw: bytes) -> list[dict]:
        """[u64 msgpack size][u64 compressed size][zstd msgpack][pad to 8][8-aligned binary buffers]."""
        inner_size = int.from_bytes(raw[0:8], "little")
        compressed_size = int.from_bytes(raw[8:16], "little")
        window = msgspec.msgpack.decode(
            self._decompressor.decompress(raw[16 : 16 + compressed_size], max_output_size=inner_size)
        )
        buffers, offset = [], _aligned(16 + compressed_size)
        for length in window["binaryBufferLengths"]:
            buffers.append(raw[offset : offset + length])
            offset = _aligned(offset + length)
        return [_fill_arrays(message, buffers) for message in window["messages"]]


def _aligned(offset: int) -> int:
    return (offset + 7) // 8 * 8


def _fill_arrays(value, buffers):
    if isinstance(value, dict):
        if "__binary_index" in value and "dtype" in value:
            return np.frombuffer(buffers[value["__binary_index"]], dtype=np.dtype(value["dtype"]))
        return {k: _fill_arrays(v, buffers) for k, v in value.items()}
    if isinstance(value, list):
        return [_fill_arrays(v, buffers) for v in value]
    return value
