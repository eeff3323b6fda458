"""Minari datasets of the tasks (rigid_gym.agents.datasets, `rigid-gym dataset`): what they
hold, and that every episode replays bit for bit from its seed and actions."""

import gymnasium as gym
import numpy as np
import pytest

minari = pytest.importorskip("minari", reason="the datasets need Minari: pip install "
                                              "'rigid_gym[datasets]'")

from rigid_gym.agents import datasets
from rigid_gym.envs.scripted import scripted_policy

from rigid_gym.cli import main


@pytest.fixture(autouse=True)
def datasets_path(tmp_path, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    return tmp_path


def replay_by_hand(dataset):
    """Replay every episode with recover_environment, its seed and its actions; assert each
    observation, reward, termination, truncation and is_success is the stored one, bit for
    bit."""
    env = dataset.recover_environment()
    for seed, episode in zip(datasets.episode_seeds(dataset), dataset.iterate_episodes()):
        obs, info = env.reset(seed=seed)
        for t in range(len(episode) + 1):
            for key in obs:
                assert np.array_equal(obs[key], episode.observations[key][t]), (episode.id, t)
            assert info["is_success"] == episode.infos["is_success"][t]
            if t == len(episode):
                break
            obs, reward, terminated, truncated, info = env.step(episode.actions[t])
            assert np.array_equal(reward, episode.rewards[t])
            assert (terminated, truncated) == (episode.terminations[t], episode.truncations[t])


@pytest.mark.parametrize("task", ["Push", "Stack", "Throw"])
def test_a_scripted_dataset_loads_back_and_replays_bit_for_bit(task, capsys):
    env_id, dataset_id = f"rigid_gym/{task}-v0", f"rigid_gym/{task.lower()}/test-v0"
    assert main(["dataset", env_id, "--episodes", "3", "--seed", "5",
                 "--dataset-id", dataset_id]) == 0
    assert f"{dataset_id}: 3 episodes" in capsys.readouterr().out
    dataset = minari.load_dataset(dataset_id)
    env = gym.make(env_id)
    steps = env.spec.max_episode_steps
    assert dataset.total_episodes == 3 and dataset.total_steps == 3 * steps
    assert datasets.episode_seeds(dataset) == [5, 6, 7]
    meta = dataset.storage.metadata
    assert meta["policy"] == "scripted" and meta["action_noise"] == 0.0
    assert meta["rigid_gym_version"] and meta["requirements"] == [
        f"rigid_gym=={meta['rigid_gym_version']}"]
    assert dataset.recover_environment().spec.id == env_id
    assert dataset.recover_environment(eval_env=True).spec.id == env_id
    policy = scripted_policy(env)
    for episode in dataset.iterate_episodes():
        for key, space in env.observation_space.items():
            assert episode.observations[key].shape == (steps + 1, *space.shape)
            assert episode.observations[key].dtype == np.float32
        assert episode.actions.shape == (steps, *env.action_space.shape)
        assert episode.rewards.shape == episode.terminations.shape == (steps,)
        assert episode.infos["is_success"].shape == (steps + 1,)
        # the actions are the scripted policy's at the stored observations
        for t in (0, steps // 2, steps - 1):
            obs = {key: value[t] for key, value in episode.observations.items()}
            assert np.array_equal(episode.actions[t], policy(obs).astype(np.float32))
    assert meta["success_rate"] == np.mean([e.infos["is_success"][-1]
                                            for e in dataset.iterate_episodes()])
    replay_by_hand(dataset)
    assert main(["dataset", "--verify", dataset_id]) == 0
    assert "3 of 3 episodes replay bit for bit" in capsys.readouterr().out


def test_noisy_and_random_datasets_replay_too():
    noisy = datasets.write_dataset("rigid_gym/push/noisy-test-v0", "rigid_gym/Push-v0",
                                   "scripted", 2, noise=0.3, seed=1)
    random = datasets.write_dataset("rigid_gym/throw/random-test-v0", "rigid_gym/Throw-v0",
                                    "random", 2, seed=1)
    assert noisy.storage.metadata["action_noise"] == 0.3
    policy = scripted_policy(gym.make("rigid_gym/Push-v0"))
    episode = noisy[0]
    clean = np.stack([policy({k: v[t] for k, v in episode.observations.items()})
                      for t in range(len(episode))]).astype(np.float32)
    assert not np.array_equal(episode.actions, clean)  # the noise is in what was stepped
    assert np.all(np.abs(episode.actions) <= 1.0)
    for dataset in (noisy, random):
        replay_by_hand(dataset)
        assert all(result.ok for result in datasets.verify(dataset))


def rewrite(dataset, dataset_id, seeds, change=None):
    """A copy of ``dataset`` as ``dataset_id`` with the reset seeds ``seeds``; ``change``
    edits the first episode's actions in place."""
    env = dataset.recover_environment()
    buffers = []
    for k, (seed, e) in enumerate(zip(seeds, dataset.iterate_episodes())):
        actions = e.actions.copy()
        if change and k == 0:
            change(actions)
        buffers.append(minari.data_collector.EpisodeBuffer(
            id=k, seed=seed, observations=e.observations, actions=actions, rewards=e.rewards,
            terminations=e.terminations, truncations=e.truncations,
            infos={"is_success": list(e.infos["is_success"])}))
    return datasets.create(dataset_id, env, buffers, "scripted", 0.0, "a copy")


def test_a_tampered_action_fails_verify(capsys):
    original = datasets.write_dataset("rigid_gym/push/original-v0", "rigid_gym/Push-v0",
                                      "scripted", 2)
    seeds = datasets.episode_seeds(original)
    assert all(r.ok for r in datasets.verify(rewrite(original, "rigid_gym/push/copy-v0", seeds)))

    def tamper(actions):
        actions[10, 0] = -actions[10, 0] if actions[10, 0] else 0.5

    rewrite(original, "rigid_gym/push/tampered-v0", seeds, tamper)
    assert main(["dataset", "--verify", "rigid_gym/push/tampered-v0"]) == 1
    out = capsys.readouterr().out
    assert "episode 0 (seed 0, 50 steps): FAIL, observation" in out and "at step 11" in out
    assert "episode 1 (seed 1, 50 steps): pass" in out
    assert "1 of 2 episodes replay bit for bit" in out
    # a wrong seed is caught the same way, at the reset
    (result, _) = datasets.verify(rewrite(original, "rigid_gym/push/reseeded-v0", [7, 1]))
    assert not result.ok and "at step 0" in result.mismatch


def test_episodes_reset_without_a_seed_replay_in_sequence():
    env = gym.make("rigid_gym/Stack-v0")
    buffers = datasets.play(env, scripted_policy(env), [4, None, None])
    dataset = datasets.create("rigid_gym/stack/stream-v0", env, buffers, "scripted", 0.0, "s")
    assert datasets.episode_seeds(dataset) == [4, None, None]
    assert not np.array_equal(dataset[1].observations["desired_goal"][0],
                              dataset[2].observations["desired_goal"][0])
    assert [r.ok for r in datasets.verify(dataset)] == [True, True, True]
    unseeded = datasets.create("rigid_gym/stack/unseeded-v0", env, buffers[1:], "scripted",
                               0.0, "s")
    results = datasets.verify(unseeded)
    assert [r.ok for r in results] == [False, False]
    assert "no reset seed" in results[0].mismatch and "did not replay" in results[1].mismatch


def test_the_recipes_write_every_shipped_dataset(capsys):
    assert main(["dataset", "--recipes", "--episodes", "1"]) == 0
    out = capsys.readouterr().out
    local = minari.list_local_datasets()
    for recipe in datasets.RECIPES:
        assert f"{recipe.dataset_id}: 1 episodes" in out
        assert local[recipe.dataset_id]["total_episodes"] == 1
    assert len({r.dataset_id for r in datasets.RECIPES}) == 3 * len(datasets.RECIPE_TASKS)
    assert {"rigid_gym/tower/expert-v0", "rigid_gym/insert/random-v0"} <= set(local)
    # regenerating replaces them
    assert main(["dataset", "--recipes", "--episodes", "2"]) == 0
    assert minari.load_dataset("rigid_gym/stack/noisy-v0").total_episodes == 2


@pytest.mark.parametrize("args, message", [
    (["dataset", "rigid_gym/Push-v0"], "give ENV_ID and --dataset-id, or --verify ID"),
    (["dataset", "--verify", "rigid_gym/push/none-v0"], "no dataset rigid_gym/push/none-v0"),
    (["dataset", "rigid_gym/Push-v0", "--dataset-id", "a/b-v0", "--noise", "-1"],
     "must be in [0, 10], got -1"),
    (["dataset", "Nope-v0", "--dataset-id", "a/b-v0"], "unknown env id 'Nope-v0'"),
])
def test_bad_dataset_arguments_fail_clearly(args, message, usage_error):
    assert message in usage_error(args)


@pytest.mark.parametrize("dataset_id", ["push", "t/push-v0", "rigid_gym/push/expert"])
def test_a_bad_dataset_id_fails_before_playing_and_leaves_nothing(dataset_id, usage_error,
                                                                   datasets_path, monkeypatch):
    played = []
    monkeypatch.setattr(datasets, "play", lambda *a, **k: played.append(1))
    assert f"{dataset_id!r} is not a dataset id" in usage_error(
        ["dataset", "rigid_gym/Push-v0", "--episodes", "1", "--dataset-id", dataset_id])
    assert not played and not any(datasets_path.iterdir())


def test_a_failed_write_leaves_nothing(datasets_path, monkeypatch):
    def fail(*args, **kwargs):
        (datasets_path / "rigid_gym" / "push" / "a-v0" / "data").mkdir(parents=True)
        raise OSError("disk full")

    monkeypatch.setattr(minari, "create_dataset_from_buffers", fail)
    with pytest.raises(OSError, match="disk full"):
        datasets.write_dataset("rigid_gym/push/a-v0", "rigid_gym/Push-v0", "scripted", 1)
    assert not any(datasets_path.iterdir())


@pytest.mark.parametrize("damage, named", [
    (lambda data: __import__("shutil").rmtree(data / "1"), "episode 1's folder {data}/1 is missing"),
    (lambda data: (data / "1" / "part-0.arrow").write_bytes(
        (data / "1" / "part-0.arrow").read_bytes()[:-40]), "{data}/1/part-0.arrow is not a whole"),
    (lambda data: (data / "metadata.json").write_text("garbage{"),
     "{data}/metadata.json is not readable JSON"),
    (lambda data: (data / "0" / "metadata.json").unlink(), "{data}/0/metadata.json is missing"),
], ids=["no-episode-folder", "truncated-arrow", "garbage-metadata", "no-episode-metadata"])
def test_verify_names_the_damaged_file_without_a_traceback(damage, named, datasets_path,
                                                           capsys):
    assert main(["dataset", "rigid_gym/Push-v0", "--episodes", "2", "--dataset-id",
                 "rigid_gym/push/a-v0"]) == 0
    data = datasets_path / "rigid_gym" / "push" / "a-v0" / "data"
    damage(data)
    capsys.readouterr()
    assert main(["dataset", "--verify", "rigid_gym/push/a-v0"]) == 1
    err = capsys.readouterr().err
    assert named.format(data=data) in err and "Traceback" not in err and "usage" not in err
    assert "write it again, or delete it (minari delete rigid_gym/push/a-v0)" in err


def test_an_existing_dataset_is_not_overwritten(usage_error):
    args = ["dataset", "rigid_gym/Push-v0", "--episodes", "1", "--dataset-id", "rigid_gym/push/a-v0"]
    assert main(args) == 0
    assert "rigid_gym/push/a-v0 already exists" in usage_error(args)


def test_behaviour_cloning_fits_the_dataset_actions():
    from rigid_gym.agents.offline import clone

    dataset = datasets.write_dataset("rigid_gym/push/bc-test-v0", "rigid_gym/Push-v0",
                                     "scripted", 3)
    policy = clone("rigid_gym/push/bc-test-v0", hidden=(64, 64), epochs=60, batch_size=32)
    observations = {k: np.concatenate([e.observations[k][:-1] for e in dataset])
                    for k in ("observation", "desired_goal")}
    actions = np.concatenate([e.actions for e in dataset])
    predicted, _ = policy.predict(observations)
    assert predicted.shape == actions.shape and np.all(np.abs(predicted) <= 1.0)
    error = np.mean((predicted - actions) ** 2)
    assert error < 0.1 * np.mean((actions - actions.mean(0)) ** 2)  # far better than the mean
    action, _ = policy.predict({k: v[0] for k, v in observations.items()})  # one observation
    assert action.shape == (3,)
