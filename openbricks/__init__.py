"""openbricks: the hub runtime frozen into the firmware (drivers, interfaces, robotics, services)."""

__version__ = "2.7.1"

# Where the flasher records its provenance verdict after writing an image: the hub's NVS (namespace
# "ob_firmware", key "provenance", a blob "<official|customized> <version>"). NVS rather than a file
# on the user filesystem, so deleting files or reformatting the VFS can't fake or lose it. The record
# names the version it was made for: an image flashed later by another tool, which leaves the old
# record behind, then reads as (customized), because nothing vouched for it.
PROVENANCE_NAMESPACE = "ob_firmware"
PROVENANCE_KEY = "provenance"
_VERDICTS = ("official", "customized")


def _flashed_hub_name():
    """The name `openbricks flash --name` wrote to NVS, or None (no name, or no NVS on this build)."""
    try:
        from openbricks.bluetooth import hub_name

        return hub_name()
    except (ImportError, AttributeError, OSError, ValueError):
        return None


# The hub's name (manual 7.8: NVS-backed), read once at boot; BLE refuses to advertise without one.
# host_calls.set_hub_name() keeps it current when the host renames the hub.
HUB_NAME = _flashed_hub_name()


def provenance():
    """ "official" when the flasher verified this exact version's signature, else "customized"."""
    try:
        import esp32

        buf = bytearray(48)
        size = esp32.NVS(PROVENANCE_NAMESPACE).get_blob(PROVENANCE_KEY, buf)
        verdict, version = bytes(buf[:size]).decode().split(" ", 1)
    except (ImportError, AttributeError, OSError, ValueError):
        return "customized"  # no record (or no NVS at all): nothing vouches for this image
    return "official" if verdict == "official" and version == __version__ else "customized"


def record_provenance(verdict):
    """Store the flasher's verdict ("official" / "customized") for the running firmware version."""
    if verdict not in _VERDICTS:
        raise ValueError("provenance verdict must be 'official' or 'customized', not %r" % (verdict,))
    import esp32

    nvs = esp32.NVS(PROVENANCE_NAMESPACE)
    nvs.set_blob(PROVENANCE_KEY, ("%s %s" % (verdict, __version__)).encode())
    nvs.commit()


def firmware_label():
    """The firmware's version with its provenance, e.g. "2.7.1 (official)" or "2.7.1 (customized)"."""
    return "%s (%s)" % (__version__, provenance())
