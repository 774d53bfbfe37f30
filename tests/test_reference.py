"""qprr's coordinate layer on a third-party multirotor from example-robot-data."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from qprr import charts as co
from qprr.errors import UnknownNameError
from qprr.platforms import multirotor_model as load_reference


@pytest.mark.parametrize("name", ["hector", "iris"])
def test_xi_kinetic_energy_on_a_reference_quadrotor(name):
    """For any free-flyer, 1/2 v^T M v = 1/2 xi_dot^T (S^T M S) xi_dot with v = S xi_dot."""
    model = load_reference(name)
    assert model.nq == 7 and model.nv == 6
    data = model.createData()
    rng = np.random.default_rng(0)
    xi6, rates6 = rng.uniform(-1, 1, 6), rng.uniform(-1, 1, 6)
    xi, rates = np.concatenate([xi6, np.zeros(3)]), np.concatenate([rates6, np.zeros(3)])
    q, v = co.xi_to_q(xi)[:7], co.rate_map(xi)[:6, :6] @ rates6
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    S = co.rate_map(xi)[:6, :6]
    assert pin.computeKineticEnergy(model, data, q, v) == pytest.approx(0.5 * rates6 @ S.T @ M @ S @ rates6, rel=1e-12)
    # the hover force is the weight of the whole robot
    g = pin.computeGeneralizedGravity(model, data, pin.neutral(model))
    assert g[2] == pytest.approx(pin.computeTotalMass(model) * np.linalg.norm(model.gravity.linear), rel=1e-12)
    assert np.allclose(rates, co.v_to_xi_dot(xi, np.concatenate([v, np.zeros(3)])))


def test_unknown_reference_name():
    with pytest.raises(UnknownNameError, match="'hector', 'iris'"):
        load_reference("crazyflie")
