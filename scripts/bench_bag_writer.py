"""Time the recorder's bag writer on a synthetic 20 s run (the main job's message mix), without ROS.

Per 1 ms step: /pa10/joint_states (7 joints) and, per joint, <j>/state and <j>/effort (15 messages); every
10 steps /clock and a /tf-sized payload; at the start one reference batch per joint. That is the main job's
bag: 20 s -> 20001 steps, about 304,000 messages. Reports the wall and CPU time of ``BagWriter.write`` calls
plus ``close()``: CPU per message [us] and per simulated second [ms], best of ``--repeat``.

    .venv/bin/python scripts/bench_bag_writer.py [--seconds 20] [--repeat 3] [--compression zstd|none]
                                                 [--save-record FILE]

``--save-record benchmarks/bench_bag_writer.json``: the figures as a record (scripts/bench_record.py).
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import script_main  # noqa: E402  (first: a Ctrl-C while the modules load is one line)
import bench_record  # noqa: E402

from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime  # noqa: E402

from pa10_dnbs.arm import load_arm  # noqa: E402
from pa10_dnbs.cli_values import OneLineParser, seconds, whole_in  # noqa: E402
from pa10_dnbs.bag.bag_writer import BagWriter  # noqa: E402
from pa10_dnbs.wire import joint_state_cdr  # noqa: E402

JOINT_NAMES = load_arm("pa10").joint_names  # the main job's arm

ZERO = QosTime(0, 0)
QOS = [Qos(QosHistory.KEEP_LAST, 10, QosReliability.RELIABLE, QosDurability.VOLATILE, ZERO, ZERO,
           QosLiveliness.AUTOMATIC, ZERO, False)]


def _messages(n_steps: int):
    """(topic, type, t_ns, payload) of a synthetic run, payloads of the graph's sizes."""
    js_t, st_t = "sensor_msgs/msg/JointState", "sensor_msgs/msg/JointState"
    out = []
    for k in range(n_steps):
        sec, ns = divmod(k * 1_000_000, 1_000_000_000)
        t_ns = (k // 10) * 10_000_000  # log time: the latest /clock (100 Hz)
        out.append(("/pa10/joint_states", js_t, t_ns, joint_state_cdr.encode(
            sec, ns, list(JOINT_NAMES), [0.001 * k] * 7, [0.5] * 7, [1.5] * 7)))
        for j in JOINT_NAMES:
            out.append((f"/pa10/{j}/state", st_t, t_ns, joint_state_cdr.encode(sec, ns, [j], [0.001 * k], [0.5], [])))
            out.append((f"/pa10/{j}/effort", st_t, t_ns, joint_state_cdr.encode(sec, ns, [j], [], [], [1.5])))
        if k % 10 == 0:
            out.append(("/clock", "rosgraph_msgs/msg/Clock", t_ns, bytes(12)))
            out.append(("/tf", "tf2_msgs/msg/TFMessage", t_ns, bytes(680)))
    return out


def run(n_steps: int, compression: str) -> tuple[float, float, int, int]:
    """(wall s, CPU s, messages, file bytes) of writing ``n_steps`` steps."""
    msgs = _messages(n_steps)
    with tempfile.TemporaryDirectory() as tmp:
        w = BagWriter(Path(tmp) / "b", compression=compression)
        for topic, msgtype, _, _ in msgs:
            if not w.has_topic(topic):
                w.add_topic(topic, msgtype, QOS)
        t0, c0 = time.perf_counter(), time.process_time()
        for topic, _, t_ns, data in msgs:
            w.write(topic, t_ns, data)
        w.close()
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        size = sum(f.stat().st_size for f in (Path(tmp) / "b").iterdir())
    return wall, cpu, len(msgs), size


def main() -> None:
    ap = OneLineParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=seconds, default=20.0)
    ap.add_argument("--repeat", type=whole_in(1), default=3)
    ap.add_argument("--compression", default="zstd", choices=("zstd", "none"))
    bench_record.add_argument(ap)
    a = ap.parse_args()
    record = bench_record.Record.start("bench_bag_writer")
    n_steps = int(round(a.seconds * 1000)) + 1
    runs = [run(n_steps, a.compression) for _ in range(a.repeat)]
    cpu, wall, n, size = min((r[1], r[0], r[2], r[3]) for r in runs)
    print(f"{n} messages ({a.seconds:g} s of 1 kHz steps, {a.compression}), {size / 1e6:.1f} MB: "
          f"CPU {cpu:.2f} s, wall {wall:.2f} s (best CPU of {a.repeat}; all CPU "
          f"{', '.join(f'{r[1]:.2f}' for r in runs)}); {1e6 * cpu / n:.2f} us CPU per message, "
          f"{1e3 * cpu / a.seconds:.1f} ms CPU per simulated second")
    record.save(a.save_record, {
        "seconds": a.seconds, "repeat": a.repeat, "compression": a.compression, "messages": n,
        "bag_mb": round(size / 1e6, 2), "cpu_s_best": round(cpu, 3), "wall_s_of_best": round(wall, 3),
        "cpu_s_all": [round(r[1], 3) for r in runs], "cpu_us_per_message": round(1e6 * cpu / n, 3),
        "cpu_ms_per_simulated_s": round(1e3 * cpu / a.seconds, 2)})


if __name__ == "__main__":
    sys.exit(script_main.run(main, "bench_bag_writer", interrupted="no record written: run the same command again"))
