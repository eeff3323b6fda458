"""The tasks under the RL tools people use with Gymnasium: its vector modes, RecordVideo and a
CleanRL-style wrapper stack, torchrl's GymEnv and RL Baselines3 Zoo. A test whose tool is not
installed is skipped (torchrl, moviepy for RecordVideo, rl_zoo3: the ``zoo`` extra)."""

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from rigid_gym.envs import ENV_IDS

TASK_IDS = [i for i in ENV_IDS if "Dense" not in i]


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_sync_and_async_vector_modes_step_the_same_episodes(env_id):
    """Gymnasium's own vector envs (one env per copy, NEXT_STEP autoreset) over an episode's
    end: async (one process per copy) gives the bits of sync (one process)."""
    length = gym.spec(env_id).max_episode_steps
    actions = np.random.default_rng(0).uniform(-1, 1, (length + 5, 2) + gym.make(
        env_id).action_space.shape).astype(np.float32)
    runs = []
    for mode in ("sync", "async"):
        envs = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode)
        observations, _ = envs.reset(seed=4)
        steps = [observations]
        for action in actions:
            observations, _reward, terminated, truncated, _info = envs.step(action)
            steps.append(observations)
            if len(steps) == length + 1:
                assert truncated.all() and not terminated.any()
        envs.close()
        runs.append(steps)
    for sync, asynchronous in zip(*runs):
        for key in sync:
            assert sync[key].shape[0] == 2
            assert sync[key].tobytes() == asynchronous[key].tobytes()
    first = gym.make(env_id).reset(seed=4)[0]
    assert runs[0][0]["observation"][0].tobytes() == first["observation"].tobytes()


def test_record_video_writes_an_episode(tmp_path):
    """RecordVideo's file holds the episode as the env draws it: one frame for the reset and
    one per step, each the env's rgb_array frame of that step up to the video codec's
    loss (a mean difference under 3 of 255) and nearer it than any other step's."""
    pytest.importorskip("moviepy", reason="RecordVideo writes videos with moviepy")
    from moviepy import VideoFileClip

    env = gym.wrappers.RecordVideo(gym.make("rigid_gym/Push-v0", render_mode="rgb_array"),
                                   str(tmp_path / "videos"), episode_trigger=lambda episode: True)
    env.reset(seed=0)
    drawn = [env.unwrapped.render()]
    actions = np.random.default_rng(0).uniform(-1, 1, (50, 3)).astype(np.float32)
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        drawn.append(env.unwrapped.render())
    assert truncated and not terminated
    env.close()
    (video,) = (tmp_path / "videos").glob("*.mp4")
    with VideoFileClip(str(video)) as clip:
        assert clip.fps == env.metadata["render_fps"]
        frames = np.array(list(clip.iter_frames()), dtype=np.float64)
    assert frames.shape == (51, 480, 480, 3)
    drawn = np.array(drawn, dtype=np.float64)
    errors = np.abs(frames - drawn).mean(axis=(1, 2, 3))
    assert errors.max() < 3.0, errors
    # and each video frame is nearest its own step's picture (every 4th pixel compared)
    nearest = [np.abs(frame[::4, ::4] - drawn[:, ::4, ::4]).mean(axis=(1, 2, 3)).argmin()
               for frame in frames]
    assert nearest == list(range(51))


def cleanrl_env(env_id: str, gamma: float = 0.99):
    """The wrapper stack of CleanRL's ppo_continuous_action.py (Gymnasium 1.x signatures)."""

    def thunk():
        env = gym.make(env_id)
        env = gym.wrappers.FlattenObservation(env)
        env = gym.wrappers.RecordEpisodeStatistics(env)
        env = gym.wrappers.ClipAction(env)
        env = gym.wrappers.NormalizeObservation(env)
        env = gym.wrappers.TransformObservation(env, lambda obs: np.clip(obs, -10, 10),
                                                env.observation_space)
        env = gym.wrappers.NormalizeReward(env, gamma=gamma)
        env = gym.wrappers.TransformReward(env, lambda reward: np.clip(reward, -10, 10))
        return env

    return thunk


def test_a_cleanrl_wrapper_stack_runs_and_counts_episodes():
    envs = gym.vector.SyncVectorEnv([cleanrl_env("rigid_gym/PushDense-v0") for _ in range(2)])
    size = 24 + 3 + 3  # observation, achieved_goal, desired_goal
    assert envs.single_observation_space.shape == (size,)
    observations, _ = envs.reset(seed=0)
    episodes = []
    for _ in range(60):
        actions = envs.action_space.sample() * 3.0  # ClipAction brings these into [-1, 1]
        observations, rewards, _terminated, _truncated, infos = envs.step(actions)
        assert observations.shape == (2, size) and np.abs(observations).max() <= 10.0
        assert np.isfinite(rewards).all()
        if "episode" in infos:
            episodes += [int(n) for n in infos["episode"]["l"][infos["_episode"]]]
    assert episodes == [50, 50]


def test_torchrl_gym_env_passes_its_spec_check_and_rolls_out():
    pytest.importorskip("torchrl")
    from torchrl.envs import GymEnv
    from torchrl.envs.utils import check_env_specs

    env = GymEnv("rigid_gym/Push-v0")
    check_env_specs(env)
    rollout = env.rollout(60)  # stops at the first done: truncation after 50 steps
    assert rollout["observation"].shape == (50, 24)
    assert rollout["desired_goal"].shape == (50, 3)
    assert rollout["next", "truncated"][-1].item()
    env.close()


def test_zoo_settings_are_hyperparams_yml_in_the_zoo_format():
    pytest.importorskip("rl_zoo3")
    from rigid_gym.agents.train import hyperparams_table
    from rigid_gym.agents.zoo import BC_ONLY, ZOO_ALGOS, hyperparams

    table = hyperparams_table()
    assert sorted(hyperparams) == sorted(ENV_IDS) == sorted(table)
    assert set(BC_ONLY) == {"bc_weight", "bc_batch_size", "q_filter", "bc_relabel"}
    for env_id, entry in hyperparams.items():
        settings = table[env_id]
        assert entry["policy"] == "MultiInputPolicy"  # Dict observations
        assert (entry["n_timesteps"], entry["n_envs"]) == (settings["n_timesteps"],
                                                           settings["n_envs"])
        for key, value in settings["kwargs"].items():
            assert entry.get(key) == (None if key in BC_ONLY else value)
        off_policy = "sac" in ZOO_ALGOS[settings["algo"]]
        assert ("replay_buffer_class" in entry) == off_policy
        if settings.get("demonstrations"):
            (callback,) = entry["callback"]
            assert callback == {"rigid_gym.agents.zoo.Demonstrations":
                                {"episodes": settings["demonstrations"]}}


def test_the_zoo_callback_puts_the_demonstrations_in_the_buffer_first():
    pytest.importorskip("rl_zoo3")
    from rigid_gym.agents.zoo import Demonstrations
    from stable_baselines3 import SAC, HerReplayBuffer
    from stable_baselines3.common.env_util import make_vec_env

    model = SAC("MultiInputPolicy", make_vec_env("rigid_gym/Throw-v0", n_envs=1),
                buffer_size=1000, replay_buffer_class=HerReplayBuffer, learning_starts=100,
                policy_kwargs={"net_arch": [8]}, seed=0)
    model.learn(3, callback=Demonstrations(episodes=2))
    assert model.replay_buffer.pos == 2 * 50 + 3  # two 50-step episodes, then the run's steps


@pytest.mark.parametrize("env_id, algo, steps", [("rigid_gym/Push-v0", "tqc", 200),
                                                 ("rigid_gym/Throw-v0", "sac", 200),
                                                 ("rigid_gym/PushDense-v0", "ppo", 100)])
def test_the_zoo_trains_and_enjoys_with_the_shipped_settings(env_id, algo, steps, tmp_path):
    pytest.importorskip("rl_zoo3")
    common = ["--algo", algo, "--env", env_id, "--gym-packages", "rigid_gym"]
    train = subprocess.run([sys.executable, "-m", "rl_zoo3.train", *common, "--conf-file",
                            "rigid_gym.agents.zoo", "-n", str(steps), "-f", str(tmp_path),
                            "--num-threads", "1", "--seed", "0"],
                           check=False, capture_output=True, text=True, timeout=600)
    assert train.returncode == 0, train.stdout[-3000:] + train.stderr[-3000:]
    enjoy = subprocess.run([sys.executable, "-m", "rl_zoo3.enjoy", *common, "-f", str(tmp_path),
                            "--exp-id", "1", "-n", "60", "--no-render"],
                           check=False, capture_output=True, text=True, timeout=600)
    assert enjoy.returncode == 0, enjoy.stdout[-3000:] + enjoy.stderr[-3000:]
    assert "Mean episode length: 50.00" in enjoy.stdout
