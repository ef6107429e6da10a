"""Waiting for acknowledgements in slices (ros/acked.py): a stop ends a long flush at once."""
import threading
import time
from concurrent.futures import Future

from pa10_dnbs.ros.acked import SLICE_S, wait_acked


class NeverAcked:
    """A publisher whose subscribers never acknowledge (they were stopped by the same Ctrl-C): each wait runs
    its whole duration, in C, where no signal handler runs."""

    def __init__(self):
        self.waits = []

    def wait_for_all_acked(self, timeout) -> bool:
        seconds = timeout.nanoseconds / 1e9
        self.waits.append(seconds)
        time.sleep(seconds)
        return False


class AckedAfter:
    def __init__(self, n: int):
        self.left = n

    def wait_for_all_acked(self, timeout) -> bool:
        self.left -= 1
        return self.left <= 0


def test_a_stop_ends_a_long_flush_within_a_slice():
    """The plant's final flush (10 s) was one wait: a Ctrl-C in it waited it out, past the launcher's 5 + 3 s
    grace, to SIGKILL."""
    stop, pub = Future(), NeverAcked()
    threading.Timer(0.3, stop.set_result, args=(None,)).start()
    t0 = time.monotonic()
    assert wait_acked([pub], 10.0, stop) is False
    assert time.monotonic() - t0 < 0.3 + 3 * SLICE_S and max(pub.waits) <= SLICE_S


def test_the_timeout_and_the_acknowledgements_end_it_too():
    t0 = time.monotonic()
    assert wait_acked([NeverAcked()], 0.35) is False and time.monotonic() - t0 < 0.35 + 2 * SLICE_S
    assert wait_acked([AckedAfter(1), AckedAfter(3)], 5.0) is True
