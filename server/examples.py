"""The example programs shipped with openbricks, grouped the way the manual teaches them.

The examples are the manual's listings (`examples/*.py` in a checkout), so a first program in the
console starts from code the manual explains line by line. An installed package carries them as
`openbricks_server/example_programs/` (setup.py maps the folder there); a checkout reads the folder
itself. `examples_dir()` is the one place that decides which.

Only the hub programs at the top of the folder are examples a hub can run: `examples/host/` holds
scripts for the computer, and `examples/manual/` the printed manual's listings kept verbatim for its
tests, which the top-level programs supersede.

The grouping lives here, in `CATALOGUE`, rather than in each file's docstring, because the manual
includes those files whole and a grouping line would show in every listing. A test checks that every
shipped program has its entry and every entry its program.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

PACKAGED = Path(__file__).resolve().parent / "example_programs"
CHECKOUT = Path(__file__).resolve().parent.parent / "examples"

# (id, title) in the order they are offered
GROUPS: tuple[tuple[str, str], ...] = (
    ("drive_base", "Drive base"),
    ("sensors", "Sensors"),
    ("line_following", "Line following"),
    ("competition", "Competition"),
)

# file stem -> (group id, title); within a group, first things first
CATALOGUE: dict[str, tuple[str, str]] = {
    "first_robot": ("drive_base", "First robot: out and back"),
    "motor_basics": ("drive_base", "Motor basics"),
    "drivebase_square": ("drive_base", "Drive a square"),
    "drivebase_curve": ("drive_base", "Rounded square with curve()"),
    "esp32_drivebase": ("drive_base", "DC gear-motor drive base"),
    "calibrate_wheel_diameter": ("drive_base", "Calibrate the wheel diameter"),
    "icm45686_axle_track": ("drive_base", "Calibrate the axle track"),
    "telemetry_plot": ("drive_base", "Live graphs while driving"),
    "icm45686_square": ("sensors", "Gyro-corrected square (ICM-45686)"),
    "bno055_square": ("sensors", "Square on a BNO055 heading"),
    "color_array": ("sensors", "Name the colours under two sensors"),
    "oled_status": ("sensors", "Odometry on an OLED display"),
    "hub_led": ("sensors", "Hub LED and button"),
    "qtr_calibrate": ("line_following", "Calibrate the line sensor bar"),
    "qtr_line_follow": ("line_following", "Follow a line"),
    "colour_bare_bus": ("line_following", "Find a line with one colour sensor"),
    "full_robot": ("competition", "A whole robot: drive until red"),
    "qtr_align": ("competition", "Square up on a line (sensor bar)"),
    "color_align": ("competition", "Square up on a line (two colour sensors)"),
}


class ExampleNotFound(LookupError):
    """No shipped example has this id."""


@dataclass(frozen=True)
class Example:
    id: str  # the file's stem: drivebase_square
    title: str
    group: str
    group_title: str
    summary: str  # the docstring's first paragraph, on one line
    file: str  # drivebase_square.py

    @property
    def path(self) -> Path:
        return examples_dir() / self.file


def examples_dir() -> Path:
    """The folder the examples are read from: the installed package's copy, else the checkout's."""
    return PACKAGED if PACKAGED.is_dir() else CHECKOUT


def shipped_files(folder: Path | None = None) -> list[Path]:
    """Every hub program the package ships (the top level of the folder)."""
    folder = examples_dir() if folder is None else folder
    return sorted(p for p in folder.glob("*.py") if not p.name.startswith("_"))


def summary_of(source: str) -> str:
    """The module docstring's first paragraph, joined onto one line ('' without a docstring)."""
    try:
        doc = ast.get_docstring(ast.parse(source)) or ""
    except SyntaxError:
        return ""
    return " ".join(doc.strip().split("\n\n", 1)[0].split())


def catalogue() -> list[Example]:
    """The shipped examples in the order they are offered: by group, then as CATALOGUE lists them.

    A file without an entry is left out rather than guessed into a group (the test catches it)."""
    group_titles = dict(GROUPS)
    files = {p.stem: p for p in shipped_files()}
    order = {group: i for i, (group, _) in enumerate(GROUPS)}
    found = []
    for stem, (group, title) in CATALOGUE.items():
        path = files.get(stem)
        if path is None:
            continue
        summary = summary_of(path.read_text(encoding="utf-8"))
        found.append(Example(stem, title, group, group_titles[group], summary, path.name))
    return sorted(found, key=lambda e: order[e.group])  # stable: the catalogue's order within a group


def find(example_id: str) -> Example:
    for example in catalogue():
        if example.id == example_id:
            return example
    raise ExampleNotFound(example_id)


def source(example: Example) -> str:
    return example.path.read_text(encoding="utf-8")
