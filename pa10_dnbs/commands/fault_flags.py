"""Launcher flags for fault injection, applied on top of the config's ``faults`` section.

Each flag sets one value for the joints named by ``--fault-joints`` (all by
default). Errors name the flag (ConfigError, exit code 2).
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass, fields

from ..cli_values import plain_float, plain_int
from ..config import LINK_DELAY_MAX_MS, ConfigError
from ..faults.link_faults import CORRUPT_KINDS
from ..settings import FaultSettings, Settings, replace_in

LINK_FLAGS = {  # flag dest -> (direction, key)
    "drop_states": ("state", "drop_fraction"), "drop_efforts": ("effort", "drop_fraction"),
    "delay_states": ("state", "delay_ms"), "delay_efforts": ("effort", "delay_ms"),
    "jitter_states": ("state", "jitter_ms"), "jitter_efforts": ("effort", "jitter_ms"),
}


@dataclass(frozen=True)
class FaultFlags:
    """The fault flags as given (each None when not given; ``kill``: JOINT@SECONDS items), applied to a run's
    settings by :func:`apply_fault_flags`."""

    fault_joints: str | None = None
    drop_states: float | None = None
    drop_efforts: float | None = None
    delay_states: float | None = None
    delay_efforts: float | None = None
    jitter_states: float | None = None
    jitter_efforts: float | None = None
    corrupt_states: str | None = None
    corrupt_efforts: str | None = None
    kill: tuple[str, ...] = ()
    fault_seed: int | None = None

    @classmethod
    def of(cls, args: argparse.Namespace) -> "FaultFlags":
        """The flags of a parsed command line (``add_fault_arguments``'s)."""
        return cls(**{f.name: (tuple(getattr(args, f.name)) if f.name == "kill" else getattr(args, f.name))
                      for f in fields(cls)})


def add_fault_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("fault injection (override the config's faults section)")
    g.add_argument("--fault-joints", default=None, metavar="J,J", help="joints the flags below apply to (default all)")
    g.add_argument("--drop-states", type=plain_float, metavar="FRACTION", help="drop this fraction of state messages")
    g.add_argument("--drop-efforts", type=plain_float, metavar="FRACTION", help="drop this fraction of effort messages")
    g.add_argument("--delay-states", type=plain_float, metavar="MS", help="delay every state message by MS (0-1000)")
    g.add_argument("--delay-efforts", type=plain_float, metavar="MS", help="delay every effort message by MS (0-1000)")
    g.add_argument("--jitter-states", type=plain_float, metavar="MS", help="plus a uniform random 0..MS (MS 0-1000)")
    g.add_argument("--jitter-efforts", type=plain_float, metavar="MS", help="plus a uniform random 0..MS (MS 0-1000)")
    g.add_argument("--corrupt-states", metavar="KIND:FRACTION",
                   help=f"replace the position in this fraction of states by KIND ({', '.join(CORRUPT_KINDS)})")
    g.add_argument("--corrupt-efforts", metavar="KIND:FRACTION", help="replace the torque in this fraction of efforts")
    g.add_argument("--kill", action="append", default=[], metavar="JOINT@SECONDS",
                   help="the joint's controller process dies (SIGKILL) at this simulated time (0 <= SECONDS < "
                        "duration); repeatable, once per joint")
    g.add_argument("--fault-seed", type=plain_int, default=None, metavar="N", help="seed of the injected faults")


def _fraction(flag: str, text: str, below_one: bool = False) -> float:
    """``text`` as a fraction in [0, 1] (``below_one``: [0, 1), a drop: with every message dropped a lockstep
    step would wait for one that never comes)."""
    span = "[0, 1)" if below_one else "[0, 1]"
    try:
        v = float(text)
    except ValueError:
        raise ConfigError(f"{flag}: expected a fraction in {span}, got {text!r}") from None
    if not (0.0 <= v < 1.0 if below_one else 0.0 <= v <= 1.0):
        raise ConfigError(f"{flag}: expected a fraction in {span}, got {text!r}"
                          + (" (1 drops every message: nothing would ever arrive)" if below_one and v == 1.0 else ""))
    return v


def _set(section: dict, key: str, joints: list[int], value) -> None:
    values = list(section[key])
    for j in joints:
        values[j] = value
    section[key] = tuple(values)


def apply_fault_flags(settings: Settings, args: FaultFlags) -> Settings:
    """``settings`` with the fault flags ``args`` applied (validated again)."""
    joint_names = settings.arm.joint_names
    faults = settings.to_config()["faults"]
    if args.fault_joints is not None:
        names = [n.strip() for n in args.fault_joints.split(",") if n.strip()]
        if not names:   # '', ',' or ' , ': not "all joints", nor an unknown joint named '(none)'
            raise ConfigError(f"--fault-joints: the list names no joint, got {args.fault_joints!r} (give one or more "
                              f"of {', '.join(joint_names)}, comma-separated; without the flag: every joint)")
        bad = [n for n in names if n not in joint_names]
        if bad:
            raise ConfigError(f"--fault-joints: unknown joint {bad[0]!r} (joints: {', '.join(joint_names)})")
        twice = next((n for i, n in enumerate(names) if n in names[:i]), None)
        if twice is not None:   # as --kill refuses one: a repeat is a typo for another joint more often than not
            raise ConfigError(f"--fault-joints: joint {twice} given twice (joints: {', '.join(joint_names)})")
        joints = [joint_names.index(n) for n in names]
    else:
        joints = list(range(len(joint_names)))
    for dest, (direction, key) in LINK_FLAGS.items():
        value = getattr(args, dest)
        if value is None:
            continue
        flag = "--" + dest.replace("_", "-")
        if key == "drop_fraction":
            value = _fraction(flag, str(value), below_one=True)
        elif not 0.0 <= value <= LINK_DELAY_MAX_MS:
            raise ConfigError(f"{flag}: expected milliseconds in [0, {LINK_DELAY_MAX_MS:g}] (a later message is a lost "
                              f"one: --drop-*), got {value!r}")
        _set(faults[direction], key, joints, float(value))
    for dest, direction in (("corrupt_states", "state"), ("corrupt_efforts", "effort")):
        spec = getattr(args, dest)
        if spec is None:
            continue
        flag = "--" + dest.replace("_", "-")
        kind, sep, frac = spec.partition(":")
        if not sep or kind not in CORRUPT_KINDS:
            raise ConfigError(f"{flag}: expected KIND:FRACTION with KIND one of {', '.join(CORRUPT_KINDS)}, "
                              f"got {spec!r}")
        faults[direction]["corrupt_kind"] = kind
        _set(faults[direction], "corrupt_fraction", joints, _fraction(flag, frac))
    killed = set()
    for spec in args.kill:
        joint, sep, t = spec.partition("@")
        try:
            t_s = float(t)
        except ValueError:
            t_s = float("nan")
        if not sep or joint not in joint_names or not 0.0 <= t_s < float("inf"):
            raise ConfigError(f"--kill: expected JOINT@SECONDS with a joint of {', '.join(joint_names)} "
                              f"and finite SECONDS >= 0, got {spec!r}")
        if joint in killed:  # a joint's controller dies once: a second time would silently replace the first
            raise ConfigError(f"--kill: joint {joint} given twice (a joint's controller is killed once per run), "
                              f"got {spec!r}")
        killed.add(joint)
        _set(faults, "kill_controller_at_s", [joint_names.index(joint)], t_s)
    if args.fault_joints and all(getattr(args, d) is None for d in (*LINK_FLAGS, "corrupt_states", "corrupt_efforts")):
        raise ConfigError("--fault-joints: it picks the joints of --drop-*, --delay-*, --jitter-* and --corrupt-*, "
                          "and none of them is given")
    if args.fault_seed is not None:
        if args.fault_seed < 0:
            raise ConfigError(f"--fault-seed: expected an integer >= 0, got {args.fault_seed}")
        faults["seed"] = args.fault_seed
    checked = FaultSettings.of(faults)
    if args.fault_seed is not None and not faults_active(checked):
        raise ConfigError("--fault-seed: no fault is injected (no fault flag, and the config's faults section "
                          "injects none): the seed would draw nothing")
    return replace_in(settings, "faults", checked)


def check_kill_times(faults: FaultSettings, joint_names, duration_s: float, kill: tuple[str, ...] = ()) -> None:
    """Every kill time (``faults.kill_controller_at_s``, < 0: never) lies within the run, 0 <= t < ``duration_s``
    [s]: a later (or infinite) one would never happen, and the node counts its step from it. ConfigError naming
    --kill when the joint was named by one of ``kill`` (the flag's JOINT@SECONDS items), else the config key."""
    from_flag = {spec.partition("@")[0] for spec in kill}
    for joint, t_s in zip(joint_names, faults.kill_controller_at_s):
        if t_s >= 0.0 and not t_s < duration_s:
            where = "--kill" if joint in from_flag else "faults.kill_controller_at_s"
            raise ConfigError(f"{where}: joint {joint}'s controller would be killed at {t_s:g} s, not within the "
                              f"{duration_s:g} s run (0 <= SECONDS < duration; < 0 in the config: never)")


def faults_active(faults: FaultSettings) -> bool:
    """Whether any fault is injected (``settings.faults``)."""
    links = any(any(getattr(link, f.name)) for link in (faults.state, faults.effort) for f in fields(link)
                if f.name != "corrupt_kind")
    return links or any(t >= 0 for t in faults.kill_controller_at_s)


#: what an in-process command says when its config injects faults: only the node graph's wire carries them
IN_PROCESS_FAULTS_NOTE = ("the config's faults section is injected by `launch` alone (on the messages between the "
                          "nodes); this in-process run has no faults")
