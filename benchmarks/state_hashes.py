"""Fingerprints of trajectories: a sha256 of every state array after stepping each benchmark
scene and each task, to show that a change of the core's code left every trajectory bit for
bit as it was (compare the output before and after the change).

Scenes (dt = 1/240, ``rigid_gym.report.scenes``): the 10-cube stack and the 55-box pyramid
(sleeping on and off), the pyramid beside a rolling ball, piles of 10, 100 and 1000 falling
and settling (sleeping exact, off, and stopping slow islands), a batch of perturbed piles
stepped on the calling thread and shared out over the pool, the stages switched off one by
one, the other rotation orders, a change of dt and of materials in mid-run, gravity off the axes,
and one world timed (``profile=True``). Tasks: Push, Stack and Throw under their scripted policies through
``gym.make`` and ``gym.make_vec`` (B = 8). Each line: the case, the sha256 of its state,
listed pairs, impulses and sleeping flags, and that of its stage counts.

    python benchmarks/state_hashes.py            # every case (about a minute on 2 cores)
    python benchmarks/state_hashes.py --quick    # the cheaper half
"""

import argparse
import hashlib

import gymnasium as gym
import numpy as np
from rigid_gym._core import DYNAMIC
from rigid_gym.envs.scripted import scripted_policy

import rigid_gym as rg
from rigid_gym.report.scenes import cube_stack, pile, pyramid, pyramid_and_ball

DT = 1 / 240


def world_digest(world: rg.World) -> tuple[str, str]:
    """sha256 of the world's state, pairs, impulses and sleeping flags; sha256 of its stage
    counts."""
    h = hashlib.sha256()
    for array in world.state:
        h.update(np.ascontiguousarray(array).tobytes())
    for w in range(world.num_worlds):
        for array in world.core.pairs(w):
            h.update(np.ascontiguousarray(array).tobytes())
    h.update(world.core.asleep.tobytes())
    calls = hashlib.sha256(world.core.stage_calls.tobytes()).hexdigest()
    return h.hexdigest()[:16], calls[:16]


def scene_cases(quick: bool):
    """(name, function returning a stepped World) for each scene case."""
    def run(scene, steps, num_worlds=None, shared=None, perturb=False, profile=False,
            **config):
        def go():
            world = rg.World(scene, dt=DT, num_worlds=num_worlds, profile=profile,
                             config=rg.SolverConfig.for_scene(scene, **config))
            if perturb:
                rng = np.random.default_rng(1)
                for i, body in enumerate(scene.bodies):
                    if body.motion == DYNAMIC:
                        world.set_velocity(i, rng.normal(0.0, 0.3, (world.num_worlds, 3)))
            if shared is not None:
                world.core.force_sharing(shared)
            world.step(steps)
            return world
        return go

    def changing():
        scene = pile(10)
        world = rg.World(scene, dt=DT, config=rg.SolverConfig.for_scene(scene, sleep_speed=0.01))
        world.step(300)
        world.set_material(len(scene) - 1, mass=2.0, friction=0.3)
        world.step(100)
        world.dt = DT / 2
        world.step(100)
        world.apply_force(len(scene) - 2, (0.0, 0.0, 3.0))
        world.step(50)
        return world

    stack, pyr, ball, pile10 = cube_stack(10), pyramid(10), pyramid_and_ball(10, -1.0), pile(10)
    tilted = pile(10)
    tilted.gravity = np.array([1.3, -0.7, -9.6])
    cases = [
        ("stack", run(stack, 480)),
        ("stack, no sleep", run(stack, 480, sleep=False)),
        ("stack, timed", run(stack, 300, profile=True)),
        ("pile 10", run(pile10, 480)),
        ("pile 10, no sleep", run(pile10, 480, sleep=False)),
        ("pile 10, sleep speed", run(pile10, 480, sleep_speed=0.01)),
        ("pile 10, no collision phase", run(pile10, 240, collision_passes=0)),
        ("pile 10, no contact phase", run(pile10, 240, contact_passes=0)),
        ("pile 10, no shock", run(pile10, 240, shock_sweeps=0)),
        ("pile 10, no stages", run(pile10, 60, collision_passes=0, contact_passes=0,
                                   shock_sweeps=0)),
        ("pile 10, every pass", run(pile10, 120, detect_every_pass=True)),
        ("pile 10, no overlap, order 1", run(pile10, 240, overlap_correction=0.0,
                                             rotation_order=1, keep_energy=False)),
        ("pile 10, order 3, brute force", run(pile10, 240, rotation_order=3, sweep=False)),
        ("pile 10, changes", changing),
        ("pile 10, tilted gravity", run(tilted, 240)),
        ("pile 10 x 8, alone", run(pile10, 240, num_worlds=8, shared=False, perturb=True)),
        ("pile 10 x 8, shared", run(pile10, 240, num_worlds=8, shared=True, perturb=True)),
        ("pile 10 x 8, shared, speed", run(pile10, 240, num_worlds=8, shared=True,
                                           perturb=True, sleep_speed=0.01)),
    ]
    if not quick:
        cases += [
            ("pyramid", run(pyr, 360)),
            ("pyramid, no sleep", run(pyr, 360, sleep=False)),
            ("pyramid and ball", run(ball, 360)),
            ("pile 100", run(pile(100), 300)),
            ("pile 100, sleep speed", run(pile(100), 300, sleep_speed=0.01)),
            ("pile 1000", run(pile(1000), 6)),
        ]
    return cases


def task_digest(env_id: str, num_envs: int | None, episodes: int) -> tuple[str, str]:
    """Run ``episodes`` episodes of ``env_id`` under its scripted policy (one env through
    gym.make, or ``num_envs`` through gym.make_vec) and digest the observations and the
    final World."""
    policy = scripted_policy(gym.make(env_id))
    h = hashlib.sha256()
    if num_envs is None:
        env = gym.make(env_id)
        observation, _ = env.reset(seed=3)
        for _ in range(episodes * env.spec.max_episode_steps):
            observation, reward, terminated, truncated, _ = env.step(policy(observation))
            h.update(observation["observation"].tobytes() + np.float64(reward).tobytes())
            if terminated or truncated:
                observation, _ = env.reset()
        world = env.unwrapped.world
    else:
        envs = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point")
        observations, _ = envs.reset(seed=3)
        for _ in range(episodes * envs.unwrapped.max_episode_steps):
            actions = np.array([policy({k: v[i] for k, v in observations.items()})
                                for i in range(num_envs)], dtype=np.float32)
            observations, rewards, *_ = envs.step(actions)
            h.update(observations["observation"].tobytes() + rewards.tobytes())
        world = envs.unwrapped.world
    state, calls = world_digest(world)
    return h.hexdigest()[:16] + " " + state, calls


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the cheaper half of the cases")
    args = parser.parse_args()
    for name, make in scene_cases(args.quick):
        state, calls = world_digest(make())
        print(f"{name:32s} {state} calls {calls}", flush=True)
    for task in ("Push", "Stack", "Throw"):
        for num_envs in (None, 8):
            state, calls = task_digest(f"rigid_gym/{task}-v0", num_envs, 1 if args.quick else 2)
            label = f"{task}, " + ("make" if num_envs is None else f"make_vec {num_envs}")
            print(f"{label:32s} {state} calls {calls}", flush=True)


if __name__ == "__main__":
    main()
