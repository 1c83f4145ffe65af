"""The BLE toggle button, and the status LED that tells the user what the hub is doing.

One short press (a full press-release cycle) on the BLE button flips Bluetooth; the choice is
persisted by openbricks.bluetooth. The same timer tick owns the status LED, so one place decides
what it shows, in this order:

1. press acknowledgment: a program-button press flashes red (the press that starts a run) or green
   (the press that stops one) for ACK_MS, the moment the launcher recognises it (`notify_press`);
2. while a program runs: the state colour flashing at 2 Hz ("robot running");
3. otherwise: the state colour held solid, blue with BLE on, yellow with BLE off.

A single-colour LED cannot show colours: it blinks at 2 Hz during a run, lights for ACK_MS on a
press and is dark at idle.

The tick reads the clock instead of counting ticks, so a late or dropped timer callback costs a
repaint, never the flash rhythm.
"""

import time

from micropython import const

from openbricks import bluetooth, timers

DEFAULT_POLL_MS = const(50)
DEFAULT_TIMER_ID = timers.BLUETOOTH_BUTTON
_TIMER_ROLE = "Bluetooth button"
DEFAULT_COLOR_ON = (0, 0, 255)  # blue
# A WS2812's green die is much brighter than its red one: (255, 255, 0) reads as lime, this as yellow.
DEFAULT_COLOR_OFF = (255, 160, 0)
COLOR_START_PRESS = (255, 0, 0)
COLOR_STOP_PRESS = (0, 255, 0)
RUN_FLASH_HALF_PERIOD_MS = const(250)  # 2 Hz
ACK_MS = const(300)
DEBOUNCE_TICKS = const(2)

_DARK = (0, 0, 0)
_ACK_NONE = const(0)
_ACK_START = const(1)
_ACK_STOP = const(2)

IDENTIFY_HALF_PERIOD_MS = const(125)  # 4 Hz white blink: unlike anything else the LED shows
COLOR_IDENTIFY = (255, 255, 255)

# Written by notify_press() from any context (the launcher's timer, the hard-tick stop path), read
# and cleared by the watcher's tick: a plain int store is atomic on both interpreters.
_pending_ack = [_ACK_NONE]
_identify_until = [None]  # ticks_ms when identify() ends, or None
_running_watcher = [None]  # the BluetoothToggleButton painting the LED, if one is started


def notify_press(stop=False):
    """Record a program-button press for the LED: red for a start press, green for `stop=True`.

    Rendered by the running BluetoothToggleButton on its next tick; cheap and safe from any context.
    """
    _pending_ack[0] = _ACK_STOP if stop else _ACK_START


def identify(duration_ms):
    """Blink the status LED white at 4 Hz for `duration_ms`, so a person can tell which hub this is.

    Returns False when no started watcher owns an LED (nothing can blink), True otherwise. The blink
    takes precedence over everything but a press acknowledgment, then the LED shows the hub's state.
    """
    watcher = _running_watcher[0]
    if watcher is None or watcher._led is None:
        return False
    _identify_until[0] = time.ticks_add(time.ticks_ms(), int(duration_ms))
    return True


class BluetoothToggleButton:
    """Watches `button` (anything with pressed()) on a machine.Timer and toggles BLE per press.

    `led` (a hub StatusLED, optional) shows the BLE state, the run flash and press
    acknowledgments. `program_running` is the "a program is running" query; by default the
    launcher's.
    """

    def __init__(
        self,
        button,
        led=None,
        poll_ms=DEFAULT_POLL_MS,
        timer_id=DEFAULT_TIMER_ID,
        color_on=DEFAULT_COLOR_ON,
        color_off=DEFAULT_COLOR_OFF,
        program_running=None,
    ):
        if poll_ms <= 0:
            raise ValueError("poll_ms must be > 0, got %r" % (poll_ms,))
        self._button = button
        self._led = led
        self._poll_ms = poll_ms
        self._timer_id = timer_id
        self._color_on = color_on
        self._color_off = color_off
        self._program_running = program_running
        self._timer = None
        self._held = False  # debounced button level
        self._streak = 0  # consecutive samples disagreeing with _held
        self._ack_color = None
        self._ack_until_ms = 0
        self._run_started_ms = None
        self._shown = None  # what the LED shows now, to write only on change

    def start(self):
        """Begin polling; a second call is a no-op. Paints the LED at once and follows BLE changes
        made elsewhere (user code, the REPL). Returns self."""
        if self._timer is not None:
            return self
        if self._program_running is None:
            from openbricks import launcher

            self._program_running = launcher.program_running
        import machine

        self._held = bool(self._button.pressed())
        self._streak = 0
        _pending_ack[0] = _ACK_NONE
        bluetooth.add_state_listener(self._on_state)
        timers.claim(self._timer_id, _TIMER_ROLE, "pass timer_id= to BluetoothButton()")
        self._timer = machine.Timer(self._timer_id)
        self._timer.init(mode=machine.Timer.PERIODIC, period=self._poll_ms, callback=self._tick)
        _running_watcher[0] = self
        self._render(time.ticks_ms())
        return self

    def stop(self):
        """Stop polling, release the timer and stop following BLE changes. The LED keeps its colour."""
        if self._timer is None:
            return
        self._timer.deinit()
        self._timer = None
        timers.release(self._timer_id, _TIMER_ROLE)
        if _running_watcher[0] is self:
            _running_watcher[0] = None
        bluetooth.remove_state_listener(self._on_state)

    def is_running(self):
        return self._timer is not None

    def _on_state(self, _active):
        self._render(time.ticks_ms())

    def _tick(self, _timer=None):
        if self._released():
            try:
                bluetooth.toggle()
            except bluetooth.HubNameNotSetError as err:
                # Nothing to advertise; the LED stays on the "off" colour, the console says why.
                print("openbricks: %s" % err.args[0])
        self._render(time.ticks_ms())

    def _released(self):
        """Debounce: a level counts once DEBOUNCE_TICKS samples in a row agree; True on the tick a
        debounced press ends."""
        level = bool(self._button.pressed())
        if level == self._held:
            self._streak = 0
            return False
        self._streak += 1
        if self._streak < DEBOUNCE_TICKS:
            return False
        self._held = level
        self._streak = 0
        return not level

    def _render(self, now_ms):
        led = self._led
        if led is None:
            return
        ack = _pending_ack[0]
        if ack != _ACK_NONE:
            _pending_ack[0] = _ACK_NONE
            self._ack_color = COLOR_STOP_PRESS if ack == _ACK_STOP else COLOR_START_PRESS
            self._ack_until_ms = time.ticks_add(now_ms, ACK_MS)
        state_color = self._color_on if bluetooth.is_active() else self._color_off
        colour = getattr(led, "has_colour", False)
        identify_until = _identify_until[0]
        if identify_until is not None and time.ticks_diff(identify_until, now_ms) <= 0:
            _identify_until[0] = identify_until = None
        if self._ack_color is not None and time.ticks_diff(self._ack_until_ms, now_ms) > 0:
            want = self._ack_color if colour else True
        elif identify_until is not None:
            lit = (time.ticks_diff(identify_until, now_ms) // IDENTIFY_HALF_PERIOD_MS) % 2 == 0
            want = (COLOR_IDENTIFY if lit else _DARK) if colour else lit
        else:
            self._ack_color = None
            if self._program_running():
                if self._run_started_ms is None:
                    self._run_started_ms = now_ms
                phase = time.ticks_diff(now_ms, self._run_started_ms) // RUN_FLASH_HALF_PERIOD_MS
                lit = phase % 2 == 0
                want = (state_color if lit else _DARK) if colour else lit
            else:
                self._run_started_ms = None
                want = state_color if colour else False
        if want == self._shown:
            return
        self._shown = want
        if want is True:
            led.on()
        elif want is False or want == _DARK:
            led.off()
        else:
            led.rgb(want[0], want[1], want[2])


def reset_state():
    """Drop a pending press acknowledgment and identify blink (a fresh start in tests)."""
    _pending_ack[0] = _ACK_NONE
    _identify_until[0] = None
    _running_watcher[0] = None
