#!/usr/bin/env python3
"""Benchmark: what the observers cost the lockstep node graph (recording a bag, the live view).

Prints, for runs of --duration simulated seconds (default 10), modes interleaved:
- lockstep: real-time factor of the stepping phase (simulated / wall time),
  with the wire monitor observing /joint_states and the references;
- record: lockstep with the recorder in the wire monitor's place, writing
  every topic into an MCAP bag (what `launch --record` runs, zstd-compressed
  chunks): its real-time factor, the cost against plain lockstep (runs
  interleaved), and the bag size per simulated second; record-none: the same
  with uncompressed chunks (`--bag-compression none`);
- live: lockstep with the live view (`launch --live`) and one Foxglove
  WebSocket client subscribed to every channel for the whole run: its
  real-time factor against plain lockstep, frames the client received.
A mode's cost is given twice: from the ratio of the medians, and as the
median of each round's ratio to the lockstep run of the same round (the
paired figure, which the machine's drift between rounds moves less).
Realtime pacing and CPU per tick: scripts/bench_graph.py. Figures only; nothing is asserted (the machines
are shared and noisy).

    python scripts/bench_observers.py [--duration 10] [--repeat 3]
        [--modes lockstep record record-none live]
"""
from __future__ import annotations

import re
import resource
import shutil
import statistics
import sys
import tempfile
import threading
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
from pa10_dnbs.cli_values import OneLineParser, seconds, whole_in  # noqa: E402
from pa10_dnbs.config import default_config_path  # noqa: E402
from pa10_dnbs.live.server import LEGACY_SUBPROTOCOL, SUBPROTOCOL  # noqa: E402
from pa10_dnbs.run_settings import build_settings  # noqa: E402
from pa10_dnbs.supervisor.graph_run import GraphFailure, GraphOptions, run_graph  # noqa: E402


class LiveClient:
    """A Foxglove WebSocket client, started when the launcher says where the live view is; reads everything."""

    def __init__(self):
        self.frames = 0
        self._thread = None
        self._stop = threading.Event()

    def say(self, line: str) -> None:
        m = re.search(r"live view at (ws://\S+)", line)
        if m and self._thread is None:
            self._thread = threading.Thread(target=self._run, args=(m.group(1),), daemon=True)
            self._thread.start()

    def _run(self, url: str) -> None:
        import json

        from websockets.exceptions import ConnectionClosed
        from websockets.sync.client import connect

        with connect(url, subprotocols=[LEGACY_SUBPROTOCOL, SUBPROTOCOL], proxy=None) as ws:
            channels = {}
            js_sub = None
            while not self._stop.is_set():
                try:
                    frame = ws.recv(timeout=0.2)
                except TimeoutError:
                    continue
                except ConnectionClosed:
                    return
                if isinstance(frame, str):
                    msg = json.loads(frame)
                    if msg.get("op") == "advertise":
                        channels.update({c["topic"]: c["id"] for c in msg["channels"]})
                    if js_sub is None and len(channels) >= 6:
                        subs = {topic: i + 1 for i, topic in enumerate(channels)}
                        ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                            {"id": i, "channelId": channels[t]} for t, i in subs.items()]}))
                        js_sub = subs["/pa10/joint_states"]
                elif frame[0] == 1 and int.from_bytes(frame[1:5], "little") == js_sub:
                    self.frames += 1

    def close(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)


# every mode's cost is measured against plain lockstep (the wire monitor as the observer)
BASE = "lockstep"


def one_run(mode: str, duration: float, reliability: str | None) -> tuple[dict, float, int, int]:
    """Plant stats, children's CPU time [s], bag size [bytes] (0 without recording) and /joint_states frames
    a live client received (0 without --live) of one run."""
    with tempfile.TemporaryDirectory(prefix="pa10_bench_") as tmp:
        bag = Path(tmp) / "bag" if mode.startswith("record") else None
        client = LiveClient() if mode == "live" else None
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        try:
            joints = build_settings(default_config_path()).arm.joint_names
            res = run_graph(GraphOptions(config_path=default_config_path(), mode="lockstep", joint_names=joints,
                                         duration_s=duration, reliability=reliability,
                                         record_bag=bag, bag_compression="none" if mode == "record-none" else "zstd",
                                         live_port=0 if client else None),
                            Path(tmp), say=client.say if client else (lambda s: None),
                            on_hard_stop=lambda: shutil.rmtree(tmp, ignore_errors=True))   # a second Ctrl-C
        finally:
            if client is not None:
                client.close()
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        size = sum(f.stat().st_size for f in bag.iterdir()) if bag else 0
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    return res.stats, cpu, size, client.frames if client else 0


def main() -> int:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=seconds, default=10.0)
    ap.add_argument("--repeat", type=whole_in(1), default=3)
    ap.add_argument("--modes", nargs="+", default=["lockstep", "record", "live"],
                    choices=["lockstep", "record", "record-none", "live"])
    ap.add_argument("--reliability", default=None, choices=["reliable", "best_effort"],
                    help="per-joint QoS of every run (default: each run's own, as launch picks it: best effort "
                         "in lockstep, reliable when recording, so a mode's cost is what the user pays)")
    args = ap.parse_args()
    qos = f"{args.reliability} QoS" if args.reliability else "each run's default QoS"
    print(f"node graph, DNBS, {args.duration:g} s simulated, {qos}, {args.repeat} runs per mode; "
          f"load average at start: {open('/proc/loadavg').read().strip()}")
    rtfs = {m: [] for m in args.modes}
    paired = {m: [] for m in args.modes}  # rtf / the lockstep rtf of the same round (load drifts between rounds)
    for i in range(args.repeat):  # modes interleaved, so a slow spell of the machine hits all of them
        for mode in args.modes:
            try:
                stats, cpu, size, frames = one_run(mode, args.duration, args.reliability)
            except GraphFailure as exc:  # e.g. a node whose teardown outlived the grace period on a loaded machine
                if exc.interrupted:   # a Ctrl-C stopped the graph: it stops the benchmark
                    raise KeyboardInterrupt from None
                print(f"{mode:11s} run {i + 1}: FAILED; not counted:\n{exc}")
                continue
            rtfs[mode].append(stats["real_time_factor"])
            if mode != BASE and BASE in args.modes and len(rtfs[BASE]) == i + 1:
                paired[mode].append(stats["real_time_factor"] / rtfs[BASE][i])
            line = (f"{mode:11s} run {i + 1}: real-time factor {stats['real_time_factor']:.3f}, "
                    f"children CPU {cpu:.1f} s ({1e3 * cpu / stats['steps']:.2f} ms per step incl. start-up)")
            if size:
                line += f", bag {size / 1e6:.1f} MB = {size / 1e6 / args.duration:.2f} MB per simulated second"
            if mode == "live":
                line += f", live client received {frames} /joint_states frames"
            print(line)
    for mode, r in rtfs.items():
        if r:
            print(f"{mode:11s} real-time factor: best {max(r):.3f}, median {statistics.median(r):.3f} ({len(r)} runs)")
    print(f"load average at end: {open('/proc/loadavg').read().strip()}")
    for mode, what in (("record", "recording (zstd)"), ("record-none", "recording (uncompressed)"),
                       ("live", "the live view with a client")):
        if rtfs.get(BASE) and rtfs.get(mode):
            cost = 1 - statistics.median(rtfs[mode]) / statistics.median(rtfs[BASE])
            ratios = ", ".join(f"{r:.2f}" for r in paired[mode])
            line = f"{what} costs {100 * cost:.1f} % of the {BASE} rate (ratio of the medians)"
            if paired[mode]:
                line += (f", {100 * (1 - statistics.median(paired[mode])):.1f} % (median of the rounds' ratios: "
                         f"{ratios})")
            print(line)
    return 0


if __name__ == "__main__":
    sys.exit(script_main.run(main, "bench_observers", interrupted="the graph stopped; the lines above are the "
                                                                  "runs done"))
