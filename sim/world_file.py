"""A world written as a small TOML file beside its mat image: read and checked, without MuJoCo or numpy.

    mat = "mat.png"                 # PNG, JPEG or PDF, beside this file (or a path relative to it)
    size_mm = [2362, 1143]          # the mat's printed size: the image is stretched to it exactly
    start = { x_mm = 150, y_mm = 571, heading_deg = 0 }

Everything a team measures on its printed mat is in millimetres from the mat's lower-left corner, x
to the right, y up, headings counter-clockwise from +x, as `--x/--y/--yaw` are. The simulator's own
frame has its origin at the mat's centre and Pybricks' clockwise headings; `WorldSpec` keeps the
file's numbers and converts them once (`to_centre`), so the file reads like a ruler on the table.

The file is checked as a whole before anything is built: every problem becomes one line naming the
file, the line, the key and what it accepts, and all of them are raised together as one
`WorldFileError` (a ValueError the CLI and the console print without a traceback). tomllib reports
no positions, so `_Lines` finds a key's line in the text itself.

This module stays free of MuJoCo and numpy, so `openbricks sim run`'s own process and the console's
daemon can check a world file before a child builds it.
"""

from __future__ import annotations

import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from .job import UnknownWorldError

WORLD_SUFFIX = ".toml"
MAT_SUFFIXES = (".png", ".jpg", ".jpeg", ".pdf")

# Print colours (sRGB) that read as their names under the colour sensor model; the built-in mats
# print with the same ones (worlds/builtin/canvas.py draws with them).
PALETTE: dict[str, tuple[int, int, int]] = {
    "white": (246, 246, 242),
    "black": (22, 22, 24),
    "red": (205, 35, 45),
    "green": (30, 150, 70),
    "blue": (30, 85, 195),
    "yellow": (245, 205, 35),
    "grey": (150, 150, 150),
}
DEFAULT_PROP_SIZE_MM = (50.0, 50.0, 50.0)
DEFAULT_PROP_MASS_G = 50.0
DEFAULT_PROP_FRICTION = 0.5
DEFAULT_WALL_HEIGHT_MM = 70.0
DEFAULT_WALL_THICKNESS_MM = 20.0


class WorldFileError(UnknownWorldError):
    """A world file that cannot be used: one line per problem, each with the file, line and key."""

    def __init__(self, problems: list[str]):
        self.problems = problems
        super().__init__("\n".join(problems))


@dataclass(frozen=True)
class Box:
    """A fixed box standing on the mat: centre, extents (x, y, z) and heading (CCW degrees)."""

    x_mm: float
    y_mm: float
    size_mm: tuple[float, float, float]
    heading_deg: float = 0.0
    rgb: tuple[int, int, int] | None = None  # None: plywood, as the walls
    name: str | None = None


@dataclass(frozen=True)
class Cylinder:
    x_mm: float
    y_mm: float
    radius_mm: float
    height_mm: float
    rgb: tuple[int, int, int] | None = None
    name: str | None = None


@dataclass(frozen=True)
class Prop:
    """One kind of movable block; `count` copies are drawn onto the slots of `slots` (or stand `at`)."""

    name: str
    rgb: tuple[int, int, int]
    colour: str | None  # the palette name, when the colour was given by name
    size_mm: tuple[float, float, float] = DEFAULT_PROP_SIZE_MM
    mass_g: float = DEFAULT_PROP_MASS_G
    friction: float = DEFAULT_PROP_FRICTION
    count: int = 1
    slots: str | None = None
    at: tuple[float, float, float] | None = None  # x_mm, y_mm, heading_deg when not drawn


@dataclass(frozen=True)
class Slots:
    """Positions a group of props is drawn onto, and how far a drawn prop may sit off its slot."""

    name: str
    positions: tuple[tuple[float, float], ...]
    jitter_mm: float = 0.0
    jitter_deg: float = 0.0


@dataclass(frozen=True)
class Zone:
    name: str
    polygon: tuple[tuple[float, float], ...]

    def contains(self, x_mm: float, y_mm: float) -> bool:
        """Even-odd rule; a point on an edge counts as inside (a prop touching a line is in)."""
        inside = False
        pts = self.polygon
        for (x0, y0), (x1, y1) in zip(pts, pts[1:] + pts[:1], strict=True):
            if _on_segment(x_mm, y_mm, x0, y0, x1, y1):
                return True
            if (y0 > y_mm) != (y1 > y_mm):
                cross = x0 + (y_mm - y0) * (x1 - x0) / (y1 - y0)
                if x_mm < cross:
                    inside = not inside
        return inside


@dataclass(frozen=True)
class Rule:
    """`points` for each matching prop (or the robot) that ends inside `zone` (outside, with inside=false).
    A negative `points` is a penalty."""

    zone: str
    points: float
    prop: str | None = None  # a prop name, or None with robot=True
    robot: bool = False
    inside: bool = True
    label: str = ""


@dataclass(frozen=True)
class WorldSpec:
    """A checked world file, in the file's own frame (lower-left origin, CCW headings)."""

    path: Path
    name: str
    description: str
    mat: Path | None  # None for a bare floor of size_mm
    size_mm: tuple[float, float]
    start: tuple[float, float, float]  # x_mm, y_mm, heading_deg (CCW)
    walls: tuple[float, float] | None = (DEFAULT_WALL_HEIGHT_MM, DEFAULT_WALL_THICKNESS_MM)
    obstacles: tuple[Box | Cylinder, ...] = ()
    props: tuple[Prop, ...] = ()
    slots: dict[str, Slots] = field(default_factory=dict)
    zones: tuple[Zone, ...] = ()
    rules: tuple[Rule, ...] = ()
    time_limit_s: float | None = None

    def to_centre(self, x_mm: float, y_mm: float) -> tuple[float, float]:
        """A point of the file (lower-left origin) in the simulator's frame (mat centre origin)."""
        return x_mm - self.size_mm[0] / 2, y_mm - self.size_mm[1] / 2

    def from_centre(self, x_mm: float, y_mm: float) -> tuple[float, float]:
        return x_mm + self.size_mm[0] / 2, y_mm + self.size_mm[1] / 2

    @property
    def start_mm_deg(self) -> tuple[float, float, float]:
        """The start pose as the simulator takes it: centre origin, clockwise heading."""
        x, y = self.to_centre(self.start[0], self.start[1])
        return x, y, -self.start[2]


# -- locating keys in the text ---------------------------------------------------------------------

_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?")
_KEY = re.compile(r"^\s*([A-Za-z0-9_\-\"']+)\s*=")


class _Lines:
    """Where a key stands in the file: tomllib keeps no positions, so the text is scanned for tables
    ([name], [[name]] counted per array) and keys (`name =`, or `name =` inside an inline table)."""

    def __init__(self, text: str):
        self.lines = text.splitlines()
        self.tables: dict[tuple, int] = {}  # (table path, array index or None) -> line number
        self.keys: dict[tuple, int] = {}  # (table path, index, key) -> line number
        counts: dict[str, int] = {}
        current: tuple = ((), None)
        for number, line in enumerate(self.lines, start=1):
            stripped = line.split("#", 1)[0]
            header = _HEADER.match(stripped)
            if header:
                name = header.group(2).replace(" ", "")
                if header.group(1) == "[[":
                    index = counts.get(name, 0)
                    counts[name] = index + 1
                    current = (tuple(name.split(".")), index)
                else:
                    current = (tuple(name.split(".")), None)
                self.tables.setdefault(current, number)
                continue
            key = _KEY.match(stripped)
            if key:
                self.keys.setdefault((*current, key.group(1).strip("\"'")), number)

    def of(self, table: tuple = (), index=None, key: str | None = None, inner: str | None = None) -> int:
        """The line of `key` in a table (an array's index-th entry), else of the table; an inline
        table's `inner` key is looked for on the key's line and the lines after it."""
        if key is None:
            return self.tables.get((table, index), 1)
        number = self.keys.get((table, index, key))
        if number is None:
            return self.tables.get((table, index), 1)
        if inner:
            for offset, line in enumerate(self.lines[number - 1 : number + 20]):
                if re.search(rf"\b{re.escape(inner)}\s*=", line):
                    return number + offset
        return number


# -- checking --------------------------------------------------------------------------------------

_TOP_KEYS = {
    "name",
    "description",
    "mat",
    "size_mm",
    "start",
    "walls",
    "obstacles",
    "props",
    "slots",
    "zones",
    "scoring",
    "time_limit_s",
}


class _Checker:
    def __init__(self, path: Path, text: str):
        self.path = path
        self.where = _Lines(text)
        self.problems: list[str] = []

    def problem(self, line: int, key: str, what: str) -> None:
        self.problems.append(f"{self.path}:{line}: {key}: {what}")

    def unknown(self, table: dict, allowed: set, dotted: str, tpath=(), index=None, inline_of=None):
        for key in table:
            if key not in allowed:
                if inline_of:
                    line = self.where.of(tpath, index, inline_of, key)
                else:
                    line = self.where.of(tpath, index, key)
                known = ", ".join(sorted(allowed))
                self.problem(line, f"{dotted}{key}", f"unknown key (known here: {known})")

    def number(self, value, key, line, positive=False, minimum=None) -> float | None:
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            self.problem(line, key, f"give a number, not {value!r}")
            return None
        if positive and value <= 0:
            self.problem(line, key, f"must be positive, got {value}")
            return None
        if minimum is not None and value < minimum:
            self.problem(line, key, f"must be at least {minimum}, got {value}")
            return None
        return float(value)

    def numbers(self, value, n, key, line, positive=False) -> tuple | None:
        if not isinstance(value, list) or len(value) != n:
            self.problem(line, key, f"give {n} numbers in brackets, not {value!r}")
            return None
        out = [self.number(v, key, line, positive=positive) for v in value]
        return None if None in out else tuple(out)

    def colour(self, value, key, line) -> tuple[tuple[int, int, int], str | None] | None:
        if isinstance(value, str):
            if value.lower() in PALETTE:
                return PALETTE[value.lower()], value.lower()
            if re.fullmatch(r"#[0-9a-fA-F]{6}", value):
                return tuple(int(value[i : i + 2], 16) for i in (1, 3, 5)), None
        elif isinstance(value, list) and len(value) == 3:
            if all(isinstance(v, int) and not isinstance(v, bool) and 0 <= v <= 255 for v in value):
                return tuple(value), None
        names = ", ".join(PALETTE)
        self.problem(line, key, f'give a colour name ({names}), "#rrggbb" or [r, g, b] 0-255, not {value!r}')
        return None

    def inside_mat(self, x, y, size, key, line, what="lies outside the mat") -> bool:
        if size is None or x is None or y is None:
            return True
        if not (0 <= x <= size[0] and 0 <= y <= size[1]):
            self.problem(line, key, f"({x:g}, {y:g}) {what} (0..{size[0]:g} x 0..{size[1]:g} mm)")
            return False
        return True


def load(path) -> WorldSpec:
    """Read and check a world file; raises WorldFileError listing every problem."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise WorldFileError([f"{path}: world file does not exist"]) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise WorldFileError([f"{path}: cannot read the world file ({exc})"]) from None
    return parse(text, path)


def parse(text: str, path: Path) -> WorldSpec:
    path = Path(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        line = re.search(r"line (\d+)", str(exc))
        raise WorldFileError(
            [f"{path}:{line.group(1) if line else 1}: not valid TOML: {str(exc).split(' (at')[0]}"]
        ) from None
    c = _Checker(path, text)
    w = c.where
    c.unknown(data, _TOP_KEYS, "")

    name = data.get("name", path.stem)
    if not isinstance(name, str) or not name.strip():
        c.problem(w.of(key="name"), "name", f"give the world's name as text, not {name!r}")
        name = path.stem
    description = data.get("description", f"world file {path.name}")
    if not isinstance(description, str):
        c.problem(w.of(key="description"), "description", "give a line of text")
        description = ""

    size = None
    if "size_mm" not in data:
        c.problem(1, "size_mm", "missing: the mat's printed size, size_mm = [WIDTH, HEIGHT]")
    else:
        size = c.numbers(data["size_mm"], 2, "size_mm", w.of(key="size_mm"), positive=True)

    mat = None
    if "mat" not in data:
        c.problem(1, "mat", 'missing: the mat image beside this file, mat = "mat.png" (PNG, JPEG or PDF)')
    elif not isinstance(data["mat"], str) or not data["mat"]:
        c.problem(w.of(key="mat"), "mat", f"give the image's file name, not {data['mat']!r}")
    else:
        mat = (path.parent / data["mat"]).resolve()
        if mat.suffix.lower() not in MAT_SUFFIXES:
            c.problem(w.of(key="mat"), "mat", f"{data['mat']!r} is not a PNG, JPEG or PDF file")
        elif not mat.is_file():
            c.problem(w.of(key="mat"), "mat", f"image {data['mat']!r} not found (looked for {mat})")
        elif not _looks_like(mat):
            kind = "PDF" if mat.suffix.lower() == ".pdf" else mat.suffix.lstrip(".").upper()
            c.problem(
                w.of(key="mat"),
                "mat",
                f"{data['mat']!r} is not a {kind} file (its first bytes say otherwise)",
            )

    start = _start(c, data, size)
    walls = _walls(c, data)
    obstacles = _obstacles(c, data, size)
    slots = _slots(c, data, size)
    props = _props(c, data, size, slots)
    zones = _zones(c, data, size)
    rules = _rules(c, data, props, zones)
    time_limit = None
    if "time_limit_s" in data:
        time_limit = c.number(data["time_limit_s"], "time_limit_s", w.of(key="time_limit_s"), positive=True)

    if c.problems:
        raise WorldFileError(c.problems)
    return WorldSpec(
        path=path,
        name=name.strip(),
        description=description,
        mat=mat,
        size_mm=size,
        start=start,
        walls=walls,
        obstacles=tuple(obstacles),
        props=tuple(props),
        slots=slots,
        zones=tuple(zones),
        rules=tuple(rules),
        time_limit_s=time_limit,
    )


_SIGNATURES = {
    ".png": (b"\x89PNG\r\n\x1a\n",),
    ".jpg": (b"\xff\xd8\xff",),
    ".jpeg": (b"\xff\xd8\xff",),
    ".pdf": (b"%PDF-",),
}


def _looks_like(path: Path) -> bool:
    """Whether a mat file starts as its kind of file does: a renamed or broken file is told here, by
    the file's line, instead of failing the image decoder in the run's process."""
    try:
        with path.open("rb") as file:
            head = file.read(8)
    except OSError:
        return False
    return any(head.startswith(sig) for sig in _SIGNATURES[path.suffix.lower()])


def _table(c: _Checker, value, key, line) -> dict | None:
    if not isinstance(value, dict):
        c.problem(line, key, f"give a table ({{ ... }} or [{key}]), not {value!r}")
        return None
    return value


def _start(c, data, size):
    w = c.where
    if "start" not in data:
        c.problem(1, "start", "missing: start = { x_mm = ..., y_mm = ..., heading_deg = ... }")
        return (0.0, 0.0, 0.0)
    start = _table(c, data["start"], "start", w.of(key="start"))
    if start is None:
        return (0.0, 0.0, 0.0)
    allowed = {"x_mm", "y_mm", "heading_deg"}
    c.unknown(start, allowed, "start.", tpath=("start",), inline_of="start")
    values = []
    for key in ("x_mm", "y_mm", "heading_deg"):
        line = (
            w.of(key="start", inner=key)
            if (("start",), None) not in w.tables
            else w.of(("start",), None, key)
        )
        if key not in start:
            if key == "heading_deg":
                values.append(0.0)
                continue
            c.problem(line, f"start.{key}", "missing")
            values.append(None)
        else:
            values.append(c.number(start[key], f"start.{key}", line))
    line = w.of(key="start") if (("start",), None) not in w.tables else w.of(("start",))
    c.inside_mat(values[0], values[1], size, "start", line, "puts the robot off the mat")
    return tuple(v if v is not None else 0.0 for v in values)


def _walls(c, data):
    w = c.where
    if "walls" not in data:
        return (DEFAULT_WALL_HEIGHT_MM, DEFAULT_WALL_THICKNESS_MM)
    walls = _table(c, data["walls"], "walls", w.of(key="walls"))
    if walls is None:
        return None
    tpath = ("walls",)
    inline = (tpath, None) not in w.tables
    c.unknown(
        walls,
        {"border", "height_mm", "thickness_mm"},
        "walls.",
        tpath=tpath,
        inline_of="walls" if inline else None,
    )

    def line(key):
        return w.of(key="walls", inner=key) if inline else w.of(tpath, None, key)

    border = walls.get("border", True)
    if not isinstance(border, bool):
        c.problem(line("border"), "walls.border", "give true or false")
        border = True
    height = c.number(
        walls.get("height_mm", DEFAULT_WALL_HEIGHT_MM), "walls.height_mm", line("height_mm"), True
    )
    thick = c.number(
        walls.get("thickness_mm", DEFAULT_WALL_THICKNESS_MM), "walls.thickness_mm", line("thickness_mm"), True
    )
    if not border:
        return None
    return (height or DEFAULT_WALL_HEIGHT_MM, thick or DEFAULT_WALL_THICKNESS_MM)


def _array(c, data, key) -> list[dict]:
    value = data.get(key, [])
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        c.problem(c.where.of(key=key), key, f"give a list of tables: [[{key}]] entries")
        return []
    return value


def _obstacles(c, data, size):
    w = c.where
    out = []
    allowed = {"name", "shape", "x_mm", "y_mm", "size_mm", "heading_deg", "radius_mm", "height_mm", "colour"}
    for i, entry in enumerate(_array(c, data, "obstacles")):
        tp = ("obstacles",)
        k = f"obstacles[{i + 1}]."
        c.unknown(entry, allowed, k, tp, i)
        shape = entry.get("shape", "box")
        x = c.number(entry.get("x_mm"), k + "x_mm", w.of(tp, i, "x_mm"))
        y = c.number(entry.get("y_mm"), k + "y_mm", w.of(tp, i, "y_mm"))
        c.inside_mat(x, y, size, k + "x_mm", w.of(tp, i, "x_mm"))
        rgb = None
        if "colour" in entry:
            got = c.colour(entry["colour"], k + "colour", w.of(tp, i, "colour"))
            rgb = got[0] if got else rgb
        name = entry.get("name")
        if name is not None and (not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_\-]+", name)):
            c.problem(
                w.of(tp, i, "name"), k + "name", f"give a name of letters, digits, _ or -, not {name!r}"
            )
            name = None
        if shape == "box":
            dims = c.numbers(entry.get("size_mm"), 3, k + "size_mm", w.of(tp, i, "size_mm"), positive=True)
            heading = c.number(entry.get("heading_deg", 0.0), k + "heading_deg", w.of(tp, i, "heading_deg"))
            if None not in (x, y, dims, heading):
                out.append(Box(x, y, dims, heading, rgb, name))
        elif shape == "cylinder":
            r = c.number(entry.get("radius_mm"), k + "radius_mm", w.of(tp, i, "radius_mm"), positive=True)
            h = c.number(entry.get("height_mm"), k + "height_mm", w.of(tp, i, "height_mm"), positive=True)
            if None not in (x, y, r, h):
                out.append(Cylinder(x, y, r, h, rgb, name))
        else:
            c.problem(w.of(tp, i, "shape"), k + "shape", f'give "box" or "cylinder", not {shape!r}')
    return out


def _slots(c, data, size) -> dict[str, Slots]:
    w = c.where
    groups = data.get("slots", {})
    if not isinstance(groups, dict):
        c.problem(
            w.of(key="slots"), "slots", "give named groups: [slots.NAME] with positions = [[x, y], ...]"
        )
        return {}
    out = {}
    for name, group in groups.items():
        tp = ("slots", name)
        k = f"slots.{name}."
        line0 = w.of(tp) if (tp, None) in w.tables else w.of(("slots",), None, name)
        if not isinstance(group, dict):
            c.problem(line0, f"slots.{name}", "give a table with positions = [[x, y], ...]")
            continue
        c.unknown(group, {"positions", "jitter_mm", "jitter_deg"}, k, tp)
        line = w.of(tp, None, "positions")
        raw = group.get("positions")
        if not isinstance(raw, list) or not raw:
            c.problem(line, k + "positions", "give a list of [x_mm, y_mm] points")
            continue
        positions = []
        for j, point in enumerate(raw):
            xy = c.numbers(point, 2, f"{k}positions[{j + 1}]", line)
            if xy and c.inside_mat(*xy, size, f"{k}positions[{j + 1}]", line, "puts a slot outside the mat"):
                positions.append(xy)
        jitter = c.number(
            group.get("jitter_mm", 0.0), k + "jitter_mm", w.of(tp, None, "jitter_mm"), minimum=0
        )
        jitter_deg = c.number(
            group.get("jitter_deg", 0.0), k + "jitter_deg", w.of(tp, None, "jitter_deg"), minimum=0
        )
        out[name] = Slots(name, tuple(positions), jitter or 0.0, jitter_deg or 0.0)
    return out


def _props(c, data, size, slots) -> list[Prop]:
    w = c.where
    out = []
    allowed = {"name", "colour", "size_mm", "mass_g", "friction", "count", "slots", "at"}
    taken: dict[str, int] = {}
    for i, entry in enumerate(_array(c, data, "props")):
        tp = ("props",)
        k = f"props[{i + 1}]."
        c.unknown(entry, allowed, k, tp, i)
        got = c.colour(entry.get("colour", "grey"), k + "colour", w.of(tp, i, "colour"))
        rgb, colour_name = got if got else (PALETTE["grey"], "grey")
        name = entry.get("name", colour_name or f"prop{i + 1}")
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_\-]+", name):
            c.problem(
                w.of(tp, i, "name"), k + "name", f"give a name of letters, digits, _ or -, not {name!r}"
            )
            name = f"prop{i + 1}"
        dims = c.numbers(
            entry.get("size_mm", list(DEFAULT_PROP_SIZE_MM)), 3, k + "size_mm", w.of(tp, i, "size_mm"), True
        )
        mass = c.number(entry.get("mass_g", DEFAULT_PROP_MASS_G), k + "mass_g", w.of(tp, i, "mass_g"), True)
        friction = c.number(
            entry.get("friction", DEFAULT_PROP_FRICTION), k + "friction", w.of(tp, i, "friction"), True
        )
        count = entry.get("count", 1)
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            c.problem(w.of(tp, i, "count"), k + "count", f"give a whole number from 1 up, not {count!r}")
            count = 1
        group = entry.get("slots")
        at = None
        if group is not None and "at" in entry:
            c.problem(w.of(tp, i, "at"), k + "at", "give either slots (drawn) or at (fixed), not both")
        if group is not None:
            if not isinstance(group, str) or group not in slots:
                known = ", ".join(sorted(slots)) or "none defined: add [slots.NAME]"
                c.problem(w.of(tp, i, "slots"), k + "slots", f"no slot group {group!r} (groups: {known})")
                group = None
            else:
                taken[group] = taken.get(group, 0) + count
                if taken[group] > len(slots[group].positions):
                    c.problem(
                        w.of(tp, i, "count"),
                        k + "count",
                        f"{taken[group]} props drawn onto slot group {group!r}, which has "
                        f"{len(slots[group].positions)} positions",
                    )
        elif "at" in entry:
            raw = entry["at"]
            if isinstance(raw, list) and len(raw) == 2:
                raw = [*raw, 0.0]
            at = c.numbers(raw, 3, k + "at", w.of(tp, i, "at"))
            if at:
                c.inside_mat(at[0], at[1], size, k + "at", w.of(tp, i, "at"), "puts the prop outside the mat")
            if at and count != 1:
                c.problem(w.of(tp, i, "count"), k + "count", "a prop placed with at stands once: drop count")
        else:
            c.problem(
                w.of(tp, i), f"props[{i + 1}]", 'give slots = "GROUP" (drawn) or at = [x_mm, y_mm] (fixed)'
            )
        if None in (dims, mass, friction):
            continue
        out.append(Prop(name, rgb, colour_name, dims, mass, friction, count, group, at))
    return out


def _zones(c, data, size) -> list[Zone]:
    w = c.where
    out = []
    seen = set()
    for i, entry in enumerate(_array(c, data, "zones")):
        tp = ("zones",)
        k = f"zones[{i + 1}]."
        c.unknown(entry, {"name", "rect", "polygon"}, k, tp, i)
        name = entry.get("name")
        if not isinstance(name, str) or not name:
            c.problem(w.of(tp, i, "name"), k + "name", "give the zone a name")
            continue
        if name in seen:
            c.problem(w.of(tp, i, "name"), k + "name", f"zone {name!r} is named twice")
        seen.add(name)
        polygon = None
        if ("rect" in entry) == ("polygon" in entry):
            c.problem(
                w.of(tp, i), f"zones[{i + 1}]", "give rect = [x0, y0, x1, y1] or polygon = [[x, y], ...]"
            )
        elif "rect" in entry:
            r = c.numbers(entry["rect"], 4, k + "rect", w.of(tp, i, "rect"))
            if r:
                x0, y0, x1, y1 = min(r[0], r[2]), min(r[1], r[3]), max(r[0], r[2]), max(r[1], r[3])
                polygon = ((x0, y0), (x1, y0), (x1, y1), (x0, y1))
        else:
            raw = entry["polygon"]
            line = w.of(tp, i, "polygon")
            if not isinstance(raw, list) or len(raw) < 3:
                c.problem(line, k + "polygon", "give three or more [x_mm, y_mm] corners")
            else:
                pts = [c.numbers(p, 2, k + "polygon", line) for p in raw]
                if None not in pts:
                    polygon = tuple(pts)
        if polygon:
            out.append(Zone(name, polygon))
    return out


def _rules(c, data, props, zones) -> list[Rule]:
    w = c.where
    out = []
    zone_names = {z.name for z in zones}
    prop_names = {p.name for p in props} | {p.colour for p in props if p.colour}
    for i, entry in enumerate(_array(c, data, "scoring")):
        tp = ("scoring",)
        k = f"scoring[{i + 1}]."
        c.unknown(entry, {"zone", "prop", "robot", "points", "inside", "label"}, k, tp, i)
        zone = entry.get("zone")
        if zone not in zone_names:
            known = ", ".join(sorted(zone_names)) or "none defined: add [[zones]]"
            c.problem(w.of(tp, i, "zone"), k + "zone", f"no zone {zone!r} (zones: {known})")
        points = c.number(entry.get("points"), k + "points", w.of(tp, i, "points"))
        prop = entry.get("prop")
        robot = entry.get("robot", False)
        if not isinstance(robot, bool):
            c.problem(w.of(tp, i, "robot"), k + "robot", "give true or false")
            robot = False
        if robot == (prop is not None):
            c.problem(
                w.of(tp, i),
                f"scoring[{i + 1}]",
                'give prop = "NAME" (a prop\'s name or colour) or robot = true',
            )
        elif prop is not None and prop not in prop_names and prop != "*":
            known = ", ".join(sorted(prop_names)) or "none defined"
            c.problem(
                w.of(tp, i, "prop"),
                k + "prop",
                f'no prop named or coloured {prop!r} (props: {known}, or "*")',
            )
        inside = entry.get("inside", True)
        if not isinstance(inside, bool):
            c.problem(w.of(tp, i, "inside"), k + "inside", "give true or false")
            inside = True
        label = entry.get("label", "")
        if not isinstance(label, str):
            c.problem(w.of(tp, i, "label"), k + "label", "give a line of text")
            label = ""
        if zone in zone_names and points is not None:
            out.append(Rule(zone, points, prop, robot, inside, label))
    return out


def _on_segment(px, py, x0, y0, x1, y1, eps=1e-9) -> bool:
    cross = (x1 - x0) * (py - y0) - (y1 - y0) * (px - x0)
    if abs(cross) > eps * max(1.0, abs(x1 - x0) + abs(y1 - y0)):
        return False
    return min(x0, x1) - eps <= px <= max(x0, x1) + eps and min(y0, y1) - eps <= py <= max(y0, y1) + eps


def mat_size_argument(text: str) -> tuple[float, float]:
    """--mat-size WxH in millimetres (e.g. 2362x1143)."""
    match = re.fullmatch(r"\s*([0-9]*\.?[0-9]+)\s*[xX×]\s*([0-9]*\.?[0-9]+)\s*", text)
    if not match or float(match.group(1)) <= 0 or float(match.group(2)) <= 0:
        raise ValueError(f"{text!r}: give the mat's printed size in mm as WIDTHxHEIGHT, e.g. 2362x1143")
    return float(match.group(1)), float(match.group(2))


def bare_mat(image: Path, size_mm: tuple[float, float]) -> WorldSpec:
    """A world of one mat image on an empty walled table, the robot at the centre facing +x."""
    image = Path(image).resolve()
    if image.suffix.lower() not in MAT_SUFFIXES:
        raise WorldFileError([f"{image}: not a PNG, JPEG or PDF mat image"])
    if not image.is_file():
        raise WorldFileError([f"{image}: mat image does not exist"])
    return WorldSpec(
        path=image,
        name=image.stem,
        description=f"mat image {image.name} at {size_mm[0]:g} x {size_mm[1]:g} mm",
        mat=image,
        size_mm=size_mm,
        start=(size_mm[0] / 2, size_mm[1] / 2, 0.0),
    )


# A bare image's printed size travels with the world's name through a SimJob: IMAGE@WxH.
_SIZED = re.compile(r"^(.*)@([0-9.]+[xX][0-9.]+)$")


def sized_image(name: str) -> tuple[str, tuple[float, float] | None]:
    """(path, size) of a world named IMAGE@WxH; (name, None) for any other name."""
    match = _SIZED.match(name)
    if match and Path(match.group(1)).suffix.lower() in MAT_SUFFIXES:
        return match.group(1), mat_size_argument(match.group(2))
    return name, None


def open_world(name: str) -> WorldSpec | None:
    """The WorldSpec a --world names (a .toml file, or IMAGE@WxH); None for anything else. Raises
    WorldFileError for a world file or mat image that cannot be used."""
    path, size = sized_image(name)
    if size is not None:
        return bare_mat(Path(path), size)
    if Path(name).suffix.lower() == WORLD_SUFFIX:
        return load(name)
    if Path(name).suffix.lower() in MAT_SUFFIXES:
        raise WorldFileError(
            [
                f"{name}: a bare mat image needs its printed size: "
                "add --mat-size WIDTHxHEIGHT (mm), e.g. 2362x1143"
            ]
        )
    return None
