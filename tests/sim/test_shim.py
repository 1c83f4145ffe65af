"""The MicroPython surface a program sees in the simulator, and that none of it outlives the run."""

import sys

import pytest

from openbricks_sim import shim
from openbricks_sim.shim import Shim, ShimBusyError
from openbricks_sim.simulation import Simulation


@pytest.fixture
def sim():
    s = Simulation("empty", "st3032", epoch_ms=1_700_000_000_000)
    assert s.physics.model  # the robot's own devices on the board first: tests put theirs over them
    yield s
    s.close()


def test_installing_and_removing_the_shim_leaves_sys_modules_as_it_was(sim):
    before = {name: sys.modules.get(name) for name in shim.SHIMMED}
    runtime_before = {name: m for name, m in sys.modules.items() if name.split(".")[0] == "openbricks"}
    with Shim(sim):
        import time

        import machine

        from openbricks.drivers import st3032

        assert machine.__name__ == "openbricks_sim.shim.machine"
        assert hasattr(time, "sleep_ms")
        assert st3032 is not runtime_before.get("openbricks.drivers.st3032"), (
            "a fresh runtime, bound to the shim"
        )
    assert {name: sys.modules.get(name) for name in shim.SHIMMED} == before
    runtime_after = {name: m for name, m in sys.modules.items() if name.split(".")[0] == "openbricks"}
    assert runtime_after == runtime_before


def test_one_simulated_hub_per_process_at_a_time(sim):
    with Shim(sim), pytest.raises(ShimBusyError):
        Shim(sim).install()


def test_sleeping_moves_the_robot_and_ticks_read_simulated_time(sim):
    with Shim(sim):
        import time

        start = time.ticks_ms()
        time.sleep_ms(250)
        assert time.ticks_diff(time.ticks_ms(), start) == 250
        assert sim.physics.now_ms == 250
        assert time.time() == 1_700_000_000 and time.gmtime()[0] == 2023


def test_a_loop_that_only_reads_the_clock_still_lets_time_pass(sim):
    with Shim(sim):
        import time

        deadline = time.ticks_add(time.ticks_ms(), 20)
        spins = 0
        while time.ticks_diff(deadline, time.ticks_ms()) > 0:
            spins += 1
        assert sim.physics.now_ms >= 20 and spins > 100


def test_machine_timer_callbacks_run_on_the_simulated_clock(sim):
    with Shim(sim):
        import time

        import machine

        fired = []
        timer = machine.Timer(0)
        timer.init(mode=machine.Timer.PERIODIC, period=100, callback=lambda t: fired.append(time.ticks_ms()))
        time.sleep_ms(350)
        timer.deinit()
        time.sleep_ms(200)
        assert fired == [100, 200, 300]


def test_uart_replies_arrive_after_their_time_on_the_wire(sim):
    with Shim(sim):
        import time

        import machine

        import openbricks_native

        uart = machine.UART(1, baudrate=1_000_000, tx=14, rx=41)
        uart.write(openbricks_native.scs.ping(1))
        assert uart.any() == 0, "nothing can have come back yet"
        time.sleep_us(200)
        assert uart.read() == openbricks_native.scs.status(1, 0, b"")


class Register:
    """A one-register I2C chip: reads return what was last written."""

    def __init__(self):
        self.value = b"\x00"

    def read_mem(self, reg, n, addrsize=8):
        return self.value * n

    def write_mem(self, reg, data, addrsize=8):
        self.value = data[:1]


def test_i2c_reaches_attached_devices_and_takes_wire_time(sim):
    sim.board.attach_i2c(1, 0x29, Register())  # the second controller: nothing else is wired there
    with Shim(sim):
        import machine

        i2c = machine.I2C(1, scl=machine.Pin(4), sda=machine.Pin(5), freq=400_000)
        assert i2c.scan() == [0x29]
        t0 = sim.clock.now_us()
        i2c.writeto_mem(0x29, 0x80, b"\x03")
        assert i2c.readfrom_mem(0x29, 0x80, 2) == b"\x03\x03"
        assert sim.clock.now_us() - t0 >= 100, "two register transactions at 400 kHz"
        with pytest.raises(OSError):
            i2c.readfrom_mem(0x30, 0, 1)


def test_inputs_analog_and_outputs_go_through_the_board(sim):
    sim.board.set_analog(3, lambda: 1234)
    sim.board.set_pulse(5, 580)
    seen = []
    sim.board.watch_output(21, lambda pin, level: seen.append((pin, level)))
    with Shim(sim):
        import machine

        assert machine.ADC(machine.Pin(3)).read() == 1234
        assert machine.time_pulse_us(machine.Pin(5), 1, 30_000) == 580
        button = machine.Pin(39, machine.Pin.IN, machine.Pin.PULL_UP)
        assert button.value() == 1, "an unconnected pulled-up input reads high"
        presses = []
        button.irq(lambda pin: presses.append(pin.value()), trigger=machine.Pin.IRQ_FALLING)
        sim.board.set_input(39, 0)
        assert button.value() == 0 and presses == [0]
        machine.Pin(21, machine.Pin.OUT).on()
        assert seen == [(21, 1)]


def test_nvs_survives_a_second_run_on_the_same_store():
    store = {}
    for expected in (None, 7):
        s = Simulation("empty", "st3032", nvs=store)
        try:
            with Shim(s):
                import esp32

                nvs = esp32.NVS("openbricks")
                if expected is None:
                    with pytest.raises(OSError):
                        nvs.get_i32("runs")
                    nvs.set_i32("runs", 7)
                    nvs.commit()
                else:
                    assert nvs.get_i32("runs") == expected
        finally:
            s.close()


def test_the_native_module_carries_the_cores_and_the_serial_bus_engine(sim):
    with Shim(sim):
        import _openbricks_native

        import openbricks_native

        assert _openbricks_native.motor_process is openbricks_native.motor_process
        assert _openbricks_native.Servo is openbricks_native.Servo
        assert _openbricks_native.serial_bus(1) is sim.serial_bus(1)


def test_a_failing_timer_callback_is_printed_and_the_timer_keeps_firing(sim, capsys):
    with Shim(sim):
        import time

        import machine

        fired = []

        def failing(_t):
            fired.append(time.ticks_ms())
            raise ValueError("callback bug")

        timer = machine.Timer(1)
        timer.init(period=10, callback=failing)
        time.sleep_ms(30)
        timer.deinit()
        assert fired == [10, 20, 30]
    assert capsys.readouterr().out.count("ValueError: callback bug") == 3


def test_scheduled_callbacks_run_later_and_a_full_queue_refuses_more(sim):
    with Shim(sim):
        import time

        import micropython

        ran = []
        for i in range(micropython.SCHEDULER_DEPTH):
            micropython.schedule(ran.append, i)
        with pytest.raises(RuntimeError, match="schedule queue full"):
            micropython.schedule(ran.append, "one too many")
        assert ran == [], "nothing runs inside schedule()"
        time.sleep_ms(1)
        assert ran == list(range(micropython.SCHEDULER_DEPTH))
        micropython.schedule(ran.append, "room again")
        time.sleep_ms(1)
        assert ran[-1] == "room again"


def test_get_blob_refuses_a_buffer_shorter_than_the_blob(sim):
    with Shim(sim):
        import esp32

        nvs = esp32.NVS("shim")
        nvs.set_blob("name", b"twelve bytes")
        nvs.commit()
        with pytest.raises(OSError) as err:
            nvs.get_blob("name", bytearray(4))
        assert err.value.args[0] == -4364  # ESP_ERR_NVS_INVALID_LENGTH
        assert nvs.get_blob("name", bytearray(12)) == 12
