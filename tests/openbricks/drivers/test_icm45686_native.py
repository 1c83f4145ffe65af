"""The ICM-45686 driver on the C heading core, and its Python fallback held to the same numbers."""

import math

from machine import board

from fakes.spi_imu import ICM45686Chip
from openbricks.drivers import icm45686

NEEDS_NATIVE = True


def _stream(integrator, samples):
    t_us = 0
    for gyro_z_dps, dt_us in samples:
        t_us += dt_us
        integrator.update(gyro_z_dps, t_us & 0xFFFFFFFF)
    return integrator


def _scenario():
    """Boot at rest with a biased gyro, a noisy still stretch, a turn, a dropout, a slow drift."""
    samples = [(0.7 + 0.2 * math.sin(i * 0.7), 1000) for i in range(800)]
    samples += [(-90.0 + 0.7, 1000) for _ in range(1000)]
    samples += [(0.7, 250_000)]  # a gap longer than 100 ms: not integrated
    samples += [(0.75 + 0.1 * math.cos(i * 0.3), 5000) for i in range(4000)]
    return samples


def test_the_driver_uses_the_native_integrator_when_the_host_has_it():
    import _openbricks_native

    board.attach_spi(17, ICM45686Chip())
    imu = icm45686.ICM45686(sck=12, mosi=13, miso=11, cs=17)
    assert isinstance(imu._yaw, _openbricks_native.ImuYaw)


def test_python_fallback_matches_the_c_core_sample_for_sample():
    import _openbricks_native

    native = _stream(_openbricks_native.ImuYaw(scale=-1.0), _scenario())
    python = _stream(icm45686._YawIntegrator(-1.0), _scenario())
    assert native.calibrated() and python.calibrated()
    assert abs(native.bias() - python.bias()) < 1e-3, (native.bias(), python.bias())
    assert abs(native.heading() - python.heading()) < 0.05, (native.heading(), python.heading())
    assert abs(native.heading() - 90.0) < 0.5


def test_seeded_bias_agrees_and_implausible_seeds_are_refused_by_both():
    import _openbricks_native

    for integrator in (_openbricks_native.ImuYaw(scale=-1.0), icm45686._YawIntegrator(-1.0)):
        integrator.seed_bias(1.5)
        assert integrator.calibrated()
        _stream(integrator, [(1.5 + 20.0, 1000) for _ in range(1001)])
        assert abs(integrator.heading() - -20.0) < 0.05
        try:
            integrator.seed_bias(float("nan"))
        except ValueError:
            pass
        else:
            raise AssertionError("%s accepted a NaN bias" % type(integrator).__name__)
