"""Plausibility of values read in a declared unit: the bounds and the likely unit named."""
import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError, ParameterError
from mt_accuracy_ros.core.inputs.plausibility import (BOUNDS, check_plausible, likely_unit,
                                                      temperature_quantity)


@pytest.mark.parametrize("values, quantity, declared, likely", [
    ([3.2, 48.1, -10.0], "error", "m", "um"),        # micrometres declared as metres
    ([0.0, 400.0], "position", "m", "mm"),           # a 400 m travel: millimetres
    ([290.0, 310.0], "temperature", "degC", "K"),    # kelvin declared as degC
    ([290.0, 310.0], "temperature_hot", "degC", "K"),
    ([0.0, 0.5], "travel", "mm", "m"),               # a 0.5 mm laser run: metres
    ([-0.002, 0.004], "deviation_spread", "um", "mm"),
    ([24000.0], "spindle_speed", "rad/s", "rpm"),
    ([0.0, 360.0], "angle", "rad", "deg"),
    ([1.4], "uncertainty", "m", "um"),
])
def test_implausible_values_are_refused_naming_the_likely_unit(values, quantity, declared,
                                                               likely):
    assert likely_unit(np.array(values), quantity, declared) == likely
    with pytest.raises(ParameterError) as refused:
        check_plausible(np.array(values), quantity, declared, "column c", "declare it: c:UNIT")
    message = str(refused.value)
    assert message.startswith("column c: ")
    assert "look" in message and f"like {likely.replace('um', 'µm')}" in message
    assert message.endswith("declare it: c:UNIT") and "\n" not in message


def test_the_message_names_the_range_found_and_the_declared_unit():
    with pytest.raises(ParameterError, match=r"^column dev_x \(err\.x\): values 3\.2 … 48\.1 "
                       r"declared m look like µm \(plausible error: \|error\| ≤ 5 mm\)$"):
        check_plausible(np.array([3.2, 48.1]), "error", "m", "column dev_x (err.x)")


@pytest.mark.parametrize("values, quantity, unit", [
    ([-12.0, 35.5], "error", "um"), ([0.0, 800.0], "position", "mm"),
    ([18.0, 24.0], "temperature", "degC"), ([20.0, 120.0], "temperature_hot", "degC"),
    ([291.0, 300.0], "temperature", "K"), ([0.0, 500.0], "travel", "mm"),
    ([-3.0, 4.0], "deviation_spread", "um"), ([12000.0], "spindle_speed", "rpm"),
    ([np.nan, 5.0], "error", "um"),        # non-finite values are the readers' to refuse
])
def test_plausible_values_pass(values, quantity, unit):
    check_plausible(np.array(values), quantity, unit, "column c")


def test_degrees_fahrenheit_are_refused_only_outside_the_range():
    # 60 ... 100 degF read as degC is a plausible hot sensor: it cannot be told apart.
    check_plausible(np.array([60.0, 100.0]), "temperature_hot", "degC", "T")
    with pytest.raises(ParameterError, match="look like °F"):
        check_plausible(np.array([60.0, 100.0]), "temperature", "degC", "T")


def test_values_no_unit_explains_say_so_and_the_caller_chooses_the_error():
    with pytest.raises(InputDataError, match="fit no known unit"):
        check_plausible(np.array([1e12, 2e12]), "position", "m", "c", error=InputDataError)
    assert likely_unit(np.array([1e12]), "position", "m") is None


def test_an_unknown_quantity_is_refused_listing_the_known():
    with pytest.raises(ParameterError, match="unknown quantity 'length'; known: position"):
        check_plausible(np.array([1.0]), "length", "m", "c")


def test_hot_sensors_by_name_and_every_bound_is_well_formed():
    assert temperature_quantity("spindle_front") == "temperature_hot"
    assert temperature_quantity("T3") == "temperature"
    for bound in BOUNDS.values():
        assert bound.measure in ("magnitude", "span", "value") and bound.low < bound.high
        assert bound.low <= bound.typical <= bound.high or bound.family == "temperature"
