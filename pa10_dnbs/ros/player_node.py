"""player node: publishes a bag's messages with their recorded timing, like ``ros2 bag play``.

Payloads go out as recorded (raw CDR). Timing: a message logged at t is
published at wall time w0 + (t - t_first) / rate. Options: topic selection,
start offset [s], loop, the arm's topics moved into another namespace
(``namespace``: /pa10/s1/state -> /arm2/s1/state; global ones stay),
/clock from the bag's timeline at ``clock_hz``
(the recorded /clock is then not replayed), and waiting until every
publisher has a subscriber. Publishers use the recorded reliability and
durability, keep_last with at least ``queue_depth``. Topics whose message
package is not installed (tf2_msgs) are skipped, with a warning.

With a live view (``replay --live``, see live/view.py) the player waits for a
Foxglove client to subscribe to the arm's joint_states, then feeds the view each
message of the topics it reads as it plays it (the URDF first, whatever the
start offset), so the client sees the run at its recorded timing.
"""
from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field

from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rosgraph_msgs.msg import Clock

from ..bag.bag_reader import Bag
from ..loop.endpoint_match import MatchWait, Need
from ..wire.topics import CLOCK, find_arm, renamed
from ..wire.steps import NS_PER_S
from .bag_qos import from_bag_qos
from .msg_types import message_class
from .runtime import announce_ready

WAIT_SLICE_S = 0.02
HEARD_RECHECK_S = 0.1  # a topic seen with a subscriber is checked again after this [s of wall time]


@dataclass
class PlayOptions:
    rate: float = 1.0
    topics: list[str] = field(default_factory=list)   # empty: every topic
    start_offset_s: float = 0.0
    loop: bool = False
    clock_hz: float = 0.0                               # 0: no /clock from the player
    wait_for_subscribers_s: float = 0.0                 # 0: do not wait
    queue_depth: int = 1000
    namespace: str | None = None                        # None: topics as recorded


class PlayerNode(Node):
    def __init__(self, bag: Bag, opt: PlayOptions, live=None):
        """``live``: a LiveView to feed (replay --live), or None."""
        super().__init__("player")
        self.bag, self.opt, self.live = bag, opt, live
        src = find_arm(bag.topics)
        self.out_name = {t: renamed(t, src, opt.namespace) for t in bag.topics}  # bag topic -> published name
        topics = opt.topics or sorted(bag.topics)
        if opt.clock_hz > 0:
            topics = [t for t in topics if t != CLOCK]
        self.pubs = {}
        self.skipped = []
        for t in topics:
            try:
                cls = message_class(bag.topics[t].msgtype)
            except LookupError as exc:
                self.skipped.append(t)
                self.get_logger().warning(f"not playing {t}: {exc}")
                continue
            self.pubs[t] = self.create_publisher(cls, self.out_name[t],
                                                 from_bag_qos(bag.qos_profiles(t), opt.queue_depth))
        self._clock_pub = self.create_publisher(Clock, CLOCK, QoSProfile(depth=10)) if opt.clock_hz > 0 else None
        self.published = 0
        self.unheard: dict[str, int] = {}  # bag topic -> messages published while it had no matched subscriber
        self._heard_at: dict[str, float] = {}  # topic -> when a subscriber was last seen [s, perf_counter]
        self.exit_code = 0
        self.interrupted = False   # a Ctrl-C (or SIGTERM) before the bag was played through
        # topics read for the live view only (not published, or not played: /tf has no Python message package)
        shown = set(live.topics()) if live else set()
        self._live_only = [t for t in bag.topics if self.out_name[t] in shown and t not in self.pubs]
        if live is not None and src is not None:
            for topic, _, _, data in bag.messages([src.robot_description]):
                live.on_message(self.out_name[topic], bytes(data))
        announce_ready("player")

    def _wait_for_live_client(self, stop) -> bool:
        """Hold playback until a Foxglove client subscribes to the arm's joint_states (Ctrl-C stops waiting)."""
        print(f"LIVE waiting for a Foxglove client on {self.live.sink.url}", flush=True)
        while not stop.done():
            self.live.tick(time.perf_counter())  # sends the URDF to clients that subscribe meanwhile
            if self.live.sink.wanted(self.live.arm.joint_states):
                return True
            time.sleep(WAIT_SLICE_S)
        return False

    def _wait_for_subscribers(self, stop) -> bool:
        wait = MatchWait([Need(p.topic_name, "subscribers", 1, p.get_subscription_count) for p in self.pubs.values()],
                         self.opt.wait_for_subscribers_s)
        while not stop.done():
            status = wait.poll()
            if status == "met":
                return True
            if status == "timeout":
                self.get_logger().error(f"no subscriber after {self.opt.wait_for_subscribers_s:g} s on: "
                                        + ", ".join(wait.lacking))
                self.exit_code = 1
                return False
            time.sleep(WAIT_SLICE_S)
        return False

    def _publish_clock(self, t_ns: int) -> None:
        msg = Clock()
        msg.clock.sec, msg.clock.nanosec = divmod(t_ns, NS_PER_S)
        self._clock_pub.publish(msg)

    def _play_once(self, stop) -> bool:
        """One pass over the bag; False when stopped. With ``loop`` a pass lasts until the bag's last instant
        (rosbags' end time - 1 ns), whichever topics are played: the next one never starts at once after topics
        whose messages end earlier (a tight loop)."""
        t_first = self.bag.start_ns + int(round(self.opt.start_offset_s * 1e9))
        rate = self.opt.rate
        w0 = time.perf_counter()
        clock_period = 1.0 / self.opt.clock_hz if self._clock_pub else None
        clock = [w0]   # when the next /clock is due [s, perf_counter]

        def wait_until(target: float) -> float | None:
            """Sleep until ``target`` [s, perf_counter], publishing /clock and ticking the live view meanwhile; the
            time then, or None when stopped."""
            while True:
                if stop.done():
                    return None
                now = time.perf_counter()
                if self.live is not None:
                    self.live.tick(now)
                if clock_period is not None and clock[0] <= min(now, target):
                    self._publish_clock(t_first + int((clock[0] - w0) * rate * 1e9))
                    clock[0] += clock_period
                    continue
                if now >= target:
                    return now
                wake = target if clock_period is None else min(target, clock[0])
                time.sleep(min(max(wake - now, 0.0), WAIT_SLICE_S))

        for topic, _, t_ns, data in self.bag.messages(list(self.pubs) + self._live_only, start_ns=t_first):
            now = wait_until(w0 + (t_ns - t_first) / 1e9 / rate)
            if now is None:
                return False
            if topic in self.pubs:
                self._count_unheard(topic, now)
                self.pubs[topic].publish(bytes(data))
                self.published += 1
            if self.live is not None:
                self.live.on_message(self.out_name[topic], bytes(data))
        if self.live is not None:  # the last state of the pass
            self.live.tick(time.perf_counter() + self.live.decimator.period_s)
        if self.opt.loop:   # the pass ends at the bag's last instant, not at the last message played
            return wait_until(w0 + (self.bag.end_ns - 1 - t_first) / 1e9 / rate) is not None
        return True

    def _count_unheard(self, topic: str, now: float) -> None:
        """Count a message about to go out on ``topic`` with no subscriber matched (checked at most every
        ``HEARD_RECHECK_S`` while one is)."""
        if now - self._heard_at.get(topic, -1e9) < HEARD_RECHECK_S:
            return
        if self.pubs[topic].get_subscription_count() > 0:
            self._heard_at[topic] = now
        else:
            self.unheard[topic] = self.unheard.get(topic, 0) + 1

    def loop(self, executor, stop) -> None:
        if self.opt.wait_for_subscribers_s > 0 and not self._wait_for_subscribers(stop):
            self._stopped(stop)
            return
        if self.live is not None and not self._wait_for_live_client(stop):
            self._stopped(stop)
            return
        print(f"PLAYING {len(self.pubs)} topics at rate {self.opt.rate:g}", flush=True)
        while True:
            if not self._play_once(stop):
                self._stopped(stop)
                break
            if not self.opt.loop:
                break
        # let reliable subscribers take the last messages before the writers go away
        deadline = time.monotonic() + 2.0
        while not stop.done() and time.monotonic() < deadline and any(
                not p.wait_for_all_acked(Duration(seconds=0.1)) for p in self.pubs.values()):
            pass

    def _stopped(self, stop) -> None:
        """Playback ended by a signal: with ``--loop`` that is how it ends (exit 0); else the bag was not played
        through: exit 130, and close() says so."""
        if stop.done() and not self.opt.loop:
            self.interrupted, self.exit_code = True, 130

    def close(self) -> None:
        print(f"PLAYED {self.published} messages" + (f"; skipped {', '.join(self.skipped)}" if self.skipped else ""),
              flush=True)
        if self.interrupted:
            total = sum(self.bag.topics[t].count for t in self.pubs)
            print(f"pa10-dnbs replay: interrupted: played {self.published} of the bag's {total} messages on the "
                  "played topics", file=sys.stderr, flush=True)
        if self.unheard:  # named as published (--namespace moves the arm's topics), not as recorded
            published_as = {self.out_name[t]: n for t, n in self.unheard.items()}
            print(unheard_warning(published_as, self.published), file=sys.stderr, flush=True)


def unheard_warning(unheard: dict[str, int], published: int) -> str:
    """The player's line when messages went out with nobody subscribed: nothing received them (``unheard``:
    published topic name -> such messages)."""
    n = sum(unheard.values())
    return (f"WARNING replay: {n} of {published} messages went out with no subscriber matched on "
            f"{', '.join(sorted(unheard))}: nothing received them; start the subscribers first and use "
            "--wait-for-subscribers S (docs/bags.md, re-drive)")
