"""The job registry with a real store and event bus: a job's life as a client sees it (events and the
stored row), failures in the user's words, progress only on whole percents, and what a restart or a
shutdown leaves behind."""

from __future__ import annotations

import asyncio
import json

from openbricks_server.daemon.events import EventBus
from openbricks_server.daemon.jobs.registry import JobFailed, JobRegistry
from openbricks_server.daemon.store import Store
from openbricks_server.daemon.store.jobs import INTERRUPTED
from openbricks_server.errors import CliError


def _registry(path):
    store = Store(path / "console.sqlite3")
    bus = EventBus(store, "boot", store.events.begin_boot("boot"), 1000, 100)
    subscriber, _ = bus.subscribe()
    return store, JobRegistry(store, bus), subscriber


def _events(subscriber) -> list[tuple[str, dict]]:
    out = []
    while not subscriber.queue.empty():
        event = json.loads(subscriber.queue.get_nowait()[1])
        out.append((event["type"], event["data"]))
    return out


def test_a_job_is_announced_stored_and_finished_with_its_result(tmp_path):
    async def main():
        store, jobs, subscriber = _registry(tmp_path)

        async def work(job):
            jobs.running(job)
            jobs.step(job, "write the firmware")
            for percent in (0.0, 0.4, 10.0, 10.9, 55.5, 100.0):
                jobs.progress(job, percent)
            return {"hub_name": "RobotA"}

        job = jobs.create("flash", "/dev/ttyUSB0", "local", {"port": "/dev/ttyUSB0"}, batch="b1")
        await jobs.start(job, work)
        events = _events(subscriber)
        states = [data["state"] for kind, data in events if kind == "job"]
        assert states == ["queued", "running", "running", "done"]
        assert [data["progress"] for kind, data in events if kind == "job_progress"] == [
            0.0,
            10.0,
            55.5,
            100.0,
        ]
        stored = store.jobs.get(job.job_id)
        assert stored["state"] == "done" and stored["result"] == {"hub_name": "RobotA"}
        assert stored["steps"] == ["write the firmware"] and stored["batch"] == "b1"
        assert jobs.list("flash", "b1")[0]["job_id"] == job.job_id and jobs.list("servo_scan") == []
        store.close()

    asyncio.run(main())


def test_failures_keep_the_users_words_and_a_bug_fails_only_its_job(tmp_path):
    async def main():
        store, jobs, _ = _registry(tmp_path)
        reasons = {
            "cli": CliError("esptool failed probing the chip on /dev/ttyUSB0: no answer"),
            "job": JobFailed("/dev/ttyUSB9: there is no such port"),
            "bug": ZeroDivisionError("division by zero"),
        }
        started = {}
        for name, exc in reasons.items():

            async def work(job, exc=exc):
                raise exc

            started[name] = jobs.create("flash", name, "local", {})
            await jobs.start(started[name], work)
        got = {name: store.jobs.get(job.job_id) for name, job in started.items()}
        assert {g["state"] for g in got.values()} == {"failed"}
        assert got["cli"]["message"] == "esptool failed probing the chip on /dev/ttyUSB0: no answer"
        assert got["job"]["message"] == "/dev/ttyUSB9: there is no such port"
        assert got["bug"]["message"].startswith("unexpected error (ZeroDivisionError: division by zero)")
        store.close()

    asyncio.run(main())


def test_shutdown_cancels_running_jobs_and_a_restart_marks_unfinished_ones(tmp_path):
    async def main():
        store, jobs, _ = _registry(tmp_path)

        async def forever(job):
            jobs.running(job)
            await asyncio.sleep(3600)

        job = jobs.create("flash", "/dev/ttyUSB0", "local", {})
        jobs.start(job, forever)
        await asyncio.sleep(0.05)
        waiting = asyncio.create_task(jobs.wait(job.job_id, 30))
        await jobs.close()
        await waiting
        assert store.jobs.get(job.job_id)["state"] == "cancelled"
        left = jobs.create("flash", "/dev/ttyUSB1", "local", {})  # never started: as after a kill -9
        store.close()
        return left.job_id

    left = asyncio.run(main())
    store = Store(tmp_path / "console.sqlite3")
    assert store.jobs.mark_interrupted() == 1
    row = store.jobs.get(left)
    assert row["state"] == "failed" and row["message"] == INTERRUPTED
    store.close()


def test_the_history_lists_jobs_by_state_and_pages_back_through_older_ones(tmp_path):
    async def main():
        store, jobs, _ = _registry(tmp_path)

        async def fine(job):
            return {}

        async def broken(job):
            raise JobFailed("no answer from the bootloader")

        made = []
        for work in (fine, broken, fine, broken, fine):
            job = jobs.create("flash", f"/dev/ttyUSB{len(made)}", "local", {})
            made.append(job.job_id)
            await jobs.start(job, work)
            await asyncio.sleep(0.003)  # ids order by their millisecond, random within one
        newest_first = made[::-1]
        assert [j["job_id"] for j in jobs.list()] == newest_first
        failed = jobs.list(state="failed")
        assert [j["job_id"] for j in failed] == [made[3], made[1]]
        assert failed[0]["message"] == "no answer from the bootloader"
        page = jobs.list(limit=2)
        older = jobs.list(limit=2, before=page[-1]["job_id"])
        assert [j["job_id"] for j in page + older] == newest_first[:4]
        store.close()

    asyncio.run(main())


def test_each_finished_job_is_audited_with_its_real_outcome(tmp_path):
    """The request that started a flash is audited as started (202); the audit log's word for the job
    itself must be its outcome, so a failed flash never reads "done"."""

    async def main():
        store, jobs, _ = _registry(tmp_path)

        async def fails(job):
            raise JobFailed("there is no such port")

        async def works(job):
            return {}

        bad = jobs.create("flash", "/dev/ttyUSB97", "mentor", {})
        await jobs.start(bad, fails)
        good = jobs.create("flash", "/dev/ttyUSB0", "mentor", {})
        await jobs.start(good, works)
        entries = [(e["who"], e["action"], e["status"]) for e in reversed(store.audit.list())]
        assert entries == [("mentor", "flash /dev/ttyUSB97", 500), ("mentor", "flash /dev/ttyUSB0", 200)]
        store.close()

    asyncio.run(main())
