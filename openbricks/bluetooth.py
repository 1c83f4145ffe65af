"""Bluetooth on/off for the hub, persisted across reboots.

BLE is compiled into every image (it is how `openbricks run` reaches the hub); this module lets the
user switch the radio off and on, keeps that choice in NVS (namespace "openbricks", so a reboot does
not undo it) and brings the Nordic UART REPL bridge up and down with the radio. A hub that has never
been told otherwise comes up with BLE on.

The radio advertises the hub's name, written to NVS by `openbricks flash --name NAME`. A hub without
a name refuses to turn BLE on: several hubs advertising one default name could not be told apart.

MicroPython's `bluetooth` and `esp32` modules are imported where they are used, so this module
imports on builds and hosts that lack them.
"""

NVS_NAMESPACE = "openbricks"
NVS_KEY_ENABLED = "ble_enabled"
NVS_KEY_HUB_NAME = "hub_name"

_ESP_ERR_NVS_NOT_FOUND = -4354
_NAME_BUFFER_BYTES = 64

_listeners = []
_state = {"active": False}


class HubNameNotSetError(Exception):
    """BLE was asked to come on, but the hub was flashed without a name to advertise."""

    def __init__(self):
        super().__init__(
            "this hub has no name, so BLE stays off: name it with `openbricks flash --name NAME` "
            "(or write NVS namespace '%s' key '%s')" % (NVS_NAMESPACE, NVS_KEY_HUB_NAME),
        )


def _nvs():
    import esp32

    return esp32.NVS(NVS_NAMESPACE)


def _missing(err):
    return err.args and err.args[0] == _ESP_ERR_NVS_NOT_FOUND


def hub_name():
    """The name flashed into this hub (str), or None if it has none."""
    buf = bytearray(_NAME_BUFFER_BYTES)
    try:
        n = _nvs().get_blob(NVS_KEY_HUB_NAME, buf)
    except OSError as err:
        if _missing(err):
            return None
        raise
    name = bytes(buf[:n]).decode()
    return name or None


def is_enabled():
    """The persisted flag: True if BLE should be on (also when nothing was ever stored)."""
    try:
        return _nvs().get_i32(NVS_KEY_ENABLED) != 0
    except OSError as err:
        if _missing(err):
            return True
        raise


def is_active():
    """True while the radio is on and the REPL bridge is up, i.e. the hub can be found and reached."""
    return _state["active"]


def set_enabled(enabled):
    """Persist `enabled` and apply it to the radio now.

    Turning BLE on raises HubNameNotSetError on a hub without a name (and changes nothing); turning it
    off always works, so a nameless hub can still be silenced.
    """
    enabled = bool(enabled)
    if enabled and hub_name() is None:
        raise HubNameNotSetError()
    nvs = _nvs()
    nvs.set_i32(NVS_KEY_ENABLED, 1 if enabled else 0)
    nvs.commit()
    _apply(enabled)


def toggle():
    """Flip BLE and return the new state.

    Flips what the radio is doing right now (what the status LED shows), which differs from the
    persisted flag only on a nameless hub whose stored state says "on".
    """
    enabled = not is_active()
    set_enabled(enabled)
    return enabled


def apply_persisted_state():
    """Bring the radio to the persisted state; call once at boot. Returns whether BLE came up.

    A hub without a name whose stored state says "on" gets a one-line warning and stays off rather
    than an exception: at boot a traceback can be lost before USB is up, and the hub must still boot
    so it can be named.
    """
    enabled = is_enabled()
    if enabled and hub_name() is None:
        print("openbricks: %s" % HubNameNotSetError().args[0])
        enabled = False
    _apply(enabled)
    return enabled


def add_state_listener(callback):
    """Call `callback(active)` after every state change. Adding the same callback again is a no-op."""
    if callback not in _listeners:
        _listeners.append(callback)


def remove_state_listener(callback):
    """Forget a callback added with add_state_listener(); unknown callbacks are a no-op."""
    if callback in _listeners:
        _listeners.remove(callback)


def _apply(enabled):
    import bluetooth

    from openbricks import ble_repl

    radio = bluetooth.BLE()
    if enabled:
        radio.active(True)
        ble_repl.start()
    else:
        # The bridge goes first so the REPL is never left duplicated onto a dead radio.
        ble_repl.stop()
        radio.active(False)
    _state["active"] = enabled
    _notify(enabled)


def _notify(active):
    # Every listener hears about the change even if one of them fails; the first failure is raised.
    failure = None
    for callback in tuple(_listeners):
        try:
            callback(active)
        except Exception as err:
            if failure is None:
                failure = err
    if failure is not None:
        raise failure


def reset_state():
    """Forget listeners and the applied state without touching the radio (a fresh start in tests)."""
    del _listeners[:]
    _state["active"] = False
