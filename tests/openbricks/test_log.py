"""Run logs on flash: slot reuse, run indices in the header, epoch stamps, async pump, byte cap."""

import os
import time

from fakes import clock, tmpdir
from fakes.expect import raises
from openbricks import log


def _lines(text):
    return text.rstrip("\n").split("\n")


def _one_run(log_dir, *texts, max_bytes=log.MAX_BYTES):
    with log.session(log_dir, max_bytes) as sess:
        for text in texts:
            log.write(text)
    return sess.index


def test_every_line_carries_the_utc_epoch_ms_and_the_header_names_the_run():
    with tmpdir.scratch() as log_dir:
        clock.set_epoch_ms(1783950123456)
        with log.session(log_dir) as sess:
            log.write("ambient: 33\n")
            time.sleep_ms(5)
            log.write("partial ")
            log.write("line\nsecond\n")
            log.note("button pressed -> stop")
        lines = _lines(log.read_run(sess.index, log_dir))
        assert lines == [
            "1783950123456 -- run_0 --",
            "1783950123456 ambient: 33",
            "1783950123461 partial line",
            "1783950123461 second",
            "1783950123461 button pressed -> stop",
        ]


def test_a_note_after_an_unfinished_print_starts_its_own_line():
    with tmpdir.scratch() as log_dir:
        with log.session(log_dir) as sess:
            log.write("progress: 10%")
            log.note("estop engaged")
        lines = _lines(log.read_run(sess.index, log_dir))
        assert lines[1].endswith(" progress: 10%")
        assert lines[2].endswith(" estop engaged")


def test_prints_stay_in_ram_until_pumped_while_framing_is_committed_at_once():
    with tmpdir.scratch() as log_dir:
        with log.session(log_dir) as sess:
            log.write("hello\n")
            assert "hello" not in log.read_run(sess.index, log_dir)
            log.pump()
            log.flush()
            assert "hello" in log.read_run(sess.index, log_dir)
            log.note("started: test")
            assert "started: test" in log.read_run(sess.index, log_dir)


def test_ten_slot_files_are_reused_and_indices_keep_growing():
    with tmpdir.scratch() as log_dir:
        for n in range(13):
            assert _one_run(log_dir, "run %d\n" % n) == n
        assert sorted(os.listdir(log_dir)) == sorted("slot_%d.log" % k for k in range(10))
        runs = log.list_runs(log_dir)
        assert [index for index, _path in runs] == list(range(3, 13))
        assert runs[-1][1] == log_dir + "/slot_2.log"
        assert "run 12" in log.read_run(12, log_dir)
        with raises(OSError, "run 2 is not on the hub (only the last 10 runs are kept)"):
            log.read_run(2, log_dir)
        with raises(OSError, "run 13 is not on the hub"):
            log.read_run(13, log_dir)


def test_a_reused_slot_holds_only_the_new_run():
    with tmpdir.scratch() as log_dir:
        _one_run(log_dir, "x" * 500 + "\n")
        for _ in range(9):
            _one_run(log_dir)
        index = _one_run(log_dir, "short\n")
        assert index == 10
        text = log.read_run(10, log_dir)
        assert "x" not in text and len(_lines(text)) == 2


def test_a_runaway_print_loop_is_capped_but_the_framing_still_lands():
    with tmpdir.scratch() as log_dir:
        with log.session(log_dir, max_bytes=4096) as sess:
            for n in range(1000):
                log.write("line %d of a runaway loop\n" % n)
                if n % 50 == 0:
                    log.pump()
            log.note("stopped: KeyboardInterrupt (12 ms after press, 0 retries)")
        text = log.read_run(sess.index, log_dir)
        assert len(text) <= 4096 + 1024
        assert "log capped at 4096 bytes" in text
        assert "line 999" not in text
        assert _lines(text)[-1].endswith("stopped: KeyboardInterrupt (12 ms after press, 0 retries)")
        assert sess.dropped_bytes > 20000


def test_outside_a_run_the_log_calls_do_nothing():
    log.write("nobody listens\n")
    log.note("nothing")
    log.pump()
    log.flush()
    assert log.worst_write_ms() == 0
    assert log.active() is None


def test_missing_log_directory_is_created_and_an_empty_one_lists_no_runs():
    with tmpdir.scratch() as base:
        log_dir = base + "/openbricks_logs"
        assert log.list_runs(log_dir) == []
        assert _one_run(log_dir, "first\n") == 0
        assert log.list_runs(log_dir) == [(0, log_dir + "/slot_0.log")]


def test_a_file_where_the_log_folder_belongs_is_named_with_the_fix():
    with tmpdir.scratch() as base:
        log_dir = base + "/openbricks_logs"
        with open(log_dir, "w") as f:
            f.write("a file stored at the folder's name")
        with raises(OSError, "is a file, but the hub keeps its run logs in a folder of that name") as caught:
            _one_run(log_dir, "never logged\n")
        assert "mpremote rm " + log_dir in str(caught.value)
        assert "Errno" not in str(caught.value)
