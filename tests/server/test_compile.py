"""The host compile step: what a user sees before any hub is contacted."""

import time

import pytest

from openbricks_server.compile import (
    MAX_PROGRAM_BYTES,
    ProgramError,
    code_program,
    compile_program,
    read_program,
)


def test_a_good_program_compiles_to_bytecode_that_names_the_file(tmp_path):
    path = tmp_path / "square.py"
    path.write_text("from openbricks import log\nprint('héllo')\n", encoding="utf-8")
    program = compile_program(read_program(path))
    assert program.mpy.startswith(b"M\x06")  # .mpy magic and version 6
    assert b"square.py" in program.mpy  # tracebacks on the hub say File "square.py"


def test_a_syntax_error_names_file_and_line_and_quotes_it_within_milliseconds(tmp_path):
    path = tmp_path / "mission.py"
    path.write_text("print('start')\nx = (1,\nif x:\n    pass\n", encoding="utf-8")
    started = time.perf_counter()
    with pytest.raises(ProgramError) as caught:
        compile_program(read_program(path))
    elapsed_ms = (time.perf_counter() - started) * 1000
    message = str(caught.value)
    # The bracket opened on line 2 is the mistake (mpy-cross only notices on line 3): named, quoted
    # and pointed at.
    assert message == "mission.py:2: SyntaxError: '(' was never closed\n    2 | x = (1,\n      |     ^"
    assert elapsed_ms < 500


def test_syntax_only_desktop_python_has_is_named_as_such():
    with pytest.raises(ProgramError) as caught:
        compile_program(code_program("match x:\n    case 1:\n        pass\n"))
    assert str(caught.value).startswith("<code>:1: SyntaxError: invalid syntax (this is valid desktop Python")
    assert "1 | match x:" in str(caught.value)


def test_inline_code_errors_name_the_code():
    with pytest.raises(ProgramError, match=r"^<code>:1: SyntaxError"):
        compile_program(code_program("print(1 +)"))


def test_missing_file_and_folder_are_refused_clearly(tmp_path):
    with pytest.raises(ProgramError, match="nope.py: no such file"):
        read_program(tmp_path / "nope.py")
    with pytest.raises(ProgramError, match="is a folder"):
        read_program(tmp_path)


def test_non_utf8_source_is_refused_with_its_line(tmp_path):
    path = tmp_path / "latin1.py"
    path.write_bytes("x = 1\nprint('café')\n".encode("latin-1"))
    with pytest.raises(ProgramError, match=r"latin1.py, line 2: byte 0xe9 is not UTF-8"):
        read_program(path)


def test_an_oversized_program_is_refused_before_compiling(tmp_path):
    path = tmp_path / "huge.py"
    path.write_bytes(b"#" * (MAX_PROGRAM_BYTES + 1))
    with pytest.raises(ProgramError, match=f"{MAX_PROGRAM_BYTES + 1} bytes; a hub takes programs up to"):
        read_program(path)
