"""The batched core of every env: B copies of a task in one World, every array with a
leading axis of B copies. ``gym.make`` runs a batch of one (B = 1, an unbatched World) and
``gym.make_vec`` a batch of B (a batched World), through the same code: copy i of a batch
plays exactly what a single env reset with the same seed plays.

    core = TaskBatch(Push(), options, num_worlds=256, name="PushEnv")
    first = core.reset(ALL, rngs)          # Outcome of every copy's new episode
    outcome = core.step(actions)           # actions (B, a), checked and clipped

Each copy draws from its own generator (``rngs[i]``: the randomisation factors, then the
cubes' starts, the fixtures, the goal, and per observation its noise), in the order one env
alone draws them. Resets write an episode into the World that exists (no Scene is built,
nor geometry compiled, except when sizes are randomised); a step commands every gripper at
once, runs SOLVER_STEPS solver steps of all worlds in one call and observes all copies.
"""

from __future__ import annotations

import copy
from typing import NamedTuple

import numpy as np
from gymnasium.error import ResetNeeded
from rigid_gym._core import gather_observations

from rigid_gym.config import SolverConfig
from rigid_gym.scene import Scene
from rigid_gym.world import World

from .effector import FloatingEffector
from .gripper import EFFECTOR_CLASSES
from .observation import gather_index
from .options import Options
from .pixels import CopyFrames
from .task import (
    CUBE_HALF,
    CUBE_MASS,
    FRICTION,
    SOLVER_STEPS,
    STEP_TIME,
    Task,
    sparse_reward,
)

ALL = slice(None)
"""Every copy of a batch, where methods take the copies to act on."""


class Outcome(NamedTuple):
    """What copies observe after a reset or a step: ``observations`` {"observation",
    "achieved_goal", "desired_goal"} of float32 (k, ...) arrays, ``rewards`` (k,) float64,
    ``successes`` (k,) bool and ``terminated`` (k,) bool (success, where the episode ends
    on success). After a reset the rewards are those of the start state."""

    observations: dict
    rewards: np.ndarray
    successes: np.ndarray
    terminated: np.ndarray


class TaskBatch:
    """B copies of ``task`` with the checked ``options``, in one World.

    num_worlds: None for a single env (B = 1, an unbatched World, whose properties show no
        world axis) or B >= 1 copies. name: the env's class name, for errors.
    ``build`` makes the World: a vector env's at its construction, a single env's at its
    first reset and again at every reset where sizes are randomised (only a batch of one
    can randomise them: the copies of a World share its geometry).

    State, every array with the leading copy axis: ``goals`` (B, goal_size) m, ``half``
    (B, cubes) m the cubes' half edges, ``places`` (B, fixtures, 3) m, ``released`` (B,)
    bool whether the effector has let go of an object it held this episode (the shaped
    reward's memory: Throw pays for the throw, not the hold), ``rngs`` (B,) each copy's
    generator (None until its first reset); the World, its ``gripper`` (the task's effector:
    a SuctionGripper, or a ParallelGripper with ``effector="gripper"``) and the body indices
    ``cubes``, ``fixtures``, ``table``, ``gripper_body`` (the pad, or the hand) and
    ``gripper_bodies`` (with the fingers).
    """

    def __init__(self, task: Task, options: Options, num_worlds: int | None, name: str):
        self.task, self.options, self.name = task, options, name
        self.batched = num_worlds is not None
        b = 1 if num_worlds is None else int(num_worlds)
        self.num_worlds = b
        self.rngs: list = [None] * b
        self.goals = np.zeros((b, task.goal_size))
        self.half = np.full((b, task.num_cubes), CUBE_HALF)
        self.places = np.zeros((b, task.num_fixtures, 3))
        self.released = np.zeros(b, dtype=bool)
        # the goals as observed (float32), and as the goal test reads them (float64 of those)
        self.desired = np.zeros((b, task.goal_size), dtype=np.float32)
        self.desired64 = np.zeros((b, task.goal_size))
        self.world: World | None = None
        self.scene: Scene | None = None
        self.gripper: FloatingEffector | None = None
        self.cubes: list[int] = []
        self.fixtures: list[int] = []
        self.gripper_bodies: list[int] = []
        self.table = self.gripper_body = -1
        self.frames: CopyFrames | None = None  # the copies' pixels, when observed
        # how observe reads the World's state (made with the World from the task's layout:
        # gather_index), and where the holding flag and the fingers' opening lie in an
        # observation
        layout = task.observation_layout
        empty = np.zeros(0, dtype=np.int64)
        self.gather, self.minus = empty, empty
        self.holding = layout.slice("holding") if task.has_grip else None
        self.width = layout.slice("fingers.width") if "fingers.width" in layout.slices \
            else None
        self.all_worlds = np.arange(b, dtype=np.int64)

    # -- the World --------------------------------------------------------------------------

    def build(self, half: np.ndarray) -> None:
        """The Scene and World of cubes with half edges ``half`` (cubes,) m (boxes of the
        task's ``half_extents``), and the body indices. Cubes get the nominal mass and
        friction (a reset sets each episode's through ``set_material``, so a new World and a
        reused one reach an episode by the same arithmetic); poses are the resets'. Restitution is the top of its randomisation
        range: > 0 puts the collision phase into the World's config for every episode."""
        restitution = self.options.randomization.get("restitution", (0.0, 0.0))[1]
        scene = Scene()
        task = self.task
        self.table = scene.add_ground(friction=task.table_friction, name="table")
        extents = task.half_extents(half)
        self.cubes = [scene.add_body(task.object_shape(e), mass=CUBE_MASS,
                                     position=(0.0, 0.0, e[2]), friction=task.object_friction,
                                     restitution=restitution, name=f"cube{k}")
                      for k, e in enumerate(extents.tolist())]
        effector = EFFECTOR_CLASSES[task.effector]
        self.gripper_bodies = effector.add_to(scene)
        self.gripper_body = self.gripper_bodies[0]
        self.fixtures = self.task.add_fixtures(scene)
        self.scene = scene
        # compiles the scene's geometry, which later resets reuse
        self.world = World(scene, dt=STEP_TIME / SOLVER_STEPS,
                           num_worlds=self.num_worlds if self.batched else None,
                           config=SolverConfig.for_scene(scene, **effector.solver_settings))
        self.gripper = effector(self.world, self.gripper_bodies, self.cubes, extents, STEP_TIME,
                                [(i, scene.bodies[i].shape, scene.bodies[i].body_from_shape)
                                 for i in self.fixtures])
        bodies = {task.observation_layout.effector: self.gripper_body} | {
            f"cube{k}": c for k, c in enumerate(self.cubes)}
        self.gather, self.minus = gather_index(self.task.observation_layout, len(scene.bodies),
                                               bodies)
        if self.options.pixels.pixels:
            self.frames = CopyFrames(scene, self.task, half, self.options.pixels,
                                     self.num_worlds, self.cubes)

    def copy(self, *carried):
        """A deep copy of this batch (its World, gripper, goals, generators, frames) and of
        ``carried`` (what the env keeps beside it: its generator, step counts), in one copy so
        that what they share (a single env's generator is its copy's) stays shared; the task
        and the options, which never change, are not copied. What ``save_state`` keeps and
        ``restore_state`` puts back (as a copy again, so a state restores any number of
        times)."""
        memo = {id(self.task): self.task, id(self.options): self.options}
        return copy.deepcopy((self, *carried), memo)

    def built(self) -> tuple[World, FloatingEffector]:
        """The World and its gripper, which the first reset builds."""
        if self.world is None or self.gripper is None:
            raise ResetNeeded(f"{self.name}: call reset() first (it builds the World)")
        return self.world, self.gripper

    # -- episodes ---------------------------------------------------------------------------

    def reset(self, copies, rngs: list) -> Outcome:
        """Start a new episode in ``copies`` (ALL, or an int array of copy indices), copy
        ``copies[i]`` drawing from ``rngs[i]`` (kept as its generator); returns their
        Outcome."""
        rows = np.arange(self.num_worlds)[copies]
        for row, rng in zip(rows.tolist(), rngs):
            self.rngs[row] = rng
        ranges = self.options.randomization
        n = self.task.num_cubes
        # one factor per body and quantity: bodies are the cubes, then the gripper and table
        factors = {name: np.array([rng.uniform(low, high, size=n + 2) for rng in rngs])
                   for name, (low, high) in ranges.items()}
        half = CUBE_HALF * factors["size"][:, :n] if "size" in ranges \
            else np.full((len(rngs), n), CUBE_HALF)
        starts = self.task.place_cubes(rngs, half)
        places = self.task.place_fixtures(rngs, starts)
        if self.world is None or "size" in ranges:
            self.build(half[0])
        self.write(copies, rows, starts, places, factors)
        self.half[copies] = half
        self.places[copies] = places
        self.released[copies] = False
        goals = self.task.sample_goals(rngs, starts, half, places)
        self.goals[copies] = goals
        self.desired[copies] = goals
        self.desired64[copies] = self.desired[copies]
        if self.frames is not None:
            self.frames.place(rows, goals, half)
        return self.observe(copies)

    def write(self, copies, rows: np.ndarray, starts: np.ndarray, places: np.ndarray,
              factors: dict) -> None:
        """Write the episodes drawn for ``copies`` (their indices ``rows``) into the World:
        the scene's start (the gripper's pose, nothing moving, nothing held, time 0 when every
        copy starts over), then the cubes' starts (k, cubes, 3) m, the fixtures' places
        (k, fixtures, 3) m and, when randomised, the drawn materials (``factors`` {name:
        (k, cubes + 2)}). Every copy at once takes one call per body (the World's setters
        take (B, ...) values for all worlds); some copies take one each."""
        (w, gripper), n = self.built(), self.task.num_cubes
        if factors:  # factors of 1 (restitution 0) for what is not randomised
            one = np.ones((len(rows), n + 2))
            mass = CUBE_MASS * factors.get("mass", one)
            friction = factors.get("friction", one) * np.array(
                [self.task.object_friction] * n + [FRICTION, self.task.table_friction])
            restitution = factors.get("restitution", np.zeros_like(one))
        targets = [(None, ALL)] if copies is ALL else list(zip(rows.tolist(), range(len(rows))))
        for world, k in targets:
            w.reset(world)
            for j, body in enumerate(self.cubes):
                w.set_pose(body, starts[k, j], world=world)  # a cube's centre of mass is its centre
            for j, body in enumerate(self.fixtures):
                w.set_pose(body, places[k, j], world=world)
            if factors:
                for j, cube in enumerate(self.cubes):
                    w.set_material(cube, mass=mass[k, j], friction=friction[k, j],
                                   restitution=restitution[k, j], world=world)
                for body in self.gripper_bodies:  # the pad, or the hand and its fingers
                    w.set_material(body, friction=friction[k, n], world=world)
                w.set_material(self.table, friction=friction[k, n + 1], world=world)
        gripper.forget(copies)

    def step(self, actions: np.ndarray) -> Outcome:
        """One env step of every copy: ``actions`` (B, action size), checked and clipped to
        [-1, 1], command the grippers (noting the copies that let go: ``released``); the
        solver runs SOLVER_STEPS steps of every world in one call (held objects carried in
        it); returns every copy's Outcome."""
        world, gripper = self.built()
        grips = actions[:, 3] if self.task.has_grip else None
        shaped = self.options.reward_type == "shaped"  # the only reader of ``released``
        holding = gripper.grasp(ALL)[0] >= 0 if shaped else None
        gripper.command(actions[:, :3], grips)
        world.step(SOLVER_STEPS)
        if holding is not None:  # after the step: the fingers open over its solver steps
            self.released |= holding & (gripper.grasp(ALL)[0] < 0)
        return self.observe(ALL)

    # -- observations and rewards -----------------------------------------------------------

    def observe(self, copies) -> Outcome:
        """The Outcome of ``copies`` (ALL, or an int array) in their current state.

        observation: the fields of the task's ``observation_layout`` (the pad's or the hand's
        state, whether it holds a cube, the fingers' opening, each cube's state);
        achieved_goal: the cubes' positions (their ``cube<k>.position`` fields). Computed in
        float64, checked finite, noise added, then cast to float32; the goal test and the
        reward read the float32 goals, exactly as ``compute_reward`` sees them. With pixels (``obs_mode``), ``pixels`` holds the
        copies' frames (k, height, width, 3) uint8, and "pixels" mode leaves out
        ``observation``."""
        world, gripper = self.built()
        worlds = self.all_worlds[copies]
        s = world.state
        vectors = np.empty((len(worlds), len(self.gather)))
        finite = gather_observations(s.position, s.velocity, s.rotation, s.angular_velocity,
                                     worlds, self.gather, self.minus, vectors)
        held, width = gripper.grasp(worlds) if self.holding is not None else (None, None)
        if held is not None:
            vectors[:, self.holding] = (held >= 0)[:, None]
        if width is not None:
            vectors[:, self.width] = width[:, None]
        if not finite:  # a solver failure: say so here, not in a network
            self.refuse_non_finite(vectors, worlds)
        achieved = self.task.achieved_goal(vectors, s, worlds, self.cubes).astype(np.float32)
        clean = vectors  # the true state (noise makes a new array)
        noise = self.options.observation_noise
        if noise > 0.0:
            rngs = [self.rngs[i] for i in worlds.tolist()]
            vectors = vectors + np.array([rng.normal(0.0, noise, vectors.shape[1])
                                          for rng in rngs])
        achieved64 = achieved.astype(np.float64)
        desired64 = self.desired64[copies]
        successes = self.task.goal_reached(achieved64, desired64)
        if self.options.reward_type == "sparse":
            rewards = sparse_reward(successes)  # from the test just made
        elif self.options.reward_type == "shaped":
            if held is None:  # a task without a grip holds nothing
                held = np.full(len(worlds), -1, dtype=np.int64)
            finished = successes & (held < 0) if self.task.finished_by_letting_go \
                else successes
            rewards = np.where(finished, 1.0, self.task.shaped(
                clean, held, achieved64, desired64, self.half[copies], self.released[copies]))
        else:
            rewards = self.task.reward(achieved64, desired64, "dense")
        observations = {"observation": vectors.astype(np.float32), "achieved_goal": achieved,
                        "desired_goal": self.desired[copies].copy()}
        if self.frames is not None:
            observations["pixels"] = self.frames.draw(s, worlds)
            if not self.options.pixels.state:
                del observations["observation"]
        terminated = successes.copy() if self.options.terminate_on_success \
            else np.zeros(len(worlds), dtype=bool)
        return Outcome(observations, rewards, successes, terminated)

    def refuse_non_finite(self, vectors: np.ndarray, worlds: np.ndarray) -> None:
        """Raise the RuntimeError that names the first copy with a non-finite entry in its
        observation ``vectors`` (k, size) of copies ``worlds`` (k,), which has one."""
        finite = np.isfinite(vectors).all(axis=1)
        row = int(np.flatnonzero(~finite)[0])
        copy = int(worlds[row])
        bad = np.flatnonzero(~np.isfinite(vectors[row])).tolist()
        which = f" (copy {copy})" if self.num_worlds > 1 else ""
        raise RuntimeError(f"{self.name}{which}: the simulation produced non-finite state "
                           f"(observation entries {bad}) at t = {self.built()[0].time:.3f} s")

    def compute_reward(self, achieved_goal, desired_goal) -> np.ndarray:
        """The reward of goals of shape (..., goal_size) -> (...) float64 (``Task.reward``
        with the options' reward type); the shaped reward reads more than the goals, so it has
        none (a ValueError)."""
        if self.options.reward_type == "shaped":
            raise ValueError(f"{self.name}.compute_reward: the shaped reward reads the pad and "
                             "the grip as well as the goals, so it cannot be recomputed from "
                             "goals (as HER does); use reward_type 'sparse' or 'dense' there")
        return self.task.reward(np.asarray(achieved_goal, dtype=np.float64),
                                np.asarray(desired_goal, dtype=np.float64),
                                self.options.reward_type)

    def markers(self, copy: int = 0) -> list:
        """The goal markers of ``copy``'s episode (``Task.markers``)."""
        return self.task.markers(self.goals[copy], self.half[copy])

