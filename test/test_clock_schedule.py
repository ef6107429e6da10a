"""/clock once per 1 / clock_hz of simulated time, plus the last state (wire/clock_schedule.py)."""
import pytest

from pa10_dnbs.wire.clock_schedule import ClockSchedule, check_clock_hz


def test_100_hz_at_1_ms_steps_is_every_tenth_state_and_the_last():
    assert ClockSchedule.steps(100.0, 1e-3, 25) == {0, 10, 20, 25}
    assert ClockSchedule.steps(1000.0, 1e-3, 5) == {0, 1, 2, 3, 4, 5}
    assert ClockSchedule.steps(30.0, 1e-3, 100) == {0, 34, 67, 100}  # period 33.333 ms: first state of each


def test_clock_hz_range():
    check_clock_hz(0.0, 1e-3)
    check_clock_hz(1000.0, 1e-3)
    for bad in (-1.0, 1000.5, float("nan")):
        with pytest.raises(ValueError, match="Hz"):
            check_clock_hz(bad, 1e-3)
