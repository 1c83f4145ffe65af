"""The API names chapter 7 of the manual documents, read from its text.

The manual lists each class as `class openbricks.module.Name (args)` (module functions and exceptions
are written fully qualified too), followed by its members: `name(args)` on a line of its own for
methods, `NAME = value` for attributes. Example code in the chapter is never a bare signature line
(`m = JGB37Motor(...)`, `print(m.angle())`), which is what tells the two apart.
"""

import re
import subprocess
from pathlib import Path

MANUAL_NAME = "openbricks-manual-2.7.1.txt"
ROOT = Path(__file__).resolve().parents[2]
_QUALIFIED = re.compile(r"^(class |exception )?`?(openbricks(?:\.\w+)+)`?\s*(\(|$)")
# A signature alone on its line: `name(args)`, defaults may hold one call's empty parentheses (`skip=()`).
_METHOD = re.compile(
    r"^(?:classmethod |staticmethod )?`?([a-z_][a-z0-9_]*)`?\s?\([^()#=]*(=[^()#]*(\(\))?[^()#]*)?\)?`?$"
)
# A class attribute with a literal value: `NAME = 500`, `led = None`, `PINS = (1, 2, 3)`.
_ATTRIBUTE = re.compile(
    r"^`?([A-Za-z_][A-Za-z0-9_]*) = (None|True|False|-?[0-9][0-9_.]*|\([-0-9., ]*\)|'[^']*'|\"[^\"]*\")`?$"
)
_SECTION = re.compile(r"^\d+\.\d+(\.\d+)? ")


def manual_path() -> Path:
    """The manual in the `shared/spec` folder beside this checkout, or beside the main checkout of a git
    worktree (where the Makefile finds the MicroPython sources too)."""
    places = [ROOT.parent]
    common = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--path-format=absolute", "--git-common-dir"],
        capture_output=True,
        text=True,
    )
    if common.returncode == 0:
        places.append(Path(common.stdout.strip()).parent.parent)
    for place in places:
        candidate = place / "shared" / "spec" / MANUAL_NAME
        if candidate.is_file():
            return candidate
    raise FileNotFoundError(f"{MANUAL_NAME} is not in shared/spec beside {' or '.join(map(str, places))}")


def chapter_7(text: str) -> str:
    start = text.index("\n7.1 robotics")
    return text[start : text.index("\nARCHITECTURE\n", start)]


def api_names(text: str) -> list[str]:
    """Every qualified name the chapter documents, in the order it documents them."""
    names: list[str] = []
    owner = None  # the class whose members follow
    for line in chapter_7(text).splitlines():
        if line[:1].isspace():  # indented: inside example code
            continue
        line = line.strip()
        if _SECTION.match(line):
            owner = None
            continue
        qualified = _QUALIFIED.match(line)
        if qualified:
            names.append(qualified.group(2))
            owner = qualified.group(2) if qualified.group(1) == "class " else None
            continue
        member = _METHOD.match(line) or _ATTRIBUTE.match(line)
        if owner and member:
            names.append(f"{owner}.{member.group(1)}")
    return list(dict.fromkeys(names))
