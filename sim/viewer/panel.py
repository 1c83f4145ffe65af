"""The viewer's side panel: run controls, the run's status, and what the program printed.

Controls call back into the viewer (they arrive on viser's worker threads); the status and output
are redrawn by the viewer's publishing thread. Everything a program prints is HTML-escaped before it
reaches a browser: a program's output is text, never markup, in a mentor's browser least of all.
"""

from __future__ import annotations

import html
from collections.abc import Callable

import viser

# Speed choices in the dropdown: a real-time factor, or None for as fast as the machine goes.
SPEEDS: dict[str, float | None] = {
    "0.25x": 0.25,
    "0.5x": 0.5,
    "1x": 1.0,
    "2x": 2.0,
    "4x": 4.0,
    "8x": 8.0,
    "as fast as possible": None,
}

# The output box: fixed height, pinned to its newest line (column-reverse keeps the scroll position
# at the bottom as lines arrive, without any script).
_OUTPUT_STYLE = (
    "display:flex;flex-direction:column-reverse;height:14em;overflow-y:auto;"
    "background:#1e1f22;color:#e6e6e6;border-radius:4px;padding:4px 6px;"
)
_DISPLAY_STYLE = "background:#05070a;border-radius:4px;padding:4px;overflow-x:auto;"
_DISPLAY_PRE_STYLE = "margin:0;font-size:0.42em;line-height:1.0;color:#8fd3ff;"
_PRE_STYLE = "margin:0;font-size:0.78em;line-height:1.35;white-space:pre-wrap;word-break:break-all;"


def speed_label(speed: float | None) -> str:
    for label, value in SPEEDS.items():
        if value == speed:
            return label
    return f"{speed:g}x"


class ControlPanel:
    """Run folder (status, pause/resume, speed, restart, stop) and Output folder.

    With controls=False (someone who may watch but not steer) only the status and output are shown.
    """

    def __init__(
        self,
        gui,
        *,
        speed: float | None,
        controls: bool,
        on_pause: Callable[[bool], None],
        on_speed: Callable[[float | None], None],
        on_restart: Callable[[], None],
        on_stop: Callable[[], None],
        on_view: Callable[[], None],
    ):
        self._speeds = dict(SPEEDS)
        self._speeds.setdefault(speed_label(speed), speed)  # e.g. a --speed 3 from the command line
        self._paused = False
        self._pause_button = None
        with gui.add_folder("Run"):
            self._status = gui.add_markdown("starting ...")
            self._pose = gui.add_markdown("")
            if controls:
                self._pause_button = gui.add_button("Pause", icon=viser.Icon.PLAYER_PAUSE)
                self._speed = gui.add_dropdown(
                    "Speed", options=tuple(self._speeds), initial_value=speed_label(speed)
                )
                restart = gui.add_button("Restart", icon=viser.Icon.REFRESH, hint="run the program again")
                stop = gui.add_button("Stop", icon=viser.Icon.PLAYER_STOP, hint="end the run here")

                @self._pause_button.on_click
                def _(_event) -> None:
                    self._paused = not self._paused
                    self._show_pause_state()
                    on_pause(self._paused)

                @self._speed.on_update
                def _(_event) -> None:
                    on_speed(self._speeds[self._speed.value])

                restart.on_click(lambda _event: on_restart())
                stop.on_click(lambda _event: on_stop())
            view = gui.add_button("Overview camera", icon=viser.Icon.FOCUS_CENTERED)
            view.on_click(lambda _event: on_view())
        with gui.add_folder("Output"):
            self._output = gui.add_html(self._output_html([]))
        self._gui = gui
        self._display = None  # the OLED's picture, shown once the program draws on it

    def set_speed(self, speed: float | None) -> None:
        """Show `speed` as the chosen one (a run that arrived with a speed of its own)."""
        if self._pause_button is None:
            return
        label = speed_label(speed)
        if label not in self._speeds:
            self._speeds[label] = speed
            self._speed.options = tuple(self._speeds)
        self._speed.value = label

    def set_paused(self, paused: bool) -> None:
        """Show the run as paused or running (a new run starts unpaused)."""
        self._paused = paused
        self._show_pause_state()

    def show_status(self, state: str, sim_ms: int, real_time_factor: float | None) -> None:
        rate = "" if real_time_factor is None else f" · {real_time_factor:.2f}x real time"
        self._status.content = f"**{state}** · {sim_ms / 1000:.2f} s simulated{rate}"

    def show_pose(self, x_mm: float, y_mm: float, heading_deg: float) -> None:
        self._pose.content = f"x {x_mm:.1f} mm · y {y_mm:.1f} mm · heading {heading_deg:.1f}°"

    def show_output(self, lines: list[str]) -> None:
        self._output.content = self._output_html(lines)

    def show_display(self, text: str) -> None:
        """Show what the robot's OLED shows (half-block text, two pixel rows per line)."""
        content = (
            f'<div style="{_DISPLAY_STYLE}"><pre style="{_DISPLAY_PRE_STYLE}">{html.escape(text)}</pre></div>'
        )
        if self._display is None:
            with self._gui.add_folder("Display"):
                self._display = self._gui.add_html(content)
        else:
            self._display.content = content

    def _show_pause_state(self) -> None:
        if self._pause_button is None:
            return
        self._pause_button.label = "Resume" if self._paused else "Pause"
        self._pause_button.icon = viser.Icon.PLAYER_PLAY if self._paused else viser.Icon.PLAYER_PAUSE

    @staticmethod
    def _output_html(lines: list[str]) -> str:
        text = html.escape("\n".join(lines)) if lines else "<i>(no output yet)</i>"
        return f'<div style="{_OUTPUT_STYLE}"><pre style="{_PRE_STYLE}">{text}</pre></div>'
