"""Shared fixtures: the default config, and one recorded lockstep graph run, each made once per session."""
from __future__ import annotations

import copy

import pytest

from pa10_dnbs.config import default_config_path, load_config

LOCKSTEP_DURATION_S = 6.0


@pytest.fixture(scope="session")
def _default_cfg():
    return load_config(default_config_path())


@pytest.fixture
def cfg(_default_cfg):
    """A fresh deep copy of the validated default config (tests may edit it)."""
    return copy.deepcopy(_default_cfg)


@pytest.fixture(scope="session")
def lockstep_run(tmp_path_factory):
    """A 6 s lockstep DNBS run of the node graph, recorded into a bag: output dir, bag, exit code, output."""
    from graph_harness import Launcher

    from pa10_dnbs.launch.shm_cleanup import fastdds_segments

    base = tmp_path_factory.mktemp("graph")
    out, bag = base / "run", base / "bag"
    shm_before = fastdds_segments()
    la = Launcher("--mode", "lockstep", "--controller", "dnbs", "--duration", LOCKSTEP_DURATION_S, "--out", out,
                  "--record", bag, domain_id=61)
    try:
        pids = la.node_pids()
        rc = la.wait(timeout=300)
    finally:
        la.kill()
    return {"out": out, "bag": bag, "rc": rc, "output": la.output, "pids": pids, "shm_before": shm_before}
