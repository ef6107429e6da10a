"""The launcher's advice after a realtime run that missed deadlines (launch/realtime_advice.py)."""
from pa10_dnbs.launch.realtime_advice import ON_TIME_TARGET, realtime_hint


def test_the_target_is_the_benchmarks_99_percent():
    assert ON_TIME_TARGET == 0.99


def test_hint_names_a_lower_factor_and_priority_when_not_applied():
    line = realtime_hint(0.5, priority_applied=False)
    assert line.startswith("realtime --rtf 0.5: below 99 % on time")
    assert "a lower --rtf (e.g. 0.25)" in line and "--rt-priority 50" in line
    assert "scripts/bench_graph.py" in line


def test_hint_leaves_out_priority_that_is_already_in_force():
    line = realtime_hint(1.0, priority_applied=True)
    assert "a lower --rtf (e.g. 0.5)" in line and "--rt-priority" not in line
