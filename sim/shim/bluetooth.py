"""MicroPython's `bluetooth` at the level the hub runtime uses it: one radio (`BLE()`, a singleton
as on the hub) with its GATT server.

The radio keeps what the runtime did: activity, GAP name, preferred MTU, the registered GATT table,
advertising payloads, and every notification sent per connection. Stack behaviours the runtime
must cope with are modelled where they bite: advertising stops when a central connects, an
advertising payload over 31 bytes is refused, a notification longer than MTU - 3 is truncated,
the controller can run out of notification buffers (`notify_budget`), and deactivating the radio
drops the GATT table and every connection.

In the simulator no central ever connects: the virtual hub carries the link to the host itself,
outside the program, so the program's BLE set-up runs unchanged and nothing is sent. The runtime's
tests play the central on this radio (tests/openbricks/fakes/bluetooth.py), each step raising the
IRQ the real stack would raise, with the same event codes and data tuples.
"""

FLAG_READ = 0x0002
FLAG_WRITE_NO_RESPONSE = 0x0004
FLAG_WRITE = 0x0008
FLAG_NOTIFY = 0x0010
FLAG_INDICATE = 0x0020

# IRQ event codes, as MicroPython numbers them.
IRQ_CENTRAL_CONNECT = 1
IRQ_CENTRAL_DISCONNECT = 2
IRQ_GATTS_WRITE = 3
IRQ_MTU_EXCHANGED = 21

DEFAULT_MTU = 23
MAX_ADV_PAYLOAD = 31
MAC = b"\x5e\x1a\x0b\x00\x00\x01"  # the simulated hub's address; machine.unique_id() is the same

_ENODEV = 19  # the radio is not active
_ENOTCONN = 107
_ENOMEM = 12  # out of controller buffers
_EINVAL = 22


class UUID:
    """16-bit (int or 4 hex digits) or 128-bit (canonical string) UUID, compared by value."""

    def __init__(self, value):
        if isinstance(value, UUID):
            value = value._text
        if isinstance(value, int):
            value = f"{value:04X}"
        text = str(value).upper()
        digits = text.replace("-", "")
        if len(digits) not in (4, 32):
            raise ValueError(f"invalid UUID {value!r}")
        int(digits, 16)
        self._text = text

    def __eq__(self, other):
        return isinstance(other, UUID) and other._text.replace("-", "") == self._text.replace("-", "")

    def __hash__(self):
        return hash(self._text.replace("-", ""))

    def __repr__(self):
        return f"UUID('{self._text}')"

    def __str__(self):
        return self._text


class _Connection:
    def __init__(self, handle, addr):
        self.handle = handle
        self.addr = addr
        self.mtu = DEFAULT_MTU
        self.notifications = []  # payloads as the central received them


class _Radio:
    def __init__(self):
        self._active = False
        self.gap_name = b"MPY ESP32"
        self.preferred_mtu = DEFAULT_MTU
        self.irq_handler = None
        self.advertising = None  # (interval_us, adv_data, resp_data, connectable) while advertising
        self.services = []  # [(service uuid, [(char uuid, flags, value handle)])]
        self.values = {}  # value handle -> bytes
        self.append_mode = {}  # value handle -> True when gatts_set_buffer(..., append=True)
        self.connections = {}  # conn handle -> _Connection
        self.notify_budget = None  # None: unlimited; else notifications accepted before ENOMEM
        self.activations = 0

    # --- the MicroPython API ---------------------------------------------------------

    def active(self, state=None):
        if state is None:
            return self._active
        state = bool(state)
        if state and not self._active:
            self.activations += 1
        if not state:
            # The stack shuts down: links drop without events, the GATT table is gone.
            self.advertising = None
            self.services = []
            self.values = {}
            self.append_mode = {}
            self.connections = {}
        self._active = state
        return None

    def config(self, *names, **settings):
        if names:
            if len(names) != 1 or settings:
                raise TypeError("config() takes one name to read, or keyword settings to write")
            name = names[0]
            if name == "gap_name":
                return self.gap_name
            if name == "mtu":
                return self.preferred_mtu
            if name == "mac":
                return (0, MAC)
            raise ValueError(f"unknown config param {name!r}")
        for name, value in settings.items():
            if name == "gap_name":
                self.gap_name = value.encode() if isinstance(value, str) else bytes(value)
            elif name == "mtu":
                if not 23 <= value <= 517:
                    raise ValueError("mtu must be 23..517")
                self.preferred_mtu = value
            elif name in ("rxbuf", "addr_mode", "io", "bond", "le_secure", "mitm"):
                pass
            else:
                raise ValueError(f"unknown config param {name!r}")
        return None

    def irq(self, handler):
        self.irq_handler = handler

    def gap_advertise(self, interval_us, adv_data=None, *, resp_data=None, connectable=True):
        self._require_active()
        if interval_us is None:
            self.advertising = None
            return
        adv = bytes(adv_data or b"")
        resp = bytes(resp_data or b"")
        if len(adv) > MAX_ADV_PAYLOAD or len(resp) > MAX_ADV_PAYLOAD:
            raise OSError(_EINVAL)
        self.advertising = (interval_us, adv, resp, connectable)

    def gap_disconnect(self, conn_handle):
        if conn_handle not in self.connections:
            return False
        self.drop(conn_handle)
        return True

    def gatts_register_services(self, definitions):
        self._require_active()
        self.services = []
        self.values = {}
        self.append_mode = {}
        next_handle = 1
        result = []
        for service_uuid, characteristics in definitions:
            entries = []
            handles = []
            next_handle += 1  # the service declaration
            for characteristic in characteristics:
                uuid, flags = characteristic[0], characteristic[1]
                next_handle += 1  # the characteristic declaration
                value_handle = next_handle
                next_handle += 1
                if flags & (FLAG_NOTIFY | FLAG_INDICATE):
                    next_handle += 1  # its CCCD
                self.values[value_handle] = b""
                entries.append((UUID(uuid), flags, value_handle))
                handles.append(value_handle)
            self.services.append((UUID(service_uuid), entries))
            result.append(tuple(handles))
        return tuple(result)

    def gatts_read(self, value_handle):
        self._require_handle(value_handle)
        value = self.values[value_handle]
        if self.append_mode.get(value_handle):
            self.values[value_handle] = b""
        return value

    def gatts_write(self, value_handle, data, send_update=False):
        self._require_handle(value_handle)
        self.values[value_handle] = bytes(data)
        if send_update:
            for conn in self.connections.values():
                self._deliver(conn, self.values[value_handle])

    def gatts_set_buffer(self, value_handle, length, append=False):
        self._require_handle(value_handle)
        self.append_mode[value_handle] = bool(append)

    def gatts_notify(self, conn_handle, value_handle, data=None):
        self._require_handle(value_handle)
        conn = self.connections.get(conn_handle)
        if conn is None:
            raise OSError(_ENOTCONN)
        if self.notify_budget is not None:
            if self.notify_budget <= 0:
                raise OSError(_ENOMEM)
            self.notify_budget -= 1
        payload = self.values[value_handle] if data is None else bytes(data)
        self._deliver(conn, payload)

    def gatts_indicate(self, conn_handle, value_handle, data=None):
        self.gatts_notify(conn_handle, value_handle, data)

    # --- the link's far end: a central --------------------------------------------------

    def accept(self, conn_handle, addr):
        """A central connects; the stack stops advertising, as NimBLE does for a connectable advert."""
        self.advertising = None
        self.connections[conn_handle] = _Connection(conn_handle, addr)
        self._event(IRQ_CENTRAL_CONNECT, (conn_handle, 0, addr))

    def drop(self, conn_handle):
        """The link to a central ends (either side hung up)."""
        conn = self.connections.pop(conn_handle)
        self._event(IRQ_CENTRAL_DISCONNECT, (conn_handle, 0, conn.addr))

    # --- internals -------------------------------------------------------------------

    def _deliver(self, conn, payload):
        # An ATT notification carries at most MTU - 3 bytes; the stack cuts the rest off.
        conn.notifications.append(bytes(payload[: conn.mtu - 3]))

    def _require_active(self):
        if not self._active:
            raise OSError(_ENODEV)

    def _require_handle(self, value_handle):
        self._require_active()
        if value_handle not in self.values:
            raise ValueError(f"invalid attribute handle {value_handle!r}")

    def _event(self, event, data):
        if self.irq_handler is not None:
            return self.irq_handler(event, data)
        return None


_radio = [_Radio()]


def BLE():
    """The radio, one per chip as on the hub."""
    return _radio[0]


def reset():
    _radio[0] = _Radio()
