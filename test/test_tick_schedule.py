"""Realtime pacing without processes: the tick schedule, deadline misses warned about once per period."""
import pytest

from pa10_dnbs.loop.miss_warnings import MissWarnings
from pa10_dnbs.loop.tick_schedule import TickSchedule


def test_ticks_follow_the_period_and_deadlines_are_a_fraction_of_it():
    s = TickSchedule(period_s=0.002, deadline_fraction=0.9)
    assert not s.begin(10.0)
    assert s.deadline == pytest.approx(10.0018) and s.next_start == pytest.approx(10.002)
    assert not s.begin(10.00205)           # 50 us late: within the 10 % tolerance, the grid holds
    assert s.deadline == pytest.approx(10.0038) and s.next_start == pytest.approx(10.004)
    assert s.late_starts == 0 and s.max_lateness_s == pytest.approx(50e-6)


def test_a_late_tick_is_counted_and_the_schedule_shifts_without_catching_up():
    s = TickSchedule(period_s=0.001)
    s.begin(0.0)
    assert s.begin(0.0035)                 # scheduled at 1 ms, started at 3.5 ms
    assert s.late_starts == 1 and s.tick == 1
    assert s.deadline == pytest.approx(0.0044)   # a full tick from its actual start
    assert s.next_start == pytest.approx(0.0045)  # no burst of ticks to make up the 2.5 ms
    assert not s.begin(0.0045)
    assert s.late_starts == 1 and s.tick == 2


def test_real_time_factor_sets_the_period_like_gazebo():
    """period = step / real_time_factor: half speed is a 2 ms tick for a 1 ms step."""
    s = TickSchedule(period_s=0.001 / 0.5)
    s.begin(0.0)
    for k in range(1, 1001):
        s.begin(k * 0.002)
    assert s.tick == 1000 and s.late_starts == 0
    assert s.next_start == pytest.approx(1001 * 0.002)


@pytest.mark.parametrize("kwargs", [{"period_s": 0}, {"period_s": float("nan")}, {"period_s": 1e-3, "deadline_fraction": 0},
                                    {"period_s": 1e-3, "deadline_fraction": 1.5}, {"period_s": 1e-3, "late_tolerance": 1}])
def test_bad_schedule_parameters_are_refused(kwargs):
    with pytest.raises(ValueError):
        TickSchedule(**kwargs)


def test_miss_warnings_at_most_once_per_period_naming_the_joints():
    w = MissWarnings(["s1", "s2", "e1"], period_s=1.0)
    assert w.poll(0.0) is None                      # nothing happened
    w.missed(10, [1])
    assert w.poll(0.5) == "steps 10-10: efforts missed the deadline: s2 1"
    w.missed(11, [1, 2])
    w.late_start(12)
    w.missed(40, [2])
    assert w.poll(1.2) is None                      # the last line went out 0.7 s ago
    assert w.poll(1.5) == "steps 11-40: efforts missed the deadline: s2 1, e1 2; 1 ticks started late"
    assert w.poll(3.0) is None and w.lines == 2     # nothing new since
    w.missed(50, [])
    assert w.poll(4.0) is None                      # an empty miss list is no miss
