"""The hub's flash on a host directory, as MicroPython's os and open show it."""

import errno
import os

import pytest

from openbricks_sim.virtual_hub.hub_fs import BLOCK_BYTES, S_IFDIR, S_IFREG, HubFS


@pytest.fixture
def fs(tmp_path):
    return HubFS(tmp_path / "flash", capacity_bytes=64 * BLOCK_BYTES)


def test_files_land_in_the_hub_directory_under_their_hub_paths(fs, tmp_path):
    hub_os = fs.os_module()
    hub_os.mkdir("/lib")
    with fs.open("/lib/helper.py", "w") as f:
        f.write("X = 1\n")
    assert (tmp_path / "flash" / "lib" / "helper.py").read_text() == "X = 1\n"
    assert hub_os.listdir("/") == ["lib"]
    assert list(hub_os.ilistdir("/lib")) == [("helper.py", S_IFREG, 0, 6)]
    assert list(hub_os.ilistdir()) == [("lib", S_IFDIR, 0, 0)]


def test_stat_is_micropythons_ten_tuple(fs):
    with fs.open("/a.bin", "wb") as f:
        f.write(b"\x00" * 300)
    info = fs.os_module().stat("/a.bin")
    assert len(info) == 10 and info[0] == S_IFREG and info[6] == 300
    assert fs.os_module().stat("/")[0] == S_IFDIR


def test_errors_are_plain_oserrors_named_as_micropython_names_them(fs):
    with pytest.raises(OSError) as caught:
        fs.os_module().stat("/missing.py")
    assert caught.value.args == (errno.ENOENT, "ENOENT") and str(caught.value) == "[Errno 2] ENOENT"
    with pytest.raises(OSError) as caught:
        fs.open("/nothing/here.txt", "w")
    assert caught.value.errno == errno.ENOENT
    fs.os_module().mkdir("/d")
    with pytest.raises(OSError) as caught:
        fs.os_module().mkdir("/d")
    assert caught.value.args[1] == "EEXIST"
    with pytest.raises(OSError) as caught:
        fs.os_module().remove("/d")
    assert caught.value.args[1] == "EISDIR"


def test_dot_dot_and_links_never_leave_the_flash(fs, tmp_path):
    (tmp_path / "secret.txt").write_text("host file")
    with fs.open("/../../secret.txt", "w") as f:
        f.write("hub file")  # `..` stops at the hub's root
    assert (tmp_path / "secret.txt").read_text() == "host file"
    assert (tmp_path / "flash" / "secret.txt").read_text() == "hub file"
    os.symlink(tmp_path / "secret.txt", tmp_path / "flash" / "link.txt")
    with pytest.raises(OSError) as caught:
        fs.open("/link.txt")
    assert caught.value.errno == errno.EACCES


def test_relative_paths_follow_the_working_directory(fs):
    hub_os = fs.os_module()
    hub_os.mkdir("sub")
    hub_os.chdir("sub")
    assert hub_os.getcwd() == "/sub"
    with fs.open("note.txt", "w") as f:
        f.write("x")
    assert hub_os.listdir("/sub") == ["note.txt"]
    hub_os.chdir("..")
    assert hub_os.getcwd() == "/"
    with pytest.raises(OSError):
        hub_os.chdir("/sub/note.txt")


def test_text_files_keep_their_newlines_as_written(fs):
    with fs.open("/crlf.txt", "w") as f:
        f.write("a\r\nb\n")
    with fs.open("/crlf.txt") as f:
        assert f.read() == "a\r\nb\n"


def test_a_full_flash_refuses_writes_with_enospc_and_frees_space_on_remove(fs):
    hub_os = fs.os_module()
    blocks = hub_os.statvfs("/")
    assert blocks[0] == BLOCK_BYTES and blocks[2] == 64
    with fs.open("/big.bin", "wb") as f:
        f.write(b"\xff" * (40 * BLOCK_BYTES))
    with pytest.raises(OSError) as caught, fs.open("/more.bin", "wb") as f:
        f.write(b"\xff" * (40 * BLOCK_BYTES))
    assert caught.value.args[1] == "ENOSPC"
    assert hub_os.statvfs("/")[3] < 24
    hub_os.remove("/big.bin")
    hub_os.remove("/more.bin")
    with fs.open("/again.bin", "wb") as f:
        f.write(b"\xff" * (40 * BLOCK_BYTES))


def test_rename_replaces_the_target_and_bad_modes_are_refused(fs):
    hub_os = fs.os_module()
    for name, text in (("/a", "new"), ("/b", "old")):
        with fs.open(name, "w") as f:
            f.write(text)
    hub_os.rename("/a", "/b")
    assert hub_os.listdir("/") == ["b"]
    with fs.open("/b") as f:
        assert f.read() == "new"
    with pytest.raises(ValueError):
        fs.open("/b", "rw")
