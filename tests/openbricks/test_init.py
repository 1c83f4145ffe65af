"""firmware_label() reports the version with the provenance the flasher recorded on the hub."""

import esp32

import openbricks
from fakes.expect import raises


def test_a_hub_without_a_provenance_record_reads_customized():
    assert openbricks.__version__ == "2.7.1"
    assert openbricks.firmware_label() == "2.7.1 (customized)"


def test_the_flashers_official_verdict_survives_a_reboot():
    openbricks.record_provenance("official")
    assert openbricks.firmware_label() == "2.7.1 (official)"
    openbricks.record_provenance("customized")
    assert openbricks.firmware_label() == "2.7.1 (customized)"


def test_a_verdict_recorded_for_another_version_does_not_vouch_for_this_one():
    nvs = esp32.NVS(openbricks.PROVENANCE_NAMESPACE)
    nvs.set_blob(openbricks.PROVENANCE_KEY, b"official 2.6.0")
    nvs.commit()
    assert openbricks.firmware_label() == "2.7.1 (customized)"


def test_an_unknown_verdict_is_rejected():
    with raises(ValueError, "must be 'official' or 'customized'"):
        openbricks.record_provenance("signed")
