"""The reference node's lookahead fits in the batches its endpoints keep (supervisor/node_specs.reference_batch):
with /clock every 2000 steps (``--clock-hz 0.5``) the lookahead took 21 batches of 100 where the endpoints keep
20, the first was gone before a controller matched, and the graph waited 30 s for it, then failed ("graph not
ready ... the references state 0 needs have not arrived")."""
from __future__ import annotations

import math
from pathlib import Path

import pytest

from graph_harness import Launcher
from pa10_dnbs.supervisor.graph_options import GraphOptions
from pa10_dnbs.supervisor.node_specs import (REALTIME_REFERENCE_BATCH, reference_batch,
                                             reference_lookahead)
from pa10_dnbs.wire.topics import REFERENCE_DEPTH

JOINTS = ["s1", "s2", "e1", "e2", "w1", "w2", "w3"]


@pytest.mark.parametrize("mode", ["lockstep", "realtime"])
@pytest.mark.parametrize("clock_hz", [1000.0, 100.0, 2.9, 0.5, 0.01])
def test_the_lookahead_fits_in_the_kept_batches_and_the_defaults_stay(mode, clock_hz):
    opt = GraphOptions(config_path=Path("config/default.yaml"), joint_names=JOINTS, mode=mode, clock_hz=clock_hz)
    batch = reference_batch(opt)
    assert math.ceil(reference_lookahead(opt) / batch) + 1 <= REFERENCE_DEPTH - 1, (batch, reference_lookahead(opt))
    if clock_hz >= 100.0:   # the default /clock and faster: the batches as they were
        assert batch == (REALTIME_REFERENCE_BATCH if mode == "realtime" else 100)


@pytest.mark.graph
def test_a_half_hertz_clock_runs(tmp_path, domain):
    rc, la = Launcher.to_end("--mode", "lockstep", "--duration", 0.5, "--clock-hz", 0.5, "--out", tmp_path / "run",
                             domain_id=domain, timeout=120)
    assert rc == 0, la.output
