"""QTR arrays over a modelled mat: calibration, every aggregate view, edge following, saved calibrations."""

import os

from fakes.expect import raises
from fakes.reflectance import LineMat
from openbricks import pins
from openbricks.drivers.qtr import QTRArray, QTRChannel, QTRElement, QTRLineSensor, QTRReading

LINE_SENSOR_X = {pin: QTRLineSensor.POSITIONS_MM[i] for i, pin in enumerate(QTRLineSensor.PINS)}


def _calibrated_line_sensor(**kwargs):
    mat = LineMat(LINE_SENSOR_X)
    qtr = QTRLineSensor(**kwargs)
    mat.sweep(-60, 60, duration_ms=2000)
    qtr.calibrate(duration_ms=2000)
    return qtr, mat


def _cal_path(name):
    return "/tmp/openbricks-qtr-test-%s.cal" % name


def _remove(path):
    try:
        os.remove(path)
    except OSError:
        pass


# -- calibration -------------------------------------------------------------------------------


def test_reading_before_calibration_raises_naming_the_fix():
    LineMat(LINE_SENSOR_X)
    qtr = QTRLineSensor()
    with raises(RuntimeError, "examples/qtr_calibrate.py") as err:
        qtr.read()
    assert "not calibrated" in str(err.value)
    assert not qtr.calibrated()


def test_a_sweep_that_missed_some_elements_names_them():
    mat = LineMat(LINE_SENSOR_X)
    qtr = QTRLineSensor()
    mat.sweep(-30, -10, duration_ms=500)  # the line never reaches the right half
    qtr.calibrate(duration_ms=500)
    with raises(RuntimeError, "never saw both mat and line") as err:
        qtr.read()
    assert "(GPIO 6, 7, 8, 9, 10)" in str(err.value)


def test_calibration_scales_mat_to_0_and_line_to_1000_per_element():
    # GPIO 3 carries a pull-up bias on some boards: per-element calibration absorbs it.
    mat = LineMat(LINE_SENSOR_X, bias={3: 400})
    qtr = QTRLineSensor()
    mat.sweep(-60, 60, duration_ms=2000)
    qtr.calibrate(duration_ms=2000)
    mat.place()
    assert qtr.read().values() == [0] * 10
    mat.place((-40, 80))  # the whole window over black
    assert qtr.read().values() == [1000] * 10
    spans = [hi - lo for lo, hi in qtr.calibration()]
    assert min(spans) > 40000


def test_calibrate_extends_an_earlier_calibration():
    mat = LineMat(LINE_SENSOR_X)
    qtr = QTRLineSensor()
    mat.sweep(-60, 0, duration_ms=500)
    qtr.calibrate(duration_ms=500)
    assert not qtr.calibrated()
    mat.sweep(0, 60, duration_ms=500)
    qtr.calibrate(duration_ms=500)
    assert qtr.calibrated()


# -- elements and the snapshot -----------------------------------------------------------------


def test_reading_behaves_like_a_list_of_elements():
    qtr, mat = _calibrated_line_sensor()
    mat.place_line(0, 20)
    r = qtr.read()
    assert isinstance(r, QTRReading)
    assert len(r) == 10
    assert all(isinstance(e, QTRElement) for e in r)
    assert [e.dark() for e in r] == [False] * 4 + [True, True] + [False] * 4
    assert r[0].white() and r[0].ambient() == 100
    assert r[4].value == 1000 and r[4].ambient() == 0
    assert r.elements[:5] == list(r)[:5]
    assert r.max() == 1000
    assert max(e.value for e in r) == 1000


def test_dark_count_and_all_dark():
    qtr, mat = _calibrated_line_sensor()
    mat.place_line(0, 20)
    assert qtr.read().dark_count() == 2
    assert not qtr.read().all_dark()
    mat.place((-40, 80))
    r = qtr.read()
    assert r.dark_count() == 10 and r.all_dark()


def test_position_follows_the_line_centre_and_is_none_off_the_line():
    qtr, mat = _calibrated_line_sensor()
    # The skip pattern's 8 mm gaps bound a centroid's error by half a gap.
    for centre in (-12.0, 0.0, 8.0, 14.0):
        mat.place_line(centre, 20)
        assert abs(qtr.read().position() - centre) <= 4.0, centre
    mat.place()
    assert qtr.position() is None


def test_edges_are_interpolated_to_the_threshold_crossing():
    qtr, mat = _calibrated_line_sensor()
    mat.place((-10.0, 20.0))  # edges at -10 and +10 mm
    r = qtr.read()
    assert abs(r.left_edge_position() - -10.0) < 1.5
    assert abs(r.right_edge_position() - 10.0) < 1.5
    mat.place()
    assert qtr.left_edge_position() is None and qtr.right_edge_position() is None


def test_an_edge_beyond_the_window_saturates_half_a_gap_off_the_array():
    qtr, mat = _calibrated_line_sensor()
    mat.place((-60.0, 40.0))  # covers -60..-20: the leftmost elements are dark
    r = qtr.read()
    assert r.left_edge_position() == -32.0
    mat.place((20.0, 40.0))
    assert qtr.read().right_edge_position() == 32.0


def test_fork_clusters_separate_where_the_centroid_lands_in_the_gap():
    qtr, mat = _calibrated_line_sensor()
    mat.place((-24.0, 8.0), (14.0, 8.0))  # one line around -20, one around +18
    r = qtr.read()
    assert abs(r.position()) < 5  # between the two lines
    assert abs(r.leftmost_position() - -20.0) < 2
    assert abs(r.rightmost_position() - 18.0) < 3
    mat.place()
    assert qtr.leftmost_position() is None and qtr.rightmost_position() is None


def test_array_views_take_a_reading_or_plain_values():
    qtr, mat = _calibrated_line_sensor()
    mat.place_line(4, 20)
    r = qtr.read()
    assert qtr.position(r) == r.position() == qtr.position(r.values())
    assert qtr.dark_count(list(r)) == r.dark_count()


def test_last_side_remembers_where_the_line_escaped():
    qtr, mat = _calibrated_line_sensor()
    assert qtr.last_side() == 0
    mat.place_line(20, 20)
    qtr.read()
    mat.place()
    qtr.read()
    assert qtr.last_side() == 1
    mat.place_line(-20, 20)
    qtr.read()
    assert qtr.last_side() == -1


# -- edge following ------------------------------------------------------------------------------


def test_edge_error_needs_a_mode_and_the_mode_is_validated():
    qtr, mat = _calibrated_line_sensor()
    assert qtr.mode() is None
    with raises(RuntimeError, "set_mode"):
        qtr.read().edge_error()
    with raises(ValueError, '"left" or "right"'):
        qtr.set_mode("centre")


def test_left_mode_is_zero_on_the_left_edge_and_positive_toward_the_mat():
    qtr, mat = _calibrated_line_sensor()
    qtr.set_mode("left")
    assert qtr.mode() == "left"
    mat.place((-16.0, 20.0))  # left edge right under channel 4 at -16 mm
    assert qtr.read().edge_error() == 0
    mat.place((-14.0, 20.0))  # line drifted right: channel 4 sees more mat -> steer right
    assert qtr.read().edge_error() > 0
    mat.place((-18.0, 20.0))  # line drifted left: channel 4 is over black -> steer left
    assert qtr.read().edge_error() < 0
    mat.place((-40.0, 60.0))
    assert qtr.read().edge_error() == -50
    mat.place()
    assert qtr.read().edge_error() == 50


def test_right_mode_mirrors_the_sign_so_positive_still_steers_right():
    qtr, mat = _calibrated_line_sensor()
    qtr.set_mode("right")
    mat.place((-4.0, 20.0))  # right edge under channel 12 at +16 mm
    assert qtr.read().edge_error() == 0
    mat.place((-2.0, 20.0))  # line drifted right: channel 12 over black -> steer right
    assert qtr.read().edge_error() > 0
    mat.place((-6.0, 20.0))  # line drifted left: channel 12 over mat -> steer left
    assert qtr.read().edge_error() < 0


def test_switching_mode_mid_run_changes_the_followed_edge_at_once():
    qtr, mat = _calibrated_line_sensor()
    mat.place((-16.0, 32.0))  # left edge at -16, right edge at +16
    qtr.set_mode("left")
    assert qtr.edge_error() == 0
    qtr.set_mode("right")
    assert qtr.edge_error() == 0
    mat.place((-12.0, 32.0))
    qtr.set_mode("left")
    left = qtr.edge_error()
    qtr.set_mode("right")
    assert left > 0 and qtr.edge_error() > 0


def test_line_sensor_setpoints_come_from_its_geometry():
    assert QTRLineSensor.LEFT_SETPOINT_MM == -16.0
    assert QTRLineSensor.RIGHT_SETPOINT_MM == 16.0
    assert QTRLineSensor.LEFT_SETPPOINT_MM == -16.0
    assert QTRArray.LEFT_SETPPOINT_MM == 0.0


def test_a_custom_array_interpolates_its_setpoint_between_elements():
    x = {11: -6.0, 12: -2.0, 13: 2.0, 14: 6.0}
    mat = LineMat(x)
    line = QTRArray(pins=(11, 12, 13, 14), pitch_mm=4.0)
    mat.sweep(-30, 30, duration_ms=1000)
    line.calibrate(duration_ms=1000)
    line.set_mode("left")  # setpoint 0.0 sits between two elements
    mat.place((0.0, 20.0))
    assert abs(line.edge_error()) <= 5
    line.LEFT_SETPOINT_MM = 20.0
    with raises(ValueError, "outside this array's window"):
        line.set_mode("left")


# -- saved calibrations ----------------------------------------------------------------------------


def test_saved_calibration_loads_into_a_fresh_sensor_on_the_same_wiring():
    path = _cal_path("roundtrip")
    try:
        qtr, mat = _calibrated_line_sensor()
        qtr.save_calibration(path)
        mat.place_line(8, 20)
        expected = qtr.read().values()
        pins.reset_claims()
        again = QTRLineSensor()
        again.load_calibration(path)
        assert again.read().values() == expected
    finally:
        _remove(path)


def test_a_calibration_for_other_wiring_is_refused_with_both_pin_lists():
    path = _cal_path("wiring")
    try:
        qtr, mat = _calibrated_line_sensor()
        qtr.save_calibration(path)
        other = QTRArray(pins=(11, 12, 13, 14, 15, 16, 17, 18, 21, 38))
        with raises(ValueError, "recorded for GPIO (1, 2, 3") as err:
            other.load_calibration(path)
        assert "wired to GPIO (11, 12" in str(err.value)
        with raises(RuntimeError, "not calibrated"):
            other.read()
    finally:
        _remove(path)


def test_missing_and_corrupt_calibration_files_say_how_to_make_one():
    path = _cal_path("corrupt")
    LineMat(LINE_SENSOR_X)
    qtr = QTRLineSensor()
    with raises(OSError, "run examples/qtr_calibrate.py"):
        qtr.load_calibration(_cal_path("missing"))
    try:
        with open(path, "w") as f:
            f.write("{not json")
        with raises(ValueError, "corrupt"):
            qtr.load_calibration(path)
        with open(path, "w") as f:
            f.write('{"format": "openbricks-qtr-1", "pins": [1, 2], "min": [1], "max": [2, 3]}')
        with raises(ValueError, "corrupt"):
            qtr.load_calibration(path)
    finally:
        _remove(path)


def test_saving_an_uncalibrated_array_is_refused():
    LineMat(LINE_SENSOR_X)
    with raises(RuntimeError, "not calibrated"):
        QTRLineSensor().save_calibration(_cal_path("never"))


# -- the flag channel, emitters and pins -------------------------------------------------------


def test_channel_is_a_one_element_detector():
    mat = LineMat({9: 0.0})
    flag = QTRChannel(pin=9)
    mat.sweep(-20, 20, duration_ms=400)
    flag.calibrate(duration_ms=400)
    mat.place()
    assert flag.white() and not flag.dark() and flag.value() == 0
    mat.place_line(0, 20)
    assert flag.dark() and flag.value() == 1000


def test_ctrl_pin_switches_the_emitters():
    from machine import board

    LineMat({1: 0.0, 2: 4.0})
    line = QTRArray(pins=(1, 2), ctrl=12)
    assert board.pins[12].value() == 1
    line.emitters(False)
    assert board.pins[12].value() == 0


def test_two_sensors_on_the_same_adc_pins_are_refused():
    LineMat(LINE_SENSOR_X)
    QTRLineSensor()
    with raises(pins.ReservedPinError, "GPIO 1"):
        QTRArray(pins=(1, 11))


def test_a_usb_pin_is_refused_on_the_s3():
    pins.set_chip("esp32s3")
    with raises(pins.ReservedPinError, "GPIO 19"):
        QTRChannel(pin=19)
