"""The `esp32` module for a program running in the simulator: NVS on a per-hub store.

The store is a plain dict {namespace: {key: value}} owned by whoever runs
the hub (a virtual hub keeps it for its lifetime, so settings survive a
simulated reboot); bind() points the module at it.
"""

_store = [{}]

# The port raises ESP-IDF errors as OSError(-code, name).
ESP_ERR_NVS_NOT_FOUND = -4354
ESP_ERR_NVS_INVALID_LENGTH = -4364


def bind(store):
    _store[0] = store if store is not None else {}


class NVS:
    """A namespace of committed values; set_*() stage, commit() publishes, as on the chip."""

    def __init__(self, namespace):
        self._namespace = namespace
        self._pending = dict(_store[0].get(namespace, {}))

    def _get(self, key):
        committed = _store[0].get(self._namespace, {})
        if key not in committed:
            raise OSError(ESP_ERR_NVS_NOT_FOUND, "ESP_ERR_NVS_NOT_FOUND")
        return committed[key]

    def set_i32(self, key, value):
        self._pending[key] = int(value)

    def get_i32(self, key):
        return self._get(key)

    def set_blob(self, key, value):
        self._pending[key] = bytes(value)

    def get_blob(self, key, buffer):
        value = self._get(key)
        if len(buffer) < len(value):
            # The port reads into the caller's buffer as it is; a short one is refused, never grown.
            raise OSError(ESP_ERR_NVS_INVALID_LENGTH, "ESP_ERR_NVS_INVALID_LENGTH")
        buffer[: len(value)] = value
        return len(value)

    def erase_key(self, key):
        self._get(key)
        self._pending.pop(key, None)

    def commit(self):
        _store[0][self._namespace] = dict(self._pending)


def mcu_temperature():
    return 41


def idf_heap_info(capabilities):
    return [(327680, 163840, 131072, 150000)]


HEAP_DATA = 4
HEAP_EXEC = 1
