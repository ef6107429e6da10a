"""Shared fixtures (the default config, one recorded lockstep graph run, each made once per session) and
the session's /dev/shm cleanup."""
from __future__ import annotations

import os

import pytest

from pa10_dnbs.config import default_config_path
from pa10_dnbs.run_settings import build_settings

LOCKSTEP_DURATION_S = 3.0


def pytest_unconfigure(config):
    """Remove the /dev/shm files of dead processes (shm_cleanup.py), this session's own in-process participants
    counted as dead: the LTTng-UST wait files rcl creates here when a test loads rclpy, and what a test's
    client left (the launcher cleans up after its nodes)."""
    from pa10_dnbs.ros.shm_cleanup import remove_stale, shm_files

    remove_stale(shm_files(), ignore_pids=frozenset({os.getpid()}))


@pytest.fixture(scope="session")
def _default_cfg():
    return build_settings(default_config_path())


@pytest.fixture
def cfg(_default_cfg):
    """The default settings (frozen: a test changes a copy, ``replace_in``)."""
    return _default_cfg


@pytest.fixture
def domain():
    """A ROS_DOMAIN_ID leased for this test alone: no other test, suite or launcher on the host has it meanwhile.

    At the end, the shared-memory files the test's ROS processes left are removed, as the launcher does
    after a run (nodes leave without destroying their DDS participant, pa10_dnbs/ros/runtime.py): every
    file whose owner is dead and that no live process maps (shm_cleanup.py).

    Every process the test started on the domain must be gone by then (within 30 s): one that outlives its
    test would meet the next test's graph on the same domain.
    """
    import time

    from pa10_dnbs.supervisor.domain_ids import is_occupied, lease_domain
    from pa10_dnbs.ros.shm_cleanup import remove_stale, shm_files

    with lease_domain() as lease:
        yield lease.domain_id
        deadline = time.monotonic() + 30.0
        while is_occupied(lease.domain_id) and time.monotonic() < deadline:
            time.sleep(0.2)
        survivors = is_occupied(lease.domain_id)
    remove_stale(shm_files())
    assert not survivors, (f"a process started on domain {lease.domain_id} outlived its test "
                           f"(its flock on {lease.domain_id}.busy: /proc/locks)")


@pytest.fixture(scope="session")
def lockstep_run(tmp_path_factory):
    """A 3 s lockstep DNBS run of the node graph, recorded into a bag: output dir, bag, exit code, output."""
    from graph_harness import Launcher

    from pa10_dnbs.ros.shm_cleanup import shm_files

    base = tmp_path_factory.mktemp("graph")
    out, bag = base / "run", base / "bag"
    from pa10_dnbs.supervisor.domain_ids import lease_domain

    shm_before = shm_files()
    with lease_domain() as lease:
        la = Launcher("--mode", "lockstep", "--controller", "dnbs", "--duration", LOCKSTEP_DURATION_S, "--out", out,
                      "--record", bag, domain_id=lease.domain_id)
        try:
            pids = la.node_pids()
            rc = la.wait(timeout=300)
        finally:
            la.kill()
    return {"out": out, "bag": bag, "rc": rc, "output": la.output, "pids": pids, "shm_before": shm_before}
