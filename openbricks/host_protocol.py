"""What a hub and a host agree on for host calls: how a frame starts, and what one call takes.

The hub writes the frames and enforces the limits (openbricks.host_calls, openbricks.tools); the
host parses the frames, checks a program's size before it scans and uploads, and asks for files in
slices of the hub's size. Plain values, importable without the hub's hardware, so the host reads
them from here rather than restating them; and the host's one reading of a plot() frame (parse_plot).
"""

FRAME_PREFIX = "@openbricks:"  # then the nonce, the kind and its JSON: `@openbricks:<nonce> <kind> <json>`
MAX_PROGRAM_BYTES = 256 * 1024  # staged program ceiling (bytes after decompression)
# Largest slice of a file one read_file call returns: the bytes, their base64 text and the JSON line
# live side by side on the hub while it prints (~4.7x this), so it stays far below its free RAM.
READ_FILE_MAX_BYTES = 4096
READ_CHUNK_BYTES = 8192  # largest slice of a run log returned by one read_run call


def parse_plot(payload):
    """(name, value) from a plot frame's JSON (what follows `<prefix><nonce> plot `), or None when it is
    not a sample, so its line stays output. The one reading of plot() frames, for every host that
    watches a run (the console for a hub or a sim run, `openbricks sim run`); the hub only writes them.
    """
    import json
    import math

    try:
        data = json.loads(payload)
    except ValueError:
        return None
    if not isinstance(data, dict):
        return None
    name, value = data.get("name"), data.get("value")
    if not isinstance(name, str) or not name or isinstance(value, bool):
        return None
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        return None
    return name, float(value)
