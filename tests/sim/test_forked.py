"""A forked child: its exit status as an interpreter would give it, its descriptors, and its handle."""

import os
import signal
import subprocess
import sys
import time

import pytest

from openbricks_sim.forked import can_fork, fork_child

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="fork() is a POSIX call")


def run(main, **fds):
    read_end, write_end = os.pipe()
    child = fork_child(main, stdout=write_end, stderr=write_end, **fds)
    os.close(write_end)
    with os.fdopen(read_end, "r") as pipe:
        text = pipe.read()
    return child.wait(timeout=30), text


def test_the_exit_status_is_the_one_an_interpreter_would_give():
    assert run(lambda: None) == (0, "")
    assert run(lambda: 7) == (7, "")
    assert run(lambda: sys.exit(3)) == (3, "")
    assert run(lambda: sys.exit("gone wrong")) == (1, "gone wrong\n")
    status, text = run(lambda: 1 / 0)
    assert status == 1 and "ZeroDivisionError" in text and text.startswith("Traceback")


def test_the_child_runs_in_a_session_of_its_own_with_fresh_signal_handlers():
    previous = signal.signal(signal.SIGTERM, lambda *_: print("the parent's handler"))
    try:

        def main():
            print(os.getsid(0) == os.getpid(), signal.getsignal(signal.SIGTERM) == signal.SIG_DFL)

        assert run(main) == (0, "True True\n")
    finally:
        signal.signal(signal.SIGTERM, previous)


def test_extra_descriptors_are_the_childs_3_4_and_nothing_else_is_open():
    spare_read, spare_write = os.pipe()  # the parent's: the child must not hold it
    first_read, first_write = os.pipe()

    def main():
        os.write(3, b"on three")
        print(sorted(int(fd) for fd in os.listdir("/proc/self/fd") if int(fd) > 2))

    try:
        status, text = run(main, extra_fds=(first_write,))
        os.close(first_write)
        assert os.read(first_read, 100) == b"on three"
        assert status == 0 and text.strip() in ("[3]", "[3, 4]")  # 4: listdir's own descriptor
    finally:
        for fd in (spare_read, spare_write, first_read):
            os.close(fd)


def test_wait_times_out_and_kill_ends_the_child():
    child = fork_child(lambda: time.sleep(60))
    started = time.monotonic()
    with pytest.raises(subprocess.TimeoutExpired):
        child.wait(timeout=0.2)
    assert 0.15 < time.monotonic() - started < 5 and child.poll() is None
    child.kill()
    assert child.wait(timeout=10) == -signal.SIGKILL and child.poll() == -signal.SIGKILL


def test_forking_is_refused_with_a_second_thread_running():
    import threading

    stop = threading.Event()
    worker = threading.Thread(target=stop.wait)
    worker.start()
    try:
        assert not can_fork()
    finally:
        stop.set()
        worker.join()
