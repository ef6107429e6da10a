"""The reference rule's torque check (arm/reference_rule.py feasible_reference, plant/reference_torque.py): a
feasible reference is kept as it is, an infeasible one is moved until it fits, and a joint no tried reference
fits is named in one line."""
import numpy as np

from pa10_dnbs.arm import load_arm
from pa10_dnbs.arm.reference_rule import TORQUE_FRACTION, feasible_reference, reference_rule
from pa10_dnbs.plant.from_config import arm_plant_params, opened_plant
from pa10_dnbs.plant.reference_torque import ReferenceTorque

LOWER, UPPER = np.array([0.0, -2.0]), np.array([2.88, 2.0])
LIMIT = np.array([22.0, 10.0])
NAMES = ("shoulder", "elbow")


def _gravity_like(fragment):
    """Peak torques [N m]: joint 0 holds an arm whose load grows with its centre and amplitude (cos-like)."""
    c, a = fragment["centre_rad"][0], fragment["amplitude_rad"][0]
    return np.array([30.0 * min(1.0, np.sin(min(c + a, np.pi / 2))), 2.0])


def test_a_feasible_reference_is_kept_as_it_is():
    frag = reference_rule(LOWER, UPPER)
    out, lines = feasible_reference(frag, LOWER, UPPER, LIMIT, lambda f: 0.1 * LIMIT, NAMES)
    assert out is frag and lines == []


def test_an_infeasible_reference_is_moved_until_it_fits_and_says_so():
    frag = reference_rule(LOWER, UPPER)
    assert (_gravity_like(frag) / LIMIT).max() > TORQUE_FRACTION  # the middle of [0, 2.88] asks too much
    out, lines = feasible_reference(frag, LOWER, UPPER, LIMIT, _gravity_like, NAMES)
    assert (_gravity_like(out) / LIMIT).max() <= TORQUE_FRACTION
    assert LOWER[0] < out["centre_rad"][0] - out["amplitude_rad"][0]  # still inside the limits
    assert out["centre_rad"][1] == frag["centre_rad"][1]             # the other joint untouched
    assert len(lines) == 1 and "joint shoulder" in lines[0] and "moved" in lines[0]


def test_a_joint_no_reference_fits_is_named_with_what_to_change():
    frag = reference_rule(LOWER, UPPER)
    out, lines = feasible_reference(frag, LOWER, UPPER, LIMIT, lambda f: np.array([50.0, 2.0]), NAMES)
    assert any("joint shoulder cannot hold" in line and "torque_limit_nm" in line for line in lines)


def test_the_plant_check_reads_gravity_from_the_arm(tmp_path):
    """Inverse dynamics along the reference on a preset: gravity makes the peak torque of the Panda's
    shoulder (joint 2) far above its inertial part alone, and every preset joint stays within 80 %."""
    arm = load_arm("panda")
    frag = reference_rule(arm.lower_rad, arm.upper_rad)
    with (opened_plant(arm, arm_plant_params(arm)) as g,
          opened_plant(arm, arm_plant_params(arm, gravity_mps2=0.0)) as z):
        pg, p0 = ReferenceTorque(g, 5.0, 0.001).peak(frag), ReferenceTorque(z, 5.0, 0.001).peak(frag)
    assert pg[1] > 5 * p0[1]
    assert (pg / arm.torque_limit_nm).max() <= TORQUE_FRACTION
