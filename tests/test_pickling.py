"""What a campaign sends to worker processes must pickle and behave identically after the round trip.

Platforms, controllers (with their QPs and States) and
allocators are pickled, unpickled and run: the closed loop must be bit-identical to the one
run with the originals.
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from qprr.actuation import Allocator
from qprr.charts import State, xi_dot_to_v, xi_to_q
from qprr.control import PayloadIDC
from qprr.sim import simulate
from qprr.thesis import gains, load_qprr
from qprr.thesis.bsg import CogStabilizer
from qprr.thesis.missions import static_mission
from qprr.thesis.scenarios import flight_controller


@pytest.fixture(scope="module")
def platform():
    return load_qprr()


def _round_trip(obj):
    return pickle.loads(pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))


def test_state_round_trip_keeps_values_and_maps(platform):
    rng = np.random.default_rng(3)
    xi = np.r_[rng.normal(size=3), 0.3, -0.2, 1.1, 0.02, 0.4, -0.3]
    xi_dot = rng.normal(size=9)
    s = State(3)
    s.update(0.5, xi_to_q(xi), xi_dot_to_v(xi, xi_dot))
    c = _round_trip(s)
    assert c.t == s.t and c.n_arm == 3
    np.testing.assert_array_equal(c.xi, s.xi)
    np.testing.assert_array_equal(c.R, s.R)
    tau = rng.normal(size=9)
    assert c.force_to_xi_list(tau) == s.force_to_xi_list(tau)  # the maps act on the copied state
    c.update(0.6, s.q, s.v)  # and the copy updates itself, not the original
    assert c.t == 0.6 and s.t == 0.5


@pytest.mark.parametrize("name", ["idc", "dsid", "mfc", "bsg", "payload-idc"])
def test_pickled_controller_and_allocator_fly_bit_identically(platform, name):
    def make():
        if name == "bsg":
            return CogStabilizer(platform, flight_controller("mfc", platform), theta_e_d=0.0)
        if name == "payload-idc":
            return PayloadIDC(platform, gains.payload_idc(), payload="estimate")
        return flight_controller(name, platform)

    mission = static_mission()
    ref = simulate(platform, make(), mission, 0.4, allocator=Allocator(platform))
    p2 = _round_trip(platform)
    res = simulate(p2, _round_trip(make()), mission, 0.4, allocator=_round_trip(Allocator(platform)))
    for key in ("xi", "xi_dot", "u", "f", "x_cm"):
        np.testing.assert_array_equal(getattr(res, key), getattr(ref, key), err_msg=key)
    assert res.status == ref.status
