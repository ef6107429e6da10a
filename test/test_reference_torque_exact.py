"""The reference rule's torque check made faster without changing a bit (plant/reference_torque.py,
PyBulletArmPlant.torque_along): one mass-matrix and one inverse-dynamics call per sampled step, and a fragment
asked twice answered once, give the values of the straightforward per-step
``mass_matrix(q) @ qdd + bias_torque(q, qd) + friction_torque(qd)``, and the rule's search the same reference."""
import numpy as np
import pytest

from chain_urdf import chain_urdf
from pa10_dnbs.arm import load_arm
from pa10_dnbs.arm.reference_rule import feasible_reference, reference_rule
from pa10_dnbs.core.reference import Reference
from pa10_dnbs.plant.from_config import arm_plant_params, opened_plant
from pa10_dnbs.plant.reference_torque import ReferenceTorque

DURATION_S, DT_S = 5.0, 0.001
SEARCH_DURATION_S = 20.0   # the default run's: the search then moves several joints over both passes


def _per_step_peak(plant, fragment, duration_s=DURATION_S):
    """The peak as reference_torque.py computed it before (one mass_matrix, bias_torque and friction_torque call
    per sampled step): the oracle."""
    arm = plant.arm
    steps = ReferenceTorque(plant, duration_s, DT_S)._steps
    ref = Reference(fragment["amplitude_rad"], fragment["envelope_rate_per_s3"], fragment["frequency_rad_s"],
                    dt_s=DT_S, centre_rad=fragment["centre_rad"])
    q = np.clip(ref.position(steps), arm.lower_rad, arm.upper_rad)
    qd, qdd = ref.velocity(steps), ref.acceleration(steps)
    tau = np.array([plant.mass_matrix(a) @ c + plant.bias_torque(a, b) + plant.friction_torque(b)
                    for a, b, c in zip(q, qd, qdd)])
    return np.abs(tau).max(axis=0)


@pytest.fixture(scope="module")
def chain_arm(tmp_path_factory):
    """A 12-joint chain whose 10 N m joints cannot hold the rule's reference: the search runs."""
    path = tmp_path_factory.mktemp("chain") / "chain12.urdf"
    path.write_text(chain_urdf(12, effort_nm=10.0, name="chain12"))
    return load_arm(str(path))


@pytest.mark.parametrize("which", ["chain", "panda"])
def test_the_peak_torque_has_the_bits_of_the_per_step_sum(which, chain_arm):
    arm = chain_arm if which == "chain" else load_arm("panda")
    params = arm_plant_params(arm, coulomb_nm=tuple(0.5 for _ in arm.joint_names), coulomb_smoothing_rad_s=0.01)
    with opened_plant(arm, params) as plant:
        fragment = reference_rule(arm.lower_rad, arm.upper_rad)
        torque = ReferenceTorque(plant, DURATION_S, DT_S)
        first = torque.peak(fragment)
        assert first.tobytes() == _per_step_peak(plant, fragment).tobytes()
        first[:] = -1.0                                   # the answer is the caller's copy
        again = torque.peak({k: list(v) for k, v in fragment.items()})
        assert again.tobytes() == _per_step_peak(plant, fragment).tobytes()
        moved = dict(fragment, centre_rad=[0.3] + list(fragment["centre_rad"][1:]))
        assert torque.peak(moved).tobytes() == _per_step_peak(plant, moved).tobytes()
        with pytest.raises(ValueError, match="q: values must be finite"):
            torque.peak(dict(fragment, centre_rad=[np.nan] * arm.n_joints))


def test_the_search_finds_the_same_reference_with_the_oracle(chain_arm):
    """feasible_reference on the weak chain, its candidates read chunk by chunk only as far as the choice needs
    (ReferenceTorque.sweep), vs every candidate's whole peak from the per-step oracle: the same fragment, the
    same lines, with a fraction of the inverse-dynamics steps."""
    arm = chain_arm
    with opened_plant(arm, arm_plant_params(arm)) as plant:
        fragment = reference_rule(arm.lower_rad, arm.upper_rad)
        torque = ReferenceTorque(plant, SEARCH_DURATION_S, DT_S)
        along, rows = plant.torque_along, []
        plant.torque_along = lambda q, qd, qdd: rows.append(len(q)) or along(q, qd, qdd)
        fast = feasible_reference(fragment, arm.lower_rad, arm.upper_rad, arm.torque_limit_nm, torque.peak,
                                  arm.joint_names, sweep=torque.sweep)
        del plant.torque_along
        asked = []
        slow = feasible_reference(fragment, arm.lower_rad, arm.upper_rad, arm.torque_limit_nm,
                                  lambda f: asked.append(1) or _per_step_peak(plant, f, SEARCH_DURATION_S),
                                  arm.joint_names)
    assert fast == slow
    assert len(fast[1]) >= 3                                    # it moved joints, over both passes
    assert sum(rows) < 0.5 * len(asked) * len(torque._steps)    # and read less than half the steps


class _ChunkMaxima:
    """A sweep over given chunk maxima (chunks, n) [N m]: the interface of plant/reference_torque.TorqueSweep."""

    def __init__(self, maxima):
        self._maxima, self._next, self.peak = maxima, 0, None

    @property
    def done(self):
        return self._next == len(self._maxima)

    def more(self):
        part = self._maxima[self._next]
        self.peak = part if self.peak is None else np.maximum(self.peak, part)
        self._next += 1

    def finish(self):
        while not self.done:
            self.more()
        return self.peak.copy()


def test_the_least_candidate_read_in_part_is_the_first_least_of_all():
    """_first_least against min over the whole keys, on random candidates full of ties (ratios on a coarse grid
    around TORQUE_FRACTION, amplitudes repeated): the same index every time."""
    from pa10_dnbs.arm.reference_rule import _first_least, _key
    rng = np.random.default_rng(5)
    limit = np.array([10.0, 20.0, 5.0])
    for _ in range(3000):
        m = int(rng.integers(1, 15))
        maxima = [np.round(rng.uniform(0.5, 1.0, (int(rng.integers(1, 6)), 3)), 1) * limit for _ in range(m)]
        amplitudes = list(rng.choice([0.25, 0.5, 1.0], m))
        keys = [_key(x.max(axis=0) / limit, a) for x, a in zip(maxima, amplitudes)]
        want = min(range(m), key=lambda k: keys[k])
        assert _first_least([_ChunkMaxima(x) for x in maxima], amplitudes, limit) == want
