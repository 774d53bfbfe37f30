"""The learning environments (qprr.envs): Gymnasium's checker, one batched implementation behind make and make_vec
(bit for bit), autoreset, seeding, bad input, the plant models, and classical controllers that really fly the tasks."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import qprr
from qprr.errors import InputError, MissingDependencyError, NonFiniteError, NotResetError, ShapeError, UnknownNameError

ROOT = Path(__file__).resolve().parents[1]
INSTALL = 'gymnasium is not installed: pip install "qprr[rl]"'
ALL_RANDOM = {
    "model.mass": (0.9, 1.1),
    "model.payload": (0.0, 0.05),
    "mean_wind": (0.0, 2.0),
    "gust": (0.0, 3.0),
    "drag": 0.3,
    "tau": (0.0, 0.03),
    "sensor_noise": 0.005,
}


@pytest.fixture(scope="module")
def envs():
    pytest.importorskip("gymnasium", reason=INSTALL)
    import qprr.envs

    return qprr.envs


@pytest.fixture(scope="module")
def platforms():
    return {name: qprr.load(name) for name in ("q-prr", "borinot_flying_arm_2")}


def test_importing_without_gymnasium_names_the_extra():
    code = "import sys; sys.modules['gymnasium'] = None\ntry:\n    import qprr.envs\nexcept ImportError as e:\n    print(type(e).__name__, e)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120, check=True)
    assert out.stdout.startswith("MissingDependencyError") and 'pip install "qprr[rl]"' in out.stdout, out.stdout + out.stderr
    assert issubclass(MissingDependencyError, ImportError)


@pytest.mark.parametrize("platform", ["q-prr", "borinot_flying_arm_2"])
@pytest.mark.parametrize("env_id", ["qprr/Hover-v0", "qprr/Reach-v0", "qprr/Carry-v0", "qprr/Track-v0"])
def test_gymnasium_checker_passes(envs, platforms, env_id, platform):
    import gymnasium
    from gymnasium.utils.env_checker import check_env

    for mode in ("thrusts", "wrench", "reference") if env_id == "qprr/Reach-v0" else ("thrusts",):
        env = gymnasium.make(env_id, platform=platforms[platform], action_mode=mode, duration=1.0)
        assert isinstance(env.unwrapped, envs.AerialEnv)
        check_env(env.unwrapped, skip_render_check=True)
        assert env.observation_space.shape == (len(env.unwrapped.observation_names),)


def test_own_platform_from_its_files(envs):
    """A user's URDF and rotor file (examples/my_platform), as qprr.platforms.resolve takes them."""
    import gymnasium
    from gymnasium.utils.env_checker import check_env

    folder = ROOT / "examples" / "my_platform"
    env = gymnasium.make("qprr/Hover-v0", urdf=folder / "quad_rrr.urdf", rotors=folder / "quad_rrr.rotors.toml", duration=1.0)
    check_env(env.unwrapped, skip_render_check=True)
    assert env.unwrapped.core.platform.name == "quad_rrr" and env.action_space.shape == (4 + 3,)


def test_make_vec_is_one_batched_simulator(envs, platforms):
    import gymnasium
    from gymnasium.vector import AutoresetMode

    venv = gymnasium.make_vec("qprr/Reach-v0", num_envs=4, platform=platforms["borinot_flying_arm_2"])
    assert type(venv) is envs.AerialVectorEnv and venv.num_envs == 4
    assert venv.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    assert venv.core.sim.n == 4 and venv.core.sim.q.shape == (4, platforms["borinot_flying_arm_2"].nq)
    p = platforms["borinot_flying_arm_2"]
    assert venv.single_action_space.shape == (p.n_rotors + p.n_arm,)  # thrusts: one per rotor, one per arm joint
    assert venv.observation_space.shape == (4, venv.single_observation_space.shape[0])
    obs, _ = venv.reset(seed=3)
    assert obs.dtype == np.float32 and obs in venv.observation_space


def _lockstep(envs, platform, mode: str, steps: int) -> tuple[float, int]:
    """A vector environment of 2 and 2 scalar ones on the same seeds and actions: the largest difference of their
    states, rewards and observations, and the number of episode ends (each followed by the autoreset)."""
    options = dict(platform=platform, action_mode=mode, duration=0.12, randomize=ALL_RANDOM)
    venv = envs.AerialVectorEnv(2, "carry", **options)
    singles = [envs.AerialEnv("carry", **options) for _ in range(2)]
    first, _ = venv.reset(seed=11)
    worst = max(float(np.abs(first[i] - e.reset(seed=11 + i)[0]).max()) for i, e in enumerate(singles))
    rng, pending, ends = np.random.default_rng(0), [False] * 2, 0
    for _ in range(steps):
        actions = (0.1 * rng.standard_normal((2, venv.single_action_space.shape[0]))).astype(np.float32)
        obs, reward, terminated, truncated, info = venv.step(actions)
        for i, env in enumerate(singles):
            if pending[i]:  # the vector environment reset it at this step: reward 0, flags False, its first observation
                o, _ = env.reset()
                r, te, tr, pending[i] = 0.0, False, False, False
            else:
                o, r, te, tr, single_info = env.step(actions[i])
                assert single_info["end"] == info["end"][i]
                pending[i], ends = te or tr, ends + (te or tr)
            assert (te, tr) == (terminated[i], truncated[i])
            state = np.abs(env.core.sim.q[0] - venv.core.sim.q[i]).max() + np.abs(env.core.sim.v[0] - venv.core.sim.v[i]).max()
            worst = max(worst, float(state), abs(r - reward[i]), float(np.abs(o - obs[i]).max()))
    return worst, ends


@pytest.mark.parametrize("mode", ["thrusts", "wrench", "reference"])
def test_vector_step_is_the_scalar_step(envs, platforms, mode):
    """Every randomisation on, episodes of 6 steps (truncations and autoresets): the same numbers, bit for bit."""
    worst, ends = _lockstep(envs, platforms["q-prr"], mode, 15)
    assert worst <= 1e-12 and ends >= 3


def test_reference_mode_flies_what_simulate_flies(envs, platforms):
    """A zero residual: the IDC on the episode's plan, its controller every 5 ms, is qprr.sim.simulate's run of the same
    controller (the derived PD gains at 5 ms: qprr.envs.actions.controller_arguments) on the same plan from the same
    state (states equal at every action, to rounding)."""
    from qprr import charts
    from qprr.control import make_controller
    from qprr.control.gains import Targets, platform_gains
    from qprr.sim import simulate

    p = platforms["borinot_flying_arm_2"]
    env = envs.AerialVectorEnv(1, "reach", platform=p, action_mode="reference", duration=1.0)
    env.reset(seed=4)
    controller = make_controller("idc", p, **platform_gains("idc", p, Targets(control_period=0.005, integral=False, payload=0.0)))
    run = simulate(p, controller, env.core.trajectories[0], 1.0, control_period=0.005, xi0=charts.q_to_xi(env.core.sim.q[0]))
    zero = np.zeros((1, env.single_action_space.shape[0]))
    worst = 0.0
    for k in range(50):
        worst = max(worst, float(np.abs(charts.q_to_xi(env.core.sim.q[0]) - run.xi[4 * k]).max()))
        env.step(zero)
    assert worst < 1e-12 and np.abs(run.xi[-1, 6:] - run.xi[0, 6:]).max() > 0.05  # the arm moved


def test_autoreset_is_next_step(envs, platforms):
    venv = envs.AerialVectorEnv(2, "hover", platform=platforms["q-prr"], action_mode="reference", duration=0.06)
    venv.reset(seed=0)
    zero = np.zeros((2, venv.single_action_space.shape[0]))
    for k in range(3):
        _, reward, terminated, truncated, info = venv.step(zero)
        assert not terminated.any() and truncated.all() == (k == 2) and reward.min() > 0.9
    assert list(info["end"]) == ["time limit"] * 2
    obs, reward, terminated, truncated, info = venv.step(zero)  # the reset step: actions ignored
    assert reward.tolist() == [0.0, 0.0] and not terminated.any() and not truncated.any() and info["t"].tolist() == [0.0, 0.0]
    fresh = envs.AerialVectorEnv(2, "hover", platform=platforms["q-prr"], action_mode="reference", duration=0.06)
    fresh.reset(seed=0)
    for _ in range(3):
        fresh.step(zero)
    assert np.array_equal(obs, fresh.step(zero)[0])
    assert not np.array_equal(obs, fresh.reset(seed=0)[0])  # the generators moved on: a new episode


def test_seeding_reproduces_episodes(envs, platforms):
    def episode(env, seed):
        out = [env.reset(seed=seed)[0]]
        rng = np.random.default_rng(1)
        for _ in range(5):
            out.append(env.step(rng.uniform(-0.2, 0.2, env.action_space.shape).astype(np.float32))[0])
        return np.array(out)

    env = envs.AerialEnv("reach", platform=platforms["q-prr"], randomize=ALL_RANDOM)
    a, b, c = episode(env, 7), episode(env, 7), episode(env, 8)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    other = envs.AerialEnv("reach", platform=platforms["q-prr"], randomize=ALL_RANDOM)
    assert np.array_equal(episode(other, 7), a)


def test_bad_input_is_named(envs, platforms):
    p = platforms["q-prr"]
    cases = [
        (UnknownNameError, dict(action_mode="torques"), ["action_mode", "'torques'", "'thrusts'", "'wrench'", "'reference'"]),
        (UnknownNameError, dict(platform="borinot"), ["platform", "'borinot'", "'borinot_flying_arm_2'"]),
        (InputError, dict(randomize={"model.payload": (-0.1, 0.2)}), ["model.payload", "-0.1", ">= 0 kg"]),
        (UnknownNameError, dict(randomize={"mass": 1.1}), ["randomize", "'mass'", "'model.mass'"]),
        (InputError, dict(randomize={"mean_wind": 2.0}), ["drag", "0.3"]),
        (InputError, dict(controller_period=0.005), ["controller_period", "reference"]),
        (InputError, dict(action_mode="reference", controller_period=0.003), ["controller_period", "divide"]),
        (UnknownNameError, dict(controller="pid"), ["controller", "'pid'", "'idc'"]),
        (UnknownNameError, dict(colour="red"), ["environment option", "'colour'", "'platform'"]),
    ]
    for error, options, words in cases:
        with pytest.raises(error) as info:
            envs.AerialEnv("hover", platform=options.pop("platform", p), **options)
        assert all(w in str(info.value) for w in words), (options, str(info.value))
    with pytest.raises(UnknownNameError, match="qprr/Reach-v0"):
        envs.AerialVectorEnv(2, "reach-v0", platform=p)
    env = envs.AerialEnv("hover", platform=p)
    with pytest.raises(NotResetError, match="reset"):
        env.step(np.zeros(env.action_space.shape))
    env.reset(seed=0)
    with pytest.raises(ShapeError, match=r"\(7,\)"):
        env.step(np.zeros(3))


def _refusal(error, call, *words) -> str:
    """The message of the ``error`` that ``call()`` raises; it must contain every one of ``words``."""
    with pytest.raises(error) as info:
        call()
    message = str(info.value)
    assert all(w in message for w in words), (words, message)
    return message


def test_non_finite_actions_are_refused_and_never_reach_the_plant(envs, platforms):
    env = envs.AerialEnv("hover", platform=platforms["q-prr"])
    env.reset(seed=0)
    q, thrust = env.core.sim.q.copy(), env.core.thrust.copy()
    action = np.zeros(env.action_space.shape, dtype=np.float32)
    action[2] = np.nan
    _refusal(NonFiniteError, lambda: env.step(action), "action[2] = nan", "policy")
    action[2] = -np.inf
    _refusal(NonFiniteError, lambda: env.step(action), "action[2] = -inf")
    assert np.array_equal(env.core.sim.q, q) and np.array_equal(env.core.thrust, thrust)  # nothing flown
    assert np.isfinite(env.step(np.zeros(env.action_space.shape))[0]).all()  # the episode goes on
    venv = envs.AerialVectorEnv(3, "hover", platform=platforms["q-prr"])
    venv.reset(seed=0)
    actions = np.zeros((3, venv.single_action_space.shape[0]))
    actions[1, 4] = np.inf
    _refusal(NonFiniteError, lambda: venv.step(actions), "actions[1, 4] = inf")


def test_actions_of_the_wrong_shape_or_kind_are_refused(envs, platforms):
    env = envs.AerialEnv("hover", platform=platforms["q-prr"])
    env.reset(seed=0)
    _refusal(ShapeError, lambda: env.step(np.zeros(8)), "action", "(7,)", "(8,)")
    _refusal(ShapeError, lambda: env.step(np.zeros((1, 7))), "action", "(1, 7)")
    _refusal(InputError, lambda: env.step(np.zeros(7) + 0.5j), "action", "complex")
    _refusal(InputError, lambda: env.step(["up"] * 7), "action", "strings")
    _refusal(InputError, lambda: env.step(None), "action", "None")
    venv = envs.AerialVectorEnv(2, "hover", platform=platforms["q-prr"])
    venv.reset(seed=0)
    _refusal(ShapeError, lambda: venv.step(np.zeros(7)), "actions", "(2, 7)", "one row per environment", "(7,)")
    big = np.full(env.action_space.shape, 5.0)  # beyond the Box: clipped to +1, as Gymnasium's bounds say
    assert np.isfinite(env.step(big)[0]).all()


def test_unknown_names_are_refused_naming_the_argument_and_the_value(envs, platforms):
    _refusal(UnknownNameError, lambda: envs.EnvSettings(platform="quadrotor"), "platform", "'quadrotor'", "'q-prr'", "'borinot_flying_arm_2'")
    _refusal(InputError, lambda: envs.EnvSettings(platform=3), "platform", "3", "a name")
    _refusal(UnknownNameError, lambda: envs.AerialEnv("hoover"), "task", "'hoover'", "'hover'", "'qprr/Hover-v0'")
    _refusal(UnknownNameError, lambda: envs.AerialVectorEnv(2, "qprr/Hover-v1"), "task", "'qprr/Hover-v1'", "'qprr/Hover-v0'")
    _refusal(UnknownNameError, lambda: envs.EnvSettings(action_mode="torques"), "action_mode", "'torques'", "'thrusts'")
    _refusal(UnknownNameError, lambda: envs.EnvSettings(action_mode=2), "action_mode", "2", "'wrench'")
    _refusal(UnknownNameError, lambda: envs.EnvSettings(integrator="rk45"), "integrator", "'rk45'", "'rk4'")
    _refusal(InputError, lambda: envs.EnvSettings(rotors="my.rotors.toml"), "rotors", "'my.rotors.toml'", "urdf")
    _refusal(InputError, lambda: envs.EnvSettings(urdf="missing.urdf", rotors="missing.toml"), "urdf", "missing.urdf", "does not exist")
    _refusal(InputError, lambda: envs.EnvSettings(platform="q-prr", urdf="a.urdf", rotors="a.toml"), "platform", "urdf", "not both")


def test_bad_randomisation_is_refused_naming_the_name_and_the_value(envs):
    from qprr.envs.randomize import Randomization

    _refusal(InputError, lambda: envs.EnvSettings(randomize={"model.mass": (1.2, 0.8)}), "model.mass", "(1.2, 0.8)", "low <= high", "(0.8, 1.2)")
    _refusal(InputError, lambda: envs.EnvSettings(randomize={"model.mass": -0.5}), "model.mass", "-0.5", "mass factor > 0")
    _refusal(InputError, lambda: envs.EnvSettings(randomize={"model.mass": 0.0}), "model.mass", "0.0", "mass factor > 0")
    normal = {"dist": "normal", "mean": 1.0, "std": 0.1}
    _refusal(InputError, lambda: envs.EnvSettings(randomize={"model.mass": normal}), "model.mass", "-inf", "low = 0.0")
    _refusal(InputError, lambda: envs.EnvSettings(randomize={"tau": (0.0, math.nan)}), "tau", "nan", "finite")
    _refusal(InputError, lambda: envs.EnvSettings(randomize={"gust": (0.0, 1.0, 2.0)}), "gust", "(low, high)")
    _refusal(InputError, lambda: envs.EnvSettings(randomize=[("tau", 0.02)]), "randomize", "mapping", "list")
    _refusal(UnknownNameError, lambda: Randomization((("wind", 2.0),)), "randomize", "'wind'", "'mean_wind'")
    _refusal(InputError, lambda: Randomization((("tau", -0.01),)), "tau", "-0.01", ">= 0 s")
    _refusal(UnknownNameError, lambda: Randomization().has("mass"), "key", "'mass'", "'model.mass'")
    _refusal(InputError, lambda: Randomization().draw(np.random.default_rng(0), math.nan), "duration", "nan")
    _refusal(InputError, lambda: Randomization().draw(0, 5.0), "rng", "default_rng")


def test_bad_numbers_and_reset_arguments_are_refused(envs, platforms):
    from qprr.envs.tasks import RewardWeights

    _refusal(InputError, lambda: envs.EnvSettings(control_period=None), "control_period", "None")
    _refusal(InputError, lambda: envs.EnvSettings(box=math.inf), "box", "inf")
    _refusal(InputError, lambda: envs.EnvSettings(duration=0.005), "duration = 0.005", "control_period = 0.02")
    _refusal(InputError, lambda: envs.EnvSettings(geometry={"home": (0, 0, 2)}), "geometry", "dict", "Geometry(")
    _refusal(InputError, lambda: RewardWeights(base=-1.0), "weights.base", "-1.0", ">= 0")
    _refusal(InputError, lambda: envs.AerialEnv("hover", platform=platforms["q-prr"], settings="fast"), "settings", "'fast'")
    env = envs.AerialEnv("hover", platform=platforms["q-prr"])
    _refusal(InputError, lambda: env.reset(seed=-1), "seed", "-1")
    _refusal(InputError, lambda: env.reset(seed=1.5), "seed", "1.5")
    _refusal(UnknownNameError, lambda: env.reset(options={"reset_mask": [True]}), "reset option", "'reset_mask'")
    venv = envs.AerialVectorEnv(2, "hover", platform=platforms["q-prr"])
    _refusal(InputError, lambda: venv.reset(seed=[0]), "seed", "[0]", "2 ints")
    _refusal(InputError, lambda: venv.reset(seed=[0, -3]), "seed[1]", "-3")
    _refusal(InputError, lambda: venv.reset(options="all"), "options", "'all'", "reset_mask")
    _refusal(InputError, lambda: venv.reset(options={"reset_mask": [1, 0]}), "reset_mask", "boolean", "(2,)")


def test_baseline_arguments_are_checked_before_flying(envs):
    _refusal(UnknownNameError, lambda: envs.baseline_return("qprr/Hoover-v0"), "env_id", "'qprr/Hoover-v0'", "'qprr/Hover-v0'")
    _refusal(UnknownNameError, lambda: envs.baseline_return("hover", controller="pid"), "controller", "'pid'", "'idc'")
    _refusal(InputError, lambda: envs.baseline_return("hover", seeds=4), "seeds", "4", "range(8)")
    _refusal(InputError, lambda: envs.baseline_return("hover", seeds=(0, -1)), "seeds[1]", "-1")
    _refusal(InputError, lambda: envs.baseline_return("hover", seeds=()), "seeds", "empty")
    _refusal(UnknownNameError, lambda: envs.baseline_return("hover", platform="quadrotor"), "platform", "'quadrotor'")
    _refusal(InputError, lambda: envs.baseline_return("hover", action_mode="thrusts"), "action_mode")


def test_motor_lag_is_the_exact_first_order_response(envs, platforms):
    p = platforms["q-prr"]
    env = envs.AerialEnv("hover", platform=p, randomize={"tau": 0.05})
    env.reset(seed=0)
    f0 = env.unwrapped.core.thrust[0].copy()
    action = np.zeros(env.action_space.shape, dtype=np.float32)
    action[0:4] = 0.5
    f_c = p.thrust_min + 0.75 * (p.thrust_max - p.thrust_min)
    for k in (1, 2):
        env.step(action)
        expected = f_c + (f0 - f_c) * math.exp(-k * 0.02 / 0.05)
        assert np.allclose(env.core.thrust[0], expected, rtol=0.0, atol=1e-12)


def test_drag_is_the_simulators_aerodynamic_drag(envs, platforms):
    from qprr.envs.randomize import drag_force
    from qprr.sim.wind import AerodynamicDrag, Wind

    p = platforms["borinot_flying_arm_2"]
    rng = np.random.default_rng(4)
    q = np.array([qprr.charts.xi_to_q(np.r_[rng.normal(size=3), rng.uniform(-0.5, 0.5, 3), np.zeros(p.n_arm)]) for _ in range(5)])
    v, wind = rng.normal(size=(5, p.nv)), rng.normal(size=(5, 3))
    batch = drag_force(q, v, wind, np.full(5, 0.3))
    for i in range(5):
        scalar = AerodynamicDrag(linear=0.3, wind=Wind(mean=tuple(wind[i]))).generalized_force(0.0, q[i], v[i])
        assert np.allclose(batch[i], scalar, rtol=0.0, atol=1e-13)


def test_inverse_dynamics_baseline_reaches_and_hovers(envs, platforms):
    """IDC on the plan (zero residual): the end effector within 5 cm of the target over the last second of Reach on the
    Q-PRR (4 s: the plan arrives at 2.5 s), the base within 10 cm of home over the last second of Hover on borinot
    (docs/rl.md, success criteria)."""
    reach = envs.baseline_return("qprr/Reach-v0", "idc", seeds=(0, 1), platform=platforms["q-prr"], duration=4.0)
    assert reach.status is envs.BaselineStatus.DONE and reach.success_rate == 1.0, reach
    assert 120.0 < reach.mean_return < 200.0, reach  # at most 200 steps of reward <= 1
    hover = envs.baseline_return("qprr/Hover-v0", "idc", seeds=(0,), platform=platforms["borinot_flying_arm_2"], duration=2.0)
    assert hover.success_rate == 1.0 and hover.mean_return > 0.95 * 100, hover


def test_carry_attaches_the_payload(envs, platforms):
    env = envs.AerialVectorEnv(1, "carry", platform=platforms["q-prr"], action_mode="reference", duration=4.0)
    env.reset(seed=2)
    zero = np.zeros((1, env.single_action_space.shape[0]))
    assert env.core.sim.payload_mass[0] == 0.0
    attached_at = None
    for _ in range(175):
        _, _, terminated, _, info = env.step(zero)
        assert not terminated[0]
        if info["attached"][0]:
            attached_at = info["t"][0]
            break
    assert attached_at is not None and 1.0 < attached_at <= 3.5, attached_at  # on the way to the pick pose (3 s)
    assert env.core.sim.payload_mass[0] == envs.tasks.CARRY_MASS_FRACTION * platforms["q-prr"].total_mass
    assert env.step(zero)[4]["ee_error"][0] > 0.2  # attached: the target is now the goal


def test_mpc_baseline_is_skipped_with_its_install_command(envs, monkeypatch):
    import qprr.envs.baseline as baseline

    monkeypatch.setattr(baseline, "CONTROLLERS", tuple(name for name in baseline.CONTROLLERS if name != "mpc"))  # as without crocoddyl
    result = envs.baseline_return("qprr/Hover-v0", "mpc", seeds=(0,))
    assert result.status is envs.BaselineStatus.SKIPPED and 'pip install "qprr[mpc]"' in result.reason
    assert math.isnan(result.mean_return) and "skipped" in str(result)
