"""Learning-environment speed: the batched core and the Gymnasium vector environment against one bare Pinocchio step.

    python benchmarks/env_benchmark.py [--platform q-prr] [--integrator euler] [--quick]

For N = 1, 16, 64, 256 copies, measured side by side in this run:

* ``bare``: one Pinocchio ABA + integrate step of the same model in a Python loop (``pin.aba``, the integrator's
  velocity update, ``pin.integrate``: the cheapest a scalar simulator written in Python can be), seconds per step;
* the batched core (:class:`qprr.sim.batch.BatchSimulator`): one call steps the N copies by ``dt``; its cost per copy
  divided by ``bare`` is the ratio printed (issue 32: at most 1.5 at N = 64);
* with gymnasium installed (the ``rl`` extra), the vector environment of ``qprr/Hover-v0`` made by
  ``gymnasium.make_vec(..., num_envs=N)``: environment steps per second (each is one control period, several
  integration steps, with the observation, reward and autoreset), under random actions (an untrained policy: the arm
  thrown against its stops, crashes, resets) and under a constant action (as RotorPy's rate is measured);
* with rotorpy installed (the ``peers`` extra does not pin it: ``pip install rotorpy``), its batched quadrotor
  environment at the same N, for scale (a quadrotor without an arm).

Every line is printed when it completes; absolute numbers hold on this machine only (printed first).  ``--quick``: a
smoke run of a few seconds (fewer steps, one round).
"""

from __future__ import annotations

import argparse
import sys
import time
from importlib.util import find_spec
from pathlib import Path

import numpy as np
import pinocchio as pin

from qprr.platforms import resolve
from qprr.sim import SimConfig
from qprr.sim.batch import BatchSimulator

sys.path.insert(0, str(Path(__file__).resolve().parent))  # benchmarks/machine.py, wherever this runs from
from machine import machine_lines

SIZES = (1, 16, 64, 256)


def bare_step(platform, integrator: str, steps: int, rounds: int) -> float:
    """Seconds per bare ABA + integrate step (the best of ``rounds``): gravity held, semi-implicit Euler (one ABA) or
    explicit midpoint (two ABA), as the batched core's integrator."""
    model, data = platform.model, platform.model.createData()
    q0 = platform.neutral_q()
    tau = pin.computeGeneralizedGravity(model, data, q0).copy()
    dt, h = 1e-3, 0.5e-3
    best = float("inf")
    for _ in range(rounds):
        q, v = q0.copy(), np.zeros(model.nv)
        start = time.perf_counter()
        for _ in range(steps):
            if integrator == "euler":
                v = v + dt * pin.aba(model, data, q, v, tau)
                q = pin.integrate(model, q, dt * v)
            else:
                v_half = v + h * pin.aba(model, data, q, v, tau)
                a_half = pin.aba(model, data, pin.integrate(model, q, h * v), v_half, tau)
                q, v = pin.integrate(model, q, dt * v_half), v + dt * a_half
        best = min(best, (time.perf_counter() - start) / steps)
    return best


def core_step(platform, integrator: str, n: int, steps: int, rounds: int) -> float:
    """Seconds per copy per step of the batched core (the best of ``rounds``), gravity held on every copy."""
    sim = BatchSimulator(platform, n, SimConfig(integrator=integrator))
    q0 = platform.neutral_q()
    tau = np.tile(pin.computeGeneralizedGravity(platform.model, platform.model.createData(), q0), (n, 1))
    best = float("inf")
    for _ in range(rounds):
        sim.reset(q0, np.zeros(platform.nv))
        start = time.perf_counter()
        for _ in range(steps):
            sim.step(tau)
        best = min(best, (time.perf_counter() - start) / steps / n)
    return best


def env_rate(platform_name: str, n: int, steps: int, random: bool) -> float:
    """Environment steps per second of ``gymnasium.make_vec("qprr/Hover-v0", num_envs=n)`` under random actions (an
    untrained policy: arms thrown against their stops, crashes and resets) or under the constant action 0 (every rotor
    at mid-range thrust, as RotorPy's rate below is measured)."""
    import gymnasium

    import qprr.envs  # noqa: F401  (registers the environments)

    envs = gymnasium.make_vec("qprr/Hover-v0", num_envs=n, platform=platform_name)
    envs.reset(seed=0)
    actions = [envs.action_space.sample() if random else np.zeros(envs.action_space.shape, dtype=envs.action_space.dtype) for _ in range(8)]
    start = time.perf_counter()
    for k in range(steps):
        envs.step(actions[k % 8])
    rate = steps * n / (time.perf_counter() - start)
    envs.close()
    return rate


def rotorpy_rate(n: int, steps: int) -> float:
    """Environment steps per second of RotorPy's batched ``QuadrotorEnv`` (a Crazyflie, thrust commands, its RK4 at
    100 Hz on torch tensors) under constant actions."""
    import torch
    from rotorpy.learning.quadrotor_environments import QuadrotorEnv
    from rotorpy.vehicles.crazyflie_params import quad_params

    def zeros(*shape):
        return torch.zeros(*shape, dtype=torch.float64)

    hover_speed = float(np.sqrt(quad_params["mass"] * 9.81 / (4 * quad_params["k_eta"])))
    initial = {"x": zeros(n, 3), "v": zeros(n, 3), "w": zeros(n, 3), "wind": zeros(n, 3)}
    initial["q"] = torch.tensor([0.0, 0.0, 0.0, 1.0], dtype=torch.float64).repeat(n, 1)
    initial["rotor_speeds"] = torch.full((n, 4), hover_speed, dtype=torch.float64)
    env = QuadrotorEnv(n, initial_states=initial, control_mode="cmd_motor_thrusts", quad_params=dict(quad_params))
    env.reset()
    action = np.zeros((n, 4))
    start = time.perf_counter()
    for _ in range(steps):
        env.step(action)
    return steps * n / (time.perf_counter() - start)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--platform", default="q-prr", help="a platform name (default q-prr)")
    parser.add_argument("--integrator", default="euler", choices=("euler", "midpoint"), help="the core's integrator")
    parser.add_argument("--quick", action="store_true", help="a smoke run of a few seconds")
    args = parser.parse_args(argv)
    rounds, work = (1, 2000) if args.quick else (3, 20000)
    for line in machine_lines(("gymnasium",)):
        print(line)
    platform = resolve(args.platform)
    bare = bare_step(platform, args.integrator, work // 4, rounds)
    print(f"bare ABA + integrate step ({args.integrator}, {platform.name}, nv = {platform.nv}): {bare * 1e6:.2f} us")
    sizes = ", ".join(map(str, SIZES))
    print(f"ratio (the 'x bare ABA' of each line, N = {sizes}) = the batched core's cost per copy and step / one bare step")
    has_envs = find_spec("gymnasium") is not None
    for n in SIZES:
        core = core_step(platform, args.integrator, n, max(10, work // n), rounds)
        line = f"N = {n}: {1.0 / core:,.0f} core-steps/s, {core / bare:.2f} x bare ABA"
        if has_envs:
            steps = max(5, work // (10 * n))
            line += f"; {env_rate(args.platform, n, steps, True):,.0f} env-steps/s random actions"
            line += f", {env_rate(args.platform, n, steps, False):,.0f} constant (qprr/Hover-v0, one control period each)"
        print(line, flush=True)
    if not has_envs:
        print('gymnasium not installed: pip install "qprr[rl]" (the environments\' steps per second)')
    if find_spec("rotorpy") is None or find_spec("torch") is None:
        print('rotorpy not installed: pip install "rotorpy[batched]" (its batched environment, for scale)')
        return 0
    for n in SIZES:
        print(f"rotorpy N = {n}: {rotorpy_rate(n, max(5, work // (10 * n))):,.0f} env-steps/s (QuadrotorEnv, one RK4 step of 10 ms each)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
