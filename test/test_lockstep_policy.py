"""The lockstep plant's resend / timeout decisions, with a fake clock, and what the launcher says of a timeout."""
import pytest

from pa10_dnbs.loop.lockstep_policy import LockstepPolicy


def test_resend_every_period_then_time_out():
    p = LockstepPolicy(resend_s=0.25, timeout_s=1.0)
    p.published(7, 100.0)
    assert p.action(100.1) is None
    assert p.next_check_s(100.1) == pytest.approx(0.15)
    assert p.action(100.3) == "resend"
    assert p.action(100.4) is None                 # the next resend only a period later
    assert p.next_check_s(100.4) == pytest.approx(0.15)
    assert p.action(100.56) == "resend"
    assert p.action(101.01) == "timeout"
    assert p.next_check_s(101.01) == 0.0


def test_a_new_state_restarts_the_clock():
    p = LockstepPolicy(resend_s=0.25, timeout_s=1.0)
    p.published(0, 0.0)
    assert p.action(0.3) == "resend"
    p.published(1, 0.9)
    assert p.action(1.0) is None and p.action(1.2) == "resend" and p.action(1.95) == "timeout"


def test_bad_periods_are_refused():
    with pytest.raises(ValueError):
        LockstepPolicy(resend_s=0.0)


def test_a_nominal_lockstep_run_that_stepped_past_a_missing_effort_says_it_is_not_deterministic():
    from pa10_dnbs.commands.launch_report import _unforced_timeouts

    def stats(*timeouts):
        return {"joints": [{"name": n, "effort_timeouts": t} for n, t in zip(("s1", "s2", "s3"), timeouts)]}

    assert _unforced_timeouts(stats(0, 0, 0), 1.0) is None
    msg = _unforced_timeouts(stats(0, 2, 1), 1.0)
    assert "3 times (s2: 2, s3: 1; --effort-timeout 1 s" in msg and "not the in-process run bit for bit" in msg
