"""Worlds a team uploads to the console: a world file and its mat image, kept in the console's data
folder (DATA/worlds/NAME/) so every sim run and sweep of the console can use them by name.

An upload is one zip holding the world file (.toml) and the files it names (the page zips a world
file and its mat itself when they are picked as two files). It is checked whole by the simulator's
own world-file reader before anything is kept: every problem comes back as one line with the key
and the line, and a refused upload leaves nothing behind. A new upload of the same name replaces
the old one, the way saving a program replaces it.
"""

from __future__ import annotations

import io
import re
import shutil
import tempfile
import zipfile
from pathlib import Path, PurePosixPath

from openbricks_sim.job import WORLD_ALIASES
from openbricks_sim.world_file import MAT_SUFFIXES, WORLD_SUFFIX, WorldFileError, WorldSpec, load

MAX_UPLOAD_BYTES = 64 * 2**20  # a high-resolution mat as PNG, with room to spare
MAX_FILES = 16
_NAME = re.compile(r"[^a-z0-9_-]+")


class WorldUploadError(ValueError):
    """An upload that cannot be kept: `problems` holds one line each (a world file's own lines)."""

    def __init__(self, message: str, problems: list[str] | None = None):
        super().__init__(message)
        self.problems = problems or [message]


def world_name(title: str) -> str:
    """The name a world is listed and run by: its file's name, lower-case, letters, digits, _ and -."""
    return _NAME.sub("_", title.strip().lower()).strip("_")[:60]


class WorldStore:
    """The uploaded worlds under one folder, one sub-folder each."""

    def __init__(self, folder: Path):
        self.folder = folder

    def _world_file(self, name: str) -> Path | None:
        if not name or world_name(name) != name:
            return None
        folder = self.folder / name
        files = sorted(folder.glob(f"*{WORLD_SUFFIX}")) if folder.is_dir() else []
        return files[0] if files else None

    def path(self, name: str) -> Path | None:
        """The world file of an uploaded world, or None."""
        return self._world_file(name)

    def list(self) -> list[dict]:
        worlds = []
        if not self.folder.is_dir():
            return worlds
        for folder in sorted(p for p in self.folder.iterdir() if p.is_dir() and not p.name.startswith(".")):
            path = self._world_file(folder.name)
            if path is None:
                continue
            try:
                spec = load(path)
            except WorldFileError:
                continue  # its mat was removed by hand: not runnable, not listed
            worlds.append(_summary(folder.name, spec))
        return worlds

    def save_zip(self, data: bytes) -> dict:
        """Check and keep an uploaded zip; returns the world's summary. Raises WorldUploadError."""
        try:
            archive = zipfile.ZipFile(io.BytesIO(data))
        except zipfile.BadZipFile:
            raise WorldUploadError(
                "the upload is not a zip: send a zip of the world file (.toml) and its mat image"
            ) from None
        entries = [e for e in archive.infolist() if not e.is_dir() and not _hidden(e.filename)]
        if len(entries) > MAX_FILES:
            raise WorldUploadError(f"the zip holds {len(entries)} files; a world needs its .toml and its mat")
        if sum(e.file_size for e in entries) > MAX_UPLOAD_BYTES:
            raise WorldUploadError(f"the zip unpacks to more than {MAX_UPLOAD_BYTES // 2**20} MB")
        tomls = [e for e in entries if e.filename.lower().endswith(WORLD_SUFFIX)]
        if len(tomls) != 1:
            raise WorldUploadError(
                f"the zip holds {len(tomls)} world files (.toml): put exactly one in, beside its mat image"
            )
        self.folder.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=".upload-", dir=self.folder))
        try:
            for entry in entries:
                base = PurePosixPath(entry.filename.replace("\\", "/")).name  # never a path out of the folder
                if base.lower().endswith(WORLD_SUFFIX) or base.lower().endswith(MAT_SUFFIXES):
                    (staging / base).write_bytes(archive.read(entry))
            world_path = staging / PurePosixPath(tomls[0].filename.replace("\\", "/")).name
            try:
                spec = load(world_path)
            except WorldFileError as exc:
                problems = [p.replace(str(staging) + "/", "") for p in exc.problems]
                raise WorldUploadError("the world file has problems", problems) from None
            _check_image(spec)
            name = world_name(spec.name)
            if not name:
                raise WorldUploadError(f"the world's name {spec.name!r} has no letters or digits: rename it")
            if name in WORLD_ALIASES:
                raise WorldUploadError(f"{name!r} is a built-in world's name: give yours another name")
            target = self.folder / name
            if target.exists():
                shutil.rmtree(target)
            staging.rename(target)
            return _summary(name, load(target / world_path.name))
        finally:
            if staging.exists():
                shutil.rmtree(staging, ignore_errors=True)


def _hidden(filename: str) -> bool:
    parts = PurePosixPath(filename.replace("\\", "/")).parts
    return any(p.startswith(".") or p == "__MACOSX" for p in parts)


def _check_image(spec: WorldSpec) -> None:
    """The mat must be an image the simulator can read: checked from its header, not decoded."""
    if spec.mat is None or spec.mat.suffix.lower() == ".pdf":
        if spec.mat is not None and not spec.mat.read_bytes()[:5] == b"%PDF-":
            raise WorldUploadError(f"mat: {spec.mat.name} is not a PDF")
        return
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(spec.mat) as image:
            image.verify()
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise WorldUploadError(f"mat: {spec.mat.name} is not a readable PNG or JPEG image ({exc})") from None


def _summary(name: str, spec: WorldSpec) -> dict:
    return {
        "name": name,
        "description": spec.description,
        "size_mm": list(spec.size_mm),
        "uploaded": True,
        "props": sum(p.count for p in spec.props),
        "zones": len(spec.zones),
    }
