"""The MicroPython REPL over BLE: a Nordic UART Service bridge.

The host's program channel is MicroPython's raw REPL; over the air it rides the Nordic UART Service.
What the central writes to RX becomes REPL input through a stream attached with `os.dupterm`, and
what the REPL prints goes back as TX notifications.

- Input. Writes land in an append-mode GATT buffer (several writes between two IRQs are kept), are
  queued here and pushed into the REPL with `os.dupterm_notify`, which is also how a Ctrl-C reaches a
  running program: the port turns the interrupt character into a KeyboardInterrupt as it drains us.
- Output. print() must never wait for the radio, so writes only go into a fixed RAM ring (no heap
  churn per print on a hub that runs for hours) and schedule a flush that sends it in notifications
  of MTU - 3 bytes. A flush can stall (scheduler queue
  full, or the controller out of buffers); a timer pump restarts it, so buffered bytes never wait for
  a next write that may not come.
- Links. One central at a time (the REPL is one stream). Output is held until the central shows it
  listens (its first write, or a grace period after connecting), so nothing is notified into a link
  that has not subscribed yet; output made while no one is connected is kept (the newest
  TX_BUFFER_BYTES) for the next connection. On disconnect the hub advertises again.

Public surface: start(), stop(), is_running(), pump_tx(); log_entries() / dump_log() / clear_log()
give a small ring of link events for diagnosing a link without a working link.
"""

import io
import os
import time

import micropython
from micropython import const

from openbricks import bluetooth as _settings
from openbricks import timers

NUS_SERVICE_UUID = "6E400001-B5A3-F393-E0A9-E50E24DCCA9E"
NUS_RX_UUID = "6E400002-B5A3-F393-E0A9-E50E24DCCA9E"  # central -> hub (REPL input)
NUS_TX_UUID = "6E400003-B5A3-F393-E0A9-E50E24DCCA9E"  # hub -> central (REPL output)

# 247 lets one notification fill one 251-byte LE data packet (minus the 4-byte L2CAP header).
PREFERRED_MTU = const(247)
ADV_INTERVAL_US = const(100_000)
TX_BUFFER_BYTES = const(4096)
RX_BUFFER_BYTES = const(4352)  # two 2 KB raw-paste windows in flight, plus a write of slack
PUMP_MS = const(20)
CONNECT_GRACE_MS = const(1000)
DUPTERM_SLOT = const(0)
DEFAULT_TIMER_ID = timers.BLE_REPL
_TIMER_ROLE = "BLE REPL pump"

_IRQ_CENTRAL_CONNECT = const(1)
_IRQ_CENTRAL_DISCONNECT = const(2)
_IRQ_GATTS_WRITE = const(3)
_IRQ_MTU_EXCHANGED = const(21)

_FLAG_READ = const(0x0002)
_FLAG_WRITE_NO_RESPONSE = const(0x0004)
_FLAG_WRITE = const(0x0008)
_FLAG_NOTIFY = const(0x0010)

_ATT_HEADER_BYTES = const(3)
_DEFAULT_MTU = const(23)
_ADV_MAX_BYTES = const(31)
_AD_FLAGS = b"\x02\x01\x06"  # LE general discoverable, BR/EDR not supported
_AD_SHORT_NAME = const(0x08)
_AD_COMPLETE_NAME = const(0x09)
_AD_UUID128_COMPLETE = const(0x07)

_MP_STREAM_POLL = const(3)
_MP_STREAM_CLOSE = const(4)
_MP_STREAM_POLL_RD = const(0x0001)
_MP_STREAM_POLL_WR = const(0x0004)
_EINVAL = const(22)
_DISCARD_STEP = const(64)

_LOG_SIZE = const(32)

_bridge = None
_log = []
_log_next = [0]


def _note(text):
    entry = (time.ticks_ms(), text)
    if len(_log) < _LOG_SIZE:
        _log.append(entry)
    else:
        _log[_log_next[0]] = entry
        _log_next[0] = (_log_next[0] + 1) % _LOG_SIZE


def log_entries():
    """The recorded link events as (ticks_ms, text), oldest first."""
    if len(_log) < _LOG_SIZE:
        return list(_log)
    start = _log_next[0]
    return _log[start:] + _log[:start]


def dump_log():
    """Print the link events one per line (each line is bounded, so printing over BLE cannot feed
    the log it is printing)."""
    for stamp, text in log_entries():
        print("%d %s" % (stamp, text))


def clear_log():
    """Forget the recorded BLE events (dump_log() then prints nothing)."""
    del _log[:]
    _log_next[0] = 0


def _uuid128_le(text):
    digits = text.replace("-", "")
    out = bytearray(16)
    for i in range(16):
        out[15 - i] = int(digits[2 * i : 2 * i + 2], 16)
    return bytes(out)


def _ad(ad_type, value):
    return bytes((len(value) + 1, ad_type)) + value


def advertising_payloads(name):
    """(advertisement, scan response) for a hub called `name`.

    The name goes in the advertisement, so even a passive scan sees it; the 128-bit NUS UUID (18
    bytes, too many to share 31 bytes with a useful name) goes in the scan response for centrals
    that filter by service. A name longer than the advertisement's room is sent shortened.
    """
    encoded = name.encode()
    room = _ADV_MAX_BYTES - len(_AD_FLAGS) - 2
    if len(encoded) <= room:
        adv = _AD_FLAGS + _ad(_AD_COMPLETE_NAME, encoded)
    else:
        adv = _AD_FLAGS + _ad(_AD_SHORT_NAME, encoded[:room])
    return adv, _ad(_AD_UUID128_COMPLETE, _uuid128_le(NUS_SERVICE_UUID))


class _ReplStream(io.IOBase):
    """The REPL's end of the bridge, as `os.dupterm` wants it.

    readinto() returns None, never 0, when nothing is queued: 0 means end of file, and the port
    detaches a stream that reports it. write() never raises, for the same reason.
    """

    def __init__(self, bridge):
        self._bridge = bridge

    def readinto(self, buf):
        return self._bridge.take_input(buf)

    def write(self, buf):
        return self._bridge.queue_output(buf)

    def ioctl(self, op, arg):
        if op == _MP_STREAM_POLL:
            ready = 0
            if arg & _MP_STREAM_POLL_RD and self._bridge.has_input():
                ready |= _MP_STREAM_POLL_RD
            if arg & _MP_STREAM_POLL_WR:
                ready |= _MP_STREAM_POLL_WR
            return ready
        if op == _MP_STREAM_CLOSE:
            return 0
        return -_EINVAL


class _Bridge:
    def __init__(self, ble):
        self._ble = ble
        self._rx_handle = None
        self._tx_handle = None
        self._conn = None
        self._mtu = _DEFAULT_MTU
        self._listening = False
        self._connected_ms = 0
        self._rx = micropython.RingIO(RX_BUFFER_BYTES)
        self._tx = micropython.RingIO(TX_BUFFER_BYTES)
        # The notification being sent: taken out of the ring, kept here until the stack accepts it,
        # so a refused notify loses nothing. Sized for the largest MTU the hub agrees to.
        self._chunk = bytearray(PREFERRED_MTU - _ATT_HEADER_BYTES)
        self._chunk_start = 0
        self._chunk_end = 0
        self._scratch = bytearray(_DISCARD_STEP)
        self._flush_pending = False
        self._timer = None
        self._adv = None
        self._previous_term = None
        self.stream = _ReplStream(self)
        self.dropped_tx_bytes = 0
        self.dropped_rx_bytes = 0

    def open(self, name, timer_id):
        import bluetooth
        import machine

        ble = self._ble
        ble.config(gap_name=name, mtu=PREFERRED_MTU)
        ble.irq(self._irq)
        service = (
            bluetooth.UUID(NUS_SERVICE_UUID),
            (
                (bluetooth.UUID(NUS_TX_UUID), _FLAG_READ | _FLAG_NOTIFY),
                (bluetooth.UUID(NUS_RX_UUID), _FLAG_WRITE | _FLAG_WRITE_NO_RESPONSE),
            ),
        )
        ((self._tx_handle, self._rx_handle),) = ble.gatts_register_services((service,))
        ble.gatts_set_buffer(self._rx_handle, RX_BUFFER_BYTES, True)
        self._previous_term = os.dupterm(self.stream, DUPTERM_SLOT)
        timers.claim(timer_id, _TIMER_ROLE, "pass timer_id= to ble_repl.start()")
        self._timer_id = timer_id
        self._timer = machine.Timer(timer_id)
        self._timer.init(mode=machine.Timer.PERIODIC, period=PUMP_MS, callback=_pump_tick)
        self._adv = advertising_payloads(name)
        self._advertise()
        _note("started as %s" % name)

    def close(self):
        # Every step runs even if the radio is already gone, so stop() always completes.
        current = os.dupterm(self._previous_term, DUPTERM_SLOT)
        if current is not self.stream:
            os.dupterm(current, DUPTERM_SLOT)  # someone replaced us meanwhile: leave theirs attached
        if self._timer is not None:
            self._timer.deinit()
            self._timer = None
            timers.release(self._timer_id, _TIMER_ROLE)
        ble = self._ble
        for step in (self._drop_link, self._stop_advertising):
            try:
                step()
            except OSError as err:
                _note("stop: %r" % (err,))
        ble.irq(None)
        _note("stopped")

    def _drop_link(self):
        conn = self._conn
        self._conn = None
        if conn is not None:
            self._ble.gap_disconnect(conn)

    def _stop_advertising(self):
        self._ble.gap_advertise(None)

    def _advertise(self):
        adv, resp = self._adv
        self._ble.gap_advertise(ADV_INTERVAL_US, adv, resp_data=resp)

    # --- radio side (BLE IRQs, scheduled like a soft interrupt) ----------------------

    def _irq(self, event, data):
        if event == _IRQ_GATTS_WRITE:
            conn, handle = data[0], data[1]
            if handle == self._rx_handle and conn == self._conn:
                self._receive(self._ble.gatts_read(handle))
        elif event == _IRQ_CENTRAL_CONNECT:
            self._on_connect(data[0])
        elif event == _IRQ_CENTRAL_DISCONNECT:
            self._on_disconnect(data[0])
        elif event == _IRQ_MTU_EXCHANGED:
            if data[0] == self._conn:
                self._mtu = data[1]
                _note("mtu %d" % data[1])

    def _on_connect(self, conn):
        if self._conn is not None:
            # The REPL is a single stream; a second central would interleave two sessions.
            _note("refused second central %d" % conn)
            self._ble.gap_disconnect(conn)
            return
        self._conn = conn
        self._mtu = _DEFAULT_MTU
        self._listening = False
        self._connected_ms = time.ticks_ms()
        _note("connected %d" % conn)

    def _on_disconnect(self, conn):
        if conn != self._conn:
            return
        self._conn = None
        self._listening = False
        _note("disconnected %d, %d bytes held" % (conn, self._held()))
        self._advertise()

    def _receive(self, data):
        kept = self._rx.write(data)
        if kept < len(data):
            # Only a host ignoring raw-paste flow control can get here.
            self.dropped_rx_bytes += len(data) - kept
            _note("rx overflow, dropped %d" % (len(data) - kept))
        # A central that writes has subscribed: held output can go now.
        self._listening = True
        notify = getattr(os, "dupterm_notify", None)
        if notify is not None:
            notify(None)
        self._schedule_flush()

    # --- REPL side -------------------------------------------------------------------

    def has_input(self):
        return self._rx.any() > 0

    def take_input(self, buf):
        n = self._rx.readinto(buf)
        return n if n else None

    def queue_output(self, buf):
        n = len(buf)
        data = memoryview(buf)
        if n > TX_BUFFER_BYTES:
            self._discard(n - TX_BUFFER_BYTES)
            data = data[n - TX_BUFFER_BYTES :]
        room = TX_BUFFER_BYTES - self._tx.any()
        if len(data) > room:
            # Keep the newest output: it is what a reconnecting host needs to resume.
            self._discard(len(data) - room)
        self._tx.write(data)
        self._schedule_flush()
        return n

    def _held(self):
        return self._tx.any() + self._chunk_end - self._chunk_start

    def _discard(self, count):
        """Drop the `count` oldest output bytes (or all there are): the pending chunk goes first."""
        self.dropped_tx_bytes += count
        pending = self._chunk_end - self._chunk_start
        if pending:
            taken = min(pending, count)
            self._chunk_start += taken
            count -= taken
        while count > 0:
            got = self._tx.readinto(self._scratch, min(count, _DISCARD_STEP))
            if not got:
                return
            count -= got

    def _schedule_flush(self):
        if self._flush_pending:
            return
        self._flush_pending = True
        try:
            micropython.schedule(_scheduled_flush, None)
        except RuntimeError:
            # Scheduler queue full: the pump restarts the flush on its next tick.
            self._flush_pending = False

    def flush(self):
        self._flush_pending = False
        if self._conn is None or not self._listening:
            return
        size = min(self._mtu - _ATT_HEADER_BYTES, len(self._chunk))
        chunk = memoryview(self._chunk)
        while True:
            if self._chunk_start == self._chunk_end:
                self._chunk_start = 0
                self._chunk_end = self._tx.readinto(self._chunk, size)
                if not self._chunk_end:
                    return
            # A chunk taken under a larger MTU (before a reconnect) goes out in pieces of the new one.
            end = min(self._chunk_end, self._chunk_start + size)
            try:
                self._ble.gatts_notify(self._conn, self._tx_handle, chunk[self._chunk_start : end])
            except OSError as err:
                # Controller out of buffers, or the link just dropped: keep the bytes, the pump
                # retries at its pace (a retry loop here would starve the VM).
                _note("notify failed %r, %d bytes held" % (err, self._held()))
                return
            self._chunk_start = end

    def pump(self):
        if self._conn is not None and not self._listening:
            if time.ticks_diff(time.ticks_ms(), self._connected_ms) >= CONNECT_GRACE_MS:
                self._listening = True
        if self._held():
            self.flush()


def _scheduled_flush(_arg):
    bridge = _bridge
    if bridge is not None:
        bridge.flush()


def _pump_tick(_timer):
    bridge = _bridge
    if bridge is not None:
        bridge.pump()


def start(timer_id=DEFAULT_TIMER_ID):
    """Bring the bridge up: NUS registered, REPL duplicated onto it, hub advertising. Idempotent.

    The radio must already be on (openbricks.bluetooth turns it on first); the advertised name is
    the one flashed into NVS, and a hub without one raises HubNameNotSetError.
    """
    global _bridge
    if _bridge is not None:
        return
    name = _settings.hub_name()
    if name is None:
        raise _settings.HubNameNotSetError()
    import bluetooth

    ble = bluetooth.BLE()
    if not ble.active():
        raise OSError(
            "ble_repl.start(): the BLE radio is off; turn BLE on with openbricks.bluetooth.set_enabled(True)"
        )
    bridge = _Bridge(ble)
    bridge.open(name, timer_id)
    _bridge = bridge


def stop():
    """Tear the bridge down: REPL detached, link dropped, advertising stopped. Idempotent."""
    global _bridge
    bridge = _bridge
    if bridge is None:
        return
    _bridge = None
    bridge.close()


def is_running():
    """True while the NUS bridge is up (between start() and stop())."""
    return _bridge is not None


def pump_tx():
    """Restart a stalled TX flush if bytes are waiting; a no-op when idle or stopped. The bridge's
    own timer calls this every PUMP_MS; other periodic code may call it too."""
    bridge = _bridge
    if bridge is not None:
        bridge.pump()


def reset_state():
    """Forget the bridge and the event log without touching the radio (a fresh start in tests)."""
    global _bridge
    _bridge = None
    clear_log()
