"""What the faults did, for metrics.json and the report: injected, detected, restarts."""
from __future__ import annotations

from ..ros.plant.counters import FAULT_KEYS, REPORT_KEYS
from ..config_yaml import dumpable



def fault_report(settings, plant_stats: dict, result) -> dict:
    """{'configured': the faults section, 'joints': per joint plant + controller counters, 'restarts': [...]}."""
    joints = []
    for pj in plant_stats["joints"]:
        name = pj["name"]
        ctrl = result.controllers.get(name)
        joints.append({"name": name, "plant": {k: pj.get(k) for k in REPORT_KEYS}, "controller": ctrl})
    used = settings.to_config()
    return {"configured": dumpable(used["faults"]), "guards": dumpable(used["guards"]), "joints": joints,
            "restarts": result.restarts}


def detected_faults(faults: dict, skip: tuple[str, ...] = ()) -> list[str]:
    """Per joint with any non-zero fault counter (plant's FAULT_KEYS but ``skip``, injected state faults, the
    controller's guard counters: ``bad_states_*``, ``ekf_resets_*``, ``nonfinite_torques``, injected effort
    faults) or lost counters: '<joint>: <counter> <count>, ...'; [] when there is none."""
    parts = []
    for j in faults["joints"]:
        p, c = j["plant"], j["controller"] or {}
        items = [f"{k} {p[k]}" for k in FAULT_KEYS if p.get(k) and k not in skip]
        inj = p.get("injected_state_faults") or {}
        items += [f"states {k} {v}" for k, v in inj.items() if k != "messages" and v]
        items += [f"{k} {v}" for k, v in c.items()
                  if (k.startswith(("bad_states_", "ekf_resets_", "injected_effort_")) or k == "nonfinite_torques")
                  and not k.endswith("_messages") and v]
        if j["controller"] is None:
            items.append("controller counters lost (its last process was killed)")
        if items:
            parts.append(f"{j['name']}: " + ", ".join(items))
    return parts


def fault_note(faults: dict) -> str:
    """One Markdown line: each joint with anything non-zero (``detected_faults``), and the restarts."""
    parts = detected_faults(faults)
    restarts = ", ".join(f"{r['joint']} (exit {r['exit_code']}, {r['mode']})" for r in faults["restarts"])
    return "faults: " + ("; ".join(parts) or "none detected") + (f"; restarts: {restarts}" if restarts else "")
