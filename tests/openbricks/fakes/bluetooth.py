"""The test's side of the hub's radio: a central (the laptop) on the simulator's `bluetooth`
model (sim/shim/bluetooth.py), which install() gives the runtime.

The test connects, writes to a characteristic, negotiates the MTU and disconnects; each step
raises the IRQ the real stack would raise. What the hub sent is read back per connection.
"""

from .hardware import bluetooth as _model

FLAG_NOTIFY = _model.FLAG_NOTIFY
FLAG_WRITE = _model.FLAG_WRITE
FLAG_WRITE_NO_RESPONSE = _model.FLAG_WRITE_NO_RESPONSE
IRQ_MTU_EXCHANGED = _model.IRQ_MTU_EXCHANGED
IRQ_GATTS_WRITE = _model.IRQ_GATTS_WRITE
UUID = _model.UUID
reset = _model.reset

# --- the test's side: the central ----------------------------------------------------


def radio():
    return _model.BLE()


def connect(conn_handle=0, addr=b"\xaa\xbb\xcc\xdd\xee\xff", racing=False):
    """A central connects; the stack stops advertising, as NimBLE does for a connectable advert.

    `racing=True`: this central answered the same advert as one that connected just before it,
    so it gets a link although advertising has already stopped.
    """
    ble = radio()
    if not ble._active:
        raise AssertionError("a central cannot connect: the hub's radio is off")
    if ble.advertising is None and not racing:
        raise AssertionError("a central cannot connect: the hub is not advertising")
    ble.accept(conn_handle, addr)
    return conn_handle


def disconnect(conn_handle=0):
    radio().drop(conn_handle)


def exchange_mtu(conn_handle, central_mtu):
    """ATT MTU exchange: both sides settle on the smaller of their preferred MTUs."""
    ble = radio()
    conn = ble.connections[conn_handle]
    conn.mtu = min(central_mtu, ble.preferred_mtu)
    ble._event(IRQ_MTU_EXCHANGED, (conn_handle, conn.mtu))
    return conn.mtu


def write(conn_handle, uuid, data):
    """The central writes `data` to the characteristic `uuid` (at most MTU - 3 bytes per write)."""
    ble = radio()
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
    conn = radio().connections[conn_handle]
    size = conn.mtu - 3
    for start in range(0, len(data), size):
        write(conn_handle, uuid, data[start : start + size])


def handle_of(uuid):
    wanted = UUID(uuid)
    for _service, entries in radio().services:
        for char_uuid, _flags, value_handle in entries:
            if char_uuid == wanted:
                return value_handle
    raise AssertionError("no characteristic %s is registered" % wanted)


def flags_of(uuid):
    wanted = UUID(uuid)
    for _service, entries in radio().services:
        for char_uuid, flags, _value_handle in entries:
            if char_uuid == wanted:
                return flags
    raise AssertionError("no characteristic %s is registered" % wanted)


def notifications(conn_handle=0):
    return radio().connections[conn_handle].notifications


def received(conn_handle=0):
    """Everything the central got by notification, joined."""
    return b"".join(notifications(conn_handle))


def limit_notifications(count):
    """Accept `count` more notifications, then fail with ENOMEM as NimBLE does when its buffers are
    full; None lifts the limit (the controller drained its queue)."""
    radio().notify_budget = count


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
    adv = radio().advertising
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
