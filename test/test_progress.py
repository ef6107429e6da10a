"""The progress bar: drawn on a terminal only, simulated time, real-time factor and worst |e| so far."""
import io

from pa10_dnbs.report.progress import ProgressBar, format_progress


class Tty(io.StringIO):
    def isatty(self):
        return True


class FakeClock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


def test_quiet_when_the_output_is_not_a_terminal():
    out = io.StringIO()
    bar = ProgressBar(1000, 1e-3, "simulate dnbs", stream=out)
    bar.update(500, 0.1)
    bar.log(lambda line: None, "a log line")
    bar.close()
    assert out.getvalue() == "" and not bar.enabled


def test_draws_simulated_time_rtf_and_worst_error_on_a_terminal():
    out, clock = Tty(), FakeClock()
    bar = ProgressBar(20_000, 1e-3, "launch lockstep dnbs", stream=out, clock=clock)
    bar.update(0)
    clock.t += 10.0
    bar.update(5000, 0.3)
    clock.t += 10.0
    bar.update(10_000, 0.1)  # a smaller |e| later: the worst stays
    assert bar.real_time_factor == 0.5
    assert bar.worst_abs_error == 0.3
    text = bar.text()
    assert "10.0/20.0 s" in text and "RTF 0.50" in text and "worst |e| 3.0e-01 rad" in text
    assert "[############............]" in text
    bar.close()
    lines = out.getvalue()
    assert lines.startswith("\r\x1b[K") and lines.endswith("\n") and lines.count("\n") == 1


def test_redraws_at_most_every_min_interval():
    out, clock = Tty(), FakeClock()
    bar = ProgressBar(1000, 1e-3, "x", stream=out, clock=clock, min_interval_s=0.2)
    for k in range(100):  # 100 updates within 0.1 s: drawn once
        clock.t += 0.001
        bar.update(k)
    assert out.getvalue().count("\r") == 1


def test_log_lines_do_not_tear_the_bar():
    out, clock = Tty(), FakeClock()
    bar = ProgressBar(1000, 1e-3, "x", stream=out, clock=clock)
    bar.update(10)
    said = []
    bar.log(lambda line: (said.append(line), out.write(line + "\n")), "launch: plant running")
    assert said == ["launch: plant running"]
    assert out.getvalue().endswith("\r\x1b[Klaunch: plant running\n")  # the bar's line was cleared first


def test_format_before_anything_is_known():
    assert format_progress("analyse b", 0, 0, 1e-3, None, None) == \
        "analyse b [........................]    0.0/0.0 s  RTF -  worst |e| -"
