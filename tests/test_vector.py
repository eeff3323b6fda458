"""The natively batched envs (envs/vector.py), the SB3 adapter, and the one-call step they use."""

import multiprocessing
import threading

import gymnasium as gym
import numpy as np
import pytest
from rigid_gym.envs import ENV_IDS
from rigid_gym.envs.scripted import scripted_policy

import rigid_gym as rg
from rigid_gym.report.scenes import cube_stack, pile

TASK_IDS = [i for i in ENV_IDS if "Dense" not in i]


@pytest.mark.parametrize("scene, rests", [(cube_stack(5), True), (pile(30), False)],
                         ids=["stack", "pile"])
def test_timed_steps_in_chunks_equal_one_untimed_call(scene, rests):
    """World.step(n) runs n whole steps in one call of the core, which counts its stages and,
    with profile=True, times them as it goes. Timing and splitting the steps into calls with
    the profile read between them change nothing: the same bits, batched or not (a pile
    exercises pair-buffer growth, relisting, shock levels and side contacts). The broad phase
    runs in every step, except in the steps of a world at rest (the settled stack)."""
    for num_worlds in (None, 3):
        fused = rg.World(scene, dt=1 / 240, num_worlds=num_worlds)
        timed = rg.World(scene, dt=1 / 240, num_worlds=num_worlds, profile=True)
        fused.step(150)
        seconds = 0.0
        for _ in range(3):
            timed.step(50)
            total = sum(p["seconds"] for p in timed.profile().values())
            assert total > seconds
            seconds = total
        for name in ("position", "orientation", "velocity", "angular_velocity"):
            np.testing.assert_array_equal(getattr(fused, name), getattr(timed, name))
        broad = fused.profile()["broad_phase"]["calls"]
        assert broad < 150 * (num_worlds or 1) if rests else broad == 150 * (num_worlds or 1)
        assert {n: p["calls"] for n, p in fused.profile().items()} == {
            n: p["calls"] for n, p in timed.profile().items()}


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_each_copy_equals_a_single_env_with_its_seed(env_id):
    """Copy i of make_vec(seed=s) plays exactly what gym.make reset with s + i plays, through
    grips, throws and two same-step autoresets (120 steps of the scripted policy)."""
    num_envs = 3
    envs = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point")
    singles = [gym.make(env_id) for _ in range(num_envs)]
    observation, _ = envs.reset(seed=10)
    single_obs = [env.reset(seed=10 + i)[0] for i, env in enumerate(singles)]
    for i in range(num_envs):
        np.testing.assert_array_equal(observation["observation"][i], single_obs[i]["observation"])
    policy = scripted_policy(singles[0])
    endings = 0
    for _ in range(max(120, gym.spec(env_id).max_episode_steps + 20)):  # an episode's end
        actions = np.stack([policy({k: v[i] for k, v in observation.items()})
                            for i in range(num_envs)])
        observation, reward, terminated, truncated, infos = envs.step(actions)
        for i, env in enumerate(singles):
            expected, expected_reward, done, cut, info = env.step(actions[i])
            assert (terminated[i], truncated[i]) == (done, cut)
            if done or cut:
                endings += 1
                np.testing.assert_array_equal(infos["final_obs"][i]["observation"],
                                              expected["observation"])
                assert infos["final_info"]["is_success"][i] == info["is_success"]
                expected, _ = env.reset()
            np.testing.assert_array_equal(observation["observation"][i], expected["observation"])
            np.testing.assert_array_equal(observation["desired_goal"][i],
                                          expected["desired_goal"])
            assert reward[i] == expected_reward
    assert endings >= num_envs


def test_noisy_copies_draw_the_noise_a_single_env_draws():
    """observation_noise comes from each copy's own np_random, in the order one env alone
    draws it: copy i's noisy observations equal a single env's reset with seed + i."""
    kwargs = {"observation_noise": 0.01}
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=2, vectorization_mode="vector_entry_point",
                        **kwargs)
    singles = [gym.make("rigid_gym/Push-v0", **kwargs) for _ in range(2)]
    observation, _ = envs.reset(seed=4)
    expected = [env.reset(seed=4 + i)[0] for i, env in enumerate(singles)]
    actions = np.random.default_rng(0).uniform(-1, 1, (5, 2, 3))
    for step in range(6):
        for i in range(2):
            np.testing.assert_array_equal(observation["observation"][i],
                                          expected[i]["observation"])
        if step < 5:
            observation = envs.step(actions[step])[0]
            expected = [env.step(actions[step][i])[0] for i, env in enumerate(singles)]
    assert not np.array_equal(observation["observation"][0], observation["observation"][1])


@pytest.mark.parametrize("task", ["Push", "Stack", "Throw"])
def test_a_direct_call_of_the_entry_point_gets_the_registered_episode_length(task):
    """The vector entry point called without ``max_episode_steps`` (as a user or a library
    may, outside ``gym.make_vec``) truncates episodes where the registered id does: Stack at
    100 steps, Push and Throw at 50."""
    from rigid_gym.envs import vector

    envs = getattr(vector, task.lower())(num_envs=2)
    expected = gym.spec(f"rigid_gym/{task}-v0").max_episode_steps
    assert envs.max_episode_steps == expected == {"Push": 50, "Stack": 100, "Throw": 50}[task]
    envs.reset(seed=0)
    for _ in range(expected - 1):
        _, _, _, truncated, _ = envs.step(np.zeros(envs.action_space.shape))
        assert not truncated.any()
    _, _, _, truncated, _ = envs.step(np.zeros(envs.action_space.shape))
    assert truncated.all()
    envs.close()


def test_a_non_finite_copy_is_named():
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=3, vectorization_mode="vector_entry_point")
    envs.reset(seed=0)
    inner = envs.unwrapped
    inner.world.state.velocity[1, inner.core.cubes[0], 2] = np.nan
    with pytest.raises(RuntimeError, match=r"PushEnv \(copy 1\): .*non-finite state"):
        envs.step(np.zeros((3, 3)))


def test_vector_env_refuses_what_it_cannot_do():
    with pytest.raises(ValueError, match="num_envs: must be an int >= 1, got 0"):
        gym.make_vec("rigid_gym/Push-v0", num_envs=0, vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError, match="cannot include 'size'"):
        gym.make_vec("rigid_gym/Push-v0", num_envs=2, vectorization_mode="vector_entry_point",
                     randomize=True)
    with pytest.raises(ValueError, match="render_mode must be None"):
        gym.make_vec("rigid_gym/Push-v0", num_envs=2, vectorization_mode="vector_entry_point",
                     render_mode="rgb_array")
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=2, vectorization_mode="vector_entry_point")
    envs.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions must have shape \(2, 3\)"):
        envs.step(np.zeros(3))


@pytest.mark.parametrize("bad", [
    "abc", "0.5", np.full((2, 3), 0.5j), np.zeros((2, 3), dtype=object), {"x": 0.5},
    [["0.5", "0", "0"]] * 2,
], ids=["str", "numeric str", "complex", "object", "dict", "list of str"])
def test_actions_that_are_not_real_numbers_are_refused(bad):
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=2, vectorization_mode="vector_entry_point")
    envs.reset(seed=0)
    with pytest.raises(ValueError, match=r"RigidGymVectorEnv\.step: actions must be a real "
                                         r"numeric array \(bool, int or float\) in "
                                         r"Box\(-1\.0, 1\.0, \(2, 3\), float32\), got "):
        envs.step(bad)


@pytest.mark.filterwarnings("ignore:.*use of fork\\(\\) may lead to deadlocks")  # Python >= 3.12
@pytest.mark.parametrize("when", ["after a step", "during a step"])
def test_a_forked_child_steps_a_vector_env_its_parent_stepped(when):
    """The parent's steps started the solver's thread pool; a forked child has none of its
    threads, and must start a pool of its own rather than wait for ever on the parent's.
    "during a step": forks while another thread is inside a batched step, holding the pool's
    locks (without the child forgetting the pool, about a third of such children hang). Every
    step is shared out, as a batch that found sharing faster would step."""
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=4)
    envs.unwrapped.world.core.force_sharing(True)
    envs.reset(seed=0)
    for _ in range(5):
        envs.step(envs.action_space.sample())

    def child():
        for _ in range(100):
            envs.step(envs.action_space.sample())

    forks, stepping, stepper = 1, threading.Event(), None
    if when == "during a step":  # World.step releases the GIL: the forks land inside it
        world = envs.unwrapped.world

        def step_until_cleared():
            while stepping.is_set():
                world.step(10)

        forks = 10
        stepping.set()
        stepper = threading.Thread(target=step_until_cleared)
        stepper.start()
    try:
        for _ in range(forks):
            process = multiprocessing.get_context("fork").Process(target=child)
            process.start()
            process.join(timeout=30)
            if process.is_alive():  # hung: fail rather than block the suite
                process.kill()
                process.join()
                pytest.fail(f"a child forked {when} hung in its batched steps")
            assert process.exitcode == 0
    finally:
        stepping.clear()
        if stepper is not None:
            stepper.join()


def test_materials_can_be_randomized_per_copy():
    envs = gym.make_vec("rigid_gym/Push-v0", num_envs=4, vectorization_mode="vector_entry_point",
                        randomize={"mass": (0.5, 2.0), "friction": (0.5, 1.5)})
    envs.reset(seed=3)
    masses = 1.0 / envs.unwrapped.world.model.inverse_mass[:, envs.unwrapped.core.cubes[0]]
    assert len(set(masses.round(12))) == 4
    assert np.all((masses >= 0.05) & (masses <= 0.2))


def test_world_load_refuses_another_structure():
    world = rg.World(cube_stack(2), num_worlds=2)
    with pytest.raises(ValueError, match="differs in shape or motion"):
        world.load(_bigger_stack(), 1)


def _bigger_stack():
    scene = rg.Scene()
    scene.add_ground()
    for k in range(2):
        scene.add_body(rg.Box((0.03, 0.03, 0.03)), mass=0.1, position=(0, 0, 0.03 + 0.06 * k))
    return scene


@pytest.mark.parametrize("algorithm", ["sac_her", "ppo"])
def test_sb3_trains_on_the_batched_env(algorithm):
    """SAC + HER (compute_reward through env_method) and PPO learn from SB3VecEnv for a few
    hundred steps, with episodes ending (terminal_observation) along the way."""
    sb3 = pytest.importorskip("stable_baselines3")
    from rigid_gym.agents.vec_env import SB3VecEnv
    from stable_baselines3.common.vec_env import VecMonitor

    env_id = "rigid_gym/Push-v0" if algorithm == "sac_her" else "rigid_gym/PushDense-v0"
    envs = VecMonitor(SB3VecEnv(gym.make_vec(env_id, num_envs=4)))
    if algorithm == "sac_her":
        model = sb3.SAC("MultiInputPolicy", envs, replay_buffer_class=sb3.HerReplayBuffer,
                        learning_starts=200, batch_size=32, seed=0,
                        policy_kwargs={"net_arch": [16, 16]})
    else:
        model = sb3.PPO("MultiInputPolicy", envs, n_steps=64, batch_size=64, seed=0,
                        policy_kwargs={"net_arch": [16, 16]})
    model.learn(600)
    assert model.num_timesteps >= 600
    assert len(model.ep_info_buffer) >= 8  # 600 steps of 4 envs: episodes of 50 ended
    assert all(np.isfinite(info["r"]) for info in model.ep_info_buffer)


def test_sb3_adapter_reports_the_last_observation_of_an_episode():
    pytest.importorskip("stable_baselines3")
    from rigid_gym.agents.vec_env import SB3VecEnv

    envs = SB3VecEnv(gym.make_vec("rigid_gym/Push-v0", num_envs=2))
    envs.seed(5)
    first = envs.reset()
    assert first["observation"].shape == (2, 24)
    for step in range(50):
        observation, _reward, done, infos = envs.step(np.zeros((2, 3), dtype=np.float32))
    assert done.all()
    assert all(info["TimeLimit.truncated"] for info in infos)
    assert all(info["terminal_observation"]["observation"].shape == (24,) for info in infos)
    assert not np.array_equal(observation["desired_goal"][0],
                              infos[0]["terminal_observation"]["desired_goal"])
    assert envs.env_method("compute_reward", observation["achieved_goal"],
                           observation["desired_goal"], infos, indices=[0])[0].shape == (2,)
