"""servo-id over a USB adapter: scan, the --old-id rule, re-ID verified by read-back, clear refusals."""

import subprocess
import sys

import pytest

from openbricks_native import scs

from .servo_rig import ServoRig


@pytest.fixture
def rig(request):
    ids, echo = request.param
    rig = ServoRig(ids, echo=echo)
    yield rig
    rig.close()


def servo_id(port, *args):
    return subprocess.run(
        [sys.executable, "-m", "openbricks_server.cli", "servo-id", "-p", port, "--timeout", "0.005", *args],
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.mark.parametrize("rig", [([1, 7], False), ([1, 7], True)], indirect=True, ids=["plain", "echoing"])
def test_scan_lists_the_ids_that_answer(rig):
    done = servo_id(rig.port, "--scan")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"servo ids on the bus on {rig.port}: 1, 7"


@pytest.mark.parametrize("rig", [([1], True)], indirect=True)
def test_a_lone_servo_is_re_ided_and_verified(rig):
    done = servo_id(rig.port, "4")
    assert done.returncode == 0, done.stderr
    assert "servo 1 is now id 4 (read back from the servo)" in done.stdout
    assert rig.ids() == [4]
    assert rig.bus.servo(4).regs[scs.REG_LOCK] == 1  # EEPROM locked again


@pytest.mark.parametrize("rig", [([1, 2], False)], indirect=True)
def test_several_servos_need_old_id_and_taken_ids_are_refused(rig):
    done = servo_id(rig.port, "5")
    assert done.returncode == 1 and "2 servos answer (ids 1, 2): pass --old-id" in done.stderr
    done = servo_id(rig.port, "2", "--old-id", "1")
    assert done.returncode == 1 and "id 2 is already taken" in done.stderr
    done = servo_id(rig.port, "5", "--old-id", "9")
    assert done.returncode == 1 and "no servo answers at --old-id 9; the bus has ids 1, 2" in done.stderr
    assert rig.ids() == [1, 2]
    done = servo_id(rig.port, "5", "--old-id", "2")
    assert done.returncode == 0 and rig.ids() == [1, 5]


@pytest.mark.parametrize("rig", [([], False)], indirect=True)
def test_an_empty_bus_and_bad_ids_are_user_errors(rig):
    done = servo_id(rig.port, "3")
    assert done.returncode == 1 and "no servo answers on the bus" in done.stderr
    done = servo_id(rig.port, "254")
    assert done.returncode == 2 and "new id 254: servo bus ids are 0..253" in done.stderr  # a usage error
    assert "Traceback" not in done.stderr


def test_a_port_that_does_not_exist_is_reported():
    done = servo_id("/dev/nonexistent-adapter", "--scan")
    assert done.returncode == 1 and "cannot open /dev/nonexistent-adapter" in done.stderr


class _LateFrameThenEcho:
    """An echoing adapter under load: a late reply to the previous request arrives first, then the
    echo of this one, and no servo answers."""

    def __init__(self, late_frame):
        self.late_frame = late_frame
        self.pending = b""

    def reset_input_buffer(self):
        pass  # the late frame lands just after the flush, as it does on a busy host

    def write(self, data):
        self.pending = self.late_frame + bytes(data)

    def flush(self):
        pass

    def read(self, n):
        out, self.pending = self.pending[:n], self.pending[n:]
        return out


def test_an_echo_behind_a_late_frame_is_not_taken_for_a_servo_reply(monkeypatch):
    # Regression: the echo was skipped only at the start of the buffer, so an echoed ping behind a
    # late frame read as a reply from the pinged id and the scan listed phantom servos.
    from openbricks_native import scs
    from openbricks_server.servo_id import UsbServoBus

    bus = UsbServoBus.__new__(UsbServoBus)
    bus.scs, bus.port, bus.timeout_s = scs, "/dev/fake", 0.02
    bus.serial = _LateFrameThenEcho(late_frame=scs.status(1, 0, b""))
    assert not bus.ping(241)
