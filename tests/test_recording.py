"""Recordings: what the .rrd file holds equals what the env or World did, files are complete
after an episode, an exception, close(), Ctrl-C, a killed process and in SubprocVecEnv
workers, a file that cannot be written fails alone, and bad input fails."""

import errno
import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pyarrow as pa
import pytest
import rerun as rr
from rerun.chunk import RrdReader
from rigid_gym._core import STATIC
from rigid_gym.envs.scripted import scripted_policy

import rigid_gym as rg
from rigid_gym import quaternion as quat
from rigid_gym.cli import find_rerun
from rigid_gym.meshes import l_shape_mesh
from rigid_gym.recordable import Marker, Series
from rigid_gym.recording import RecordRerun, WorldRecorder

TASK_IDS = ["rigid_gym/Push-v0", "rigid_gym/Stack-v0", "rigid_gym/Throw-v0"]
TASK_IDS += ["rigid_gym/Reach-v0", "rigid_gym/PickAndPlace-v0", "rigid_gym/Slide-v0",
             "rigid_gym/Flip-v0"]


@pytest.fixture(autouse=True)
def strict_rerun(monkeypatch):
    """Malformed data raises instead of being dropped with a warning (here and in the
    processes the tests start)."""
    monkeypatch.setenv("RERUN_STRICT", "1")
    rr.set_strict_mode(True)
    yield
    rr.set_strict_mode(False)


# -- reading files back ---------------------------------------------------------------------------

def temporal(path, entity: str, component: str):
    """(steps (T,) int64, values pa.Array with one entry per row) of a temporal component,
    sorted by step (an entity may be split over several chunks)."""
    steps, values = [], []
    stream = RrdReader(path).stream().filter(content=entity, is_static=False, components=component)
    for chunk in stream:
        batch = chunk.to_record_batch()
        if component in batch.schema.names:
            steps.append(batch.column("step").to_numpy())
            values.append(batch.column(component))
    assert steps, f"{path} has no {component} at {entity}"
    step = np.concatenate(steps)
    order = np.argsort(step, kind="stable")
    return step[order], pa.concat_arrays(values).take(pa.array(order))


def rows(values: pa.Array, width: int) -> np.ndarray:
    """A column of (nested) lists as a (T, width) array of its numbers."""
    while pa.types.is_list(values.type) or pa.types.is_fixed_size_list(values.type):
        values = values.flatten()
    return values.to_numpy().reshape(-1, width)


def static_rows(path) -> dict:
    """{(entity, component): number of static rows holding it} over the whole file."""
    counts = {}
    for chunk in RrdReader(path).stream().filter(is_static=True):
        batch = chunk.to_record_batch()
        for name in batch.schema.names:
            if ":" in name:
                key = (chunk.entity_path, name)
                counts[key] = counts.get(key, 0) + batch.num_rows
    return counts


def views_beside(path) -> dict:
    """{view kind ("3D", "TimeSeries"): [origins]} of the blueprint beside the file ``path``
    (``<application id>.rbl`` in its folder), which must be that application's only one."""
    application_id = RrdReader(path).recordings()[0].application_id
    reader = RrdReader(path.parent / f"{application_id}.rbl")
    assert [b.application_id for b in reader.blueprints()] == [application_id]
    assert RrdReader(path).blueprints() == []  # the file itself holds only the recording
    views = {}
    for chunk in reader.stream(store=reader.blueprints()[0]):
        batch = chunk.to_record_batch()
        if "ViewBlueprint:class_identifier" in batch.schema.names:
            kind = batch.column("ViewBlueprint:class_identifier").to_pylist()[0][0]
            origin = batch.column("ViewBlueprint:space_origin").to_pylist()[0][0]
            views.setdefault(kind, []).append(origin)
    return views


def xyzw(orientation: np.ndarray) -> np.ndarray:
    return np.asarray(orientation)[..., [1, 2, 3, 0]]


def verified(path) -> bool:
    """Whether ``path`` is a complete rerun file (``rerun rrd verify``: CRCs, footer)."""
    return subprocess.run([find_rerun(), "rrd", "verify", str(path)],
                          check=False, capture_output=True).returncode == 0


# -- an env episode -------------------------------------------------------------------------------

def run_episode(env, seed: int):
    """Run the scripted policy to the episode's end; return per-step body poses
    (T + 1, n, 3), (T + 1, n, 4), the sim times (T + 1,) s, actions (T, a), rewards (T,) and
    successes (T,)."""
    observation, _ = env.reset(seed=seed)
    policy = scripted_policy(env)
    world = env.unwrapped.world
    positions, orientations, times = [world.position.copy()], [world.orientation.copy()], [0.0]
    actions, rewards, successes = [], [], []
    done = False
    while not done:
        action = policy(observation)
        observation, reward, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        positions.append(world.position.copy())
        orientations.append(world.orientation.copy())
        times.append(world.time)
        actions.append(action)
        rewards.append(reward)
        successes.append(float(info["is_success"]))
    if isinstance(env, RecordRerun):
        env.sync()  # the writer process writes finished episodes' files in the background
    return (np.array(positions), np.array(orientations), np.array(times), np.array(actions),
            np.array(rewards), np.array(successes))


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_the_file_holds_the_episode_exactly(env_id, tmp_path):
    # chunk_steps 16: the rows reach the writer in several pieces, the first with the reset
    env = RecordRerun(gym.make(env_id), tmp_path, episode_trigger=lambda k: True, run="test",
                      contacts=True, chunk_steps=16)
    positions, orientations, times, actions, rewards, successes = run_episode(env, seed=3)
    steps = len(rewards)  # the whole episode: 50 env steps (Stack 100)
    # recording (contacts included) does not change what the env does
    bare = run_episode(gym.make(env_id), seed=3)
    np.testing.assert_array_equal(bare[0], positions)
    np.testing.assert_array_equal(bare[1], orientations)
    task = env.unwrapped
    path = tmp_path / env_id.replace("/", "-") / "test-episode-0.rrd"
    assert env.paths == [path]

    recordings = RrdReader(path).recordings()
    assert [r.application_id for r in recordings] == [env_id.replace("/", "-")]
    views = views_beside(path)
    assert views["3D"] == ["/world"]
    assert sorted(views["TimeSeries"]) == ["/action", "/reward", "/success"]
    for body in task.scene.bodies:
        entity = f"/world/bodies/{body.name}"
        if body.motion == STATIC:  # logged once, with its pose
            assert static_rows(path)[(entity, "Transform3D:translation")] == 1
            continue
        step, translation = temporal(path, entity, "Transform3D:translation")
        _, quaternion = temporal(path, entity, "Transform3D:quaternion")
        assert step.tolist() == list(range(steps + 1))
        # rerun stores float32: the file equals the env's float64 values rounded to float32
        np.testing.assert_array_equal(rows(translation, 3),
                                      positions[:, body.index].astype(np.float32))
        np.testing.assert_array_equal(rows(quaternion, 4),
                                      xyzw(orientations[:, body.index]).astype(np.float32))
    step, reward = temporal(path, "/reward", "Scalars:scalars")
    assert step.tolist() == list(range(1, steps + 1))
    np.testing.assert_array_equal(reward.flatten().to_numpy(), rewards)
    _, action = temporal(path, "/action", "Scalars:scalars")
    np.testing.assert_array_equal(rows(action, actions.shape[1]), actions)
    _, success = temporal(path, "/success", "Scalars:scalars")
    np.testing.assert_array_equal(success.flatten().to_numpy(), successes)
    # sim_time is the World's time in ns
    sim_time = [batch.to_record_batch().column("sim_time").cast(pa.int64()).to_numpy()
                for batch in RrdReader(path).stream().filter(content="/reward", is_static=False)]
    np.testing.assert_array_equal(np.concatenate(sim_time),
                                  np.round(times[1:] * 1e9).astype(np.int64))
    # contacts: rows at every step; at reset the cubes rest on the table
    step, points = temporal(path, "/world/contacts/points", "Points3D:positions")
    assert step.tolist() == list(range(steps + 1))
    assert len(points[0]) >= 4 * task.num_cubes
    step, arrows = temporal(path, "/world/contacts/forces", "Arrows3D:vectors")
    assert step.tolist() == list(range(steps + 1))
    assert len(arrows[0]) == 0  # no solver step before step 1
    assert len(rows(arrows, 3)) > 0 or not task.num_cubes  # Reach's pad touches nothing


def test_the_gripper_s_hand_and_fingers_are_in_the_file(tmp_path):
    """effector="gripper": the hand and both fingers are bodies of the file, boxes of their
    sizes (the fingers in DRIVEN_COLOR), moving as in the env (float32) through a scripted
    episode that closes the fingers on the cube; the action series' last entry is named
    "fingers"."""
    from rigid_gym.envs.gripper import FINGER_HALF_EXTENTS, HAND_HALF_EXTENTS

    from rigid_gym.render import DRIVEN_COLOR

    env = RecordRerun(gym.make("rigid_gym/PickAndPlace-v0", effector="gripper",
                               max_episode_steps=12), tmp_path,
                      episode_trigger=lambda k: True, run="test")
    positions, *_ = run_episode(env, seed=0)
    path = env.paths[0]
    scene = env.unwrapped.scene
    widths = positions[:, scene.index("finger1"), 1] - positions[:, scene.index("finger0"), 1]
    assert widths.max() - widths.min() > 0.03  # the fingers closed on the cube
    for name, half in (("hand", HAND_HALF_EXTENTS), ("finger0", FINGER_HALF_EXTENTS),
                       ("finger1", FINGER_HALF_EXTENTS)):
        entity = f"/world/bodies/{name}"
        step, translation = temporal(path, entity, "Transform3D:translation")
        assert step.tolist() == list(range(len(positions)))
        np.testing.assert_array_equal(rows(translation, 3),
                                      positions[:, scene.index(name)].astype(np.float32))
        np.testing.assert_allclose(static_values(path, entity, "Boxes3D:half_sizes"), [half])
    (color,) = static_values(path, "/world/bodies/finger0", "Boxes3D:colors")
    assert color == int.from_bytes(bytes([*np.round(255 * np.array(DRIVEN_COLOR)).astype(int),
                                          255]), "big")
    labels = static_values(path, "/action", "SeriesLines:names")
    assert labels == ["x", "y", "z", "fingers"]


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_geometry_goals_and_layout_are_in_every_file_once(env_id, tmp_path):
    """The second file reuses what the first built (geometry, layout): both hold it all."""
    env = RecordRerun(gym.make(env_id, max_episode_steps=3), tmp_path,
                      episode_trigger=lambda k: True, run="test")
    for seed in range(2):
        run_episode(env, seed=seed)
        markers = env.unwrapped.markers()  # at the goals (Flip's: the goal's orientation)
        goals = [static_transform(env.paths[-1], f"/world/goals/{k}")
                 for k in range(len(markers))]
        np.testing.assert_allclose(np.concatenate(goals)[:, :2],
                                   np.array([m.position for m in markers])[:, :2].astype(
                                       np.float32))
        if env_id == "rigid_gym/Flip-v0":  # the target's orientation, as rerun's x, y, z, w
            (quaternion,) = static_values(env.paths[-1], "/world/goals/0",
                                          "Transform3D:quaternion")
            np.testing.assert_allclose(quaternion, xyzw(env.unwrapped.goal[None])[0], atol=1e-6)
        else:
            np.testing.assert_allclose(np.concatenate(goals)[:, :2], env.unwrapped.goal.reshape(
                -1, 3)[:, :2].astype(np.float32))
    assert len(env.paths) == 2
    for path in env.paths:
        assert set(views_beside(path)) == {"3D", "TimeSeries"}
        counts = static_rows(path)
        for body in env.unwrapped.scene.bodies:  # one row of geometry per body
            entity = f"/world/bodies/{body.name}"
            geometry = {k: n for k, n in counts.items()
                        if k[0] == entity and not k[1].startswith("Transform3D")}
            assert geometry and set(geometry.values()) == {1}, (body.name, geometry)
        goals = {k for k in counts if k[0].startswith("/world/goals/")}
        assert goals and all(counts[k] == 1 for k in goals)
        assert counts[("/world", "ViewCoordinates:xyz")] == 1


def static_values(path, entity: str, component: str) -> list:
    """The static row of ``component`` at ``entity``: a list of its instances."""
    for chunk in RrdReader(path).stream().filter(is_static=True, content=entity):
        batch = chunk.to_record_batch()
        if component in batch.schema.names:
            return batch.column(component).to_pylist()[0]
    raise AssertionError(f"{path} has no static {component} at {entity}")


def blueprint_values(path, component: str) -> list:
    """The first row of ``component`` in the layout beside ``path``: a list of instances."""
    application_id = RrdReader(path).recordings()[0].application_id
    reader = RrdReader(path.parent / f"{application_id}.rbl")
    for chunk in reader.stream(store=reader.blueprints()[0]):
        batch = chunk.to_record_batch()
        if component in batch.schema.names:
            return batch.column(component).to_pylist()[0]
    raise AssertionError(f"the layout of {path} has no {component}")


@pytest.mark.parametrize("env_id", TASK_IDS)
def test_the_3d_view_looks_through_the_env_camera_and_every_series_is_named(env_id, tmp_path):
    """The layout's 3D view tracks /world/camera, a Pinhole at the env camera's eye, looking
    at its target, with its field of view (the view opens framed as render() frames); each
    plot's lines have names and colours, all distinct."""
    env = RecordRerun(gym.make(env_id, max_episode_steps=2), tmp_path,
                      episode_trigger=lambda k: True, run="view")
    run_episode(env, seed=0)
    path = env.paths[0]
    eye, target, fov = env.unwrapped.camera_view
    np.testing.assert_allclose(static_values(path, "/world/camera", "Transform3D:translation")[0],
                               eye, atol=1e-6)
    xyzw_ = np.array(static_values(path, "/world/camera", "Transform3D:quaternion")[0])
    forward = quat.rotate(xyzw_[[3, 0, 1, 2]], np.array([0.0, 0.0, 1.0]))  # RDF: z ahead
    direction = np.subtract(target, eye)
    np.testing.assert_allclose(forward, direction / np.linalg.norm(direction), atol=1e-6)
    focal = static_values(path, "/world/camera", "Pinhole:image_from_camera")[0][0]
    height = static_values(path, "/world/camera", "Pinhole:resolution")[0][1]
    assert np.degrees(2 * np.arctan(0.5 * height / focal)) == pytest.approx(fov, abs=1e-4)
    assert blueprint_values(path, "EyeControls3D:tracking_entity") == ["/world/camera"]
    np.testing.assert_allclose(blueprint_values(path, "EyeControls3D:position")[0], eye,
                               atol=1e-6)
    np.testing.assert_allclose(blueprint_values(path, "EyeControls3D:look_target")[0], target,
                               atol=1e-6)
    actions = env.action_space.shape[0]
    assert static_values(path, "/action", "SeriesLines:names") == ["x", "y", "z", "grip"][:actions]
    assert static_values(path, "/reward", "SeriesLines:names") == ["reward"]
    assert static_values(path, "/success", "SeriesLines:names") == ["success"]
    colors = [c for name in ("/action", "/reward", "/success")
              for c in static_values(path, name, "SeriesLines:colors")]
    assert len(colors) == actions + 2 and len(set(colors)) == len(colors)


class FallingBox(gym.Env):
    """Not a rigid_gym task: a box falling onto the ground, recordable only through the
    members of ``rigid_gym.recordable.Recordable``."""

    observation_space = gym.spaces.Box(-np.inf, np.inf, (3,), np.float64)
    action_space = gym.spaces.Box(-1.0, 1.0, (1,), np.float32)
    camera_view = ((1.0, -1.0, 1.0), (0.0, 0.0, 0.2), 40.0)
    scalar_series = (Series("height", ("box",), ((0.2, 0.4, 0.9),)),)

    def __init__(self):
        scene = rg.Scene()
        scene.add_ground()
        scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0.0, 0.0, 0.5),
                       name="box")
        self.world = rg.World(scene, dt=0.01)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.world.reset()
        return self.world.position[1].copy(), {}

    def step(self, action):
        self.world.step(4)
        return self.world.position[1].copy(), 0.0, False, False, {}

    def markers(self):
        return [Marker(rg.Sphere(0.02), (0.0, 0.0, 0.02), (0.9, 0.2, 0.2), 0.5)]

    def scalars(self, action, reward, info):
        return [float(self.world.position[1, 2])]


def test_an_env_of_another_kind_is_recorded_through_the_protocol(tmp_path):
    env = RecordRerun(FallingBox(), tmp_path, episode_trigger=lambda k: True, run="box")
    env.reset(seed=0)
    heights = [env.step(env.action_space.sample())[0][2] for _ in range(5)]
    env.close()
    path = env.paths[0]
    _, height = temporal(path, "/height", "Scalars:scalars")
    np.testing.assert_array_equal(height.flatten().to_numpy(), heights)
    assert static_values(path, "/height", "SeriesLines:names") == ["box"]
    np.testing.assert_allclose(static_transform(path, "/world/goals/0"), [[0.0, 0.0, 0.02]])
    assert views_beside(path) == {"3D": ["/world"], "TimeSeries": ["/height"]}


def static_transform(path, entity: str) -> np.ndarray:
    """The static translation (1, 3) of ``entity``."""
    for chunk in RrdReader(path).stream().filter(is_static=True, content=entity):
        batch = chunk.to_record_batch()
        if "Transform3D:translation" in batch.schema.names:
            return rows(batch.column("Transform3D:translation"), 3)
    raise AssertionError(f"{path} has no static translation at {entity}")


def test_an_exception_in_step_leaves_a_complete_file_with_the_steps_so_far(tmp_path):
    env = RecordRerun(gym.make("rigid_gym/Push-v0"), tmp_path, episode_trigger=lambda k: True,
                      run="crash")
    env.reset(seed=0)
    for _ in range(6):
        env.step(env.action_space.sample())
    with pytest.raises(ValueError, match="action must be finite"):
        env.step(np.array([np.nan, 0.0, 0.0]))
    step, _ = temporal(env.paths[0], "/world/bodies/cube0", "Transform3D:translation")
    assert step.tolist() == list(range(7))
    assert verified(env.paths[0])


def test_close_after_the_episode_ended_returns_once_its_file_is_written(tmp_path):
    """The episode's end handed the file over: close() has no episode open, and still waits."""
    env = RecordRerun(gym.make("rigid_gym/Push-v0", max_episode_steps=5), tmp_path,
                      episode_trigger=lambda k: True, run="ended")
    env.reset(seed=0)
    for _ in range(5):
        truncated = env.step(env.action_space.sample())[3]
    assert truncated
    env.close()
    assert verified(env.paths[0])
    step, _ = temporal(env.paths[0], "/world/bodies/cube0", "Transform3D:translation")
    assert step.tolist() == list(range(6))


def test_a_process_that_dies_of_an_exception_leaves_a_complete_file(tmp_path):
    script = textwrap.dedent(f"""
        import gymnasium as gym
        import rigid_gym
        from rigid_gym.recording import RecordRerun
        env = RecordRerun(gym.make("rigid_gym/Throw-v0"), {str(tmp_path)!r},
                          episode_trigger=lambda k: True, run="died")
        env.reset(seed=0)
        for _ in range(5):
            env.step(env.action_space.sample())
        raise RuntimeError("the training loop crashed")
    """)
    result = subprocess.run([sys.executable, "-c", script], check=False, capture_output=True,
                            text=True)
    assert "the training loop crashed" in result.stderr
    path = tmp_path / "rigid_gym-Throw-v0" / "died-episode-0.rrd"
    step, _ = temporal(path, "/world/bodies/cube0", "Transform3D:translation")
    assert step.tolist() == list(range(6))


def test_a_process_killed_outright_still_gets_its_finished_episodes_written(tmp_path):
    """SIGKILL runs no atexit hook: the writer, left alone, completes the files it was handed
    (the finished episodes'; the open one's rows had not been handed over)."""
    script = textwrap.dedent(f"""
        import time
        import gymnasium as gym
        import rigid_gym
        from rigid_gym.recording import RecordRerun
        env = RecordRerun(gym.make("rigid_gym/Throw-v0", max_episode_steps=3),
                          {str(tmp_path)!r}, episode_trigger=lambda k: True, run="killed")
        for episode in range(2):
            env.reset(seed=episode)
            for _ in range(3):
                env.step(env.action_space.sample())
        env.reset(seed=2)
        env.step(env.action_space.sample())
        print("episode 2 under way", flush=True)
        time.sleep(60)
    """)
    with subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                          text=True) as process:
        assert process.stdout.readline() == "episode 2 under way\n"
        process.kill()
    folder = tmp_path / "rigid_gym-Throw-v0"
    for episode in range(2):
        path = folder / f"killed-episode-{episode}.rrd"
        for _ in range(600):  # the writer outlives the process: wait for it to finish (60 s
            if verified(path):  # at most: it may still be importing rerun on a busy machine)
                break
            time.sleep(0.1)
        step, _ = temporal(path, "/world/bodies/cube0", "Transform3D:translation")
        assert step.tolist() == [0, 1, 2, 3]


def interrupted_recording(folder, delay: float, episode_steps: int = 3) -> tuple[list, float]:
    """A process that records Throw episodes to ``folder`` endlessly, sent SIGINT on its
    whole process group (as a terminal sends Ctrl-C) ``delay`` s after its first recorded
    reset. Returns the files of the episodes it finished, once the writer has completed
    them, and the seconds the process took to exit after the signal.

    The process starts with SIGINT's default disposition, as a terminal's foreground job
    has: a process started in the background of a non-interactive shell (``pytest &`` in a
    script) inherits SIGINT ignored, and Python then never raises KeyboardInterrupt."""
    script = textwrap.dedent(f"""
        import signal
        signal.signal(signal.SIGINT, signal.default_int_handler)  # a foreground job's
        import gymnasium as gym
        import rigid_gym
        from rigid_gym.recording import RecordRerun
        env = RecordRerun(gym.make("rigid_gym/Throw-v0", max_episode_steps={episode_steps}),
                          {str(folder)!r}, episode_trigger=lambda k: True, run="interrupted")
        env.reset(seed=0)
        print("reset", flush=True)
        while True:
            for _ in range({episode_steps}):
                env.step(env.action_space.sample())
            print(env.paths[-1], flush=True)  # finished
            env.reset()
    """)
    process = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True, start_new_session=True)  # a group of its own
    assert process.stdout.readline() == "reset\n"
    time.sleep(delay)
    os.killpg(process.pid, signal.SIGINT)
    sent = time.perf_counter()
    finished, errors = process.communicate(timeout=120)
    took = time.perf_counter() - sent
    assert process.returncode == -signal.SIGINT, errors  # ended by the KeyboardInterrupt
    found = re.search(r"writer process \(pid (\d+)\) completes", errors)
    if found:  # the writer completes the files after the process has exited
        pid = int(found.group(1))
        while os.path.exists(f"/proc/{pid}") and "zombie" not in Path(
                f"/proc/{pid}/status").read_text(errors="replace"):
            time.sleep(0.05)
    return finished.split(), took


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("delay", [0.0, 0.1])
def test_ctrl_c_after_the_first_recorded_reset_loses_no_finished_episode(tmp_path, delay):
    """SIGINT while the writer process is still importing (0 and 0.1 s after the reset): it does
    not reach the writer, the process exits without waiting for it, and every episode the
    env finished is written once the writer has ended."""
    finished, _ = interrupted_recording(tmp_path, delay)
    assert finished or delay == 0.0
    for path in finished:
        assert verified(path), path


def test_a_writer_that_died_is_reported_not_ignored(tmp_path):
    from rigid_gym.recording_writer import writer

    env = RecordRerun(gym.make("rigid_gym/Throw-v0", max_episode_steps=2), tmp_path,
                      episode_trigger=lambda k: True, run="w")
    run_episode(env, seed=0)  # synced: written before the writer is killed
    dead = writer()
    dead.process.kill()
    dead.process.wait()
    assert verified(env.paths[0])
    with pytest.raises(RuntimeError, match=r"rerun writer process .* has ended \(exit code -9\)"):
        run_episode(env, seed=1)
    with pytest.raises(RuntimeError, match="rerun writer process .* has ended"):
        writer()  # a new recorder too: files handed to the dead writer may be lost
    dead.stop()  # acknowledged: the next recording starts a new writer
    fresh = RecordRerun(gym.make("rigid_gym/Throw-v0", max_episode_steps=2), tmp_path,
                        episode_trigger=lambda k: True, run="fresh")
    run_episode(fresh, seed=0)
    assert writer() is not dead
    assert (tmp_path / "rigid_gym-Throw-v0" / "fresh-episode-0.rrd").exists()


@pytest.fixture
def unwritable_folder(tmp_path):
    """A Push recorder's folder (``<folder>/rigid_gym-Push-v0``) in which no file can be made:
    read-only by its mode, or for root (whom modes do not stop) immutable (``chattr +i``); the
    test is skipped where neither holds."""
    folder = tmp_path / "unwritable" / "rigid_gym-Push-v0"
    folder.mkdir(parents=True)
    folder.chmod(0o555)
    immutable = (writable(folder) and shutil.which("chattr") is not None
                 and subprocess.run(["chattr", "+i", str(folder)],
                                    check=False, capture_output=True).returncode == 0)
    if writable(folder):
        folder.chmod(0o755)
        pytest.skip("no way to make a folder unwritable here")
    yield folder
    if immutable:
        subprocess.run(["chattr", "-i", str(folder)], check=False)
    folder.chmod(0o755)


def writable(folder) -> bool:
    """Whether a file can be made in ``folder`` (trying is the only test that holds for root)."""
    probe = folder / "probe"
    try:
        probe.touch()
    except OSError:
        return False
    probe.unlink()
    return True


@pytest.mark.parametrize("cause", ["unwritable folder", "name too long"])
def test_a_file_that_cannot_be_written_fails_alone_and_says_why(cause, tmp_path, request):
    """Beside a good recording open at the same time: the good file is complete, the bad
    recorder raises an OSError naming its file and the OS's reason, and the next recording
    works."""
    def recorder(folder, run):
        return RecordRerun(gym.make("rigid_gym/Push-v0", max_episode_steps=5), folder,
                           episode_trigger=lambda k: True, run=run)

    if cause == "unwritable folder":
        bad = recorder(request.getfixturevalue("unwritable_folder").parent, "bad")
        errnos = {errno.EACCES, errno.EPERM}
    else:
        bad = recorder(tmp_path / "bad", "b" * 300)  # 300 + "-episode-0.rrd" > 255 characters
        errnos = {errno.ENAMETOOLONG}
    good = recorder(tmp_path / "good", "good")
    bad.reset(seed=0)
    good.reset(seed=0)
    for _ in range(5):
        bad.step(bad.action_space.sample())  # its episode ends first, while good's is open
        good.step(good.action_space.sample())
    good.close()  # the bad file's error is not the good recorder's
    assert verified(good.paths[0])
    step, _ = temporal(good.paths[0], "/world/bodies/cube0", "Transform3D:translation")
    assert step.tolist() == list(range(6))
    with pytest.raises(OSError) as raised:
        bad.close()
    assert raised.value.errno in errnos
    message = str(raised.value)
    assert str(bad.paths[0]) in message and os.strerror(raised.value.errno) in message
    bad.close()  # raised once
    fresh = recorder(tmp_path / "fresh", "fresh")
    run_episode(fresh, seed=1)
    fresh.close()
    assert verified(fresh.paths[0])


def test_a_world_recorder_raises_the_error_of_its_file(tmp_path):
    from rigid_gym.recording_writer import writer

    world = rg.World(every_shape_scene(), dt=1 / 120)
    path = tmp_path / f"{'w' * 300}.rrd"
    recorder = WorldRecorder(world, path)
    recorder.record()
    with pytest.raises(OSError, match="File name too long"):
        recorder.close()
    # in a with block, the block's own exception goes first; the file's error is kept
    with pytest.raises(KeyError, match="the block's"), WorldRecorder(world, path) as recorder:
        recorder.record()
        raise KeyError("the block's")
    assert writer().failures.pop(str(path))[0] == errno.ENAMETOOLONG


def test_trigger_names_and_unfinished_episodes(tmp_path):
    env = RecordRerun(gym.make("rigid_gym/Throw-v0", max_episode_steps=2), tmp_path,
                      episode_trigger=lambda k: k % 2 == 0, run="r1")
    for episode in range(3):
        env.reset(seed=episode)
        for _ in range(2):
            env.step(env.action_space.sample())
    env.reset()  # episode 3 (not recorded) ...
    env.reset()  # ... and episode 4, left unfinished: close() completes it
    env.step(env.action_space.sample())
    env.close()
    folder = tmp_path / "rigid_gym-Throw-v0"
    assert sorted(p.name for p in folder.iterdir()) == [
        "r1-episode-0.rrd", "r1-episode-2.rrd", "r1-episode-4.rrd", "rigid_gym-Throw-v0.rbl"]
    step, _ = temporal(folder / "r1-episode-4.rrd", "/world/bodies/gripper",
                       "Transform3D:translation")
    assert step.tolist() == [0, 1]


def test_rerun_off_records_nothing_and_breaks_nothing(tmp_path, monkeypatch):
    monkeypatch.setenv("RERUN", "off")
    env = RecordRerun(gym.make("rigid_gym/Throw-v0", max_episode_steps=2), tmp_path,
                      episode_trigger=lambda k: True)
    run_episode(env, seed=0)
    env.close()
    with WorldRecorder(env.unwrapped.world, tmp_path / "world.rrd") as recorder:
        recorder.record()
    assert env.paths == [] and not any(tmp_path.rglob("*.rr[db]"))


# -- a World --------------------------------------------------------------------------------------

def every_shape_scene() -> rg.Scene:
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    shapes = [rg.Box((0.1, 0.2, 0.05)), rg.Sphere(0.1), rg.Capsule(0.05, 0.2), l_shape_mesh(),
              rg.Compound([(rg.Box((0.05, 0.05, 0.05)), rg.Pose((0.1, 0.0, 0.0))),
                           (rg.Sphere(0.05), rg.Pose((-0.1, 0.0, 0.0)))])]
    for k, shape in enumerate(shapes):
        scene.add_body(shape, density=500.0, position=(0.5 * k, 0.0, 0.5),
                       orientation=(np.cos(0.3), np.sin(0.3), 0.0, 0.0),
                       angular_velocity=(1.0, 2.0, 3.0), name=type(shape).__name__.lower())
    return scene


def test_a_world_recording_holds_every_body_pose_and_shape(tmp_path):
    world = rg.World(every_shape_scene(), dt=1 / 120, num_worlds=2)
    world.set_velocity("sphere", velocity=(1.0, 0.0, 0.0), world=1)
    path = tmp_path / "world.rrd"
    positions, orientations = [], []
    with WorldRecorder(world, path, world_index=1, contacts=True, chunk_steps=7) as recorder:
        for _ in range(20):
            recorder.record()
            positions.append(world.position[1].copy())
            orientations.append(world.orientation[1].copy())
            world.step()
    positions, orientations = np.array(positions), np.array(orientations)
    for body in world.scene.bodies[1:]:
        entity = f"/world/bodies/{body.name}"
        step, translation = temporal(path, entity, "Transform3D:translation")
        _, quaternion = temporal(path, entity, "Transform3D:quaternion")
        assert step.tolist() == list(range(20))
        np.testing.assert_array_equal(rows(translation, 3),
                                      positions[:, body.index].astype(np.float32))
        np.testing.assert_array_equal(rows(quaternion, 4),
                                      xyzw(orientations[:, body.index]).astype(np.float32))
    assert views_beside(path) == {"3D": ["/world"]}  # a World has no reward plot
    # 20 rows sent every 7 steps: in 3 chunks
    chunks = RrdReader(path).stream().filter(content="/world/bodies/box", is_static=False)
    assert len(list(chunks)) == 3
    counts = static_rows(path)
    for body, component in [("box", "Boxes3D:half_sizes"), ("sphere", "Ellipsoids3D:half_sizes"),
                            ("capsule", "Capsules3D:lengths"), ("mesh", "Mesh3D:vertex_positions"),
                            ("ground", "Mesh3D:vertex_positions"),
                            ("compound", "Boxes3D:half_sizes"),
                            ("compound", "Ellipsoids3D:half_sizes")]:
        assert counts[(f"/world/bodies/{body}", component)] == 1
    # geometry is in body-frame coordinates: the mesh's shape frame is offset from its body
    # frame (centre of mass, principal axes) by body_from_shape
    spec = world.scene.bodies[world.scene.index("mesh")]
    (chunk,) = RrdReader(path).stream().filter(content="/world/bodies/mesh", is_static=True,
                                                components="Mesh3D:vertex_positions")
    vertices = rows(chunk.to_record_batch().column("Mesh3D:vertex_positions"), 3)
    shape_vertices = spec.shape.vertices[spec.shape.triangles].reshape(-1, 3)
    np.testing.assert_allclose(vertices, spec.body_from_shape.apply(shape_vertices), atol=1e-6)
    assert np.linalg.norm(spec.body_from_shape.position) > 0.01
    # the compound's parts are placed by their poses, in the body frame
    spec = world.scene.bodies[world.scene.index("compound")]
    (chunk,) = RrdReader(path).stream().filter(content="/world/bodies/compound", is_static=True,
                                                components="Boxes3D:centers")
    np.testing.assert_allclose(rows(chunk.to_record_batch().column("Boxes3D:centers"), 3)[0],
                               spec.body_from_shape.apply([0.1, 0.0, 0.0]), atol=1e-6)


def test_a_closed_world_recorder_refuses_more_rows(tmp_path):
    world = rg.World(every_shape_scene(), dt=1 / 120)
    recorder = WorldRecorder(world, tmp_path / "w.rrd")
    recorder.record()
    recorder.close()
    recorder.close()  # idempotent
    with pytest.raises(ValueError, match="is closed"):
        recorder.record()


# -- SubprocVecEnv workers ------------------------------------------------------------------------

def make_recorded(rank: int, folder: str):
    def make():
        return RecordRerun(gym.make("rigid_gym/Throw-v0", max_episode_steps=4), folder,
                           episode_trigger=lambda k: True, run=f"worker{rank}")
    return make


def test_subproc_vec_env_workers_write_complete_files(tmp_path):
    """SB3's default start method (forkserver): streams are made in the workers."""
    from stable_baselines3.common.vec_env import SubprocVecEnv

    envs = SubprocVecEnv([make_recorded(rank, str(tmp_path)) for rank in range(2)])
    envs.seed(0)
    envs.reset()
    for _ in range(10):  # 2 whole episodes per worker, and a third one under way
        envs.step(np.stack([envs.action_space.sample() for _ in range(2)]))
    envs.close()
    folder = tmp_path / "rigid_gym-Throw-v0"
    for rank in range(2):
        for episode, length in [(0, 4), (1, 4), (2, 2)]:
            step, _ = temporal(folder / f"worker{rank}-episode-{episode}.rrd",
                               "/world/bodies/cube0", "Transform3D:translation")
            assert step.tolist() == list(range(length + 1))


# -- bad input ------------------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs, message", [
    ({"run": "a/b"}, "RecordRerun.run: must be a non-empty name"),
    ({"run": ""}, "RecordRerun.run: must be a non-empty name"),
    ({"episode_trigger": 3}, "RecordRerun.episode_trigger: expected a function"),
    ({"contacts": "yes"}, "RecordRerun.contacts: must be a bool"),
    ({"force_scale": -1.0}, "RecordRerun.force_scale: must be finite and > 0 m per N, got -1.0"),
    ({"chunk_steps": 0}, "RecordRerun.chunk_steps: must be an int >= 1, got 0"),
])
def test_bad_wrapper_arguments_are_refused(kwargs, message, tmp_path):
    with pytest.raises(ValueError, match=message.replace(".", r"\.").replace("(", r"\(")):
        RecordRerun(gym.make("rigid_gym/Push-v0"), tmp_path, **kwargs)


def test_only_rigid_gym_envs_and_worlds_can_be_recorded(tmp_path):
    with pytest.raises(ValueError, match="RecordRerun.env: expected a rigid_gym env, got "
                                         "CartPoleEnv"):
        RecordRerun(gym.make("CartPole-v1"), tmp_path)
    with pytest.raises(ValueError, match="WorldRecorder.world: expected a rigid_gym.World"):
        WorldRecorder(every_shape_scene(), tmp_path / "w.rrd")
    with pytest.raises(ValueError, match=r"world_index: must be an int in \[0, 0\], got 1"):
        WorldRecorder(rg.World(every_shape_scene(), dt=0.01), tmp_path / "w.rrd", world_index=1)


def test_by_default_episodes_0_1_8_27_and_so_on_are_recorded():
    from rigid_gym.recording import cubic_schedule

    assert [k for k in range(3001) if cubic_schedule(k)] == [
        0, 1, 8, 27, 64, 125, 216, 343, 512, 729, 1000, 2000, 3000]
