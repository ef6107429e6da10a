"""Scheduling policies for the graph's processes (Linux), on every thread of this process.

Linux schedules threads, not processes: the policy is set on each thread in
/proc/self/task (the DDS threads included); threads started later inherit
it from the thread that starts them.

``apply_batch()``: SCHED_BATCH, which any process may choose. It keeps the
thread's share of the CPU (same weight as the default policy) and only
stops its wake-ups from preempting the running thread. The launcher's
``--sched-batch`` gives it to every node but the plant: the plant is the
loop's clock, the others are work its messages trigger, and a controller
woken by its state no longer interrupts the plant between two of its
state publishes (docs/timing.md, "SCHED_BATCH for everything but the plant":
why it is opt-in).

``apply_fifo(priority)``: SCHED_FIFO, on every node of the graph (``--rt-priority``, by default
``DEFAULT_RT_PRIORITY`` = 50, what ros2_control's controller manager asks for on its loop thread).
Needs root, CAP_SYS_NICE or an RLIMIT_RTPRIO (``ulimit -r``) at least the priority, and a cgroup with
real-time runtime; the launcher asks once (``granted_priority``) and, where it is refused, says so and
runs the graph at the default policy. A policy a thread gets later replaces this one.
The whole graph shares the class: with the loop (plant, controllers) alone under SCHED_FIFO, an
observer at the default policy starved whenever the loop needed the whole machine (a recorded lockstep
run lost most of its bag, 3 of 3 runs; docs/benchmarks_log.md, "SCHED_FIFO for the whole
graph, by default").

Observers (recorder, wire monitor, live view) are never put below the loop: SCHED_IDLE, or nice 10,
was tried and taken out: with other work on the machine the observers starved, lost the run or hung at
teardown, and a lockstep run in CI stalled for over a second with them (docs/timing.md).
"""
from __future__ import annotations

import os
import threading

MIN_PRIORITY, MAX_PRIORITY = 1, 99
DEFAULT_RT_PRIORITY = 50  # ros2_control's controller manager's SCHED_FIFO priority (its thread_priority)


def check_priority(priority: int) -> None:
    """ValueError unless 0 (off) or 1..99."""
    if priority != 0 and not MIN_PRIORITY <= priority <= MAX_PRIORITY:
        raise ValueError(f"rt_priority must be 0 (off) or {MIN_PRIORITY}..{MAX_PRIORITY}, got {priority}")


def apply_fifo(priority: int) -> tuple[bool, str]:
    """Put every thread of this process under SCHED_FIFO at ``priority``; (applied, what happened)."""
    check_priority(priority)
    if priority == 0:
        return False, "rt_priority 0: default scheduling"
    if not hasattr(os, "sched_setscheduler"):
        return False, f"rt_priority {priority}: SCHED_FIFO is not available on this OS; default scheduling"
    done, refused = _on_every_thread(os.SCHED_FIFO, priority)
    if refused:
        limit = _rlimit_rtprio()
        return False, (f"rt_priority {priority}: SCHED_FIFO not permitted (needs root, CAP_SYS_NICE or "
                       f"`ulimit -r` >= {priority}, now {limit}, and real-time runtime in the cgroup); "
                       "default scheduling" + (f" (it was set on {done} threads, which keep it)" if done else ""))
    return True, f"rt_priority {priority}: SCHED_FIFO on {done} threads"


def fifo_permitted(priority: int) -> tuple[bool, str]:
    """Whether this process's threads may take SCHED_FIFO at ``priority``: (permitted, what to say).

    Asked on a short-lived thread of its own, which takes the policy and gives it back; no other thread
    of the process changes. ``priority`` 0: (False, ...) without asking.
    """
    check_priority(priority)
    if priority == 0:
        return False, "rt_priority 0: default scheduling"
    if not hasattr(os, "sched_setscheduler"):
        return False, f"rt_priority {priority}: SCHED_FIFO is not available on this OS; default scheduling"
    answer: list[BaseException | None] = []

    def ask() -> None:
        try:
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))  # 0: this thread only (Linux)
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
            answer.append(None)
        except OSError as exc:
            answer.append(exc)

    thread = threading.Thread(target=ask, name="fifo_probe")
    thread.start()
    thread.join()
    if answer and answer[0] is None:
        return True, f"rt_priority {priority}: SCHED_FIFO permitted"
    return False, (f"rt_priority {priority}: SCHED_FIFO not permitted here (needs root, CAP_SYS_NICE or "
                   f"`ulimit -r` >= {priority}, now {_rlimit_rtprio()}, and real-time runtime in the cgroup: "
                   f"{answer[0] if answer else 'no answer'}); default scheduling")


def granted_priority(priority: int) -> tuple[int, str | None]:
    """The priority the graph's nodes get: ``priority`` where the OS allows SCHED_FIFO at it, else 0 and the
    line that says why (None when there is nothing to say)."""
    if priority == 0:
        return 0, None
    permitted, why = fifo_permitted(priority)
    return (priority, None) if permitted else (0, why)


def apply_batch() -> tuple[bool, str]:
    """Put every thread of this process under SCHED_BATCH; (applied, what happened)."""
    if not hasattr(os, "SCHED_BATCH"):
        return False, "sched_batch: SCHED_BATCH is not available on this OS; default scheduling"
    done, refused = _on_every_thread(os.SCHED_BATCH, 0)
    if refused:  # a thread under SCHED_FIFO cannot leave it without the privilege that set it
        return False, f"sched_batch: refused by the OS (after {done} threads); default scheduling"
    return True, f"sched_batch: SCHED_BATCH on {done} threads"


def policy_name(tid: int = 0) -> str:
    """The scheduling policy of thread ``tid`` (0: the calling thread), e.g. 'SCHED_BATCH'."""
    policy = os.sched_getscheduler(tid)
    names = {getattr(os, n): n for n in ("SCHED_OTHER", "SCHED_BATCH", "SCHED_IDLE", "SCHED_FIFO", "SCHED_RR")
             if hasattr(os, n)}
    return names.get(policy, str(policy))


def _on_every_thread(policy: int, priority: int) -> tuple[int, bool]:
    """Set ``policy`` on each thread of this process: (threads done, whether the OS refused one)."""
    try:
        tids = [int(t) for t in os.listdir("/proc/self/task")]
    except OSError:
        tids = [0]
    done = 0
    for tid in tids:
        try:
            os.sched_setscheduler(tid, policy, os.sched_param(priority))
            done += 1
        except ProcessLookupError:  # the thread ended meanwhile
            continue
        except PermissionError:
            return done, True
    return done, False


def _rlimit_rtprio():
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_RTPRIO)
        return "unlimited" if soft == resource.RLIM_INFINITY else soft
    except (ImportError, AttributeError, OSError):
        return "unknown"
