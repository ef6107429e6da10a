"""What a launched run's report says of counters nobody injected (commands/launch_report.py), without a graph:
the guard and plant fault counters (rev_e 1); the graph tests run them end to end (test_graph_robot.py)."""
from pa10_dnbs.commands.launch_report import _unforced_faults
from pa10_dnbs.supervisor.fault_report import detected_faults, fault_note

PLANT = {"effort_timeouts": 0, "nonfinite_efforts": 0, "out_of_range_efforts": 0, "malformed_efforts": 0,
         "missed_ticks": 0, "resent_states": 0, "timeout_ranges": [], "injected_state_faults": None}
CONTROLLER = {"bad_states_nonfinite": 0, "bad_states_position": 0, "bad_states_speed": 0, "nonfinite_torques": 0,
              "ekf_resets_alpha": 0, "ekf_resets_torque": 0, "states": 301, "efforts": 301}


def _faults(**changes):
    """metrics.json's faults section of joints s1, s2; ``changes``: 'joint__side__counter' = value."""
    joints = [{"name": n, "plant": dict(PLANT), "controller": dict(CONTROLLER)} for n in ("s1", "s2")]
    for key, value in changes.items():
        joint, side, counter = key.split("__")
        next(j for j in joints if j["name"] == joint)[side][counter] = value
    return {"joints": joints, "restarts": []}


def test_a_clean_run_says_nothing():
    assert detected_faults(_faults()) == [] and _unforced_faults(_faults()) is None
    assert fault_note(_faults()) == "faults: none detected"


def test_a_guard_counter_without_injection_is_named_in_the_note_and_the_warning():
    f = _faults(s1__controller__bad_states_position=301, s2__plant__out_of_range_efforts=2)
    assert fault_note(f) == "faults: s1: bad_states_position 301; s2: out_of_range_efforts 2"
    msg = _unforced_faults(f)
    assert msg.startswith("faults detected with none injected: s1: bad_states_position 301; "
                          "s2: out_of_range_efforts 2 ("), msg


def test_effort_timeouts_alone_are_left_to_their_own_note():
    f = _faults(s2__plant__effort_timeouts=3)
    assert _unforced_faults(f) is None and fault_note(f) == "faults: s2: effort_timeouts 3"


def test_a_second_effort_publisher_is_named_unless_its_joint_was_restarted():
    from pa10_dnbs.commands.launch_report import second_effort_publishers

    def stats(*publishers):
        return {"joints": [{"name": n, "effort_publishers": p, "stale_efforts": 7 * (p - 1)}
                           for n, p in zip(("s1", "s2", "s3"), publishers)]}

    assert second_effort_publishers(stats(1, 1, 1), []) is None
    msg = second_effort_publishers(stats(2, 1, 3), [])
    assert msg.startswith("a second publisher on an effort topic: s1: 2 publishers, 7 efforts for steps already "
                          "applied, s3: 3 publishers, 14 efforts for steps already applied ("), msg
    # a killed controller's publisher outlives it in the graph for a while: its restart is no second publisher
    assert second_effort_publishers(stats(2, 1, 1), [{"joint": "s1", "exit_code": -9, "mode": "resume"}]) is None


def test_the_reference_line_names_the_trajectories_taken_from_the_topic():
    from pa10_dnbs.commands.launch_report import received_trajectories, reference_note

    none = {"trajectory_topic": "/pa10/trajectory", "trajectories_accepted": 0, "trajectories_refused": 0,
            "accepted": [], "refused_reasons": []}
    assert not received_trajectories(None) and not received_trajectories(none)
    assert reference_note("t.yaml", none, 1e-3).startswith("reference: the trajectory of `t.yaml` from t = 0")
    taken = {**none, "trajectories_accepted": 1, "trajectories_refused": 2, "refused_reasons": ["no points", "x"],
             "accepted": [{"start_step": 3300, "end_step": 4100, "points": 2, "knots": 3, "dropped_points": 0}]}
    assert received_trajectories(taken)
    assert reference_note(None, taken, 1e-3) == (
        "reference: eq. 27; from step 3300 (t = 3.300 s) the trajectory received on `/pa10/trajectory` (2 points), "
        "its last point reached at step 4100 (t = 4.100 s) and held; 2 received on `/pa10/trajectory` refused, "
        "changing nothing (the first: no points; every reason in logs/reference.log)")
    refused_only = {**none, "trajectories_refused": 1, "refused_reasons": ["no points"]}
    assert reference_note(None, refused_only, 1e-3).startswith("reference: eq. 27; 1 received on")
