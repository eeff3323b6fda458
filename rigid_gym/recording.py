"""Episode recordings: any env or World to a rerun ``.rrd`` file, replayed with ``rerun FILE``.

    env = RecordRerun(gym.make("rigid_gym/Push-v0"))  # to recordings/rigid_gym-Push-v0/
    with WorldRecorder(world, "fall.rrd") as recorder:  # any World
        recorder.record()
        for _ in range(240):
            world.step()
            recorder.record()

Replay with ``rigid-gym replay FILE`` (or ``rerun FILE``: the viewer the rerun-sdk wheel
installs, which must be the SDK's version).

**What a file holds** (entity paths; frames are right-handed, z up):

- ``/world``: ``ViewCoordinates.RIGHT_HAND_Z_UP``, once.
- ``/world/bodies/<name>``: a ``Transform3D`` every step, the *body* frame: ``World.position``
  (centre of mass, m) and ``World.orientation`` converted to rerun's (x, y, z, w); a static
  body's once. Once, the body's geometry in body-frame coordinates: each primitive placed by
  ``BodySpec.body_from_shape`` (and its Compound part pose), an instance of ``Boxes3D``,
  ``Ellipsoids3D``, ``Capsules3D`` or ``Mesh3D`` (meshes, and a Plane as a square of
  ``PLANE_HALF_SIZE``).
- ``/world/goals/<k>``: an env's goal markers (its ``_add_markers``), translucent, once.
- ``/world/contacts/points`` (option ``contacts``): ``Points3D`` every step, the contact points
  within ``CONTACT_MARGIN``; ``/world/contacts/forces``: ``Arrows3D`` at each touching pair's
  contact centroid, its mean force on the pair's first body during the last solver step
  (impulse / dt), ``force_scale`` m per N.
- ``/reward``, ``/action``, ``/success`` (envs): ``Scalars`` every env step: the reward, the
  action as passed to ``step`` (one series per entry), ``info["is_success"]`` as 0 / 1.

Timelines: ``step`` (sequence: env steps, 0 = the state after ``reset``; for a World,
``World.steps``) and ``sim_time`` (duration: ``World.time``, s). Poses and contacts are rows at
every step from 0; rewards, actions and successes at steps 1, 2, ... (the step they led to).
Rerun stores translations and quaternions as float32 and scalars as float64.

**Cost.** Static geometry is logged once per file, from archetypes built once per scene, and
the blueprint from ``.rbl`` bytes built once per layout (building both for every file took
longer than the episode's data). Per step only numpy copies are buffered, and buffers are
sent with ``send_columns`` at the end of an episode (or every ``chunk_steps`` steps, bounding
memory). A 50-step Push file costs ~7 ms: half opening it (stream, file sink, blueprint,
scene), half sending the columns and closing (``benchmarks/recording.py``).

**Files are complete** when an episode ends (terminated or truncated), at ``close()``, when
``step`` or ``reset`` raises (what was buffered is written, then the exception propagates), and
at interpreter exit (an ``atexit`` hook closes any open file). A stream is created only when an
episode starts, so the wrappers can be built inside SubprocVecEnv workers (each process
writes its own files; the default run name contains the process id). ``RERUN=off`` in the
environment turns recording off: nothing is written and nothing fails.
"""

from __future__ import annotations

import atexit
import functools
import os
import re
import tempfile
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from rigid_gym import quaternion as quat
from rigid_gym.envs.base import RigidGymEnv
from rigid_gym.kernels.integrate import STATIC
from rigid_gym.render import MARKER_COLOR, _body_colors, _corner_normals, tessellate
from rigid_gym.scene import Scene
from rigid_gym.shapes import Box, Capsule, Compound, Mesh, Plane, Pose, Sphere

RECORDINGS = "recordings"
"""Default output folder of ``RecordRerun``."""
CHUNK_STEPS = 1000
"""Buffered steps after which rows are sent, so that a long episode's memory stays bounded."""
CONTACT_MARGIN = 1e-3
"""m: contacts closer than this are recorded (resting contacts barely overlap)."""
FORCE_SCALE = 0.05
"""m of arrow per N of contact force (a 0.1 kg cube's weight, 0.98 N, is a 5 cm arrow)."""
PLANE_HALF_SIZE = 1.0
"""m: a Plane (the ground) is drawn as the square |x|, |y| <= this."""
ACTION_NAMES = ("x", "y", "z", "grip")
"""Names of the action entries in the plots: the pad's motion along x, y, z, and the grip."""
CONTACT_COLOR = (230, 40, 40)
FORCE_COLOR = (250, 150, 30)
RUN_PATTERN = re.compile(r"[A-Za-z0-9_.-]+")


# -- the episode wrapper ------------------------------------------------------------------------

class RecordRerun(gym.Wrapper):
    """Record a rigid_gym env's episodes, one ``.rrd`` file each (like ``RecordVideo``).

    env: a rigid_gym env (``gym.make("rigid_gym/...")``, wrapped or not).
    folder: output folder; files go to ``folder/<env id>/<run>-episode-<k>.rrd``, the env id
        with every character outside ``[A-Za-z0-9_.-]`` replaced by ``-``
        (``recordings/rigid_gym-Push-v0/...``); k counts resets from 0.
    episode_trigger: ``k -> bool``, which episodes to record; default ``cubic_schedule``.
    run: a name made of ``[A-Za-z0-9_.-]``; default ``<date>-<time>-<process id>``, unique
        per process. Wrappers that share a folder and an env id need different runs.
    contacts: also record contact points and force arrows (``force_scale`` m per N).
    chunk_steps: steps buffered before they are sent (>= 1).

    ``paths`` lists the files started so far.
    """

    def __init__(self, env: gym.Env, folder: str | os.PathLike = RECORDINGS,
                 episode_trigger=None, run: str | None = None, contacts: bool = False,
                 force_scale: float = FORCE_SCALE, chunk_steps: int = CHUNK_STEPS):
        super().__init__(env)
        if not isinstance(env.unwrapped, RigidGymEnv):
            raise ValueError(f"RecordRerun.env: expected a rigid_gym env, got "
                             f"{type(env.unwrapped).__name__}")
        if episode_trigger is not None and not callable(episode_trigger):
            raise ValueError(f"RecordRerun.episode_trigger: expected a function episode index "
                             f"-> bool, got {episode_trigger!r}")
        self.episode_trigger = cubic_schedule if episode_trigger is None else episode_trigger
        self.run = _run_name(run, "RecordRerun.run")
        self.env_id = env.spec.id if env.spec is not None else type(env.unwrapped).__name__
        self.folder = Path(folder) / re.sub(r"[^A-Za-z0-9_.-]+", "-", self.env_id)
        self.options = _Options(contacts, force_scale, chunk_steps, "RecordRerun")
        self.paths: list[Path] = []
        self.episode_id = -1
        self._layout: _Layout | None = None  # built at the first recorded episode
        self._recording: _Recording | None = None
        self._step = 0

    def reset(self, **kwargs):
        self._end_episode()
        result = self.env.reset(**kwargs)
        self.episode_id += 1
        if self.episode_trigger(self.episode_id):
            self._begin_episode()
        return result

    def step(self, action):
        try:
            observation, reward, terminated, truncated, info = self.env.step(action)
            if self._recording is not None:
                self._step += 1
                self._record_step(action, reward, info)
        except BaseException:
            self._end_episode()
            raise
        if terminated or truncated:
            self._end_episode()
        return observation, reward, terminated, truncated, info

    def close(self):
        self._end_episode()
        super().close()

    def _begin_episode(self) -> None:
        task = self.env.unwrapped
        name = f"{self.run}-episode-{self.episode_id}"
        path = self.folder / f"{name}.rrd"
        recording = _open(path, name, task.world, 0, self.options, self._scene_layout)
        if recording is None:
            return
        self._recording, self._step = recording, 0
        self.paths.append(path)
        try:
            markers = _Markers()
            task._add_markers(markers)
            recording.log_markers(markers.shapes)
            recording.log_action_names(ACTION_NAMES[:self.action_space.shape[0]])
            recording.record_state(0)
        except BaseException:
            self._end_episode()
            raise

    def _scene_layout(self) -> _Layout:
        """The layout of the env's scene, built again only when the World is a new one."""
        task = self.env.unwrapped
        if self._layout is None or self._layout.scene is not task.world.scene:
            eye, target, _ = task.camera_view
            blueprint = _blueprint_file(self.folder.name, tuple(eye), tuple(target), True, False)
            self._layout = _Layout(task.world.scene, self.folder.name, blueprint)
        return self._layout

    def _record_step(self, action, reward, info) -> None:
        self._recording.record_state(self._step)
        self._recording.record_scalars(self._step, float(reward),
                                       np.asarray(action, dtype=np.float64).ravel(),
                                       float(bool(info.get("is_success", False))))

    def _end_episode(self) -> None:
        recording, self._recording = self._recording, None
        if recording is not None:
            recording.close()


def cubic_schedule(episode: int) -> bool:
    """Episodes 0, 1, 8, 27, ..., 729, then every 1000th: RecordVideo's default trigger
    (Gymnasium's ``capped_cubic_video_schedule``, whose module needs moviepy)."""
    if episode < 1000:
        return round(episode ** (1.0 / 3.0)) ** 3 == episode
    return episode % 1000 == 0


# -- the World recorder -------------------------------------------------------------------------

class WorldRecorder:
    """Record any World to ``path`` (an ``.rrd`` file): call ``record()`` for the state to
    start from and after each step, then ``close()`` (or use it as a context manager).

    world_index: which world of a batched World, in [0, num_worlds).
    application_id: the name rerun shows for the recording.
    contacts, force_scale, chunk_steps: as for ``RecordRerun``.
    The file is opened by the first ``record()``.
    """

    def __init__(self, world, path: str | os.PathLike, *, world_index: int = 0,
                 application_id: str = "rigid_gym", contacts: bool = False,
                 force_scale: float = FORCE_SCALE, chunk_steps: int = CHUNK_STEPS):
        from rigid_gym.world import World

        if not isinstance(world, World):
            raise ValueError(f"WorldRecorder.world: expected a rigid_gym.World, got "
                             f"{type(world).__name__}")
        if (isinstance(world_index, bool) or not isinstance(world_index, (int, np.integer))
                or not 0 <= world_index < world.num_worlds):
            raise ValueError(f"WorldRecorder.world_index: must be an int in "
                             f"[0, {world.num_worlds - 1}], got {world_index!r}")
        self.world = world
        self.path = Path(path)
        self.world_index = int(world_index)
        self.application_id = str(application_id)
        self.options = _Options(contacts, force_scale, chunk_steps, "WorldRecorder")
        self._recording: _Recording | None = None
        self._state = "new"  # then "open" (or "off" when rerun is off), then "closed"

    def record(self) -> None:
        """Buffer the current state at step ``world.steps``, time ``world.time``."""
        if self._state == "closed":
            raise ValueError(f"WorldRecorder.record: {self.path} is closed; make a new recorder")
        if self._state == "new":
            self._recording = _open(self.path, self.path.stem, self.world, self.world_index,
                                    self.options, self._layout)
            self._state = "off" if self._recording is None else "open"
        if self._recording is not None:
            self._recording.record_state(self.world.steps)

    def _layout(self) -> _Layout:
        grid = not any(isinstance(b.shape, Plane) for b in self.world.scene.bodies)
        return _Layout(self.world.scene, self.application_id,
                       _blueprint_file(self.application_id, None, None, False, grid))

    def close(self) -> None:
        """Write what is buffered and complete the file (idempotent)."""
        if self._recording is not None:
            self._recording.close()
        self._state = "closed"

    def __enter__(self) -> WorldRecorder:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()


# -- one file -----------------------------------------------------------------------------------

class _Options:
    """Validated recording options shared by both recorders."""

    def __init__(self, contacts, force_scale, chunk_steps, where: str):
        if not isinstance(contacts, bool):
            raise ValueError(f"{where}.contacts: must be a bool, got {contacts!r}")
        try:
            scale = float(force_scale)
        except (TypeError, ValueError):
            scale = np.nan
        if not np.isfinite(scale) or scale <= 0.0:
            raise ValueError(f"{where}.force_scale: must be a finite number of m per N > 0, "
                             f"got {force_scale!r}")
        if (isinstance(chunk_steps, bool) or not isinstance(chunk_steps, (int, np.integer))
                or chunk_steps < 1):
            raise ValueError(f"{where}.chunk_steps: must be an int >= 1, got {chunk_steps!r}")
        self.contacts = contacts
        self.force_scale = scale
        self.chunk_steps = int(chunk_steps)


class _Layout:
    """What every file of one scene shares, built once (for each file, building them took
    longer than writing an episode's data): every body's geometry as rerun archetypes in its
    body frame, and the blueprint, the bytes of an ``.rbl`` file for ``application_id``
    (``_blueprint_file``). ``scene``: the World's scene (``World.load`` keeps it: only poses
    and materials change)."""

    def __init__(self, scene: Scene, application_id: str, blueprint: bytes):
        self.scene = scene
        self.application_id = application_id
        self.blueprint = blueprint
        self.entities = [f"world/bodies/{rr.escape_entity_path_part(b.name)}"
                         for b in scene.bodies]
        colors = np.round(255 * _body_colors(scene, None)).astype(np.uint8)
        self.geometry = [_geometry(body.shape, body.body_from_shape,
                                   np.append(colors[body.index], 255)) for body in scene.bodies]
        self._markers: dict[int, tuple] = {}

    def marker_geometry(self, k: int, shape, rgba: np.ndarray) -> list:
        """Marker k's archetypes in its own frame, built again only when its shape (object)
        or colour differs from the last file's (Push's disc is a 48-gon mesh: ~1 ms)."""
        last = self._markers.get(k)
        if last is None or last[0] is not shape or not np.array_equal(last[1], rgba):
            last = self._markers[k] = (shape, rgba, _geometry(shape, Pose(), rgba))
        return last[2]


def _open(path: Path, recording_id: str, world, index: int, options: _Options,
          layout) -> _Recording | None:
    """A new recording of world ``index`` of ``world`` to ``path``, or None when rerun is off
    (``RERUN=off``, ``0`` or ``false``, which rerun documents; checked first so that no
    disabled stream is made: rerun warns about each when it is dropped). ``layout``: a
    function that gives the scene's ``_Layout``, called only when rerun is on."""
    if os.environ.get("RERUN", "").strip().lower() in ("0", "off", "false"):
        return None
    layout = layout()
    stream = rr.RecordingStream(layout.application_id, recording_id=recording_id)
    if not rr.is_enabled(stream):  # turned off some other way
        return None
    return _Recording(stream, path, world, index, options, layout)


class _Recording:
    """One ``.rrd`` file of one world of ``world`` (index ``index``): the scene is logged on
    creation; ``record_*`` buffer rows that ``flush`` sends as columns; ``close`` completes it.
    """

    def __init__(self, stream: rr.RecordingStream, path: Path, world, index: int,
                 options: _Options, layout: _Layout):
        self.world, self.index, self.options = world, index, options
        self.entities, self.layout = layout.entities, layout
        self.moving = [b.index for b in world.scene.bodies if b.motion != STATIC]
        self.states = _Rows()
        self.scalars = _Rows()
        self.contacts = _Rows()
        path.parent.mkdir(parents=True, exist_ok=True)
        self.stream = stream
        self.stream.save(path)  # a file sink: before any logging
        atexit.register(self.close)
        self.closed = False
        # the blueprint as its .rbl file's contents (rerun's own importer reads them)
        self.stream.log_file_from_contents(file_path="blueprint.rbl",
                                           file_contents=layout.blueprint)
        _log_scene(self.stream, world, index, layout, options.contacts)

    def log_markers(self, markers: list) -> None:
        """Static goal markers: (shape, Pose, RGBA uint8 (4,)) each, as a pose and the
        shape's geometry in the marker's frame."""
        for k, (shape, pose, rgba) in enumerate(markers):
            self.stream.log(f"world/goals/{k}", _transform(pose.position, pose.orientation),
                            *self.layout.marker_geometry(k, shape, rgba), static=True)

    def log_action_names(self, names) -> None:
        """Name the series of ``/action`` (one name per action entry)."""
        self.stream.log("action", rr.SeriesLines(names=list(names)), static=True)

    def record_state(self, step: int) -> None:
        """Buffer the moving bodies' poses (and contacts, if on) at ``step``."""
        w, s = self.world, self.world.state
        sim_time = w.time
        self.states.append(step, sim_time, position=s.position[self.index, self.moving],
                           orientation=s.orientation[self.index, self.moving])
        if self.options.contacts:
            points, origins, vectors = _contacts(w, self.index, self.options.force_scale)
            self.contacts.append(step, sim_time, points=points, origins=origins, vectors=vectors)
        if len(self.states) >= self.options.chunk_steps:
            self.flush()

    def record_scalars(self, step: int, reward: float, action: np.ndarray,
                       success: float) -> None:
        """Buffer an env step's reward, action (a,) and success (0 or 1) at ``step``."""
        self.scalars.append(step, self.world.time, reward=reward, action=action, success=success)

    def flush(self) -> None:
        """Send every buffered row as columns and empty the buffers."""
        if len(self.states):
            self._send_states(*self.states.take())
        if len(self.scalars):
            self._send_scalars(*self.scalars.take())
        if len(self.contacts):
            self._send_contacts(*self.contacts.take())

    def close(self) -> None:
        """Flush, then close the file (writes its footer). Idempotent."""
        if self.closed:
            return
        self.closed = True
        atexit.unregister(self.close)
        try:
            self.flush()
        finally:
            self.stream.disconnect()  # sends what the batcher holds, then writes the footer

    def _send_states(self, indexes, rows: dict) -> None:
        position = np.stack(rows["position"])  # (T, moving bodies, 3)
        xyzw = _xyzw(np.stack(rows["orientation"]))
        for k, body in enumerate(self.moving):
            self.stream.send_columns(self.entities[body], indexes=indexes,
                                     columns=rr.Transform3D.columns(translation=position[:, k],
                                                                    quaternion=xyzw[:, k]))

    def _send_scalars(self, indexes, rows: dict) -> None:
        actions = np.stack(rows["action"])  # (T, a)
        self.stream.send_columns("reward", indexes=indexes,
                                 columns=rr.Scalars.columns(scalars=np.array(rows["reward"])))
        self.stream.send_columns("success", indexes=indexes,
                                 columns=rr.Scalars.columns(scalars=np.array(rows["success"])))
        self.stream.send_columns("action", indexes=indexes, columns=rr.Scalars.columns(
            scalars=actions.ravel()).partition(lengths=np.full(len(actions), actions.shape[1])))

    def _send_contacts(self, indexes, rows: dict) -> None:
        points, origins = rows["points"], rows["origins"]  # ragged: (k, 3) per row
        points_column = rr.Points3D.columns(positions=np.concatenate(points))
        arrows_column = rr.Arrows3D.columns(origins=np.concatenate(origins),
                                            vectors=np.concatenate(rows["vectors"]))
        self.stream.send_columns("world/contacts/points", indexes=indexes,
                                 columns=points_column.partition(lengths=[len(p) for p in points]))
        self.stream.send_columns("world/contacts/forces", indexes=indexes,
                                 columns=arrows_column.partition(lengths=[len(o) for o in origins]))


class _Rows:
    """Rows buffered for columns: a step, a time (s) and named values per row."""

    def __init__(self):
        self.steps: list[int] = []
        self.times: list[float] = []
        self.values: dict[str, list] = {}

    def __len__(self) -> int:
        return len(self.steps)

    def append(self, step: int, sim_time: float, **values) -> None:
        """Values (numbers or arrays; arrays may differ in shape between rows) are copied."""
        self.steps.append(step)
        self.times.append(sim_time)
        for name, value in values.items():
            self.values.setdefault(name, []).append(np.array(value))

    def take(self) -> tuple[list, dict]:
        """(the two time columns, {name: list of rows}), and empty the buffer."""
        nanoseconds = np.round(np.array(self.times) * 1e9).astype(np.int64)  # not truncated
        indexes = [rr.TimeColumn("step", sequence=np.array(self.steps, dtype=np.int64)),
                   rr.TimeColumn("sim_time", duration=nanoseconds.astype("timedelta64[ns]"))]
        rows = self.values
        self.steps, self.times, self.values = [], [], {}
        return indexes, rows


# -- static scene -------------------------------------------------------------------------------

def _log_scene(stream: rr.RecordingStream, world, index: int, layout: _Layout,
               contacts: bool) -> None:
    """Coordinates, every body's geometry in its body frame (static bodies with their pose in
    world ``index``), the contacts' styles."""
    stream.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for body, path, archetypes in zip(world.scene.bodies, layout.entities, layout.geometry):
        if body.motion == STATIC:
            stream.log(path, _transform(world.state.position[index, body.index],
                                        world.state.orientation[index, body.index]),
                       static=True)
        stream.log(path, *archetypes, static=True)
    if contacts:
        stream.log("world/contacts/points",
                   rr.Points3D.from_fields(radii=[0.004], colors=[CONTACT_COLOR]), static=True)
        stream.log("world/contacts/forces",
                   rr.Arrows3D.from_fields(radii=[0.002], colors=[FORCE_COLOR]), static=True)


def _geometry(shape, pose: Pose, rgba: np.ndarray) -> list:
    """The archetypes that draw ``shape`` placed at ``pose`` in an entity's frame, in colour
    ``rgba`` (4,) uint8, to be logged as one static row: a Compound's parts are flattened,
    and primitives of a kind share one archetype (its instances placed by their poses)."""
    leaves = _primitives(shape, pose)
    archetypes = []
    for kind, build in _ARCHETYPES:
        parts = [(s, p) for s, p in leaves if isinstance(s, kind)]
        if parts:
            archetypes.append(build(parts, rgba))
    return archetypes


def _primitives(shape, pose: Pose) -> list:
    """(shape, Pose) of every primitive of ``shape`` placed at ``pose`` (Compounds flattened,
    their part poses composed with ``pose``)."""
    if not isinstance(shape, Compound):
        return [(shape, pose)]
    return [leaf for part, part_pose in shape.parts
            for leaf in _primitives(part, Pose(pose.apply(part_pose.position),
                                               quat.multiply(pose.orientation,
                                                             part_pose.orientation)))]


def _boxes(parts: list, rgba: np.ndarray) -> rr.Boxes3D:
    """One box instance per (Box, Pose) in ``parts``, all in colour ``rgba`` (4,) uint8."""
    return rr.Boxes3D(half_sizes=[s.half_extents for s, _ in parts],
                      centers=[p.position for _, p in parts],
                      quaternions=[_xyzw(p.orientation) for _, p in parts], colors=[rgba],
                      fill_mode=rr.components.FillMode.Solid)


def _spheres(parts: list, rgba: np.ndarray) -> rr.Ellipsoids3D:
    """One ellipsoid instance per (Sphere, Pose) in ``parts`` (a sphere needs no turn)."""
    return rr.Ellipsoids3D(half_sizes=[[s.radius] * 3 for s, _ in parts],
                           centers=[p.position for _, p in parts], colors=[rgba],
                           fill_mode=rr.components.FillMode.Solid)


def _capsules(parts: list, rgba: np.ndarray) -> rr.Capsules3D:
    """One capsule instance per (Capsule, Pose) in ``parts``. Ours are centred on their
    origin; rerun's run from theirs along +z, so each starts at -half_length."""
    return rr.Capsules3D(lengths=[2.0 * s.half_length for s, _ in parts],
                         radii=[s.radius for s, _ in parts],
                         translations=[p.apply([0.0, 0.0, -s.half_length]) for s, p in parts],
                         quaternions=[_xyzw(p.orientation) for _, p in parts], colors=[rgba],
                         fill_mode=rr.components.FillMode.Solid)


def _meshes(parts: list, rgba: np.ndarray) -> rr.Mesh3D:
    """Meshes as triangle soups with crease-aware normals (as the renderer shades them),
    Planes as a square of PLANE_HALF_SIZE (two triangles) facing +z; all in one Mesh3D."""
    positions, normals, triangles, count = [], [], [], 0
    for shape, pose in parts:
        if isinstance(shape, Plane):
            h = PLANE_HALF_SIZE
            corners = np.array([[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]])
            faces = np.array([[0, 1, 2], [0, 2, 3]])
            normal = np.tile([0.0, 0.0, 1.0], (4, 1))
        else:
            vertices, mesh_triangles = tessellate(shape)
            corners = vertices[mesh_triangles].reshape(-1, 3)
            faces = np.arange(len(corners)).reshape(-1, 3)
            normal = _corner_normals(vertices, mesh_triangles)
        positions.append(pose.apply(corners))
        normals.append(normal @ pose.rotation().T)
        triangles.append(faces + count)
        count += len(corners)
    return rr.Mesh3D(vertex_positions=np.concatenate(positions),
                     vertex_normals=np.concatenate(normals),
                     triangle_indices=np.concatenate(triangles), albedo_factor=rgba)


_ARCHETYPES = ((Box, _boxes), (Sphere, _spheres), (Capsule, _capsules), ((Mesh, Plane), _meshes))
"""(kind of primitive, the function that builds their archetype)."""


def _transform(position, orientation) -> rr.Transform3D:
    """position (3,) m, orientation (4,) (w, x, y, z)."""
    return rr.Transform3D(translation=position,
                          quaternion=rr.Quaternion(xyzw=_xyzw(orientation)))


def _xyzw(q) -> np.ndarray:
    """Quaternion(s) (..., 4) (w, x, y, z) -> rerun's (x, y, z, w)."""
    return np.asarray(q)[..., [1, 2, 3, 0]]


class _Markers:
    """Collects an env's goal markers: stands in for the Renderer in ``_add_markers``."""

    def __init__(self):
        self.shapes: list = []

    def add_marker(self, shape, position=(0.0, 0.0, 0.0), color=MARKER_COLOR, alpha=1.0,
                   orientation=(1.0, 0.0, 0.0, 0.0)) -> int:
        """As ``Renderer.add_marker``: the marker's shape, pose, colour (r, g, b) in [0, 1]
        and opacity in (0, 1]; returns its index."""
        rgba = np.round(255 * np.append(np.asarray(color, dtype=np.float64), alpha))
        self.shapes.append((shape, Pose(position, orientation), rgba.astype(np.uint8)))
        return len(self.shapes) - 1


@functools.lru_cache(maxsize=32)
def _blueprint_file(application_id: str, eye: tuple | None, target: tuple | None,
                    scalars: bool, grid: bool) -> bytes:
    """``_blueprint(eye, target, scalars, grid)`` saved for ``application_id`` as an ``.rbl``
    file's bytes; built once per layout (it takes ~25 ms)."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "blueprint.rbl"
        _blueprint(eye, target, scalars, grid).save(application_id, path)
        return path.read_bytes()


def _blueprint(eye, target, scalars: bool, grid: bool) -> rrb.Blueprint:
    """The 3D view (from ``eye`` (3,) m towards ``target`` (3,) m if given; rerun's line grid
    at z = 0 only if ``grid``: a table would hide it), beside plots of the reward, the action
    and success when ``scalars``; playing on ``sim_time``."""
    controls = None if eye is None else rrb.EyeControls3D(position=eye, look_target=target)
    view = rrb.Spatial3DView(origin="/world", name="scene", eye_controls=controls,
                             line_grid=grid)
    if scalars:
        plots = rrb.Vertical(*(rrb.TimeSeriesView(origin=f"/{name}", name=name)
                               for name in ("reward", "action", "success")))
        view = rrb.Horizontal(view, plots, column_shares=[3, 1])
    return rrb.Blueprint(view, rrb.BlueprintPanel(state="collapsed"),
                         rrb.SelectionPanel(state="collapsed"),
                         rrb.TimePanel(timeline="sim_time", play_state="playing"))


# -- helpers ------------------------------------------------------------------------------------

def _contacts(world, index: int, force_scale: float):
    """World ``index``'s contacts at the current poses: points (k, 3) m, and for every pair
    that exchanged an impulse in the last solver step and still touches, an arrow origin
    (the centroid of its points) and vector (its mean force on its first body x
    ``force_scale``), (p, 3) each, m."""
    collider = world.collider
    count = int(collider.pair_count[index])
    pairs = np.stack([collider.pair_a[index, :count], collider.pair_b[index, :count]], axis=1)
    impulses = collider.pair_impulse[index, :count].copy()  # before contacts() reuses buffers
    found = world.contacts(margin=CONTACT_MARGIN)
    mine = found.world == index
    points, a, b = found.point[mine], found.body_a[mine], found.body_b[mine]
    origins, vectors = [], []
    for (i, j), impulse in zip(pairs, impulses):
        touching = ((a == i) & (b == j)) | ((a == j) & (b == i))
        if np.any(impulse) and np.any(touching):
            origins.append(points[touching].mean(axis=0))
            vectors.append(impulse / world.dt * force_scale)
    return points, np.reshape(origins, (-1, 3)), np.reshape(vectors, (-1, 3))


def _run_name(run: str | None, where: str) -> str:
    """``run``, checked, or ``<date>-<time>-<process id>``."""
    if run is None:
        return f"{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}"
    if not isinstance(run, str) or not RUN_PATTERN.fullmatch(run):
        raise ValueError(f"{where}: must be a non-empty name of letters, digits, '_', '.' and "
                         f"'-' (it names files), got {run!r}")
    return run
