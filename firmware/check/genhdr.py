"""The headers MicroPython's build generates before it compiles a binding (genhdr/): the qstr table,
the root pointers and the version, made by MicroPython's own scripts from the sources being
checked, preprocessed under the target's configuration, as py/mkrules.cmake does for the port.
"""

import sys
from pathlib import Path

from steps import run


def generate(micropython, compiler, cpp_flags, bindings, out):
    """Write out/genhdr/*.h for `bindings` (the user C module's files); returns out (the include root)."""
    genhdr = out / "genhdr"
    genhdr.mkdir(parents=True, exist_ok=True)
    py = micropython / "py"
    python = sys.executable
    run(
        [python, str(py / "makeversionhdr.py"), str(genhdr / "mpversion.h")],
        "makeversionhdr.py",
        cwd=micropython,
    )
    last = genhdr / "qstr.i.last"
    flags = [*cpp_flags, "-DNO_QSTR"]
    run(
        [
            python,
            str(py / "makeqstrdefs.py"),
            "pp",
            *compiler,
            "-E",
            "output",
            str(last),
            "cflags",
            *flags,
            "cxxflags",
            *flags,
            "sources",
            *map(str, bindings),
        ],
        "collecting the bindings' qstrs (makeqstrdefs.py pp)",
    )
    for mode, collected in (("qstr", "qstrdefs.collected.h"), ("root_pointer", "root_pointers.collected")):
        run(
            [python, str(py / "makeqstrdefs.py"), "split", mode, str(last), str(genhdr / mode), "_"],
            f"makeqstrdefs.py split {mode}",
        )
        run(
            [
                python,
                str(py / "makeqstrdefs.py"),
                "cat",
                mode,
                "_",
                str(genhdr / mode),
                str(genhdr / collected),
            ],
            f"makeqstrdefs.py cat {mode}",
        )
    # The qstr list, preprocessed under the port's configuration (Q(...) lines survive as strings).
    listing = "".join(
        path.read_text()
        for path in (
            py / "qstrdefs.h",
            micropython / "ports" / "esp32" / "qstrdefsport.h",
            genhdr / "qstrdefs.collected.h",
        )
        if path.is_file()
    )
    quoted = "\n".join(f'"{line}"' if line.startswith("Q(") else line for line in listing.splitlines())
    preprocessed = run([*compiler, "-E", *cpp_flags, "-"], "preprocessing the qstr list", input=quoted)
    lines = [
        line[1:-1] if line.startswith('"Q(') and line.endswith(')"') else line
        for line in preprocessed.splitlines()
    ]
    (genhdr / "qstrdefs.preprocessed.h").write_text("\n".join(lines) + "\n")
    (genhdr / "qstrdefs.generated.h").write_text(
        run([python, str(py / "makeqstrdata.py"), str(genhdr / "qstrdefs.preprocessed.h")], "makeqstrdata.py")
    )
    (genhdr / "root_pointers.h").write_text(
        run(
            [python, str(py / "make_root_pointers.py"), str(genhdr / "root_pointers.collected")],
            "make_root_pointers.py",
        )
    )
    return out


def binding_sources(module_dir):
    return sorted(Path(module_dir).glob("*.c"))
