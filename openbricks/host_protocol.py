"""What a hub and a host agree on for host calls: how a frame starts, and what one call takes.

The hub writes the frames and enforces the limits (openbricks.host_calls, openbricks.tools); the
host parses the frames, checks a program's size before it scans and uploads, and asks for files in
slices of the hub's size. Plain values, importable without the hub's hardware, so the host reads
them from here rather than restating them.
"""

FRAME_PREFIX = "@openbricks:"  # then the nonce, the kind and its JSON: `@openbricks:<nonce> <kind> <json>`
MAX_PROGRAM_BYTES = 256 * 1024  # staged program ceiling (bytes after decompression)
# Largest slice of a file one read_file call returns: the bytes, their base64 text and the JSON line
# live side by side on the hub while it prints (~4.7x this), so it stays far below its free RAM.
READ_FILE_MAX_BYTES = 4096
READ_CHUNK_BYTES = 8192  # largest slice of a run log returned by one read_run call
