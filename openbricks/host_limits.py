"""What a hub takes from a host in one host call: the limits both sides go by.

The hub enforces them (openbricks.host_calls); the host checks a program's size before it scans and
uploads, and asks for files in slices of the hub's size. Plain numbers, importable without the
hub's hardware, so the host reads them from here rather than restating them.
"""

MAX_PROGRAM_BYTES = 256 * 1024  # staged program ceiling (bytes after decompression)
# Largest slice of a file one read_file call returns: the bytes, their base64 text and the JSON line
# live side by side on the hub while it prints (~4.7x this), so it stays far below its free RAM.
READ_FILE_MAX_BYTES = 4096
READ_CHUNK_BYTES = 8192  # largest slice of a run log returned by one read_run call
