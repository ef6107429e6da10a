"""The launcher's advice after a realtime run that missed deadlines (supervisor/realtime_advice.py)."""
from pa10_dnbs.config import default_config_path
from pa10_dnbs.config_error import said_as
from pa10_dnbs.commands.fault_flags import FaultFlags, apply_fault_flags
from pa10_dnbs.supervisor.realtime_advice import ON_TIME_TARGET, injected_misses, realtime_hint
from pa10_dnbs.run_settings import build_settings
from pa10_dnbs.setting_flags import SETTING_FLAGS


def test_the_target_is_the_benchmarks_99_percent():
    assert ON_TIME_TARGET == 0.99


def test_hint_names_a_lower_factor_and_priority_when_not_applied():
    text = realtime_hint(0.5, priority_applied=False)
    assert text.startswith("realtime `real_time_factor` 0.5") and "--" not in text   # settings, not flags
    line = said_as(text, SETTING_FLAGS)   # as the launcher prints it
    assert line.startswith("realtime --rtf 0.5: below 99 % on time")
    assert "a lower --rtf (e.g. 0.25)" in line and "--rt-priority 50" in line
    assert "scripts/bench_graph.py" in line


def test_hint_leaves_out_priority_that_is_already_in_force():
    line = said_as(realtime_hint(1.0, priority_applied=True), SETTING_FLAGS)
    assert "a lower --rtf (e.g. 0.5)" in line and "--rt-priority" not in line


def test_injected_effort_drops_are_named_not_blamed_on_the_cpu():
    """A realtime run with --drop-efforts misses ticks by design: the hint says so instead of 'a lower --rtf'."""
    from pa10_dnbs.cli import build_parser

    cfg = build_settings(default_config_path())
    assert injected_misses(cfg.faults) == []
    args = build_parser().parse_args(["launch", "--mode", "realtime", "--drop-efforts", "0.05", "--out", "x"])
    faulty = apply_fault_flags(cfg, FaultFlags.of(args))
    assert injected_misses(faulty.faults) == ["efforts dropped"]
    line = said_as(realtime_hint(0.5, priority_applied=True, injected=injected_misses(faulty.faults)), SETTING_FLAGS)
    assert "efforts dropped" in line and "by design" in line
    assert "lower --rtf" not in line and "CPU each tick" not in line
