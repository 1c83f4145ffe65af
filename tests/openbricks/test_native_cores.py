"""With the native cores present, openbricks._native hands out the very same objects."""

NEEDS_NATIVE = True


def test_the_cores_are_re_exported_unchanged():
    import _openbricks_native

    from openbricks._native import DriveBase, Observer, Servo, TrapezoidalProfile, available, motor_process

    assert available()
    assert motor_process is _openbricks_native.motor_process
    assert Servo is _openbricks_native.Servo
    assert TrapezoidalProfile is _openbricks_native.TrapezoidalProfile
    assert Observer is _openbricks_native.Observer
    assert DriveBase is _openbricks_native.DriveBase
