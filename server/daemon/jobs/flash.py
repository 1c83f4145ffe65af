"""Flash jobs: one per USB port, run in parallel (at most `parallel` at once, the rest queued), each the
CLI's own flash routine (`openbricks_server.flash.flasher`) with its steps and esptool's write progress
turned into job events. A port fails alone: its job says why; the others go on.

A hub whose link goes through the port being flashed (a USB hub the console holds) is handed over for
the job: its link is closed, it shows `flashing`, and it reconnects afterwards under its new name.

Firmware is a file uploaded first (`store_upload`), kept under the data dir by its content hash, or else
the newest release for each board's chip, from the releases the request found (`find_releases`: a cached
image, or one from OPENBRICKS_RELEASES_URL) before any job started.
"""

from __future__ import annotations

import asyncio
import hashlib
import re
from dataclasses import asdict, dataclass
from pathlib import Path

from ulid import ULID

from openbricks_server.daemon.hubs.errors import HubOperationError
from openbricks_server.daemon.jobs.registry import Job, JobFailed, JobRegistry
from openbricks_server.errors import CliError
from openbricks_server.flash.esptool_runner import Esptool
from openbricks_server.flash.flasher import FlashRequest, flash_hub, older_version_refusal
from openbricks_server.flash.image import FirmwareImage, inspect_bytes, inspect_image
from openbricks_server.flash.ports import missing_port
from openbricks_server.flash.releases import Releases

UPLOADS_DIR = "firmware-uploads"
MAX_FIRMWARE_BYTES = 16 * 1024 * 1024  # the largest ESP32 flash
FIRMWARE_ID = re.compile(r"^[0-9a-f]{16}$")
_UNSAFE_NAME = re.compile(r"[^A-Za-z0-9._-]")
DOWNGRADE_HINT = "send allow_downgrade: true to flash it anyway"


@dataclass(frozen=True)
class FlashTarget:
    port: str
    name: str
    actor: object | None = None  # the HubActor whose link goes through `port`, if the console holds one


def hubs_by_port(hubs) -> dict[str, object]:
    """The console's hubs whose link goes through a serial port (USB hubs, virtual hubs' ptys), by port."""
    actors = hubs.list() if hubs is not None else []
    return {a.backend.serial_port: a for a in actors if a.backend.serial_port is not None}


class _JobReport:
    """The flasher's reporter: steps become the job's steps, the write its progress."""

    def __init__(self, jobs: JobRegistry, job: Job):
        self.jobs, self.job = jobs, job

    def step(self, text: str) -> None:
        self.jobs.step(self.job, text)

    def note(self, text: str) -> None:
        self.jobs.step(self.job, f"  {text}")

    def detail(self, text: str) -> None:
        self.jobs.step(self.job, f"  {text}")

    def progress(self, percent: float) -> None:
        self.jobs.progress(self.job, percent)


class FlashJobs:
    def __init__(self, jobs: JobRegistry, data_dir: Path, parallel: int):
        self.jobs = jobs
        self.uploads = Path(data_dir) / UPLOADS_DIR
        self.parallel = parallel
        self._slots = asyncio.Semaphore(parallel)
        self.chips: dict[str, str] = {}  # port -> the chip esptool found there on its last flash

    # -- firmware ---------------------------------------------------------------------------------------

    def store_upload(self, data: bytes, filename: str) -> tuple[str, FirmwareImage]:
        """Check an uploaded image (ImageError if no hub can take it) and keep it; returns (id, image)."""
        name = _UNSAFE_NAME.sub("_", Path(filename).name)[:100] or "firmware.bin"
        inspect_bytes(data, Path(name))  # refuses what no hub can boot, before anything is kept
        firmware_id = hashlib.sha256(data).hexdigest()[:16]
        folder = self.uploads / firmware_id
        folder.mkdir(parents=True, exist_ok=True)
        path = folder / name
        if not path.is_file():
            part = path.with_name(path.name + ".part")
            part.write_bytes(data)
            part.replace(path)
        return firmware_id, inspect_image(path)

    def uploaded(self, firmware_id: str) -> FirmwareImage | None:
        if not FIRMWARE_ID.match(firmware_id):
            return None
        found = sorted(p for p in (self.uploads / firmware_id).glob("*") if not p.name.endswith(".part"))
        return inspect_image(found[0]) if found else None

    # -- jobs -------------------------------------------------------------------------------------------

    def start(
        self,
        targets: list[FlashTarget],
        image: FirmwareImage | None,
        allow_downgrade: bool,
        who: str,
        releases: Releases | None = None,
    ) -> tuple[str, list[Job]]:
        """One job per target, all started now (at most `parallel` flash at once); returns (batch, jobs).
        Without `image`, each board gets the newest release for its chip from `releases`."""
        batch = str(ULID())
        started = []
        for target in targets:
            params = {
                "port": target.port,
                "name": target.name,
                "firmware": str(image.path) if image else None,
                "allow_downgrade": allow_downgrade,
            }
            job = self.jobs.create("flash", target.port, who, params, batch)
            self.jobs.start(job, lambda job, t=target: self._flash(job, t, image, releases, allow_downgrade))
            started.append(job)
        return batch, started

    async def _flash(self, job: Job, target: FlashTarget, image, releases, allow_downgrade: bool) -> dict:
        async with self._slots:
            self.jobs.running(job)
            problem = await asyncio.to_thread(missing_port, target.port)
            if problem:
                raise JobFailed(f"{target.port}: {problem}")
            report = _JobReport(self.jobs, job)
            request = FlashRequest(port=target.port, name=target.name, image=image, releases=releases)
            confirm = (lambda _question: None) if allow_downgrade else older_version_refusal(DOWNGRADE_HINT)
            if target.actor is None:
                result = await flash_hub(request, report, confirm, echo=report.detail)
            else:
                async with target.actor.handed_over("flash", job.who):
                    result = await flash_hub(request, report, confirm, echo=report.detail)
                    target.actor.rename(result.hub_name)
            self.chips[target.port] = result.chip
            return asdict(result)

    # -- probing ----------------------------------------------------------------------------------------

    async def probe(self, targets: list[FlashTarget], who: str) -> list[dict]:
        """The chip on each port, asked of esptool (which resets the board into its bootloader and back):
        one `{"port", "chip", "error"}` per port, probed together; a port that fails says why."""

        async def one(target: FlashTarget) -> dict:
            async with self._slots:
                try:
                    problem = await asyncio.to_thread(missing_port, target.port)
                    if problem:
                        return {"port": target.port, "chip": None, "error": f"{target.port}: {problem}"}
                    if target.actor is None:
                        chip = await Esptool(target.port).probe_chip()
                    else:
                        async with target.actor.handed_over("chip probe", who):
                            chip = await Esptool(target.port).probe_chip()
                except (CliError, HubOperationError) as exc:
                    return {"port": target.port, "chip": None, "error": str(exc)}
            self.chips[target.port] = chip
            return {"port": target.port, "chip": chip, "error": None}

        return list(await asyncio.gather(*(one(target) for target in targets)))
