"""A fake of MicroPython's `bluetooth` module, at the level the hub runtime uses it.

The radio (`BLE()`, a singleton as on the hub) keeps what the runtime did:
activity, GAP name, preferred MTU, the registered GATT table, advertising
payloads, and every notification sent per connection. The test plays the
central (the laptop): connect, write to a characteristic, negotiate the MTU,
disconnect; each step raises the IRQ the real stack would raise, with the
same event codes and data tuples.

Stack behaviours the runtime must cope with are modelled where they bite:
advertising stops when a central connects, an advertising payload over 31
bytes is refused, a notification longer than MTU - 3 is truncated, the
controller can run out of notification buffers (`limit_notifications`), and
deactivating the radio drops the GATT table and every connection.
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
            value = "%04X" % value
        text = str(value).upper()
        digits = text.replace("-", "")
        if len(digits) not in (4, 32):
            raise ValueError("invalid UUID %r" % (value,))
        int(digits, 16)
        self._text = text

    def __eq__(self, other):
        return isinstance(other, UUID) and other._text.replace("-", "") == self._text.replace("-", "")

    def __hash__(self):
        return hash(self._text.replace("-", ""))

    def __repr__(self):
        return "UUID('%s')" % self._text

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
                return (0, b"\x24\x0a\xc4\x00\x11\x22")
            raise ValueError("unknown config param %r" % (name,))
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
                raise ValueError("unknown config param %r" % (name,))
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
        disconnect(conn_handle)
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
            raise ValueError("invalid attribute handle %r" % (value_handle,))

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


# --- the test's side: the central ----------------------------------------------------


def radio():
    return _radio[0]


def connect(conn_handle=0, addr=b"\xaa\xbb\xcc\xdd\xee\xff", racing=False):
    """A central connects; the stack stops advertising, as NimBLE does for a connectable advert.

    `racing=True`: this central answered the same advert as one that connected just before it,
    so it gets a link although advertising has already stopped.
    """
    ble = _radio[0]
    if not ble._active:
        raise AssertionError("a central cannot connect: the hub's radio is off")
    if ble.advertising is None and not racing:
        raise AssertionError("a central cannot connect: the hub is not advertising")
    ble.advertising = None
    ble.connections[conn_handle] = _Connection(conn_handle, addr)
    ble._event(IRQ_CENTRAL_CONNECT, (conn_handle, 0, addr))
    return conn_handle


def disconnect(conn_handle=0):
    ble = _radio[0]
    conn = ble.connections.pop(conn_handle)
    ble._event(IRQ_CENTRAL_DISCONNECT, (conn_handle, 0, conn.addr))


def exchange_mtu(conn_handle, central_mtu):
    """ATT MTU exchange: both sides settle on the smaller of their preferred MTUs."""
    ble = _radio[0]
    conn = ble.connections[conn_handle]
    conn.mtu = min(central_mtu, ble.preferred_mtu)
    ble._event(IRQ_MTU_EXCHANGED, (conn_handle, conn.mtu))
    return conn.mtu


def write(conn_handle, uuid, data):
    """The central writes `data` to the characteristic `uuid` (at most MTU - 3 bytes per write)."""
    ble = _radio[0]
    conn = ble.connections[conn_handle]
    data = bytes(data)
    if len(data) > conn.mtu - 3:
        raise AssertionError("a write of %d bytes exceeds MTU %d - 3" % (len(data), conn.mtu))
    handle = handle_of(uuid)
    if ble.append_mode.get(handle):
        ble.values[handle] = ble.values[handle] + data
    else:
        ble.values[handle] = data
    ble._event(IRQ_GATTS_WRITE, (conn_handle, handle))


def write_stream(conn_handle, uuid, data):
    """Write `data` as a host does: split into MTU - 3 sized writes."""
    conn = _radio[0].connections[conn_handle]
    size = conn.mtu - 3
    for start in range(0, len(data), size):
        write(conn_handle, uuid, data[start : start + size])


def handle_of(uuid):
    wanted = UUID(uuid)
    for _service, entries in _radio[0].services:
        for char_uuid, _flags, value_handle in entries:
            if char_uuid == wanted:
                return value_handle
    raise AssertionError("no characteristic %s is registered" % wanted)


def flags_of(uuid):
    wanted = UUID(uuid)
    for _service, entries in _radio[0].services:
        for char_uuid, flags, _value_handle in entries:
            if char_uuid == wanted:
                return flags
    raise AssertionError("no characteristic %s is registered" % wanted)


def notifications(conn_handle=0):
    return _radio[0].connections[conn_handle].notifications


def received(conn_handle=0):
    """Everything the central got by notification, joined."""
    return b"".join(notifications(conn_handle))


def limit_notifications(count):
    """Accept `count` more notifications, then fail with ENOMEM as NimBLE does when its buffers are
    full; None lifts the limit (the controller drained its queue)."""
    _radio[0].notify_budget = count


def ad_fields(payload):
    """Split an advertising payload into [(AD type, bytes)], checking its length bytes."""
    fields = []
    i = 0
    while i < len(payload):
        length = payload[i]
        if length == 0 or i + 1 + length > len(payload):
            raise AssertionError("malformed AD structure at byte %d of %r" % (i, payload))
        fields.append((payload[i + 1], bytes(payload[i + 2 : i + 1 + length])))
        i += 1 + length
    return fields


def advertised_fields():
    """AD fields of the advertisement and the scan response together."""
    adv = _radio[0].advertising
    if adv is None:
        return []
    return ad_fields(adv[1]) + ad_fields(adv[2])


def advertised_name():
    for ad_type, value in advertised_fields():
        if ad_type in (0x08, 0x09):  # shortened / complete local name
            return value.decode()
    return None


def advertised_uuid128s():
    """Complete / incomplete lists of 128-bit service UUIDs, as canonical strings."""
    found = []
    for ad_type, value in advertised_fields():
        if ad_type in (0x06, 0x07):
            for start in range(0, len(value), 16):
                digits = "".join("%02X" % b for b in reversed(value[start : start + 16]))
                found.append(
                    "%s-%s-%s-%s-%s" % (digits[:8], digits[8:12], digits[12:16], digits[16:20], digits[20:])
                )
    return found
