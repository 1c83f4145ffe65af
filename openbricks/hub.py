"""Board-level peripherals: the status LED and the BLE button of each supported devkit.

    hub = ESP32S3DevkitHub()      # restores BLE, watches GPIO 38, paints the LED blue/yellow
    hub.led.rgb(0, 80, 0)

A hub is one per board: constructing another (a program's `hub = ESP32S3DevkitHub()` after the
frozen main.py built one at boot) retires the previous one first, so there is only ever one watcher
on the BLE button and one owner of the LED. The pins a hub wires are claimed with openbricks.pins, so
a driver pointed at them fails at construction, naming the hub and the argument that moves it.
"""

import sys

from micropython import const

from openbricks import pins

_ESP32_LED_PIN = const(2)
_ESP32_BLE_BUTTON_PIN = const(5)
_ESP32S3_LED_PIN = const(48)
_ESP32S3_BLE_BUTTON_PIN = const(38)

_current = [None]  # the hub wired last


class StatusLED:
    """A user-visible status LED. Single-colour LEDs do on/off; addressable ones also do rgb()."""

    has_colour = False

    def on(self):
        """Turn the LED on (RGB LEDs restore their last colour)."""
        raise NotImplementedError

    def off(self):
        """Turn the LED off."""
        raise NotImplementedError

    def rgb(self, r, g, b):
        """Set the colour (each channel 0..255). Raises on LEDs that have no colour."""
        raise NotImplementedError("this status LED is single-colour: use on() / off()")


class Button:
    """A momentary pushbutton on the hub."""

    def pressed(self):
        """True while the button is held down."""
        raise NotImplementedError


class Hub:
    """Board-level peripherals baked into a devkit."""

    #: The status LED (a StatusLED), or None on a hub built without one.
    led = None
    #: The Bluetooth on/off button (a Button), or None.
    bluetooth_button = None
    #: The BluetoothToggleButton watching that button, when the hub was built with bluetooth=True.
    bluetooth_toggle = None
    _pins = ()

    def close(self):
        """Stop watching the BLE button, turn the LED off and release the hub's pins."""
        if self.bluetooth_toggle is not None:
            self.bluetooth_toggle.stop()
            self.bluetooth_toggle = None
        if self.led is not None:
            self.led.off()
        owner = type(self).__name__
        for pin in self._pins:
            pins.release(pin, owner)
        self._pins = ()
        if _current[0] is self:
            _current[0] = None

    def _wire(self, make_led, led_pin, button_pin, bluetooth):
        if led_pin is not None and led_pin == button_pin:
            raise ValueError(
                "led_pin and bluetooth_button_pin are both GPIO %s: the LED and the button need a pin each"
                % (led_pin,)
            )
        previous = _current[0]
        if previous is not None:
            previous.close()
        owner = type(self).__name__
        led = None
        if led_pin is not None:
            led = make_led(led_pin, owner, _hint(owner, "led_pin"))
        try:
            button = PushButton(
                button_pin,
                role="Bluetooth button",
                owner=owner,
                hint=_hint(owner, "bluetooth_button_pin") + " or bluetooth=False",
            )
        except pins.ReservedPinError:
            if led_pin is not None:
                pins.release(led_pin, owner)
            raise
        self.led = led
        self.bluetooth_button = button
        self._pins = (button_pin,) if led_pin is None else (led_pin, button_pin)
        _current[0] = self
        if bluetooth:
            from openbricks import bluetooth as _bluetooth
            from openbricks.bluetooth_button import BluetoothToggleButton

            _bluetooth.apply_persisted_state()
            self.bluetooth_toggle = BluetoothToggleButton(button, led=led).start()


def _hint(owner, argument):
    return "pass %s=<another GPIO> to %s()" % (argument, owner)


class SimpleLED(StatusLED):
    """Single-colour LED on one digital pin."""

    def __init__(self, pin, active_high=True, owner=None, hint=""):
        import machine

        pins.claim(pin, "status LED", hint, self if owner is None else owner, True)
        self._pin_id = pin
        self._active_high = bool(active_high)
        self._pin = machine.Pin(pin, machine.Pin.OUT, value=0 if self._active_high else 1)

    def on(self):
        self._pin.value(1 if self._active_high else 0)

    def off(self):
        self._pin.value(0 if self._active_high else 1)

    def rgb(self, r, g, b):
        raise NotImplementedError(
            "the status LED on GPIO %s is single-colour: use on() / off()" % (self._pin_id,)
        )


class NeoPixelLED(StatusLED):
    """One WS2812 / NeoPixel, the onboard LED of the ESP32-S3 DevKitC-1.

    `brightness` (0.0-1.0) scales every channel on write: a WS2812 at full drive is dazzling indoors.
    """

    has_colour = True

    def __init__(self, pin, brightness=0.2, owner=None, hint=""):
        import machine
        import neopixel

        if not 0.0 <= brightness <= 1.0:
            raise ValueError("brightness must be 0.0-1.0, got %r" % (brightness,))
        pins.claim(pin, "status LED", hint, self if owner is None else owner, True)
        self._brightness = brightness
        self._colour = (255, 255, 255)
        self._pixel = neopixel.NeoPixel(machine.Pin(pin, machine.Pin.OUT), 1)

    def rgb(self, r, g, b):
        for name, value in (("r", r), ("g", g), ("b", b)):
            if not isinstance(value, int) or not 0 <= value <= 255:
                raise ValueError("rgb() channels are integers 0..255, got %s=%r" % (name, value))
        self._colour = (r, g, b)
        self._show(self._colour)

    def on(self):
        self._show(self._colour)

    def off(self):
        self._show((0, 0, 0))

    def _show(self, colour):
        scale = self._brightness
        self._pixel[0] = (int(colour[0] * scale), int(colour[1] * scale), int(colour[2] * scale))
        self._pixel.write()


class PushButton(Button):
    """A pushbutton between a GPIO and GND (active_low, internal pull-up) or 3V3 (pull-down)."""

    def __init__(self, pin, active_low=True, role="button", owner=None, hint=""):
        import machine

        pins.claim(pin, role, hint, self if owner is None else owner, False)
        self._active_low = bool(active_low)
        pull = machine.Pin.PULL_UP if self._active_low else machine.Pin.PULL_DOWN
        self._pin = machine.Pin(pin, machine.Pin.IN, pull)

    def pressed(self):
        level = self._pin.value()
        return level == 0 if self._active_low else level == 1


class ESP32DevkitHub(Hub):
    """ESP32 DevKitC-V4: blue LED on GPIO 2, BLE button on GPIO 5.

    With `bluetooth=True` the persisted BLE state is restored and the button toggles BLE; the
    single-colour LED blinks at 2 Hz while a program runs and is dark at idle. `led_pin=None` leaves
    the LED alone.
    """

    def __init__(self, led_pin=_ESP32_LED_PIN, bluetooth_button_pin=_ESP32_BLE_BUTTON_PIN, bluetooth=True):
        def make_led(pin, owner, hint):
            return SimpleLED(pin, owner=owner, hint=hint)

        self._wire(make_led, led_pin, bluetooth_button_pin, bluetooth)


class ESP32S3DevkitHub(Hub):
    """ESP32-S3 DevKitC-1: WS2812 RGB LED on GPIO 48, BLE button on GPIO 38.

    With `bluetooth=True` the persisted BLE state is restored, the button toggles BLE and the LED
    shows it: blue on, yellow off, flashing at 2 Hz while a program runs. GPIO 38 keeps the button
    off the ten analog pins (GPIO 1-10). `led_pin=None` leaves the LED alone.
    """

    def __init__(
        self,
        led_pin=_ESP32S3_LED_PIN,
        bluetooth_button_pin=_ESP32S3_BLE_BUTTON_PIN,
        brightness=0.2,
        bluetooth=True,
    ):
        if not 0.0 <= brightness <= 1.0:
            raise ValueError("brightness must be 0.0-1.0, got %r" % (brightness,))

        def make_led(pin, owner, hint):
            return NeoPixelLED(pin, brightness, owner=owner, hint=hint)

        self._wire(make_led, led_pin, bluetooth_button_pin, bluetooth)


def for_this_board(**kwargs):
    """The hub class of the chip this runs on, constructed with `kwargs` (what the frozen main.py
    uses, so one script serves both images)."""
    chip = pins.chip()
    if chip == pins.ESP32S3:
        return ESP32S3DevkitHub(**kwargs)
    if chip == pins.ESP32:
        return ESP32DevkitHub(**kwargs)
    raise OSError(
        "no ESP32 or ESP32-S3 detected (%s): construct ESP32DevkitHub() or ESP32S3DevkitHub() explicitly"
        % (getattr(sys.implementation, "_machine", sys.platform),)
    )


def current():
    """The hub wired last, or None."""
    return _current[0]


def reset_state():
    """Forget the wired hub without touching hardware (a fresh start in tests)."""
    _current[0] = None
