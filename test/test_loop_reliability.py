"""Which QoS reliability the launcher gives the per-joint state/effort topics (supervisor/graph_options.py)."""
from pathlib import Path

import pytest

from pa10_dnbs.supervisor.graph_options import GraphOptions, loop_reliability

CFG = Path("config/default.yaml")


@pytest.mark.parametrize("mode", ["lockstep", "realtime"])
def test_best_effort_on_one_host_without_a_recorder(mode):
    assert loop_reliability(GraphOptions(CFG, mode=mode)) == "best_effort"


def test_lockstep_stays_reliable_when_a_bag_records_the_loop():
    assert loop_reliability(GraphOptions(CFG, record_bag=Path("bag"))) == "reliable"


def test_lockstep_stays_reliable_across_network_namespaces():
    assert loop_reliability(GraphOptions(CFG, netns={"controllers": "ns1"})) == "reliable"


def test_realtime_is_best_effort_even_when_recorded():
    assert loop_reliability(GraphOptions(CFG, mode="realtime", record_bag=Path("bag"))) == "best_effort"


@pytest.mark.parametrize("asked", ["reliable", "best_effort"])
def test_an_explicit_choice_wins(asked):
    for opt in (GraphOptions(CFG, reliability=asked), GraphOptions(CFG, reliability=asked, record_bag=Path("b")),
                GraphOptions(CFG, mode="realtime", reliability=asked)):
        assert loop_reliability(opt) == asked


def test_a_graph_that_never_matched_across_namespaces_says_to_link_them():
    """``--netns plant=NS`` with NS holding no link to the others: the plant's "graph not ready" after 30 s named
    no cause (0 subscribers matched); the namespaces' link is the usual one."""
    from pa10_dnbs.supervisor.netns import netns_hint

    failure = "plant: FAILED graph not ready after start_timeout_s = 30 s: /pa10/s1/state: 0 of 1"
    hint = netns_hint(failure, {"plant": "host_a", "reference": "host_a"})
    assert hint == ("\n(with `netns`, the nodes in host_a meet the others only through a link between the namespaces, "
                    "as scripts/netns_hosts.sh makes one: docs/graph.md, \"Several hosts on one machine\")")
    assert netns_hint(failure, {}) == "" and netns_hint("interrupted (SIGINT)", {"plant": "host_a"}) == ""
