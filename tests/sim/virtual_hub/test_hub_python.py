"""What code on a virtual hub sees of Python: its flash for open/os/import, MicroPython's tracebacks,
deflate, and NVS that outlives the process. In-process, with no simulator behind it."""

import io
import sys
import types
import zlib

import pytest

from openbricks_sim.virtual_hub import deflate_module
from openbricks_sim.virtual_hub.hub_fs import HubFS
from openbricks_sim.virtual_hub.hub_python import HubPython
from openbricks_sim.virtual_hub.nvs_store import PersistentNVS


@pytest.fixture
def hub(tmp_path):
    fs = HubFS(tmp_path / "flash")
    python = HubPython(fs, types.ModuleType("time"), "openbricks virtual hub (simulated) with ESP32S3")
    python.install()
    try:
        yield python
    finally:
        python.forget_flash_modules()
        python.uninstall()


def run(hub, source, filename="<stdin>"):
    hub.run(hub.compile(source, filename))
    return hub.namespace


def write(hub, path, text):
    with hub.fs.open(path, "w") as f:
        f.write(text)


def test_open_and_os_reach_the_flash_not_the_host(hub, tmp_path):
    namespace = run(
        hub, "import os\nf = open('/made.txt', 'w')\nf.write('on the hub')\nf.close()\nnames = os.listdir()"
    )
    assert (tmp_path / "flash" / "made.txt").read_text() == "on the hub"
    assert namespace["names"] == ["made.txt"]
    namespace = run(hub, "import uos, sys\nsame = uos is sys.modules.get('os')\nplatform = sys.platform")
    assert namespace["same"] is True  # the hub's os, as its sys.modules shows it
    assert sys.modules["os"].getpid  # the host's os module is untouched
    assert namespace["platform"] == "esp32"


def test_imports_reach_only_what_the_esp32_port_has(hub):
    for name in ("subprocess", "socket", "ctypes", "importlib", "shutil", "openbricks_sim"):
        with pytest.raises(ImportError, match=f"no module named '{name}'"):
            run(hub, f"import {name}")
    namespace = run(hub, "import json, struct, math, utime, ujson\nok = json is ujson")
    assert namespace["ok"] is True


def test_sys_is_micropythons_and_io_open_reaches_only_the_flash(hub):
    namespace = run(
        hub,
        "import sys, io\n"
        "name = sys.implementation.name\n"
        "version = sys.implementation.version\n"
        "hidden = [a for a in ('executable', 'meta_path', '_getframe') if hasattr(sys, a)]\n"
        "host = [m for m in ('subprocess', 'importlib', 'posixpath', 'openbricks_sim') if m in sys.modules]\n"
        "try:\n"
        "    io.open('/../../etc/passwd')\n"
        "except OSError as exc:\n"
        "    refused = exc.args[0]\n",
    )
    assert namespace["name"] == "micropython" and namespace["version"][:3] == (1, 27, 0)
    assert namespace["hidden"] == [] and namespace["host"] == []
    assert namespace["refused"] == 2  # ENOENT: /etc/passwd on the flash, not the host's


def test_a_module_on_the_flash_imports_from_the_program_directory_and_lib(hub):
    hub.fs.os_module().mkdir("/lib")
    write(hub, "/lib/shapes.py", "def square(n):\n    return n * n\n")
    write(hub, "/helper_mod.py", "import shapes\nVALUE = shapes.square(7)\n")
    namespace = run(hub, "import helper_mod\nvalue = helper_mod.VALUE\nwhere = helper_mod.__file__")
    assert namespace["value"] == 49 and namespace["where"] == "/helper_mod.py"
    hub.forget_flash_modules()
    assert "helper_mod" not in sys.modules and "shapes" not in sys.modules


def test_a_package_on_the_flash_imports_its_submodules(hub):
    hub.fs.os_module().mkdir("/pkg")
    write(hub, "/pkg/__init__.py", "from . import inner\n")
    write(hub, "/pkg/inner.py", "NAME = 'inner'\n")
    assert run(hub, "import pkg\nname = pkg.inner.NAME")["name"] == "inner"


def test_an_mpy_on_the_flash_is_refused_with_the_reason(hub):
    with hub.fs.open("/compiled.mpy", "wb") as f:
        f.write(b"M\x06\x00\x1f")
    with pytest.raises(ImportError, match="copy the source"):
        run(hub, "import compiled")


def test_host_standard_modules_win_over_files_on_the_flash(hub):
    write(hub, "/json.py", "raise RuntimeError('the flash file must not shadow a built-in module')\n")
    assert run(hub, "import json\nok = json.dumps(1)")["ok"] == "1"


def test_tracebacks_read_like_micropythons(hub):
    write(hub, "/failing.py", "def explode():\n    open('/missing.txt')\n")
    with pytest.raises(OSError) as caught:
        run(hub, "import failing\nfailing.explode()")
    text = hub.traceback.format(caught.value)
    assert text == (
        "Traceback (most recent call last):\n"
        '  File "<stdin>", line 2, in <module>\n'
        '  File "/failing.py", line 2, in explode\n'
        "OSError: [Errno 2] ENOENT\n"
    )
    with pytest.raises(KeyboardInterrupt) as caught:
        run(hub, "raise KeyboardInterrupt")
    assert hub.traceback.format(caught.value).endswith("KeyboardInterrupt: \n")
    with pytest.raises(SyntaxError) as caught:
        hub.compile("x = (", "<stdin>")
    assert hub.traceback.format(caught.value).startswith(
        'Traceback (most recent call last):\n  File "<stdin>", line 1'
    )


def test_print_exception_is_in_sys_and_a_reset_empties_the_namespace(hub):
    out = io.StringIO()
    hub.namespace["out"] = out
    run(hub, "import sys\ntry:\n    1/0\nexcept Exception as e:\n    sys.print_exception(e, out)")
    assert out.getvalue().endswith("ZeroDivisionError: division by zero\n")
    hub.reset()
    assert "out" not in hub.namespace


def test_deflate_round_trips_in_every_container():
    for fmt in (deflate_module.RAW, deflate_module.ZLIB, deflate_module.GZIP):
        sink = io.BytesIO()
        with deflate_module.DeflateIO(sink, fmt) as writer:
            writer.write(b"openbricks " * 100)
        packed = sink.getvalue()
        assert len(packed) < 200
        source = io.BytesIO(packed)
        auto = fmt if fmt == deflate_module.RAW else deflate_module.AUTO
        assert deflate_module.DeflateIO(source, auto).read() == b"openbricks " * 100
    host_packed = zlib.compress(b"from the host")
    assert deflate_module.DeflateIO(io.BytesIO(host_packed), deflate_module.ZLIB).read() == b"from the host"
    with pytest.raises(OSError):
        deflate_module.DeflateIO(io.BytesIO(b"not zlib at all"), deflate_module.ZLIB).read()


def test_nvs_commits_survive_a_new_process(tmp_path):
    path = tmp_path / "nvs.json"
    nvs = PersistentNVS(path)
    nvs["openbricks"] = {"hub_name": b"RobotA", "ble_enabled": 0}
    again = PersistentNVS(path)
    assert again == {"openbricks": {"hub_name": b"RobotA", "ble_enabled": 0}}
    path.write_text("{broken")
    with pytest.raises(ValueError, match="move it aside"):
        PersistentNVS(path)


def test_gc_reports_memory_as_micropython_does(hub):
    namespace = run(hub, "import gc\ngc.collect()\nfree = gc.mem_free()\nused = gc.mem_alloc()")
    assert namespace["free"] > 0 and 10_000_000 < namespace["used"] < 2_000_000_000


MEMORY_VFS = """\
import io, os, vfs

class MemoryVFS:
    def __init__(self, files):
        self.files = files
        self.calls = []
    def mount(self, readonly, mkfs):
        self.calls.append(('mount', readonly))
    def umount(self):
        self.calls.append(('umount',))
    def chdir(self, path):
        self.calls.append(('chdir', path))
    def ilistdir(self, path):
        return iter([(name, 0x8000, 0) for name in sorted(self.files)])
    def stat(self, path):
        if path == '/':
            return (0x4000, 0, 0, 0, 0, 0, 0, 0, 0, 0)
        if path[1:] not in self.files:
            raise OSError(2)
        return (0x8000, 0, 0, 0, 0, 0, len(self.files[path[1:]]), 0, 0, 0)
    def open(self, path, mode):
        self.calls.append(('open', path, mode))
        return io.BytesIO(self.files[path[1:]]) if 'b' in mode else io.StringIO(self.files[path[1:]].decode())

memory = MemoryVFS({'greeting.py': b'WORDS = "hello from memory"\\n', 'note.txt': b'a note'})
"""


def test_a_filesystem_mounted_by_hub_code_serves_open_listdir_chdir_and_imports(hub):
    run(hub, MEMORY_VFS)
    namespace = run(
        hub,
        "os.mount(memory, '/mem')\n"
        "table = [point for _fs, point in vfs.mount()]\n"
        "listing = os.listdir('/mem')\n"
        "note = open('/mem/note.txt').read()\n"
        "os.chdir('/mem')\n"
        "here = os.getcwd()\n"
        "import greeting\n"
        "words = greeting.WORDS\n"
        "os.umount('/mem')\n"
        "after = (os.getcwd(), len(vfs.mount()))\n",
    )
    assert namespace["table"] == ["/", "/mem"]
    assert namespace["listing"] == ["greeting.py", "note.txt"]
    assert namespace["note"] == "a note" and namespace["here"] == "/mem"
    assert namespace["words"] == "hello from memory"
    assert namespace["after"] == ("/", 1)  # unmounting the working directory goes back to the flash
    calls = namespace["memory"].calls
    assert calls[0] == ("mount", False) and ("chdir", "/") in calls and calls[-1] == ("umount",)


def test_a_soft_reset_unmounts_everything_but_the_flash(hub):
    run(hub, MEMORY_VFS + "os.mount(memory, '/mem')\n")
    hub.reset()
    namespace = run(hub, "import vfs\ntable = [point for _fs, point in vfs.mount()]\n")
    assert namespace["table"] == ["/"]
    with pytest.raises(OSError):
        run(hub, "import os\nos.umount('/mem')\n")
