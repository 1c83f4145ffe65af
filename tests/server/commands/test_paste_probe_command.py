"""The paste probe sends data, never code: each size is one host call, exactly that many bytes long."""

from openbricks_server.commands.paste_probe import probe_command, sizes


def test_each_probe_is_a_host_call_of_exactly_the_probed_size():
    for size in sizes(8192):
        probe, padding = probe_command(size, f"paste-probe-{size}")
        assert len(probe.source) == size
        assert probe.source.startswith(
            f"import openbricks.host_calls as h;h.tag('{probe.tag}');h.paste_probe("
        )
        assert probe.source.endswith("padding='" + "." * padding + "')")
