"""The event stream over a real WebSocket: order, resuming from the ring and from the store, gaps that
are never silent, and a slow client that is resynced while a fast one keeps up."""

import json
import os
import threading
import time

import pytest

from openbricks_server.daemon.hub_events import HubState, OutputLine, RunStart

from .conftest import start_daemon


def recv(ws, timeout=30):
    return json.loads(ws.recv(timeout=timeout))


def numbered(ws, count, timeout=30):
    """The next `count` numbered events (control messages other than gap/resync are skipped)."""
    out = []
    while len(out) < count:
        message = recv(ws, timeout)
        if message["seq"] is not None:
            out.append(message)
    return out


def start_run(daemon, hub="hub-a"):
    daemon.call(daemon.ctx.hub_events.hub_changed, HubState(hub, hub.upper(), "virtual", hub, "running"))
    return daemon.call(daemon.ctx.hub_events.run_started, RunStart(hub, "daemon", int(time.time() * 1000)))


def emit(daemon, run_id, first, count, text="line {}"):
    lines = [
        OutputLine(n, text.format(n), None, int(time.time() * 1000)) for n in range(first, first + count)
    ]
    for line in lines:
        daemon.call(daemon.ctx.hub_events.run_output, run_id, [line])


def test_events_arrive_in_order_with_per_run_line_numbers(daemon):
    with daemon.websocket() as ws:
        hello = recv(ws)
        assert hello["type"] == "hello" and hello["seq"] is None and hello["data"]["boot"]
        run_a = start_run(daemon, "hub-a")
        run_b = start_run(daemon, "hub-b")
        for n in range(1, 6):
            emit(daemon, run_a, n, 1, "a{}")
            emit(daemon, run_b, n, 1, "b{}")
        events = numbered(ws, 4 + 10)
    seqs = [e["seq"] for e in events]
    assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))
    assert [e["type"] for e in events[:4]] == ["hub", "run_started", "hub", "run_started"]
    assert set(events[0]) == {"seq", "type", "hub", "run", "ts", "data"}
    for run, prefix in ((run_a, "a"), (run_b, "b")):
        lines = [ln for e in events if e["run"] == run and e["type"] == "output" for ln in e["data"]["lines"]]
        assert [(ln["line_no"], ln["text"]) for ln in lines] == [(n, f"{prefix}{n}") for n in range(1, 6)]
        assert all(e["hub"] == ("hub-a" if prefix == "a" else "hub-b") for e in events if e["run"] == run)


def test_a_reconnecting_client_gets_exactly_what_it_missed_from_the_ring(daemon):
    run = start_run(daemon)
    with daemon.websocket() as ws:
        boot = recv(ws)["data"]["boot"]
        emit(daemon, run, 1, 5)
        last = numbered(ws, 5)[-1]["seq"]
    emit(daemon, run, 6, 20)
    with daemon.websocket(f"since={last}&boot={boot}") as ws:
        assert recv(ws)["type"] == "hello"
        missed = numbered(ws, 20)
        emit(daemon, run, 26, 1)
        live = numbered(ws, 1)
    assert [e["seq"] for e in missed + live] == list(range(last + 1, last + 22))
    assert [e["data"]["lines"][0]["line_no"] for e in missed + live] == list(range(6, 27))


def test_past_the_ring_a_client_is_replayed_from_the_store(tmp_path):
    daemon = start_daemon(tmp_path / "data", ring_size=50)
    try:
        run = start_run(daemon)
        with daemon.websocket() as ws:
            boot = recv(ws)["data"]["boot"]
            since = daemon.ctx.events.seq
        emit(daemon, run, 1, 300)
        with daemon.websocket(f"since={since}&boot={boot}") as ws:
            recv(ws)
            replayed = numbered(ws, 300)
    finally:
        daemon.stop()
    assert [e["seq"] for e in replayed] == list(range(since + 1, since + 301))
    assert [e["data"]["lines"][0]["text"] for e in replayed] == [f"line {n}" for n in range(1, 301)]


def test_events_that_are_truly_gone_are_announced_as_a_gap(tmp_path):
    daemon = start_daemon(tmp_path / "data", ring_size=10)
    try:
        run = start_run(daemon)
        with daemon.websocket() as ws:
            boot = recv(ws)["data"]["boot"]
            since = daemon.ctx.events.seq
        emit(daemon, run, 1, 3)
        for n in range(5):  # progress notices are not stored
            daemon.call(lambda n=n: daemon.ctx.events.publish("progress", {"n": n}, persist=False))
        emit(daemon, run, 4, 30)
        with daemon.websocket(f"since={since}&boot={boot}") as ws:
            recv(ws)
            messages = [recv(ws) for _ in range(3 + 1 + 30)]
    finally:
        daemon.stop()
    types = [m["type"] for m in messages]
    assert types == ["output"] * 3 + ["gap"] + ["output"] * 30
    gap = messages[3]["data"]
    assert (gap["from_seq"], gap["to_seq"]) == (since + 4, since + 8)
    assert gap["reason"] == "not_kept" and gap["hint"]


def test_a_client_of_an_unknown_lifetime_is_told_so(daemon):
    with daemon.websocket("since=5&boot=01HZZZZZZZZZZZZZZZZZZZZZZZ") as ws:
        assert recv(ws)["type"] == "hello"
        gap = recv(ws)
    assert gap["type"] == "gap" and gap["data"]["reason"] == "unknown_lifetime"


def test_a_slow_client_is_resynced_while_a_fast_one_keeps_up(tmp_path):
    daemon = start_daemon(tmp_path / "data", client_queue=16)
    try:
        run = start_run(daemon)
        total = 400
        fast_events, fast_done = [], threading.Event()
        with daemon.websocket() as fast, daemon.websocket(rcvbuf=4096) as slow:
            recv(fast), recv(slow)
            first = daemon.ctx.events.seq + 1

            def read_fast():
                while len(fast_events) < total:
                    message = recv(fast)
                    fast_events.append(message)
                fast_done.set()

            reader = threading.Thread(target=read_fast, daemon=True)
            reader.start()
            started = time.monotonic()
            for n in range(1, total + 1):
                # ~20 KB of incompressible text per event: the slow client's buffers fill within the test
                big = [os.urandom(1000).hex() for _ in range(10)]
                lines = [OutputLine(n * 10 + i, big[i], None, int(time.time() * 1000)) for i in range(10)]
                daemon.call(daemon.ctx.hub_events.run_output, run, lines)
            assert fast_done.wait(30), "the fast client was held up by the slow one"
            fast_seconds = time.monotonic() - started
            slow_messages = []
            while True:  # now the slow client reads: a resync, then everything, in order, once
                message = recv(slow)
                slow_messages.append(message)
                if message["seq"] == first + total - 1:
                    break
    finally:
        daemon.stop()
    assert [m["seq"] for m in fast_events] == list(range(first, first + total))
    assert fast_seconds < 20
    kinds = [m["type"] for m in slow_messages]
    assert "resync" in kinds and "gap" not in kinds
    seqs = [m["seq"] for m in slow_messages if m["seq"] is not None]
    assert seqs == list(range(first, first + total))


def test_a_client_asking_for_batches_gets_every_event_in_order_in_few_frames(daemon):
    """`batch_ms`: frames are arrays of envelopes, at most one per interval, and nothing is lost."""
    with daemon.websocket("batch_ms=100") as ws:
        hello = json.loads(ws.recv(timeout=30))
        assert [m["type"] for m in hello] == ["hello"]
        run = start_run(daemon)
        total = 2 + 200  # the hub's status and the run's start, then its lines
        t0 = time.monotonic()
        writer = threading.Thread(target=emit, args=(daemon, run, 1, 200))
        writer.start()
        frames, events = 0, []
        while len(events) < total:
            frame = json.loads(ws.recv(timeout=30))
            assert isinstance(frame, list) and frame, "each frame is a non-empty array of envelopes"
            frames += 1
            events += [m for m in frame if m["seq"] is not None]
        elapsed = time.monotonic() - t0
        writer.join()
        ws.send(json.dumps({"cmd": "ping", "id": "p"}))
        reply = json.loads(ws.recv(timeout=30))
    seqs = [e["seq"] for e in events]
    assert seqs == list(range(seqs[0], seqs[0] + total))
    lines = [ln["line_no"] for e in events if e["type"] == "output" for ln in e["data"]["lines"]]
    assert lines == list(range(1, 201))
    assert frames <= elapsed / 0.1 + 2, f"{frames} frames in {elapsed:.2f} s at one per 100 ms"
    assert [m["type"] for m in reply] == ["reply"] and reply[0]["data"]["ok"]


def test_garbage_from_a_client_gets_an_error_reply_and_the_stream_goes_on(daemon):
    with daemon.websocket() as ws:
        recv(ws)
        replies = []
        for bad in ("not json", "[1, 2]", '{"cmd": 5}', '{"cmd": "launch_missiles", "id": 7}'):
            ws.send(bad)
            replies.append(recv(ws))
        ws.send(b"\x00\x01binary")
        replies.append(recv(ws))
        ws.send(json.dumps({"cmd": "ping", "id": "p1"}))
        pong = recv(ws)
    assert all(r["type"] == "reply" and r["data"]["ok"] is False for r in replies)
    assert [r["data"]["error"]["error"] for r in replies] == ["bad_message"] * 3 + [
        "unknown_command",
        "bad_message",
    ]
    assert replies[3]["data"]["id"] == 7 and "ping" in replies[3]["data"]["error"]["message"]
    assert pong["data"] == {"id": "p1", "cmd": "ping", "ok": True, "result": {"seq": daemon.ctx.events.seq}}


@pytest.mark.parametrize("query", ["since=-1", "since=abc", "batch_ms=0", "batch_ms=5000"])
def test_a_bad_resume_point_or_batch_interval_is_refused_before_the_stream_opens(daemon, query):
    from websockets.exceptions import InvalidStatus

    with pytest.raises(InvalidStatus) as refused:
        with daemon.websocket(query):
            pass
    assert refused.value.response.status_code in (403, 422)
