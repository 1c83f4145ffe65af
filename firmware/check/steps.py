"""How the check fails and how it runs the tools it drives: one error that says what failed, where,
and how to fix it, and one way to run a step with a time limit that turns its failure into that error.
"""

import subprocess

STEP_LIMIT_S = 600


class CheckError(Exception):
    pass


def run(command, what, limit_s=STEP_LIMIT_S, **kwargs):
    """Run `command`; its stdout, or CheckError naming `what` with the tail of its output."""
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=limit_s, **kwargs)
    except subprocess.TimeoutExpired:
        raise CheckError(f"{what} did not finish within {limit_s} s") from None
    except OSError as err:
        raise CheckError(f"{what} could not start: {err}") from None
    if result.returncode != 0:
        raise CheckError(f"{what} failed:\n{(result.stdout + result.stderr)[-6000:]}")
    return result.stdout
