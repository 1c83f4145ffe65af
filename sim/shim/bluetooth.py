"""An inert `bluetooth` for a program running in the simulator.

A simulated robot has no radio: the virtual hub carries the BLE link to the
host itself, outside the program. The stack here accepts the runtime's calls
(activate, name, register services, advertise) so hub code that sets up the
BLE bridge runs unchanged, but no central ever connects and nothing is sent.
"""

FLAG_READ = 0x0002
FLAG_WRITE_NO_RESPONSE = 0x0004
FLAG_WRITE = 0x0008
FLAG_NOTIFY = 0x0010
FLAG_INDICATE = 0x0020

_ENOTCONN = 107


class UUID:
    def __init__(self, value):
        self._value = value.lower() if isinstance(value, str) else int(value)

    def __eq__(self, other):
        return isinstance(other, UUID) and other._value == self._value

    def __hash__(self):
        return hash(self._value)

    def __repr__(self):
        return f"UUID({self._value!r})"


class _Radio:
    def __init__(self):
        self._active = False
        self._config = {"gap_name": "openbricks-sim", "mtu": 23, "mac": (0, b"\x5e\x1a\x0b\x00\x00\x01")}
        self._values = {}
        self._next_handle = 1

    def active(self, state=None):
        if state is not None:
            self._active = bool(state)
        return self._active

    def config(self, *names, **settings):
        self._config.update(settings)
        if names:
            return self._config.get(names[0])
        return None

    def irq(self, handler):
        pass

    def gap_advertise(self, interval_us, adv_data=None, *, resp_data=None, connectable=True):
        pass

    def gap_disconnect(self, conn_handle):
        return False

    def gatts_register_services(self, definitions):
        handles = []
        for _uuid, characteristics in definitions:
            service = []
            for _characteristic in characteristics:
                handle = self._next_handle
                self._next_handle += 1
                self._values[handle] = b""
                service.append(handle)
            handles.append(tuple(service))
        return tuple(handles)

    def gatts_read(self, value_handle):
        return self._values.get(value_handle, b"")

    def gatts_write(self, value_handle, data, send_update=False):
        self._values[value_handle] = bytes(data)

    def gatts_set_buffer(self, value_handle, length, append=False):
        pass

    def gatts_notify(self, conn_handle, value_handle, data=None):
        raise OSError(_ENOTCONN)

    def gatts_indicate(self, conn_handle, value_handle, data=None):
        raise OSError(_ENOTCONN)


_radio = [None]


def BLE():
    if _radio[0] is None:
        _radio[0] = _Radio()
    return _radio[0]


def reset():
    _radio[0] = None
