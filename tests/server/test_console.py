"""The commands' shared terminal output: steps, the progress bar."""

import io

from openbricks_server.console import ProgressBar


def test_a_progress_bar_on_a_terminal_has_no_colour_under_no_color(monkeypatch):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    def drawn():
        stream = Terminal()
        bar = ProgressBar("writing", stream)
        bar.update(50)
        bar.finish()
        return stream.getvalue()

    monkeypatch.delenv("NO_COLOR", raising=False)
    monkeypatch.setenv("TERM", "xterm-256color")
    assert "\x1b[3" in drawn() or "\x1b[9" in drawn()  # coloured
    monkeypatch.setenv("NO_COLOR", "1")
    plain = drawn()
    assert "100%" in plain and "\x1b[3" not in plain and "\x1b[9" not in plain
