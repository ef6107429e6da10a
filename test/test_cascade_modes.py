"""scripts/cascade_modes.py's parts: its one-step map is the loop DNBS's linear part and its bias run as written,
the EKF gain is the scalar Riccati recursion's fixed point, and gravity that takes more stiffness than the PD
gives makes a mode grow that the adaptive bias can hold (the bare Kinova's joint 4, docs/arms.md)."""
import numpy as np
from script_module import load_script

S = load_script("cascade_modes")
T = 1e-3


def test_the_step_map_is_the_loop_stepped_by_hand():
    rng = np.random.default_rng(1)
    n = 2
    a = rng.normal(size=(n, n))
    m_inv = np.linalg.inv(a @ a.T + np.eye(n))
    G, D = rng.normal(size=(n, n)), rng.normal(size=(n, n))
    k_a, k_u, k_i = np.array([3.0, 5.0]), np.array([40.0, 20.0]), np.array([2.0, 1.0])
    A = S.step_matrix(T, m_inv, G, D, k_a, k_u, k_i)
    dq, dv, b = rng.normal(size=n), rng.normal(size=n), rng.normal(size=n)
    x = np.concatenate([dq, dv, b])
    for _ in range(50):
        e2 = -(k_a * dq + dv)
        u = k_u * e2 + b
        dv = dv + T * m_inv @ (u - G @ dq - D @ dv)
        dq = dq + T * dv
        b = b + k_i * e2
        x = A @ x
        assert np.allclose(x, np.concatenate([dq, dv, b]), rtol=1e-12, atol=1e-12)


def test_the_ekf_gain_is_the_scalar_riccati_fixed_point():
    q, r, p = 0.01, 1.0, 1.0
    for _ in range(10000):
        p = p - p * p / (p + r) + q   # the prior: predict after the update
    assert abs(S.ekf_gain(q, r) - p / (p + r)) < 1e-12 and 0.09 < S.ekf_gain(q, r) < 0.1


def test_gravity_beyond_the_pd_grows_and_the_adaptive_bias_holds_it():
    """One joint, J = 0.003 kg m^2 (an inverted pendulum: gravity takes 0.7 N m/rad), the rule's k_u = 0.4 J / T
    and k_a = 2: k_a k_u = 2.4 N m/rad holds it; with k_a = 0.2 (0.24 N m/rad) the PD falls, a slow integrator on
    e2 catches it."""
    J, G = 0.003, np.array([[-0.7]])
    poses = [(np.array([[1.0 / J]]), G, np.zeros((1, 1)))]
    k_u = np.array([0.4 * J / T])
    held = S.fastest_mode(T, poses, np.array([2.0]), k_u, np.zeros(1))[0]
    falls = S.fastest_mode(T, poses, np.array([0.2]), k_u, np.zeros(1))[0]
    caught = S.fastest_mode(T, poses, np.array([0.2]), k_u, np.array([0.01 * k_u[0]]))[0]
    assert held < 0 < falls and caught < 0, (held, falls, caught)
