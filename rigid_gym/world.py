"""World: the state arrays of one or many copies of a scene, step(), and queries.

    world = rg.World(scene, dt=1/240)                  # arrays (n, 3), (n, 4) ...
    world = rg.World(scene, dt=1/240, num_worlds=256)  # arrays (256, n, 3), (256, n, 4) ...
    world.step(240)

State is held per body at the centre of mass in the principal frame (see ``rigid_gym.scene``).
Every array has a leading world axis internally; a world built without ``num_worlds`` shows it
dropped. The arrays live in the compiled core (``World.core``, a ``rigid_gym._core.Batch``
that owns every buffer the step uses); ``World.state`` and ``World.model`` are numpy views of
them. ``World.model`` and the arrays returned by properties are read-only views: change them
with the setters (``set_material`` for masses and materials), which validate their input
before anything reaches the core and wake the bodies they change (a sleeping body's step is
skipped on the grounds that nothing about it changed). ``save_state``/``restore_state``,
``copy.deepcopy`` and ``pickle`` snapshot a World (``rigid_gym.snapshots``).
"""

from __future__ import annotations

import copy
import dataclasses
from typing import NamedTuple

import numpy as np

from rigid_gym import _core
from rigid_gym import quaternion as quat
from rigid_gym._core import DYNAMIC, STATIC
from rigid_gym.checks import in_range, integer
from rigid_gym.collision import Contacts, uses_sweep
from rigid_gym.config import SolverConfig
from rigid_gym.geometry import compile_geometry, max_pair_contacts
from rigid_gym.joints import FIXED, REVOLUTE, joint_model, joint_settings, limits_of
from rigid_gym.scene import Scene
from rigid_gym.shapes import Compound, Mesh
from rigid_gym.snapshots import SavedStates


class State(NamedTuple):
    """Everything that changes during a step. B worlds, n bodies, float64.

    position (B, n, 3) m; orientation (B, n, 4) (w, x, y, z); velocity (B, n, 3) m/s;
    angular_momentum (B, n, 3) kg m^2/s about the centre of mass, world frame;
    angular_velocity (B, n, 3) rad/s (derived from L for dynamic bodies, set for kinematic);
    rotation (B, n, 3, 3) R(q), derived; force (B, n, 3) N and torque (B, n, 3) N m applied
    during the next step and then cleared.
    """

    position: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    angular_momentum: np.ndarray
    angular_velocity: np.ndarray
    rotation: np.ndarray
    force: np.ndarray
    torque: np.ndarray


class Attachments(NamedTuple):
    """Bodies held rigidly by another (``World.attach``), leading world axis B: parent (B, n)
    int32 (-1: free), offset_position (B, n, 3) m in the parent's frame, offset_orientation
    (B, n, 4) relative to the parent's."""

    parent: np.ndarray
    offset_position: np.ndarray
    offset_orientation: np.ndarray


class JointImpulses(NamedTuple):
    """What each joint transmitted to its body_a over the last step, leading world axis
    where batched: impulse ([B,] J, 3) N s and angular_impulse ([B,] J, 3) N m s about a's
    centre of mass (world frame), both including the pre-stabilisation's share; motor
    ([B,] J) N m s or N s, the motor's part along the joint's axis (within max_motor dt)."""

    impulse: np.ndarray
    angular_impulse: np.ndarray
    motor: np.ndarray


class Model(NamedTuple):
    """What stays fixed while stepping.

    motion (n,) int32 STATIC/KINEMATIC/DYNAMIC; inverse_mass (B, n) 1/kg;
    inverse_moments (B, n, 3) principal 1/kg m^2; friction (B, n) and restitution (B, n)
    per body (a pair uses sqrt(mu_a mu_b) and max(e_a, e_b)); gravity (3,) m/s^2.
    Per-body parameters carry a world axis so they can differ between worlds.
    """

    motion: np.ndarray
    inverse_mass: np.ndarray
    inverse_moments: np.ndarray
    friction: np.ndarray
    restitution: np.ndarray
    gravity: np.ndarray


class World:
    """A scene being simulated with a fixed time step ``dt`` (s).

    num_worlds: None for one world (arrays without the world axis) or B >= 1 identical copies
        stepped together (arrays with a leading axis of length B).
    config: a SolverConfig; default ``SolverConfig.for_scene(scene)``.
    profile: True times each stage of every step (``World.profile()``, ``World.profiling``);
        the step is the same, with a clock read per stage (20-100 ns each, a share of a
        small scene's step of a few microseconds). Stage calls are counted either way.
    """

    def __init__(self, scene: Scene, dt: float = 1.0 / 240.0, num_worlds: int | None = None,
                 config: SolverConfig | None = None, profile: bool = False):
        if not isinstance(scene, Scene):
            raise ValueError(f"World: scene must be a rigid_gym.Scene, got {type(scene).__name__}")
        if len(scene) == 0:
            raise ValueError("World: the scene has no bodies")
        try:
            dt = float(dt)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"World.dt: expected a number of seconds, got {dt!r}") from exc
        if not np.isfinite(dt) or dt <= 0.0:
            raise ValueError(f"World.dt: must be finite and > 0 s, got {dt!r}")
        self.scene = scene
        self.dt = dt
        self.batched = num_worlds is not None
        self.num_worlds = 1 if num_worlds is None else integer(num_worlds, "World.num_worlds", 1,
                                                                other="None")
        self.config = SolverConfig.for_scene(scene, dt) if config is None else config
        self._config_from_scene = config is None
        if not isinstance(profile, bool):
            raise ValueError(f"World.profile: must be True or False, got {profile!r}")
        self.geometry = compile_geometry(scene.bodies, self.config.box_edge_segments)
        motion = np.array([b.motion for b in scene.bodies], dtype=np.int32)
        sweep = uses_sweep(self.geometry.body_unbounded, self.config.sweep)
        self._bind(_core.Batch(self.num_worlds, self.geometry._asdict(), motion,
                               tuple(scene.gravity.tolist()), self.config.settings(sweep),
                               max_pair_contacts(self.geometry)))
        if scene.joints:
            if self.config.joint_passes == 0:
                raise ValueError("World: the scene has joints but config.joint_passes is 0 "
                                 "(the joint stages off); give joint_passes >= 1")
            self.core.set_joints(*joint_model(scene.joints))
            self._load_joint_settings(scene, slice(None))
        for current, new in zip(self._materials(), _build_model(scene, self.num_worlds)[1:5]):
            current[...] = new
        for current, new in zip(self.state, _build_state(scene, self.num_worlds)):
            current[...] = new
        self._refresh_derived()
        self._initial_state = tuple(a.copy() for a in self.state)
        self.steps = 0
        self.profiling = profile
        self.saved: SavedStates[tuple[_core.Batch, int]] = SavedStates("World")
        """The states kept by ``save_state``: (a copy of the core, the step count) by id."""

    def _bind(self, core: _core.Batch) -> None:
        """Own ``core`` and name its arrays: ``state``, ``model`` (read-only views) and
        ``attached``."""
        self.core = c = core
        self.state = State(**{name: getattr(c, name) for name in _core.STATE})
        self.model = Model(np.array([b.motion for b in self.scene.bodies], dtype=np.int32),
                           *self._materials(), self.scene.gravity.copy())
        for array in self.model:  # read-only through this name; set_material writes the core's
            array.flags.writeable = False
        self.attached = Attachments(*(getattr(c, name) for name in _core.ATTACHMENTS))

    # -- snapshots ---------------------------------------------------------------------------

    def save_state(self) -> int:
        """Keep a copy of everything that decides the next steps (every world's state, model
        and attachments, the time, and what the solver carries from step to step: sleeping's
        bookkeeping, the broad phase's order) and return its id (an int), as PyBullet's
        ``saveState`` (panda-gym's ``sim.save_state``) does."""
        return self.saved.save((self.core.copy(), self.steps))

    def restore_state(self, state_id: int) -> None:
        """Put the World back, in place, to the state saved as ``state_id`` (``save_state``),
        which stays saved: from there every world steps on bit for bit as it did then. Arrays
        read from this World before (``state``, ``position``, ...) stay its views."""
        core, steps = self.saved.get(state_id, "restore_state")
        self.core.assign(core)
        self.steps = steps

    def remove_state(self, state_id: int) -> None:
        """Forget the state saved as ``state_id``, freeing its memory."""
        self.saved.remove(state_id)

    def __deepcopy__(self, memo: dict) -> World:
        """An independent World in the same state as this one, saved states included, that
        steps on bit for bit as this one does (the core's every buffer is copied)."""
        copied = object.__new__(World)
        memo[id(self)] = copied
        for name, value in self.__dict__.items():
            if name not in ("core", "state", "model", "attached", "saved"):
                copied.__dict__[name] = copy.deepcopy(value, memo)
        copied._bind(self.core.copy())
        copied.saved = copy.copy(self.saved)
        copied.saved.states = {k: (core.copy(), steps)
                               for k, (core, steps) in self.saved.states.items()}
        return copied

    def __getstate__(self) -> dict:
        """What pickle stores: the arguments that build this World again and the arrays of its
        state, model and attachments (and of each saved state). A new core starts with no
        sleeping bookkeeping, which changes nothing when ``sleep_speed`` is 0 (sleeping is
        then exact: ``src/solver/sleep.h``); with ``sleep_speed`` > 0 the bodies' slow time
        lives in the core only, so such a World refuses to be pickled (copy.deepcopy and
        save_state keep it). The step and stage counts of ``profile()`` start again at 0."""
        if self.config.sleep and self.config.sleep_speed > 0.0:
            raise ValueError("World: a World with SolverConfig.sleep_speed > 0 cannot be "
                             "pickled (the time each body has moved slowly lives in the core); "
                             "use copy.deepcopy or World.save_state within the process")
        built = {"scene": self.scene, "dt": self.dt,
                 "num_worlds": self.num_worlds if self.batched else None,
                 "config": None if self._config_from_scene else self.config,
                 "profile": self.profiling}
        return {"built": built, "steps": self.steps, "arrays": _core_arrays(self.core),
                "saved": {k: (_core_arrays(core), steps)
                          for k, (core, steps) in self.saved.states.items()},
                "next_state_id": self.saved.next_id}

    def __setstate__(self, state: dict) -> None:
        World.__init__(self, **state["built"])
        _write_core_arrays(self.core, state["arrays"])
        self.steps = state["steps"]
        for k, (arrays, steps) in state["saved"].items():
            core = self.core.copy()
            _write_core_arrays(core, arrays)
            self.saved.states[k] = (core, steps)
        self.saved.next_id = state["next_state_id"]

    # -- stepping ----------------------------------------------------------------------------

    def step(self, n: int = 1) -> None:
        """Advance every world by ``n`` steps of ``dt``. Forces and torques set with
        ``apply_force``/``apply_torque`` act during the next step only."""
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
            raise ValueError(f"World.step: n must be an int >= 0, got {n!r}")
        if n == 0:
            return
        self.core.step(int(n), self.dt)
        self.steps += int(n)

    def reset(self, world: int | None = None) -> None:
        """Put every world (or only ``world``) back to the scene's initial state; the step
        count (``time``) goes back to 0 only when every world is reset."""
        worlds = self._worlds(world, "reset")
        for current, initial in zip(self.state, self._initial_state):
            current[worlds] = initial[worlds]
        self.attached.parent[worlds] = -1
        self.core.forget(*self._range(worlds))
        if world is None:
            self.steps = 0

    def load(self, scene: Scene, world: int | None = None) -> None:
        """Put ``scene``'s bodies into ``world`` (None: every world): their poses, velocities,
        masses, friction and restitution (what a reset with new parameters needs). The scene
        must have this world's structure: the same bodies, shapes and motion classes in the
        same order (the geometry is shared by all worlds). Once every world is loaded, time
        starts again at 0, as in a new World of ``scene``, without compiling its geometry."""
        w = self._worlds(world, "load")
        if not isinstance(scene, Scene) or len(scene) != len(self.scene):
            raise ValueError(f"World.load: scene must be a Scene of {len(self.scene)} bodies")
        for mine, theirs in zip(self.scene.bodies, scene.bodies):
            if mine.motion != theirs.motion or not _same_shape(mine.shape, theirs.shape):
                raise ValueError(f"World.load: body {mine.index} ({mine.name!r}) differs in shape "
                                 f"or motion from the world's scene; only poses, velocities and "
                                 "materials may change between worlds")
        # a world with continuous collision takes any scene; one without refuses a scene that
        # needs it
        keep = {"continuous": True} if self.config.continuous else {}
        needed = SolverConfig.for_scene(scene, self.dt, **keep)
        if self._config_from_scene and needed != self.config:
            raise ValueError("World.load: the scene needs another SolverConfig.for_scene than "
                             f"this world's ({needed} vs {self.config}); "
                             "give the World an explicit config to load such scenes")
        if len(scene.joints) != len(self.scene.joints) or not all(
                np.array_equal(mine, theirs) for mine, theirs in
                zip(joint_model(self.scene.joints), joint_model(scene.joints))):
            raise ValueError("World.load: the scene's joints differ from the world's scene's in "
                             "kind, bodies, anchors or axes; only their limits and motors may "
                             "change between worlds")
        self._load_joint_settings(scene, w)
        for current, new in zip(self._materials(), _build_model(scene, 1)[1:5]):
            current[w] = new[0]
        for current, new in zip(self.state, _build_state(scene, 1)):
            current[w] = new[0]
        self.attached.parent[w] = -1
        self.core.forget(*self._range(w))
        if world is None or self.num_worlds == 1:
            self.steps = 0  # every world starts over

    def attach(self, body: int, parent: int, world: int | None = None) -> None:
        """Hold dynamic ``body`` rigidly at its current pose relative to kinematic ``parent``
        (a gripper): before every step and after the last it is put there, moving with the
        parent's velocity and not turning; in between, the step acts on it as on any body."""
        i, p = self._body(body, "attach"), self._body(parent, "attach")
        if self.model.motion[i] != DYNAMIC or self.model.motion[p] == DYNAMIC:
            raise ValueError(f"World.attach: body {i} must be dynamic and parent {p} kinematic "
                             "or static")
        worlds = self._worlds(world, "attach")
        s = self.state
        inverse = quat.conjugate(s.orientation[worlds, p])
        self.attached.offset_position[worlds, i] = np.einsum(
            "...ji,...j->...i", s.rotation[worlds, p], s.position[worlds, i] - s.position[worlds, p])
        self.attached.offset_orientation[worlds, i] = quat.multiply(inverse, s.orientation[worlds, i])
        self.attached.parent[worlds, i] = p
        self.core.forget(*self._range(worlds))
        self.core.place_attached(*self._range(worlds))

    def detach(self, body: int, world: int | None = None) -> None:
        """Let ``body`` go (``attach``): put at its place one last time, it leaves with its
        parent's current velocity."""
        i = self._body(body, "detach")
        worlds = self._worlds(world, "detach")
        self.core.place_attached(*self._range(worlds))
        self.attached.parent[worlds, i] = -1
        self.core.forget(*self._range(worlds))

    def view(self, world: int) -> WorldView:
        """One world of a batched World, seen as an unbatched one (``WorldView``)."""
        return WorldView(self, self._worlds(world, "view"))

    def _materials(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Writable views of the core's inverse_mass, inverse_moments, friction and restitution
        (``Model``'s layout), for the methods that change them."""
        inverse_mass, inverse_moments, friction, restitution = (
            getattr(self.core, name) for name in _core.MODEL)
        return inverse_mass, inverse_moments, friction, restitution

    @property
    def time(self) -> float:
        """Simulated time, s (steps * dt)."""
        return self.steps * self.dt

    def _load_joint_settings(self, scene: Scene, worlds) -> None:
        """The limits and motors of ``scene``'s joints into ``worlds`` (a slice or an index)."""
        c = self.core
        for current, new in zip((c.joint_lower, c.joint_upper, c.joint_motor_speed,
                                 c.joint_max_motor), joint_settings(scene.joints)):
            current[worlds] = new

    # -- state views -------------------------------------------------------------------------

    def _view(self, arr: np.ndarray) -> np.ndarray:
        view = arr.view() if self.batched else arr[0]
        view.flags.writeable = False
        return view

    @property
    def position(self) -> np.ndarray:
        """([B,] n, 3) centre-of-mass positions, m."""
        return self._view(self.state.position)

    @property
    def orientation(self) -> np.ndarray:
        """([B,] n, 4) unit quaternions (w, x, y, z) of the principal body frames."""
        return self._view(self.state.orientation)

    @property
    def velocity(self) -> np.ndarray:
        """([B,] n, 3) centre-of-mass velocities, m/s."""
        return self._view(self.state.velocity)

    @property
    def angular_velocity(self) -> np.ndarray:
        """([B,] n, 3) angular velocities, rad/s, world frame."""
        return self._view(self.state.angular_velocity)

    @property
    def body_angular_momentum(self) -> np.ndarray:
        """([B,] n, 3) angular momentum of each body about its centre of mass, kg m^2/s."""
        return self._view(self.state.angular_momentum)

    @property
    def rotation(self) -> np.ndarray:
        """([B,] n, 3, 3) rotation matrices of the orientations."""
        return self._view(self.state.rotation)

    # -- queries -----------------------------------------------------------------------------

    def _per_world(self, values: np.ndarray):
        return values if self.batched else float(values[0])

    def kinetic_energy(self):
        """Total kinetic energy of the dynamic bodies, J: float, or (B,) when batched."""
        dynamic = self.model.motion == DYNAMIC
        s = self.state
        mass = _safe_inverse(self.model.inverse_mass)[:, dynamic]
        linear = 0.5 * np.sum(mass * np.sum(s.velocity[:, dynamic] ** 2, axis=-1), axis=-1)
        angular = 0.5 * np.sum(s.angular_momentum[:, dynamic] * s.angular_velocity[:, dynamic],
                               axis=(-1, -2))
        return self._per_world(linear + angular)

    def potential_energy(self):
        """Gravitational potential energy of the dynamic bodies, J, zero at the origin."""
        dynamic = self.model.motion == DYNAMIC
        mass = _safe_inverse(self.model.inverse_mass)[:, dynamic]
        height = -self.state.position[:, dynamic] @ self.model.gravity
        return self._per_world(np.sum(mass * height, axis=-1))

    def linear_momentum(self) -> np.ndarray:
        """Total linear momentum of the dynamic bodies, kg m/s: ([B,] 3)."""
        dynamic = self.model.motion == DYNAMIC
        mass = _safe_inverse(self.model.inverse_mass)[:, dynamic]
        p = np.sum(mass[..., None] * self.state.velocity[:, dynamic], axis=1)
        return p if self.batched else p[0]

    def angular_momentum(self) -> np.ndarray:
        """Total angular momentum of the dynamic bodies about the world origin, kg m^2/s:
        ([B,] 3) = sum of X x M V + L."""
        dynamic = self.model.motion == DYNAMIC
        s = self.state
        mass = _safe_inverse(self.model.inverse_mass)[:, dynamic]
        orbital = np.cross(s.position[:, dynamic], mass[..., None] * s.velocity[:, dynamic])
        total = np.sum(orbital + s.angular_momentum[:, dynamic], axis=1)
        return total if self.batched else total[0]

    def contacts(self, margin: float = 0.0, world: int | None = None) -> Contacts:
        """Contacts at the current poses: every point of one body inside another or touching
        it (bodies resting on each other included), or within ``margin`` (m) of it, with the
        impulse each pair transmitted in the last step. See
        :class:`rigid_gym.collision.Contacts`; rows of all worlds together (or of ``world``
        only), with their world index."""
        margin = float(margin)
        if not np.isfinite(margin) or margin < 0.0:
            raise ValueError(f"World.contacts: margin must be finite and >= 0 m, got {margin!r}")
        worlds = self._worlds(world, "contacts")
        rows = self.core.contacts(margin, *self._range(worlds))
        found_world, body_a, body_b = rows[0], rows[1], rows[2]
        impulse = np.zeros((len(found_world), 3))
        for w in np.unique(found_world):
            a, b, pair_impulse = self.core.pairs(int(w))
            listed = {(int(i), int(j)): k for k, (i, j) in enumerate(zip(a, b))}
            for row in np.nonzero(found_world == w)[0]:
                k = listed.get((int(body_a[row]), int(body_b[row])))
                if k is not None:
                    impulse[row] = pair_impulse[k]
        return Contacts(*rows, impulse)

    def candidate_pairs(self, margin: float = 0.0, world: int = 0) -> np.ndarray:
        """(k, 2) body indices (a, b) of the pairs the broad phase lists in ``world`` at the
        current poses, boxes grown by ``margin`` (m): the pairs ``contacts`` examines. a is
        the body of higher motion class (dynamic > kinematic > static; ties: the lower index),
        so contact normals point from the ground or a gripper towards what they touch."""
        margin = float(margin)
        if not np.isfinite(margin) or margin < 0.0:
            raise ValueError(f"World.candidate_pairs: margin must be finite and >= 0 m, got "
                             f"{margin!r}")
        return self.core.candidate_pairs(margin, self._worlds(world, "candidate_pairs"))

    def listed_pairs(self, world: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """The pairs the last step listed in ``world`` as (k, 2) body indices (a, b), and the
        impulse each transmitted to its body a during that step, (k, 3) N s (zero for a pair
        that did not touch); copies."""
        a, b, impulse = self.core.pairs(self._worlds(world, "listed_pairs"))
        return np.stack([a, b], axis=1), impulse

    def joint_coordinates(self) -> np.ndarray:
        """([B,] J) each joint's coordinate at the current poses (``rigid_gym.joints``): rad
        for a revolute joint (in (-pi, pi]), m for a prismatic one, 0 for a fixed one."""
        values = self.core.joint_coordinates()
        return values if self.batched else values[0]

    def joint_impulses(self) -> JointImpulses:
        """What each joint transmitted to its body_a over the last step (body_b took the
        opposite): see :class:`JointImpulses`; copies. Divided by dt they are the mean
        reaction force (N) and torque (N m)."""
        rows = (self.core.joint_impulse, self.core.joint_angular_impulse,
                self.core.joint_motor_impulse)
        return JointImpulses(*(rows if self.batched else (r[0] for r in rows)))

    def set_joint_motor(self, joint: int, speed=None, max_motor=None,
                        world: int | None = None) -> None:
        """Set joint ``joint``'s motor: target ``speed`` (rad/s revolute, m/s prismatic) and/or
        ``max_motor`` (N m or N, >= 0; 0 switches it off); what is not given stays.
        ``world``: which world (None = all; values may then be (B,) for one per world)."""
        j = self._joint(joint, "set_joint_motor")
        worlds = self._worlds(world, "set_joint_motor")
        self.core.forget(*self._range(worlds))
        if speed is not None:
            self.core.joint_motor_speed[worlds, j] = self._scalars(
                speed, "speed", "set_joint_motor", worlds, -np.inf, np.inf)
        if max_motor is not None:
            self.core.joint_max_motor[worlds, j] = self._scalars(
                max_motor, "max_motor", "set_joint_motor", worlds, 0.0, np.inf,
                unit="N m" if self.scene.joints[j].kind == REVOLUTE else "N")

    def set_joint_limits(self, joint: int, limits, world: int | None = None) -> None:
        """Set joint ``joint``'s limits: None (none) or (lower, upper), rad in [-pi, pi]
        (revolute) or m (prismatic), lower <= upper. ``world``: which world (None = all)."""
        j = self._joint(joint, "set_joint_limits")
        spec = self.scene.joints[j]
        if spec.kind == FIXED:
            raise ValueError(f"World.set_joint_limits: joint {j} ({spec.name!r}) is fixed and "
                             "has no coordinate to limit")
        worlds = self._worlds(world, "set_joint_limits")
        lower, upper = limits_of(limits, spec.kind, f"World.set_joint_limits: joint {j}")
        self.core.forget(*self._range(worlds))
        self.core.joint_lower[worlds, j] = lower
        self.core.joint_upper[worlds, j] = upper

    def sleeping(self) -> np.ndarray:
        """([B,] n) bool: the bodies that slept through the last step (SolverConfig.sleep)."""
        asleep = self.core.asleep.astype(bool)
        return asleep if self.batched else asleep[0]

    @property
    def profiling(self) -> bool:
        """Whether steps time their stages (``World.profile()``'s seconds); settable."""
        return self.core.timed

    @profiling.setter
    def profiling(self, on: bool) -> None:
        if not isinstance(on, bool):
            raise ValueError(f"World.profiling: must be True or False, got {on!r}")
        self.core.timed = on

    def profile(self) -> dict[str, dict]:
        """Per stage of the step, in step order (``rigid_gym._core.STAGES``, the names of
        ``SolverConfig.phases``): {"on": whether the config runs it in this scene, "seconds":
        wall time spent in it (s) while ``profiling``, "calls": how many times it ran,
        "resolves": how many contact sets it resolved (a pair's contacts, or a body's with all
        its supports: the unit of the impulse stages' work; 0 in the other stages)}, summed
        over every world and every step since the World was made (resets included). The step
        counts and times its stages itself (``src/solver/timers.h``); a batch's seconds add up
        its worlds' time on every thread. A stage's seconds are its own: the impulse stages run
        again inside a relisting are theirs, not the relisting's.

        A stage with nothing to do in a step is not run (no awake pair: no collision, contact
        or shock stage; no contact found: no overlap correction); the broad phase runs once
        per step where the config lists pairs, and a step whose impulses sped a body past its
        box relists its pairs and runs the impulse stages again (their calls count it). With
        sleeping, a step of a world at rest (every dynamic body asleep and nothing changed
        since the last step) runs only the sleep check."""
        on = self.core.stages
        seconds = self.core.stage_seconds.sum(axis=0)
        calls = self.core.stage_calls.sum(axis=0)
        resolves = self.core.stage_resolves.sum(axis=0)
        return {name: {"on": on[k], "seconds": float(seconds[k]), "calls": int(calls[k]),
                       "resolves": int(resolves[k])}
                for k, name in enumerate(_core.STAGES)}

    def body_index(self, name: str) -> int:
        """Index of the body called ``name``."""
        return self.scene.index(name)

    # -- setters -----------------------------------------------------------------------------

    def set_velocity(self, body: int, velocity=None, angular_velocity=None,
                     world: int | None = None) -> None:
        """Set a body's velocity (3,) m/s and/or angular velocity (3,) rad/s, world frame.

        For a dynamic body L is set to I(t) omega (a component along a degenerate axis is lost).
        ``world``: which world (None = all; values may then be (B, 3) for one per world).
        """
        i = self._body(body, "set_velocity")
        if self.model.motion[i] == STATIC:
            raise ValueError(f"World.set_velocity: body {i} ({self.scene.bodies[i].name!r}) is "
                             "static and cannot move")
        worlds = self._worlds(world, "set_velocity")
        s = self.state
        if velocity is not None:
            s.velocity[worlds, i] = self._values(velocity, "velocity", "set_velocity", worlds)
        if angular_velocity is None:
            return  # R and omega are unchanged
        self._set_angular_velocity(
            i, worlds, self._values(angular_velocity, "angular_velocity", "set_velocity", worlds))

    def set_material(self, body: int, *, mass=None, friction=None, restitution=None,
                     world: int | None = None) -> None:
        """Change a body's mass (kg > 0, dynamic bodies only), friction (>= 0) and/or
        restitution (in [0, 1]); what is not given stays. A new mass scales the body's inertia
        with it (the same shape at another density) and keeps its velocities (L is rescaled).
        ``world``: which world (None = all; values may then be (B,) for one per world).

        Restitution > 0 is refused where the World derived its config from a scene without
        restitution (``SolverConfig.for_scene`` left the collision phase out): give the World
        an explicit config to change that.
        """
        i = self._body(body, "set_material")
        worlds = self._worlds(world, "set_material")
        self.core.forget(*self._range(worlds))
        m = Model(self.model.motion, *self._materials(), self.model.gravity)
        name = f"body {i} ({self.scene.bodies[i].name!r})"
        if mass is not None:
            if m.motion[i] != DYNAMIC:
                raise ValueError(f"World.set_material: {name} is not dynamic (infinite mass); "
                                 "only a dynamic body's mass can be set")
            value = self._scalars(mass, "mass", "set_material", worlds, 0.0, np.inf, open_low=True,
                                  unit="kg")
            spec = self.scene.bodies[i]
            omega = self.state.angular_velocity[worlds, i].copy()
            m.inverse_mass[worlds, i] = 1.0 / value
            m.inverse_moments[worlds, i] = spec.inverse_moments * (spec.mass / value)[..., None]
            self._set_angular_velocity(i, worlds, omega)
        if friction is not None:
            m.friction[worlds, i] = self._scalars(friction, "friction", "set_material", worlds,
                                                  0.0, np.inf)
        if restitution is not None:
            value = self._scalars(restitution, "restitution", "set_material", worlds, 0.0, 1.0)
            if np.any(value > 0.0) and self._config_from_scene \
                    and self.config.collision_passes == 0:
                raise ValueError(f"World.set_material: restitution > 0 for {name} needs the "
                                 "collision phase, which SolverConfig.for_scene left out (every "
                                 "restitution of the scene is 0); give the World an explicit "
                                 "config, e.g. SolverConfig(collision_passes=5)")
            m.restitution[worlds, i] = value

    def set_pose(self, body: int, position=None, orientation=None, world: int | None = None) -> None:
        """Set a body's centre-of-mass position (3,) m and/or principal-frame orientation (4,)
        unit quaternion (w, x, y, z). L is kept; omega follows from it."""
        i = self._body(body, "set_pose")
        worlds = self._worlds(world, "set_pose")
        if position is not None:
            self.state.position[worlds, i] = self._values(position, "position", "set_pose", worlds)
        if orientation is not None:
            q = self._values(orientation, "orientation", "set_pose", worlds, size=4)
            quat.check_unit(q, f"World.set_pose: body {i} orientation")
            self.state.orientation[worlds, i] = quat.normalize(q)
        self._refresh_derived(worlds)

    def apply_impulse(self, body: int, impulse, point=None, world: int | None = None) -> None:
        """Apply an impulse (3,) N s at ``point`` (3,) m, world frame (default: the centre of
        mass): V += j/M, L += (point - X) x j. Only dynamic bodies respond."""
        i = self._body(body, "apply_impulse")
        worlds = self._worlds(world, "apply_impulse")
        j = self._values(impulse, "impulse", "apply_impulse", worlds)
        if self.model.motion[i] != DYNAMIC:
            raise ValueError(f"World.apply_impulse: body {i} ({self.scene.bodies[i].name!r}) is "
                             "not dynamic (infinite mass)")
        s = self.state
        s.velocity[worlds, i] += j * self.model.inverse_mass[worlds, i][..., None]
        if point is not None:
            r = self._values(point, "point", "apply_impulse", worlds) - s.position[worlds, i]
            s.angular_momentum[worlds, i] += np.cross(r, j)
        self._refresh_derived(worlds)

    def apply_force(self, body: int, force, point=None, world: int | None = None) -> None:
        """Add a force (3,) N acting at ``point`` (3,) m (default: the centre of mass) during
        the next step; off the centre it also adds the torque (point - X) x F."""
        i = self._body(body, "apply_force")
        worlds = self._worlds(world, "apply_force")
        f = self._values(force, "force", "apply_force", worlds)
        self.state.force[worlds, i] += f
        if point is not None:
            r = self._values(point, "point", "apply_force", worlds) - self.state.position[worlds, i]
            self.state.torque[worlds, i] += np.cross(r, f)

    def apply_torque(self, body: int, torque, world: int | None = None) -> None:
        """Add a torque (3,) N m about the centre of mass during the next step."""
        i = self._body(body, "apply_torque")
        worlds = self._worlds(world, "apply_torque")
        self.state.torque[worlds, i] += self._values(torque, "torque", "apply_torque", worlds)

    # -- helpers -----------------------------------------------------------------------------

    def _set_angular_velocity(self, i: int, worlds, w: np.ndarray) -> None:
        """Body i's angular velocity in ``worlds`` (a slice or one index) to w ((3,) or
        (B, 3) rad/s); for a dynamic body L = I(t) omega (a component along a degenerate axis
        is lost)."""
        s = self.state
        s.angular_velocity[worlds, i] = w
        if self.model.motion[i] == DYNAMIC:
            r = s.rotation[worlds, i]
            moments = _safe_inverse(self.model.inverse_moments[worlds, i])
            body_w = np.einsum("...ji,...j->...i", r, w)
            s.angular_momentum[worlds, i] = np.einsum("...ij,...j->...i", r, moments * body_w)
        self._refresh_derived(worlds)

    def _refresh_derived(self, worlds=slice(None)) -> None:
        """R(q) and omega = I^-1 L of ``worlds`` (every world, or one world's index)."""
        self.core.refresh(*self._range(worlds))

    def _range(self, worlds) -> tuple[int, int]:
        """(first, last) of ``worlds``: every world (slice(None)) or one world's index."""
        return (0, self.num_worlds) if isinstance(worlds, slice) else (worlds, worlds + 1)

    def _body(self, body, method: str) -> int:
        n = len(self.scene)
        if isinstance(body, str):
            return self.scene.index(body)
        return integer(body, f"World.{method}: body", 0, n - 1, other="a name")

    def _joint(self, joint, method: str) -> int:
        if isinstance(joint, str):
            for spec in self.scene.joints:
                if spec.name == joint:
                    return spec.index
            raise ValueError(f"World.{method}: no joint named {joint!r}; joints: "
                             f"{[spec.name for spec in self.scene.joints]}")
        if not self.scene.joints:
            raise ValueError(f"World.{method}: the scene has no joint")
        return integer(joint, f"World.{method}: joint", 0, len(self.scene.joints) - 1,
                       other="a name")

    def _worlds(self, world, method: str):
        if world is None:
            return slice(None)
        return integer(world, f"World.{method}: world", 0, self.num_worlds - 1, other="None")

    def _values(self, value, field: str, method: str, worlds, size: int = 3) -> np.ndarray:
        arr = np.asarray(value, dtype=np.float64)
        allowed = [(size,)] + ([(self.num_worlds, size)] if worlds == slice(None) else [])
        if arr.shape not in allowed:
            raise ValueError(f"World.{method}: {field} must have shape "
                             f"{' or '.join(map(str, allowed))}, got {arr.shape}")
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"World.{method}: {field} must be finite, got {arr.tolist()}")
        return arr

    def _scalars(self, value, field: str, method: str, worlds, low: float, high: float,
                 open_low: bool = False, unit: str = "") -> np.ndarray:
        """``value`` as a float64 scalar, or (B,) for every world when ``worlds`` is all of
        them, checked to lie in [low, high] ((low, high] with ``open_low``) in ``unit``."""
        arr = np.asarray(value, dtype=np.float64)
        shapes = [()] + ([(self.num_worlds,)] if worlds == slice(None) else [])
        if arr.shape not in shapes:
            raise ValueError(f"World.{method}: {field} must have shape "
                             f"{' or '.join(map(str, shapes))}, got {arr.shape}")
        return in_range(arr, low, high, f"World.{method}: {field}", open_low=open_low, unit=unit)


class WorldView:
    """World ``index`` of a batched World with the interface of an unbatched one: state
    properties without the world axis, setters, ``contacts``, ``time``. It cannot step (the
    batched World steps every world at once)."""

    def __init__(self, world: World, index: int):
        self.batch, self.index = world, index
        self.scene, self.dt = world.scene, world.dt

    position = property(lambda self: self.batch.position[self.index])
    orientation = property(lambda self: self.batch.orientation[self.index])
    velocity = property(lambda self: self.batch.velocity[self.index])
    angular_velocity = property(lambda self: self.batch.angular_velocity[self.index])
    rotation = property(lambda self: self.batch.rotation[self.index])
    time = property(lambda self: self.batch.time)

    def set_pose(self, body, position=None, orientation=None) -> None:
        self.batch.set_pose(body, position, orientation, world=self.index)

    def set_velocity(self, body, velocity=None, angular_velocity=None) -> None:
        self.batch.set_velocity(body, velocity, angular_velocity, world=self.index)

    def contacts(self, margin: float = 0.0) -> Contacts:
        return self.batch.contacts(margin, world=self.index)

    def set_material(self, body, *, mass=None, friction=None, restitution=None) -> None:
        self.batch.set_material(body, mass=mass, friction=friction, restitution=restitution,
                                world=self.index)

    def reset(self) -> None:
        self.batch.reset(world=self.index)

    def load(self, scene: Scene) -> None:
        self.batch.load(scene, world=self.index)

    def attach(self, body, parent) -> None:
        self.batch.attach(body, parent, world=self.index)

    def detach(self, body) -> None:
        self.batch.detach(body, world=self.index)


CORE_ARRAYS = ("position", "orientation", "velocity", "angular_momentum", "angular_velocity",
               "rotation", "force", "torque", "inverse_mass", "inverse_moments", "friction",
               "restitution", "attach_parent", "attach_offset_position",
               "attach_offset_orientation", "joint_lower", "joint_upper", "joint_motor_speed",
               "joint_max_motor")
"""The core's arrays that Python sees (``World.state``, its materials, ``World.attached``):
with the scene, the config and the time they are all a pickled World keeps."""


def _core_arrays(core: _core.Batch) -> dict[str, np.ndarray]:
    return {name: getattr(core, name).copy() for name in CORE_ARRAYS}


def _write_core_arrays(core: _core.Batch, arrays: dict[str, np.ndarray]) -> None:
    for name in CORE_ARRAYS:
        getattr(core, name)[...] = arrays[name]


def _same_shape(a, b) -> bool:
    """Equal primitives (same type and dimensions); meshes and compounds only if identical."""
    if a is b:
        return True
    if type(a) is not type(b) or isinstance(a, (Mesh, Compound)):
        return False
    return all(np.array_equal(getattr(a, f.name), getattr(b, f.name))
               for f in dataclasses.fields(a))


def _safe_inverse(x: np.ndarray) -> np.ndarray:
    """1/x where x > 0, else 0 (mass from inverse mass: 0 for infinite-mass bodies)."""
    out = np.zeros_like(x)
    np.divide(1.0, x, out=out, where=x > 0)
    return out


def _build_model(scene: Scene, num_worlds: int) -> Model:
    bodies = scene.bodies
    return Model(
        motion=np.array([b.motion for b in bodies], dtype=np.int32),
        inverse_mass=np.tile(np.array([b.inverse_mass for b in bodies]), (num_worlds, 1)),
        inverse_moments=np.tile(np.array([b.inverse_moments for b in bodies]), (num_worlds, 1, 1)),
        friction=np.tile(np.array([b.friction for b in bodies]), (num_worlds, 1)),
        restitution=np.tile(np.array([b.restitution for b in bodies]), (num_worlds, 1)),
        gravity=scene.gravity.copy(),
    )


def _build_state(scene: Scene, num_worlds: int) -> State:
    bodies = scene.bodies
    n = len(bodies)

    def tiled(values):
        return np.ascontiguousarray(np.tile(np.array(values, dtype=np.float64),
                                            (num_worlds,) + (1,) * np.ndim(values)))

    rotation = quat.to_matrix(np.array([b.orientation for b in bodies]))
    # L = R diag(I_body) R^T omega for dynamic bodies; 0 for the rest
    body_w = np.einsum("nji,nj->ni", rotation, np.array([b.angular_velocity for b in bodies]))
    moments = np.array([b.principal_moments if b.motion == DYNAMIC else np.zeros(3)
                        for b in bodies])
    momentum = np.einsum("nij,nj->ni", rotation, moments * body_w)
    return State(
        position=tiled([b.position for b in bodies]),
        orientation=tiled([b.orientation for b in bodies]),
        velocity=tiled([b.velocity for b in bodies]),
        angular_momentum=tiled(momentum),
        angular_velocity=tiled([b.angular_velocity for b in bodies]),
        rotation=tiled(rotation),
        force=np.zeros((num_worlds, n, 3)),
        torque=np.zeros((num_worlds, n, 3)),
    )
