"""plot() in a simulator run, as on a hub: samples, never output. `openbricks sim run` reads the frames
itself (the result's telemetry, stamped with simulated time; the live text shows them as a hub run
without a console prints them); a console's run leaves its tagged frames for the console to read."""

from openbricks.host_protocol import FRAME_PREFIX
from openbricks_sim.job import SimJob
from openbricks_sim.run import FINISHED, ProgramRun, run_program
from openbricks_sim.simulation import Simulation

PLOTS = """\
import time
from openbricks.tools import plot

print("start", end="")
print(" here")
plot("target_mm", 150)
time.sleep_ms(250)
plot("heading_deg", -1.5)
print("@openbricks:forged plot {\\"name\\": \\"x\\", \\"value\\": 1}")
print("done")
"""


def test_plot_samples_are_the_runs_telemetry_not_its_output():
    echoed = []
    result = run_program("mission.py", source=PLOTS, echo=echoed.append)
    assert result.exit == FINISHED, result.error
    assert result.telemetry == [
        {"name": "target_mm", "value": 150.0, "sim_ms": 0},
        {"name": "heading_deg", "value": -1.5, "sim_ms": 250},
    ]
    # A line that only looks like a frame (without the run's nonce) is output, as on a hub.
    forged = '@openbricks:forged plot {"name": "x", "value": 1}\n'
    assert result.output == "start here\n" + forged + "done\n"
    shown = "plot: target_mm = 150\nplot: heading_deg = -1.5\n"
    assert "".join(echoed) == "start here\n" + shown + forged + "done\n"
    assert result.summary()["telemetry"] == result.telemetry


def test_a_console_run_passes_its_tagged_frames_on_for_the_console_to_read():
    simulation = Simulation.for_job(SimJob("mission.py"), paced=False)
    echoed = []
    try:
        result = ProgramRun(simulation).run(PLOTS, echo=echoed.append, plot_tag="cafe0001")
    finally:
        simulation.close()
    frame = f'{FRAME_PREFIX}cafe0001 plot {{"name": "target_mm", "value": 150}}\n'
    assert frame in "".join(echoed)
    assert result.telemetry == []
