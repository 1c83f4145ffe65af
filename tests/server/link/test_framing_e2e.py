"""Result framing through the real stack (raw-paste, host calls, run streaming) against a real
virtual hub: whatever a program prints, the host shows exactly that and gets the hub's result, and
a Ctrl-C at any point ends in a confirmed stop without an internal line showing."""

import asyncio

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from openbricks_server.link import HubException
from openbricks_server.link.host_call import FRAME_PREFIX
from openbricks_server.link.raw_repl import RawRepl
from openbricks_server.link.virtual import spawn_pty_hub

pytestmark = pytest.mark.e2e

STEP_TIMEOUT_S = 30


class Session:
    """One virtual hub over its pty, driven from one event loop across hypothesis examples."""

    def __init__(self, directory):
        self.loop = asyncio.new_event_loop()
        self.hub = self.do(spawn_pty_hub("Framing", hub_dir=str(directory), extra_args=["--speed", "max"]))
        self.repl = RawRepl(self.hub.link, timeout_s=STEP_TIMEOUT_S)
        self.do(self.repl.enter())

    def do(self, coro):
        async def bounded():
            async with asyncio.timeout(STEP_TIMEOUT_S * 2):
                return await coro

        return self.loop.run_until_complete(bounded())

    def close(self):
        self.do(self.hub.stop())
        self.loop.close()


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    s = Session(tmp_path_factory.mktemp("framing") / "Framing")
    yield s
    s.close()


def cooked(text: str) -> bytes:
    return text.replace("\n", "\r\n").encode()


# What a program prints, as (source line, the bytes the host must show).
_TEXT = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\r"), max_size=30)
_PIECES = st.one_of(
    _TEXT.map(lambda t: (f"print({t!r}, end='')", cooked(t))),
    st.binary(max_size=30).map(lambda b: (f"sys.stdout.buffer.write({b!r})", b)),
    st.sampled_from(
        [
            '@openbricks-result {"ok": true}\n',
            "@openbricks:",
            "@openbricks:- result {}\n",
            '@openbricks:deadbeef result {"ok": true, "outcome": "finished"}',
            "\x04",
            "\x04\x04>",
            "@",
        ]
    ).map(lambda t: (f"print({t!r}, end='')", cooked(t))),
)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(pieces=st.lists(_PIECES, max_size=6))
def test_whatever_a_program_prints_is_shown_verbatim_and_the_result_arrives(session, pieces):
    source = "import sys\n" + "".join(line + "\n" for line, _ in pieces)
    expected = b"".join(shown for _, shown in pieces)
    session.do(session.repl.put("/program.py", source.encode()))
    chunks = []
    result = session.do(session.repl.run("/program.py", on_output=chunks.append, timeout_s=STEP_TIMEOUT_S))
    assert result["ok"] and result["outcome"] == "finished" and isinstance(result["run"], int)
    assert b"".join(chunks) == expected


ENDLESS = "n = 0\nwhile True:\n    print('line', n, end='' if n % 3 else '\\n')\n    n += 1\n"


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(delay_s=st.floats(0.0, 0.4))
def test_a_ctrl_c_at_any_moment_ends_in_a_confirmed_stop_with_no_internal_line_shown(session, delay_s):
    session.do(session.repl.put("/program.py", ENDLESS.encode()))
    chunks = []

    async def run_and_stop():
        task = asyncio.ensure_future(
            session.repl.run("/program.py", on_output=chunks.append, timeout_s=STEP_TIMEOUT_S)
        )
        await asyncio.sleep(delay_s)
        await session.repl.interrupt()
        return await task

    try:
        result = session.do(run_and_stop())
    except HubException as exc:  # the stop reached the hub before the run command compiled
        assert "KeyboardInterrupt" in exc.summary and not chunks
        return
    assert result["ok"] and result["outcome"] in ("stopped", "finished")
    shown = b"".join(chunks)
    # What arrived is the program's stream from its start, in order, cut wherever the stop landed.
    full = b"".join(b"line %d" % n + (b"" if n % 3 else b"\r\n") for n in range(shown.count(b"line") + 1))
    assert full.startswith(shown) and FRAME_PREFIX not in shown
