"""The OpenAPI schema fuzzed with schemathesis (operator token): whatever it sends, no 5xx, and every
answer matches the schema, errors included (one error shape). Bounded: a few examples per operation."""

import pytest
import schemathesis
from hypothesis import HealthCheck, given, settings
from schemathesis import GenerationMode
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    response_schema_conformance,
    status_code_conformance,
)

from openbricks_server.daemon.hub_events import OutputLine, RunStart

from .conftest import start_daemon

EXAMPLES_PER_OPERATION = 4  # per operation and mode (valid input, invalid input)


@pytest.fixture(scope="module")
def fuzzed_daemon(tmp_path_factory):
    daemon = start_daemon(tmp_path_factory.mktemp("fuzz"))
    events = daemon.ctx.hub_events
    daemon.ctx.store.programs.save("square.py", "print('square')\n", "local")
    run = daemon.call(
        events.run_started, RunStart("hub-a", "daemon", 1_700_000_000_000, "square.py", "x=1\n")
    )
    daemon.call(events.run_output, run, [OutputLine(1, "hello", None, 1_700_000_000_001)])
    daemon.call(events.run_ended, run, "finished", None, 1_700_000_000_100)
    yield daemon
    daemon.stop()


@pytest.mark.e2e
def test_no_server_error_and_every_answer_matches_the_schema(fuzzed_daemon):
    with fuzzed_daemon.client() as client:
        spec = client.get("/openapi.json").json()
    schema = schemathesis.openapi.from_dict(spec)
    headers = {"Authorization": f"Bearer {fuzzed_daemon.token}"}
    checks = [
        not_a_server_error,
        response_schema_conformance,
        status_code_conformance,
        content_type_conformance,
    ]
    operations = [result.ok() for result in schema.get_all_operations()]
    assert len(operations) >= 15

    for operation, mode in [(op, mode) for op in operations for mode in GenerationMode]:

        @settings(
            max_examples=EXAMPLES_PER_OPERATION,
            deadline=None,
            derandomize=True,
            database=None,
            suppress_health_check=list(HealthCheck),
        )
        @given(case=operation.as_strategy(generation_mode=mode))
        def fuzz(case):
            case.call_and_validate(base_url=fuzzed_daemon.url, headers=headers, checks=checks)

        try:
            fuzz()
        except Exception as failure:
            raise AssertionError(f"{operation.label} ({mode.value} input): {failure}") from failure
