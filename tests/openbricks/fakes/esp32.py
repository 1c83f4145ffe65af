"""A fake `esp32` module: NVS namespaces that survive a simulated reboot within one test."""

_store = {}  # namespace -> {key: value}; committed values only

# The port raises ESP-IDF errors as OSError(-code, name).
ESP_ERR_NVS_NOT_FOUND = -4354
ESP_ERR_NVS_INVALID_LENGTH = -4364


def reset():
    _store.clear()


class NVS:
    def __init__(self, namespace):
        self._namespace = namespace
        self._pending = dict(_store.get(namespace, {}))

    def _get(self, key):
        committed = _store.get(self._namespace, {})
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
        _store[self._namespace] = dict(self._pending)
