"""Episode recordings: any env or World to a rerun ``.rrd`` file, replayed in rerun's viewer.

    env = RecordRerun(gym.make("rigid_gym/Push-v0"))  # to recordings/rigid_gym-Push-v0/
    with WorldRecorder(world, "fall.rrd") as recorder:  # any World
        recorder.record()
        for _ in range(240):
            world.step()
            recorder.record()

Replay with ``rigid-gym replay FILE``, which opens the file with its layout: the blueprint
file beside it, ``<application id>.rbl`` (``blueprint_of``; by hand, ``rerun FILE LAYOUT.rbl``
or ``rerun FOLDER/*``, with the viewer the rerun-sdk wheel installs, which must be the SDK's
version; ``rerun FILE`` alone shows the data in rerun's own default layout).

**What an env gives** (``rigid_gym.recordable.Recordable``, which every rigid_gym env has): its
``world`` (the bodies), ``markers()`` (the goals), ``camera_view`` (the camera of its own frames)
and ``scalar_series`` / ``scalars(action, reward, info)`` (the plots and their values per step).
The recorder knows no env class.

**The layout** (``<folder>/<application id>.rbl``, written once per folder): the 3D view (for
an env, framed as its own frames: from its camera, with the camera's field of view) beside
one plot per scalar series, each line in its series' named colour, playing on ``sim_time``.
The application id is the env id (``rigid_gym-Push-v0``), or a World recorder's
``application_id``.

**What a file holds** (entity paths; frames are right-handed, z up):

- ``/world``: ``ViewCoordinates.RIGHT_HAND_Z_UP``, once.
- ``/world/bodies/<name>``: a ``Transform3D`` every step, the *body* frame: ``World.position``
  (centre of mass, m) and ``World.orientation`` converted to rerun's (x, y, z, w); a static
  body's once. Once, the body's geometry in body-frame coordinates: each primitive placed by
  ``BodySpec.body_from_shape`` (and its Compound part pose), an instance of ``Boxes3D``,
  ``Ellipsoids3D``, ``Capsules3D`` or ``Mesh3D`` (meshes, and a Plane as a square of
  ``PLANE_HALF_SIZE``).
- ``/world/goals/<k>``: an env's goal markers (its ``markers()``), translucent, once.
- ``/world/camera`` (envs): the env camera, a ``Pinhole`` with its field of view at its pose
  (looking from the eye at the target), once; the 3D view looks through it.
- ``/world/contacts/points`` (option ``contacts``): ``Points3D`` every step, the contact points
  within ``CONTACT_MARGIN``; ``/world/contacts/forces``: ``Arrows3D`` at each touching pair's
  contact centroid, its mean force on the pair's first body during the last solver step
  (impulse / dt), ``force_scale`` m per N.
- ``/<series>`` (envs; for rigid_gym's ``/reward``, ``/action``, ``/success``): ``Scalars``
  every env step, one line per label of the series (the action: one per entry, x, y, z,
  grip), named and coloured once by a static ``SeriesLines``.

Timelines: ``step`` (sequence: env steps, 0 = the state after ``reset``; for a World,
``World.steps``) and ``sim_time`` (duration: ``World.time``, s). Poses and contacts are rows at
every step from 0; the scalar series at steps 1, 2, ... (the step they led to).
Rerun stores translations and quaternions as float32 and scalars as float64.

**Cost.** Making a rerun file has a fixed CPU cost however short the episode, a large share of a
short episode of the fastest task, so the recorders only buffer rows in numpy and hand each
file's rows to a writer process (``rigid_gym.recording_writer``, one per recording process,
started at its first file), which does all the rerun work at a lower priority while the env goes
on: the env's process pays the buffering and the hand-over, the rest runs on another core when
there is one (``benchmarks/recording.py`` measures both). Rows are handed over at the end of an
episode, or every ``chunk_steps`` steps, bounding the env process's memory; the writer holds a
file's rows (~30 bytes per moving body and step) until the file ends.

**Files are complete** once the writer has written what it was handed: at the latest when
``close()`` returns, when ``step`` or ``reset`` raises (what was buffered is written, then the
exception propagates), and when the process exits (an ``atexit`` hook hands over any open
file and waits for the writer); a process killed outright, or stopped by Ctrl-C, loses only
the rows it had not handed over (a writer killed outright loses the files it had not
finished; Ctrl-C does not reach it). On Ctrl-C the process exits at once, without waiting:
the writer completes the files in the background (and says so on standard error, with its
process id), however busy the machine. Files of finished episodes are written in the
background: ``sync()`` waits for them. A file the writer cannot write (an unwritable folder,
a name too long) is reported by its own recorder: ``sync()`` and ``close()`` raise its
OSError, naming the file; the other files, and later ones, are written. Nothing is made
until an episode starts, so the wrappers can be built inside SubprocVecEnv workers (each
worker has its own writer and files; the default run name contains the process id).
``RERUN=off`` in the environment turns recording off: nothing is written and nothing fails.
"""

from __future__ import annotations

import atexit
import os
import re
import time
from pathlib import Path
from typing import Self

import gymnasium as gym
import numpy as np
from rerun.chunk import RrdReader

from rigid_gym._core import STATIC
from rigid_gym.checks import in_range, integer
from rigid_gym.recordable import Marker, Recordable
from rigid_gym.recording_writer import Writer, blueprint_path, row_columns, writer
from rigid_gym.shapes import Plane, Pose

RECORDINGS = "recordings"
"""Default output folder of ``RecordRerun``."""
CHUNK_STEPS = 1000
"""Buffered steps after which rows are sent, so that a long episode's memory stays bounded."""
CONTACT_MARGIN = 1e-3
"""m: contacts closer than this are recorded (resting contacts barely overlap)."""
FORCE_SCALE = 0.05
"""m of arrow per N of contact force (a 0.1 kg cube's weight, 0.98 N, is a 5 cm arrow)."""
RUN_PATTERN = re.compile(r"[A-Za-z0-9_.-]+")


# -- the episode wrapper ------------------------------------------------------------------------

class RecordRerun(gym.Wrapper):
    """Record a rigid_gym env's episodes, one ``.rrd`` file each (like ``RecordVideo``).

    env: a rigid_gym env (``gym.make("rigid_gym/...")``, wrapped or not), or any env whose
        ``unwrapped`` is ``rigid_gym.recordable.Recordable``.
    folder: output folder; files go to ``folder/<env id>/<run>-episode-<k>.rrd``, the env id
        with every character outside ``[A-Za-z0-9_.-]`` replaced by ``-``
        (``recordings/rigid_gym-Push-v0/...``); k counts resets from 0.
    episode_trigger: ``k -> bool``, which episodes to record; default ``cubic_schedule``.
    run: a name made of ``[A-Za-z0-9_.-]``; default ``<date>-<time>-<process id>``, unique
        per process. Wrappers that share a folder and an env id need different runs.
    contacts: also record contact points and force arrows (``force_scale`` m per N).
    chunk_steps: steps buffered before they are sent (>= 1).

    ``paths`` lists the files started so far; files of finished episodes are written in the
    background (``sync`` waits for them, ``close`` does too, and both raise the error of a
    file that could not be written).
    """

    def __init__(self, env: gym.Env, folder: str | os.PathLike = RECORDINGS,
                 episode_trigger=None, run: str | None = None, contacts: bool = False,
                 force_scale: float = FORCE_SCALE, chunk_steps: int = CHUNK_STEPS):
        super().__init__(env)
        if not isinstance(env.unwrapped, Recordable):
            raise ValueError(f"RecordRerun.env: expected a rigid_gym env, got "
                             f"{type(env.unwrapped).__name__} (it lacks members of "
                             "rigid_gym.recordable.Recordable: world, camera_view, "
                             "scalar_series, markers, scalars)")
        if episode_trigger is not None and not callable(episode_trigger):
            raise ValueError(f"RecordRerun.episode_trigger: expected a function episode index "
                             f"-> bool, got {episode_trigger!r}")
        self.episode_trigger = cubic_schedule if episode_trigger is None else episode_trigger
        self.recordable = env.unwrapped
        """What is recorded (``rigid_gym.recordable.Recordable``): the env under the wrappers."""
        self.run = _run_name(run, "RecordRerun.run")
        self.env_id = env.spec.id if env.spec is not None else type(env.unwrapped).__name__
        self.folder = Path(folder) / re.sub(r"[^A-Za-z0-9_.-]+", "-", self.env_id)
        self.options = _Options(contacts, force_scale, chunk_steps, "RecordRerun")
        self.paths: list[Path] = []
        self.episode_id = -1
        self._layout: tuple | None = None  # (scene, the writer's key): _scene_layout
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
                self._recording.record(self._step, self.recordable.scalars(action, reward, info))
        except BaseException as error:
            self._end_episode(wait=not isinstance(error, KeyboardInterrupt))
            raise
        if terminated or truncated:
            self._end_episode()
        return observation, reward, terminated, truncated, info

    def close(self):
        """Complete the open episode's file and close the env; returns once every file is
        written, raising as ``sync`` does."""
        try:
            self._end_episode()
            self.sync()
        finally:
            super().close()

    def sync(self) -> None:
        """Wait until the files of finished episodes are written. Raises the writer's error
        (an OSError naming the file) for one of them that could not be, each error once."""
        if self.paths:
            writer().sync({str(path) for path in self.paths})

    def _begin_episode(self) -> None:
        task = self.recordable
        name = f"{self.run}-episode-{self.episode_id}"
        path = self.folder / f"{name}.rrd"
        scalars = sum(len(series.labels) for series in task.scalar_series)
        recording = _open(path, name, task.world, 0, self.options, self._scene_layout, scalars,
                          first=not self.paths)
        if recording is None:
            return
        self._recording, self._step = recording, 0
        self.paths.append(path)
        try:
            recording.send("markers", [_marker_row(marker) for marker in task.markers()])
            recording.record(0)
        except BaseException as error:
            self._end_episode(wait=not isinstance(error, KeyboardInterrupt))
            raise

    def _scene_layout(self, files: Writer) -> int:
        """The writer's key of the env's scene layout, sent again only for a new World."""
        task = self.recordable
        if self._layout is None or self._layout[0] is not task.world.scene:
            eye, target, fov = task.camera_view
            series = tuple((s.name, tuple(s.labels), tuple(map(tuple, s.rgb255().tolist())))
                           for s in task.scalar_series)
            key = files.layout(task.world.scene, self.folder.name,
                               ((tuple(map(float, eye)), tuple(map(float, target)), float(fov)),
                                series, False))
            self._layout = (task.world.scene, key)
        return self._layout[1]

    def _end_episode(self, wait: bool = False) -> None:
        """Hand the episode's file over to the writer; ``wait`` until it is written. Waiting
        raises no file's error (it runs while an exception propagates, which goes first):
        ``sync`` and ``close`` do."""
        recording, self._recording = self._recording, None
        if recording is not None:
            recording.close()
        if wait and self.paths:
            writer().sync()


def blueprint_of(path: str | os.PathLike) -> Path | None:
    """The layout of the recording ``path``: the blueprint file beside it
    (``<application id>.rbl`` in its folder), or None if there is none or ``path`` is not a
    readable rerun file."""
    try:
        recordings = RrdReader(os.fspath(path)).recordings()
    except (OSError, RuntimeError, ValueError):
        return None
    for recording in recordings:
        blueprint = blueprint_path(Path(path).parent, recording.application_id)
        if blueprint.is_file():
            return blueprint
    return None


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
        self.world_index = integer(world_index, "WorldRecorder.world_index", 0,
                                   world.num_worlds - 1)
        self.world = world
        self.path = Path(path)
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
            self._recording.record(self.world.steps)

    def _layout(self, files: Writer) -> int:
        grid = not any(isinstance(b.shape, Plane) for b in self.world.scene.bodies)
        return files.layout(self.world.scene, self.application_id, (None, (), grid))

    def close(self) -> None:
        """Write what is buffered and complete the file; returns once it is written
        (idempotent). Raises the writer's error (an OSError naming the file) if it could not
        be written."""
        self._close(errors=True)

    def __enter__(self) -> Self:
        return self

    def __exit__(self, exc_type, exc, traceback) -> None:
        # an exception from the block goes first; the file's error, if any, is then printed
        # when the writer stops
        self._close(errors=exc_type is None)

    def _close(self, errors: bool) -> None:
        self._state = "closed"
        if self._recording is not None:
            self._recording.close(wait=True, errors=errors)


# -- one file -----------------------------------------------------------------------------------

class _Options:
    """Validated recording options shared by both recorders."""

    def __init__(self, contacts, force_scale, chunk_steps, where: str):
        if not isinstance(contacts, bool):
            raise ValueError(f"{where}.contacts: must be a bool, got {contacts!r}")
        self.contacts = contacts
        self.force_scale = in_range(force_scale, 0.0, np.inf, f"{where}.force_scale",
                                    open_low=True, unit="m per N")
        self.chunk_steps = integer(chunk_steps, f"{where}.chunk_steps", 1)


def _open(path: Path, recording_id: str, world, index: int, options: _Options, layout,
          scalars: int = 0, first: bool = True) -> _Recording | None:
    """A new recording of world ``index`` of ``world`` to ``path``, or None when rerun is off
    (``RERUN=off``, ``0`` or ``false``, which rerun documents). ``layout``: a function of the
    writer that gives the key of the scene's layout there; ``scalars``: the values an env
    step records (its series' labels; 0: none); ``first``: the recorder's first file, whose
    folder is made here, so that a bad folder fails here (for later files the writer, not the
    env's process, makes the folder again if it has gone)."""
    if os.environ.get("RERUN", "").strip().lower() in ("0", "off", "false"):
        return None
    if first:
        path.parent.mkdir(parents=True, exist_ok=True)
    files = writer()
    return _Recording(files, path, recording_id, layout(files), world, index, options, scalars)


class _Recording:
    """One file of one world of ``world`` (index ``index``): opened in the writer on
    creation; ``record`` buffers rows, which ``flush`` hands to the writer; ``close``
    completes the file. Small values go to the writer as plain tuples, rows as the bytes of one
    array (``_Rows``; the writer keeps the moving bodies' columns): pickling a numpy array has a
    fixed cost however small it is, several times that of its bytes. ``scalars``: the values an
    env step records, which its rows also hold (0: a World's rows hold none)."""

    def __init__(self, files: Writer, path: Path, recording_id: str, layout: int, world,
                 index: int, options: _Options, scalars: int = 0):
        self.files, self.path = files, str(path)  # a str pickles faster than a Path
        self.world, self.index, self.options = world, index, options
        bodies = world.scene.bodies
        statics = {b.index: (tuple(world.state.position[index, b.index].tolist()),
                             tuple(world.state.orientation[index, b.index].tolist()))
                   for b in bodies if b.motion == STATIC}
        self.rows = _Rows(len(bodies), scalars)
        self.contacts: list[tuple] = []  # (step, time, points, origins, vectors): ragged rows
        self.closed = False
        files.send("open", self.path, recording_id, layout, statics, options.contacts)
        atexit.register(self.close)

    def send(self, kind: str, *values) -> None:
        """Hand the writer a message about this file: one of ``recording_writer``'s kinds
        ("markers", "rows", ...) and its values."""
        self.files.send(kind, self.path, *values)

    def record(self, step: int, scalars=None) -> None:
        """Buffer the bodies' poses (and contacts, if on) at ``step``; for an env after a step,
        also the step's ``scalars`` (its series' values, in order)."""
        w, s = self.world, self.world.state
        self.rows.append(step, w.time, s.position[self.index], s.orientation[self.index],
                         scalars)
        if self.options.contacts:
            self.contacts.append((step, w.time,
                                  *_contacts(w, self.index, self.options.force_scale)))
        if len(self.rows) >= self.options.chunk_steps:
            self.flush()

    def flush(self) -> None:
        """Hand every buffered row to the writer now, and empty the buffers."""
        self._send_rows()
        self.files.flush()

    def close(self, wait: bool = False, errors: bool = True) -> None:
        """Hand the remaining rows and the file's end to the writer; ``wait`` until it is
        written, raising the writer's error if it could not be (``errors``). Idempotent."""
        if not self.closed:
            self.closed = True
            atexit.unregister(self.close)
            if self.files.torn:  # Ctrl-C cut a message short: the writer completes the file
                return           # from what it has, and nothing more can be sent
            try:
                self._send_rows()
            finally:
                self.files.send("close", self.path, flush=True)
        if wait:
            self.files.sync({self.path} if errors else ())

    def _send_rows(self) -> None:
        if len(self.rows):
            rows = self.rows.take()
            self.send("rows", rows.tobytes(), rows.shape[1])  # bytes pickle faster than an array
        if self.contacts:
            steps, times, points, origins, vectors = zip(*self.contacts)
            self.contacts = []
            self.send("contacts", np.array(steps), np.array(times), points, origins, vectors)


class _Rows:
    """Rows buffered for columns, one float64 array of them that grows as needed (no object
    per row, and one buffer to hand over).
    A row of ``bodies`` bodies and ``scalars`` scalar values (0: a World's rows) holds:

        step, sim_time (s), positions (bodies x 3, m), orientations (bodies x 4, w x y z)
        [, the scalars]

    A row without scalars (an env's reset) has NaN there.
    """

    def __init__(self, bodies: int, scalars: int = 0):
        self.orientations, self.scalars = row_columns(bodies)
        self.width = self.scalars + scalars
        self.count = 0
        self.data = np.empty((0, self.width))

    def __len__(self) -> int:
        return self.count

    def append(self, step: int, sim_time: float, position: np.ndarray,
               orientation: np.ndarray, scalars=None) -> None:
        """Add a row: position (bodies, 3), orientation (bodies, 4), and ``scalars`` if given
        (the row's scalar values, in order)."""
        if self.count == len(self.data):
            grown = np.empty((max(64, 2 * self.count), self.width))
            grown[:self.count] = self.data[:self.count]
            self.data = grown
        row = self.data[self.count]
        row[0], row[1] = step, sim_time
        row[2:self.orientations] = position.ravel()
        row[self.orientations:self.scalars] = orientation.ravel()
        if self.width > self.scalars:
            row[self.scalars:] = np.nan if scalars is None else scalars
        self.count += 1

    def take(self) -> np.ndarray:
        """The rows (T, width), and empty the buffer (the array returned is not reused)."""
        taken, self.count = self.data[:self.count], 0
        self.data = np.empty((0, self.width))
        return taken


# -- helpers ------------------------------------------------------------------------------------

def _marker_row(marker: Marker) -> tuple:
    """A goal marker as the writer takes it: (shape, position (3,) m, orientation (4,) w, x,
    y, z, RGBA (4,) ints in [0, 255]), plain tuples (checked through Pose)."""
    pose = Pose(marker.position, marker.orientation)
    rgba = np.round(255 * np.append(np.asarray(marker.color, dtype=np.float64), marker.alpha))
    return (marker.shape, tuple(pose.position.tolist()), tuple(pose.orientation.tolist()),
            tuple(rgba.astype(int).tolist()))


def _contacts(world, index: int, force_scale: float):
    """World ``index``'s contacts at the current poses: points (k, 3) m, and for every pair
    that exchanged an impulse in the last solver step and still touches, an arrow origin
    (the centroid of its points) and vector (its mean force on its first body x
    ``force_scale``), (p, 3) each, m."""
    pairs, impulses = world.listed_pairs(index)
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
