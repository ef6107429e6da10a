"""Domain leases: one holder per id across processes, freed when the holder goes."""
import subprocess
import sys

from pa10_dnbs.supervisor.domain_ids import lease_domain, try_lease

HOLD = """
import sys, time
from pa10_dnbs.supervisor.domain_ids import try_lease
lease = try_lease(int(sys.argv[1]))
print('held' if lease else 'busy', flush=True)
sys.stdin.readline()
"""


def test_two_leases_differ_and_a_released_id_is_free_again():
    with lease_domain() as a, lease_domain() as b:
        assert a.domain_id != b.domain_id
        assert 1 <= a.domain_id <= 101 and 1 <= b.domain_id <= 101
        taken = a.domain_id
    again = try_lease(taken)
    assert again is not None
    again.release()


def test_an_id_held_by_another_process_is_busy_until_it_exits():
    with lease_domain() as mine:
        probe = subprocess.run([sys.executable, "-c", HOLD, str(mine.domain_id)], input="\n", capture_output=True,
                               text=True, timeout=30)
        assert probe.stdout.strip() == "busy", probe.stdout + probe.stderr
    child = subprocess.Popen([sys.executable, "-c", HOLD, str(mine.domain_id)], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "held"
        assert try_lease(mine.domain_id) is None
    finally:
        child.communicate("\n", timeout=30)
    lease = try_lease(mine.domain_id)  # the child exited: its lock went with it
    assert lease is not None
    lease.release()


def test_an_id_stays_busy_while_a_process_started_on_it_outlives_the_lease():
    """A launcher killed hard leaves its nodes running on the domain: no lease is granted on it until the last of
    them has exited, so they never meet the next run's graph."""
    from pa10_dnbs.supervisor.domain_ids import is_occupied, occupy
    import os

    with lease_domain() as mine:
        taken = mine.domain_id
        fd = occupy(taken)
        try:
            node = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.readline()"],
                                    stdin=subprocess.PIPE, pass_fds=(fd,), text=True)
        finally:
            os.close(fd)
    try:
        assert is_occupied(taken)
        assert try_lease(taken) is None
        with lease_domain() as other:
            assert other.domain_id != taken
    finally:
        node.communicate("\n", timeout=30)
    assert not is_occupied(taken)
    lease = try_lease(taken)
    assert lease is not None
    lease.release()


def test_the_id_just_let_go_is_leased_last():
    """A graph's exited nodes stay in their domain's discovery ~20 s (participants not destroyed): the next lease,
    of this process or another, takes the free id leased longest ago, not the one just released."""
    with lease_domain() as a:
        first = a.domain_id
    with lease_domain() as b:
        assert b.domain_id != first
        second = b.domain_id
    with lease_domain() as c:
        assert c.domain_id not in (first, second)
