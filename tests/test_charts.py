"""The one conversion between thesis coordinates xi and Pinocchio's (q, v) (qprr.charts)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from qprr import charts as co
from qprr.errors import EulerSingularityError, InputError, NonFiniteError, ShapeError

angle = st.floats(-np.pi + 1e-6, np.pi - 1e-6)
pitch = st.floats(-1.5, 1.5)
real = st.floats(-10.0, 10.0)
SETTINGS = settings(max_examples=60, deadline=None, derandomize=True)


def xi_strategy():
    return st.tuples(real, real, real, angle, pitch, angle, st.floats(-0.04, 0.04), angle, angle).map(np.array)


def rates_strategy():
    return st.lists(st.floats(-5.0, 5.0), min_size=9, max_size=9).map(np.array)


def test_rotation_is_zyx_product():
    phi, theta, psi = 0.3, -0.7, 2.1
    R = co.euler_to_rotation([phi, theta, psi])
    expected = pin.utils.rpyToMatrix(phi, theta, psi)  # Pinocchio's rpy is the same ZYX product
    np.testing.assert_allclose(R, expected, atol=1e-15)


@SETTINGS
@given(xi_strategy(), rates_strategy())
def test_round_trip_xi_qv(xi, xi_dot):
    q, v = co.xi_to_qv(xi, xi_dot)
    xi2, xi_dot2 = co.qv_to_xi(q, v)
    np.testing.assert_allclose(xi2, xi, atol=1e-9)
    np.testing.assert_allclose(xi_dot2, xi_dot, atol=1e-9 * (1 + np.abs(xi_dot).max()) / np.cos(xi[4]) ** 2)


@SETTINGS
@given(xi_strategy(), rates_strategy())
def test_rate_map_is_the_tangent_map(xi, xi_dot):
    """pin.difference(q(xi), q(xi + h xi_dot)) / h -> S(xi) xi_dot: v really is Pinocchio's velocity."""
    h = 1e-6
    dq = pin.difference(_ff_model(), co.xi_to_q(xi - h * xi_dot), co.xi_to_q(xi + h * xi_dot)) / (2 * h)
    np.testing.assert_allclose(dq, co.rate_map(xi) @ xi_dot, atol=1e-6 * (1 + np.abs(xi_dot).max()))


@SETTINGS
@given(st.tuples(angle, pitch, angle).map(np.array), st.tuples(real, real, real).map(np.array))
def test_euler_rate_matrix_gives_body_angular_velocity(euler, euler_dot):
    """omega_body^ = R^T R_dot (Thesis (3.19)), R_dot by central differences."""
    h = 1e-6
    R = co.euler_to_rotation(euler)
    R_dot = (co.euler_to_rotation(euler + h * euler_dot) - co.euler_to_rotation(euler - h * euler_dot)) / (2 * h)
    W = R.T @ R_dot
    omega = np.array([W[2, 1], W[0, 2], W[1, 0]])
    np.testing.assert_allclose(omega, co.euler_rate_matrix(euler) @ euler_dot, atol=1e-7 * (1 + np.abs(euler_dot).max()))


def test_rate_map_derivatives_match_finite_differences():
    rng = np.random.default_rng(3)
    for _ in range(5):
        xi = rng.uniform(-1.2, 1.2, 9)
        dS = co.rate_map_derivatives(xi)
        for k in range(3):
            e = np.zeros(9)
            e[3 + k] = 1e-6
            fd = (co.rate_map(xi + e) - co.rate_map(xi - e)) / 2e-6
            np.testing.assert_allclose(dS[k], fd, atol=1e-9)


@SETTINGS
@given(xi_strategy(), rates_strategy(), rates_strategy())
def test_acceleration_conversion_round_trip(xi, xi_dot, xi_ddot):
    a = co.xi_ddot_to_a(xi, xi_dot, xi_ddot)
    np.testing.assert_allclose(co.a_to_xi_ddot(xi, xi_dot, a), xi_ddot, atol=1e-8 / np.cos(xi[4]) ** 2)


def test_acceleration_conversion_matches_second_difference():
    """a = d/dt v along a curve xi(t) = xi0 + t xi_dot + t^2/2 xi_ddot."""
    rng = np.random.default_rng(4)
    xi, xi_dot, xi_ddot = rng.uniform(-1, 1, 9), rng.uniform(-1, 1, 9), rng.uniform(-1, 1, 9)
    h = 1e-5

    def v_at(t):
        return co.xi_dot_to_v(xi + t * xi_dot + 0.5 * t * t * xi_ddot, xi_dot + t * xi_ddot)

    np.testing.assert_allclose((v_at(h) - v_at(-h)) / (2 * h), co.xi_ddot_to_a(xi, xi_dot, xi_ddot), atol=1e-8)


@pytest.mark.parametrize("theta", [np.pi / 2, -np.pi / 2, np.pi / 2 - 1e-8])
def test_euler_singularity_is_reported(theta):
    xi = np.zeros(9)
    xi[4] = theta
    q = co.xi_to_q(xi)  # the configuration itself is fine
    with pytest.raises(EulerSingularityError, match="pitch"):
        co.q_to_xi(q)
    with pytest.raises(EulerSingularityError, match="pitch"):
        co.v_to_xi_dot(xi, np.zeros(9))


def test_near_singularity_still_converts():
    xi = np.zeros(9)
    xi[4] = np.pi / 2 - 1e-3
    xi[3], xi[5] = 0.2, -0.4
    np.testing.assert_allclose(co.q_to_xi(co.xi_to_q(xi)), xi, atol=1e-9)


# The old test_bad_inputs_name_the_argument, split so that each assertion runs on its own.
def test_bad_xi_shape_names_the_argument():
    # xi of any length >= 6 is a thesis chart (6 + n_arm entries): the Q-PRR's 9 is checked where the
    # platform is known (charts.as_xi with n, as kinematics and dynamics call it); too short is refused anywhere
    with pytest.raises(ShapeError, match=r"xi must have shape \(9,\)"):
        co.as_xi(np.zeros(8), "xi", 9)
    with pytest.raises(ShapeError, match=r"xi must have shape"):
        co.xi_to_q(np.zeros(5))


def test_non_finite_rates_name_the_argument():
    with pytest.raises(NonFiniteError, match="xi_dot"):
        co.xi_dot_to_v(np.zeros(9), [np.nan] + [0.0] * 8)


def test_non_unit_quaternion_is_rejected():
    q = co.xi_to_q(np.zeros(9))
    q[3:7] *= 2.0
    with pytest.raises(ShapeError, match="unit quaternion"):
        co.q_to_xi(q)


def test_rotation_of_the_wrong_shape_names_the_argument():
    with pytest.raises(ShapeError, match="R must have shape"):
        co.rotation_to_euler(np.eye(4))
    assert issubclass(ShapeError, ValueError)


_MODEL = None


def _ff_model():
    global _MODEL
    if _MODEL is None:
        import qprr

        _MODEL = qprr.load().model
    return _MODEL


# ======================================================== the chart for any number of arm joints
N_ARMS = (0, 2, 3, 5)
_MODELS: dict = {}


def free_flyer_model(n_arm: int) -> pin.Model:
    """A free-flyer model with ``n_arm`` arm joints: hector (0), borinot (2), the Q-PRR (3), hextilt (5)."""
    if n_arm not in _MODELS:
        import qprr
        import qprr.thesis

        _MODELS[n_arm] = {
            0: lambda: qprr.platforms.multirotor_model("hector"),
            2: lambda: qprr.load("borinot_flying_arm_2").model,
            3: lambda: qprr.thesis.load_qprr().model,
            5: lambda: qprr.load("hextilt_flying_arm_5").model,
        }[n_arm]()
        assert _MODELS[n_arm].nv == 6 + n_arm
    return _MODELS[n_arm]


@st.composite
def chart_state(draw, max_pitch: float = 1.5):
    """(n_arm, xi, xi_dot) for n_arm in N_ARMS (arm values within +-1, any sign)."""
    n = draw(st.sampled_from(N_ARMS))
    xi = np.array(
        [draw(real), draw(real), draw(real), draw(angle), draw(st.floats(-max_pitch, max_pitch)), draw(angle)]
        + [draw(st.floats(-1.0, 1.0)) for _ in range(n)]
    )
    w = np.array([draw(st.floats(-5.0, 5.0)) for _ in range(6 + n)])
    return n, xi, w


@SETTINGS
@given(chart_state())
def test_any_arm_round_trip(state):
    n, xi, w = state
    q, v = co.xi_to_qv(xi, w)
    assert q.shape == (7 + n,) and v.shape == (6 + n,)
    xi2, w2 = co.qv_to_xi(q, v)
    np.testing.assert_allclose(xi2, xi, atol=1e-9)
    np.testing.assert_allclose(w2, w, atol=1e-9 * (1 + np.abs(w).max()) / np.cos(xi[4]) ** 2)


@SETTINGS
@given(chart_state())
def test_any_arm_rate_map_is_the_tangent_map_on_the_manifold(state):
    """S(xi) xi_dot = pin.difference(q(xi - h xi_dot), q(xi + h xi_dot)) / 2h on the model with n_arm joints."""
    n, xi, w = state
    h = 1e-6
    dq = pin.difference(free_flyer_model(n), co.xi_to_q(xi - h * w), co.xi_to_q(xi + h * w)) / (2 * h)
    np.testing.assert_allclose(dq, co.rate_map(xi) @ w, atol=1e-6 * (1 + np.abs(w).max()))
    # and a = S xi_ddot + S_dot xi_dot is the derivative of v along xi(t) = xi + t w + t^2/2 w2
    w2 = np.cos(np.arange(6 + n)) * 2.0
    vp = co.xi_dot_to_v(xi + h * w + 0.5 * h * h * w2, w + h * w2)
    vm = co.xi_dot_to_v(xi - h * w + 0.5 * h * h * w2, w - h * w2)
    np.testing.assert_allclose((vp - vm) / (2 * h), co.xi_ddot_to_a(xi, w, w2), atol=1e-6 * (1 + np.abs(w).max()) ** 2)


@SETTINGS
@given(chart_state(max_pitch=1.3), st.lists(st.floats(-10.0, 10.0), min_size=11, max_size=11))
def test_any_arm_force_map_by_virtual_power(state, forces):
    """u = S^T tau: u . xi_dot is the power of a world force at B, a body torque and arm efforts, with omega_body
    from central differences of R (independent of T)."""
    n, xi, w = state
    f_world, tau_body, efforts = np.array(forces[0:3]), np.array(forces[3:6]), np.array(forces[6 : 6 + n])
    R = co.euler_to_rotation(xi[3:6])
    tau = np.r_[R.T @ f_world, tau_body, efforts]  # Pinocchio's generalised force of that load
    h = 1e-6
    Rp, Rm = co.euler_to_rotation(xi[3:6] + h * w[3:6]), co.euler_to_rotation(xi[3:6] - h * w[3:6])
    omega_body = pin.log3(Rm.T @ Rp) / (2 * h)
    power = f_world @ w[0:3] + tau_body @ omega_body + efforts @ w[6:]
    u = co.force_to_xi(xi, tau)
    assert u @ w == pytest.approx(power, abs=1e-6 * (1 + np.abs(forces).max()) * (1 + np.abs(w).max()))
    np.testing.assert_allclose(u[0:3], f_world, atol=1e-12 * (1 + np.abs(forces).max()))  # x, y, z are world coordinates
    np.testing.assert_allclose(co.force_from_xi(xi, u), tau, atol=1e-9 * (1 + np.abs(forces).max()) / np.cos(xi[4]))


@SETTINGS
@given(chart_state(max_pitch=1.3), st.integers(0, 2**32 - 1))
def test_state_matches_the_array_functions(state, seed):
    """The hot-loop State gives the array functions' answers, from (q, v) and from (xi, xi_dot)."""
    n, xi, w = state
    rng = np.random.default_rng(seed)
    q, v = co.xi_to_qv(xi, w)
    s = co.State(n)
    s.update(0.5, q, v)
    np.testing.assert_allclose(s.xi, xi, atol=1e-9)
    np.testing.assert_allclose(s.xi_dot, co.v_to_xi_dot(xi, v), atol=1e-9 * (1 + np.abs(w).max()))
    np.testing.assert_allclose(s.R, co.euler_to_rotation(xi[3:6]), atol=1e-14)
    assert s.arm == pytest.approx(list(xi[6:]), abs=0)
    tau, u, xdd = rng.normal(size=6 + n), rng.normal(size=6 + n), rng.normal(size=6 + n)
    np.testing.assert_allclose(s.force_to_xi(tau), co.force_to_xi(xi, tau), atol=1e-12)
    np.testing.assert_allclose(s.force_from_xi(u), co.force_from_xi(xi, u), atol=1e-10 / np.cos(xi[4]))
    np.testing.assert_allclose(s.accel_to_v(xdd), co.xi_ddot_to_a(xi, s.xi_dot, xdd), atol=1e-9 * (1 + np.abs(w).max()) ** 2)
    f3 = rng.normal(size=3)
    np.testing.assert_allclose(s.lin_to_world(f3), s.R @ f3, atol=1e-14)
    np.testing.assert_allclose(s.lin_to_body(f3), s.R.T @ f3, atol=1e-14)
    np.testing.assert_allclose(s.euler_accel_to_omega_dot(*f3), co.euler_rate_matrix(xi[3:6]) @ f3, atol=1e-14)
    s.set_applied(tau)
    np.testing.assert_allclose(s.u_applied, co.force_to_xi(xi, tau), atol=1e-12)
    t = co.State(n)
    t.update_xi(0.5, xi, w)
    np.testing.assert_allclose(t.q, q, atol=1e-15)
    np.testing.assert_allclose(t.v, v, atol=1e-13 * (1 + np.abs(w).max()))
    t.update_xi(0.5, xi, w, reuse=True)
    np.testing.assert_allclose(t.q, q, atol=1e-15)


@SETTINGS
@given(chart_state(max_pitch=1.3), st.integers(0, 2**32 - 1))
def test_state_set_from_xi_and_float_views_match_the_array_maps(state, seed):
    """set_from_xi on plain floats, the controllers' form (arrays=False, reuse=True), gives q, v and the maps of the array
    functions; the float views are the values the arrays hold; update's velocity screen returns False with only t, q, v set."""
    n, xi, w = state
    rng = np.random.default_rng(seed)
    q, v = co.xi_to_qv(xi, w)
    s = co.State(n)
    xi_before = s.xi.copy()
    s.set_from_xi(0.25, tuple(xi.tolist()), w.tolist(), arrays=False, reuse=True)
    assert s.t == 0.25 and np.array_equal(s.xi, xi_before)  # arrays=False: the xi arrays are not written
    np.testing.assert_allclose(s.q, q, atol=1e-15)
    np.testing.assert_allclose(s.v, v, atol=1e-13 * (1 + np.abs(w).max()))
    assert s.xi_floats == tuple(xi.tolist()) and s.xi_dot_floats == tuple(w.tolist())
    np.testing.assert_allclose(np.reshape(s.rotation_floats, (3, 3)), co.euler_to_rotation(xi[3:6]), atol=1e-15)
    tau, u, xdd = rng.normal(size=6 + n), rng.normal(size=6 + n), rng.normal(size=6 + n)
    np.testing.assert_allclose(s.force_to_xi_list(tau), co.force_to_xi(xi, tau), atol=1e-12)
    out = np.zeros(6 + n)
    assert s.force_from_xi(u.tolist(), out) is out
    np.testing.assert_allclose(out, co.force_from_xi(xi, u), atol=1e-10 / np.cos(xi[4]))
    np.testing.assert_allclose(s.accel_to_v_list(xdd.tolist()), co.xi_ddot_to_a(xi, w, xdd), atol=1e-9 * (1 + np.abs(w).max()) ** 2)
    q_buffer = s.q
    s.set_from_xi(0.5, xi.tolist(), w.tolist(), arrays=True, reuse=True)  # reuse: the same buffer, overwritten
    assert s.q is q_buffer and np.array_equal(s.xi, xi) and np.array_equal(s.xi_dot, w)
    # from (q, v): the float views hold exactly what the arrays hold
    m = co.State(n)
    assert m.update(0.5, q, v) is True
    assert m.xi_floats == tuple(m.xi.tolist()) and m.xi_dot_floats == tuple(m.xi_dot.tolist())
    assert np.array_equal(np.reshape(m.rotation_floats, (3, 3)), m.R)
    m.set_applied(tau)
    assert m.u_applied_floats == tuple(m.u_applied.tolist())
    # the velocity screen: |v| below the bound fills the state; not below it (or NaN) sets only t, q, v
    speed = float(np.linalg.norm(v))
    assert co.State(n).update(1.0, q, v, v_bound=speed * (1 + 1e-9) + 1e-300) is True
    for bound, vel in ((speed * (1 - 1e-9), v), (1e300, np.where(np.arange(6 + n) == 0, np.nan, v))):
        b = co.State(n)
        assert b.update(1.0, q, vel, v_bound=bound) is False
        assert b.t == 1.0 and b.q is q and b.v is vel
        assert np.array_equal(b.xi, np.zeros(6 + n)) and b.xi_floats == (0.0,) * (6 + n) and b.rotation_floats == co.State(n).rotation_floats


@pytest.mark.parametrize("n", N_ARMS)
def test_batch_functions_match_the_state(n):
    """The *_batch maps over a logged run (rows) equal the State maps row by row."""
    rng = np.random.default_rng(20 + n)
    m = 50
    xi = np.column_stack(
        [rng.uniform(-3, 3, (m, 3)), rng.uniform(-3, 3, m), rng.uniform(-1.4, 1.4, m), rng.uniform(-3, 3, m), rng.uniform(-1, 1, (m, n))]
    )
    tau, u, p = rng.normal(size=(m, 6 + n)), rng.normal(size=(m, 6 + n)), rng.normal(size=(m, 3))
    R = co.euler_to_rotation_batch(xi[:, 3:6])
    s = co.State(n)
    for k in range(m):
        s.update_xi(0.0, xi[k], np.zeros(6 + n))
        np.testing.assert_allclose(R[k], s.R, atol=1e-15)
        np.testing.assert_allclose(co.force_to_xi_batch(R, xi, tau)[k], s.force_to_xi(tau[k]), atol=1e-13)
        np.testing.assert_allclose(co.force_from_xi_batch(R, xi, u)[k], s.force_from_xi(u[k]), atol=1e-12 / np.cos(xi[k, 4]))
        np.testing.assert_allclose(co.to_body_batch(R, p, xi[:, 0:3])[k], s.lin_to_body(p[k] - xi[k, 0:3]), atol=1e-14)


def test_state_rejects_bad_sizes():
    with pytest.raises(InputError, match="n_arm"):
        co.State(-1)
    with pytest.raises(ShapeError, match="u_applied"):
        co.State(2).u_applied = np.zeros(9)


def test_state_and_hold_need_the_platform_size():
    """No Q-PRR-sized defaults: State and Hold take the arm size / the reference from the platform."""
    import qprr
    from qprr.trajectory import Hold

    p = qprr.build("HEX-RRR")
    state = co.State(p.n_arm)
    assert state.xi.shape == (p.n_xi,)
    assert np.array_equal(Hold(p.neutral_xi()).sample(0.5).xi[0], p.neutral_xi())
    with pytest.raises(TypeError):
        co.State()
    with pytest.raises(TypeError):
        Hold()
    with pytest.raises(InputError, match="platform.n_arm"):
        co.State(-1)
