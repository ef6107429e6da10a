"""Several hosts on one machine: node groups in network namespaces (``ip netns``) and the children's environment."""
from __future__ import annotations

import os
from pathlib import Path

from ..interrupt import LAUNCHER_PID_ENV
from .graph_options import GraphOptions
from .node_specs import NODE_GROUPS, node_group


def node_env(domain_id: int, discovery_range: str = "LOCALHOST") -> dict:
    """Children's environment: ``discovery_range`` LOCALHOST on one host, SUBNET across (network namespaces);
    this process as their launcher (they stop when it dies: ros/runtime.py)."""
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": discovery_range,
           "PYTHONUNBUFFERED": "1", LAUNCHER_PID_ENV: str(os.getpid())}
    env.pop("ROS_LOCALHOST_ONLY", None)  # deprecated in Jazzy; conflicts with the discovery range
    return env


def parse_netns(specs: list[str]) -> dict[str, str]:
    """['controllers=hostb', ...] -> {'controllers': 'hostb'}; ConfigError naming the setting netns on bad input."""
    from ..config import ConfigError

    out = {}
    for spec in specs:
        group, sep, ns = spec.partition("=")
        if not sep or group not in NODE_GROUPS or not ns:
            raise ConfigError(f"netns: expected GROUP=NAMESPACE with GROUP one of {', '.join(NODE_GROUPS)}, "
                              f"got {spec!r}", setting="netns")
        if not Path(f"/var/run/netns/{ns}").exists():
            raise ConfigError(f"netns: no network namespace {ns!r} (see `ip netns list`)", setting="netns")
        out[group] = ns
    return out


def in_netns(opt: GraphOptions, name: str, argv: list[str]) -> list[str]:
    ns = opt.netns.get(node_group(name))
    return ["ip", "netns", "exec", ns] + argv if ns else argv


def netns_hint(failure: str, netns: dict[str, str]) -> str:
    """What to add to a failed launch's ``failure`` when node groups ran in network namespaces (``netns``: group ->
    namespace) and the graph never matched: a namespace without a link to the others is the usual cause."""
    if not netns or "graph not ready" not in failure:
        return ""
    return (f"\n(with `netns`, the nodes in {', '.join(sorted(set(netns.values())))} meet the others only through a "
            "link between the namespaces, as scripts/netns_hosts.sh makes one: docs/graph.md, \"Several hosts on one "
            "machine\")")

