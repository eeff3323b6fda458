"""The process that writes the rerun files of ``rigid_gym.recording``, and its client.

Each file is one ``ChunkStore`` of rerun chunks, written in one go when the file is closed
(``rerun.chunk.ChunkStore.write_rrd``): a file costs the writer less CPU this way than through a
``RecordingStream``, whose file sink and batcher start and join threads for every file; the
chunks the scene's files share are built once. Its layout (blueprint) is a file beside it,
``<application id>.rbl`` in the same folder, written once: a rerun file holds one store, and a
blueprint is a store of its own, which rerun binds to recordings by their application id
(``rigid-gym replay FILE`` opens both; so does ``rerun FOLDER/*``). The recorders only buffer an
episode's rows in numpy and hand them to a writer process, which does all the rerun work while
the env goes on: one writer per recording process, started at its first file (``writer()``),
files written in the order their messages were sent.

Messages are tuples, handed over in pickled lists on the writer's standard input:

- ``("layout", key, scene, application_id, blueprint)``: what files of ``scene`` share, built
  once (``_Layout``); blueprint: the ``_blueprint`` arguments (camera, series, grid): camera
  (eye (3,) m, target (3,) m, vertical field of view (deg)) or None, series ((name, labels,
  RGB (lines, 3) ints in [0, 255]) per plot), grid a bool.
- ``("open", path, recording_id, key, statics, contacts)``: start a file (path: a str, as
  in every message about a file); statics: {body index: (position (3,) m, orientation (4,)
  w, x, y, z)} of the static bodies, as tuples.
- ``("markers", path, markers)``: goal markers, (shape, position, orientation, RGBA) each
  (``_File.markers``).
- ``("rows", path, data, w)``: rows (T, w) of ``recording._Rows``, as the bytes of a
  float64 array: step, time, every body's pose, and for an env the values of its series
  in the layout's order (none at step 0, the env's reset).
- ``("contacts", path, steps (T,), times (T,) s, points, origins, vectors)``: rows.
- ``("close", path)``: write the file (until then its chunks are held in memory: ~40 bytes
  per moving body and row).
- ``("sync",)``: answered on standard output, once everything sent before it is written, with
  the pickled list of the files that could not be written since the last answer,
  ``(path, errno or None, reason, filename or None)`` each (``_failure_error``).
- ``("stop",)``, or the end of the input (its client's process ended, however it ended):
  complete every open file and exit.

A file that cannot be written (an unwritable folder, a name too long, a full disk) is dropped,
its later messages ignored, and its error kept for the next sync's answer: the other files are
written, and the client raises the error from the recorder of that file (``Writer.sync``).
Errors no sync collected are printed on the shared standard error as the writer exits.

The writer runs at a lower priority (``NICENESS``) in a process group of its own, so Ctrl-C,
which a terminal sends to the foreground process group, never reaches it, not even while it
is still importing (~1 s after the first file); it finishes the files it was given when its
client stops it or dies. A client ending on Ctrl-C does not wait for that (``Writer.stop``):
it exits at once and says so, and the writer completes the files in the background. A write
that Ctrl-C cut short leaves part of a message, the last the writer reads.
"""

from __future__ import annotations

import atexit
import functools
import os
import pickle
import signal
import subprocess
import sys
import time
from pathlib import Path

try:
    import fcntl  # Unix only
except ImportError:
    fcntl = None  # type: ignore[assignment]  # _widen's AttributeError path

import numpy as np
import rerun as rr
import rerun.blueprint as rrb
from rerun.chunk import Chunk, ChunkStore

from rigid_gym import quaternion as quat
from rigid_gym._core import STATIC
from rigid_gym.geometry import primitives
from rigid_gym.render import body_colors, corner_normals, tessellate
from rigid_gym.scene import Scene
from rigid_gym.shapes import Box, Capsule, Mesh, Plane, Pose, Sphere

PIPE_BYTES = 1 << 20
"""bytes the pipe to the writer holds (Linux's default is 64 KiB): ~70 files of 50-step
episodes."""
NICENESS = 10
"""The writer runs at a lower priority: where it competes with the env for a core, the env
goes first, and the writer catches up while the env waits (on a full pipe, or a sync)."""
EXIT_WAIT = 10.0
"""s to wait for the exit code of a writer whose pipes have closed (it is exiting)."""
PLANE_HALF_SIZE = 1.0
"""m: a Plane (the ground) is drawn as the square |x|, |y| <= this."""
RECURRING_CACHE = 64
"""Recurring static rows kept per layout (``_Layout.static``)."""
CONTACT_COLOR = (230, 40, 40)
FORCE_COLOR = (250, 150, 30)
CAMERA_ENTITY = "world/camera"
"""Where an env's camera is (a Pinhole), which the 3D view looks through."""


# -- the client ---------------------------------------------------------------------------------

class Writer:
    """A writer process and the pipe to it (``writer()`` gives the process's own).

    ``failures``: {path: (errno, reason, filename)} of the files the writer reported it could
    not write, until their recorder raises the error (``sync``)."""

    def __init__(self):
        self.owner = os.getpid()
        # process_group=0: a group of its own, which the terminal's Ctrl-C (sent to the
        # foreground group) does not reach; the writer ends when its input does (POSIX only)
        self.process = subprocess.Popen([sys.executable, "-m", "rigid_gym.recording_writer"],
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        process_group=0)
        assert self.process.stdin is not None and self.process.stdout is not None  # PIPEs
        self.input, self.output = self.process.stdin, self.process.stdout
        _widen(self.input)
        self.layouts = 0
        self.pending: list[tuple] = []
        self.failures: dict[str, tuple] = {}
        self.stopped = False
        self.torn = False
        """Whether a write to the pipe was cut short (Ctrl-C while ``flush`` wrote): the
        writer then holds part of a message, after which nothing more may be sent."""
        atexit.register(self.stop)

    def layout(self, scene: Scene, application_id: str, blueprint: tuple) -> int:
        """Send a ``_Layout`` to build; returns its key for ``open``."""
        self.layouts += 1
        self.send("layout", self.layouts, scene, application_id, blueprint)
        return self.layouts

    def send(self, *message, flush: bool = False) -> None:
        """Hand ``message`` to the writer. Messages are held until ``flush`` (the end of a
        file or of a chunk of rows) hands them over as one pickled list, so that the writer
        wakes once per file, not once per message (a 50-step episode's are ~15 KiB)."""
        self.pending.append(message)
        if flush:
            self.flush()

    def flush(self) -> None:
        """Hand the held messages over now; waits only while the pipe is full (the writer is
        behind by ``PIPE_BYTES``, or 64 KiB where the pipe could not be widened)."""
        batch, self.pending = self.pending, []
        data = pickle.dumps(batch, protocol=pickle.HIGHEST_PROTOCOL)
        if self.torn:
            raise RuntimeError("the pipe to the rerun writer holds part of a message (a write "
                               "was interrupted); nothing more can be sent to it")
        self.torn = True
        try:
            self.input.write(data)
            self.input.flush()
        except (BrokenPipeError, ValueError) as error:  # ValueError: the pipe was closed
            raise RuntimeError(self._ended()) from error
        self.torn = False

    def sync(self, paths=frozenset()) -> None:
        """Wait until every file sent so far is written, then raise the writer's error for
        the first of ``paths`` (a container of str) that could not be written (an OSError
        with the OS's errno where there is one, else a RuntimeError; each error once). The
        errors of other files are kept for their recorders."""
        self.send("sync", flush=True)
        try:
            failures = pickle.load(self.output)
        except EOFError:
            raise RuntimeError(self._ended()) from None
        for path, *failure in failures:
            self.failures[path] = tuple(failure)
        failed = next((path for path in self.failures if path in paths), None)
        if failed is not None:
            raise _failure_error(failed, *self.failures.pop(failed))

    def stop(self, wait: bool | None = None) -> None:
        """Let the writer complete every file and exit (idempotent); ``wait`` for it (by
        default, unless this process is ending on Ctrl-C). Errors that no recorder raised are
        printed on standard error.

        Ctrl-C (an uncaught KeyboardInterrupt, as this runs at exit) does not wait: the writer,
        which Ctrl-C does not reach, completes the files it was handed on its own once its
        input ends, while this process exits at once. A writer at its lower priority behind
        busy cores can take many seconds to get there (importing rerun comes first),
        and a Ctrl-C should stop the process now."""
        atexit.unregister(self.stop)
        if os.getpid() != self.owner:  # a forked child's copy: the parent's writer
            return
        if wait is None:
            wait = not isinstance(getattr(sys, "last_value", None), KeyboardInterrupt)
        self.stopped = True
        if self.process.poll() is None:
            try:
                if not self.torn:  # else the writer reads part of a message, then the end
                    self.send("stop", flush=True)
                self.input.close()
            except (RuntimeError, OSError):
                pass  # it ended already: its error is on standard error
        if not wait and self.process.poll() is None:
            print(f"rigid_gym.recording_writer: interrupted; the writer process (pid "
                  f"{self.process.pid}) completes the files it was handed in the background",
                  file=sys.stderr, flush=True)
            return
        self.process.wait()
        for pipe in (self.input, self.output):
            try:
                pipe.close()
            except BrokenPipeError:  # a dead writer's unsent bytes
                pass
        for path, failure in self.failures.items():
            _report(_failure_error(path, *failure))
        self.failures.clear()

    def _ended(self) -> str:
        try:  # its pipes closed as it exited: the exit code follows
            code = self.process.wait(EXIT_WAIT)
        except subprocess.TimeoutExpired:
            code = None
        return (f"the rerun writer process (rigid_gym.recording_writer) has ended (exit code "
                f"{code}); the files it had not written are lost; its error, if any, is above "
                f"on standard error")


def _failure_error(path: str, errno: int | None, reason: str,
                  filename: str | None) -> Exception:
    """The error of the file ``path`` that the writer could not write: an OSError with
    ``errno`` and the OS's ``reason`` (and the ``filename`` that failed, when not the file
    itself: its folder), or, without an errno, a RuntimeError with ``reason``."""
    what = f"the rerun writer could not write {path}: {reason}"
    if errno is None:
        return RuntimeError(what)
    return OSError(errno, what, None if filename == path else filename)


def _report(error: Exception) -> None:
    """Print a file's error on standard error, where no recorder is left to raise it."""
    print(f"rigid_gym.recording_writer: {error}", file=sys.stderr, flush=True)


def _widen(pipe) -> None:
    """Let ``pipe`` hold ``PIPE_BYTES`` (where the system allows it): a writer held up for a
    moment (another process took its core) then does not hold up the env at once."""
    try:
        fcntl.fcntl(pipe.fileno(), fcntl.F_SETPIPE_SZ, PIPE_BYTES)
    except (AttributeError, OSError):  # not Linux, or above /proc/sys/fs/pipe-max-size
        pass  # the default size: the env waits sooner, nothing else changes


_writer: Writer | None = None


def writer() -> Writer:
    """This process's writer, started at the first call (again in a forked child, and after
    ``stop``). Raises if it ended otherwise: the files it was handed may be lost."""
    global _writer
    if _writer is not None and _writer.owner == os.getpid():
        if _writer.process.poll() is None:
            return _writer
        if not _writer.stopped:
            raise RuntimeError(_writer._ended())
    _writer = Writer()
    return _writer


# -- the writer process -------------------------------------------------------------------------

def main() -> None:
    """Write files from the messages on standard input until ``stop`` or its end."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # one sent to this process by its id
    os.nice(NICENESS)
    answers = os.fdopen(os.dup(1), "wb")  # standard output is for answers only:
    os.dup2(2, 1)  # what anything else prints goes to standard error
    layouts: dict[int, _Layout] = {}
    files: dict[str, _File | None] = {}  # None: a file that failed; its messages are dropped
    failures: list[tuple] = []  # (path, errno, reason, filename), until a sync answers them
    try:
        for kind, *args in _messages(sys.stdin.buffer):
            if kind == "stop":
                break
            if kind == "sync":
                pickle.dump(failures, answers)
                answers.flush()
                failures = []
            elif kind == "layout":
                key, scene, application_id, blueprint = args
                layouts[key] = _Layout(scene, application_id, blueprint)
            else:
                path = args[0]
                try:
                    _handle(files, layouts, kind, args)
                except Exception as error:  # noqa: BLE001 - any failure is this file's; others go on
                    if kind != "close":
                        files[path] = None
                    failures.append(_failure(path, error))
    finally:
        for path, file in files.items():
            if file is not None:
                try:
                    file.close()
                except Exception as error:  # noqa: BLE001 - reported like any other failure
                    failures.append(_failure(path, error))
        for failure in failures:  # no sync is left to answer them
            _report(_failure_error(*failure))


def _handle(files: dict, layouts: dict, kind: str, args: list) -> None:
    """Apply a message about one file (``open``, ``close`` or one of ``_File``'s kinds) to
    ``files`` ({path: _File, or None for a file that failed})."""
    if kind == "open":
        path, recording_id, key, statics, contacts = args
        files[path] = _File(Path(path), recording_id, layouts[key], statics, contacts)
        return
    path, *values = args
    file = files.pop(path) if kind == "close" else files[path]
    if file is None:
        return
    if kind == "close":
        file.close()
    else:
        getattr(file, kind)(*values)


def _failure(path: str, error: Exception) -> tuple:
    """What the client needs to raise ``error`` of the file ``path`` (``_failure_error``'s
    arguments)."""
    if isinstance(error, OSError) and error.errno is not None:
        filename = None if error.filename is None else str(error.filename)
        return path, error.errno, error.strerror, filename
    return path, None, f"{type(error).__name__}: {error}", None


def _messages(source):
    """The messages of the pickled lists on ``source``, in order, until its end."""
    while True:
        try:
            batch = pickle.load(source)
        except EOFError:
            return
        except pickle.UnpicklingError:  # the last one cut short: its client was interrupted
            print("rigid_gym.recording_writer: the last message was cut short (its client was "
                  "interrupted while sending it); the files before it are completed",
                  file=sys.stderr, flush=True)
            return
        yield from batch


class _Layout:
    """What every file of one scene shares, built once (for each file, building it took
    longer than writing an episode's data): every body's entity path, the scene's static rows
    (coordinates, each body's geometry in its body frame, the camera, the series' names and
    colours) as rerun chunks, a cache of rows that recur in many files (``static``), and the
    blueprint, written beside the files (``blueprint_beside``). A chunk may be written to any
    number of files: each file is a store of its own."""

    def __init__(self, scene: Scene, application_id: str, blueprint: tuple):
        self.application_id = application_id
        self.blueprint = blueprint
        self.blueprint_folders: set[Path] = set()
        self.entities = [f"world/bodies/{rr.escape_entity_path_part(b.name)}"
                         for b in scene.bodies]
        camera, self.series, _ = blueprint
        colors = np.round(255 * body_colors(scene)).astype(np.uint8)
        self.scene = [_static_chunk("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP)] + [
            _static_chunk(self.entities[body.index],
                          *_geometry(body.shape, body.body_from_shape,
                                     np.append(colors[body.index], 255)))
            for body in scene.bodies]
        if camera is not None:
            self.scene.append(_static_chunk(CAMERA_ENTITY, *_camera(*camera)))
        self.scene += [_static_chunk(name, rr.SeriesLines(names=list(labels), colors=list(rgb)))
                       for name, labels, rgb in self.series]
        self.moving = [b.index for b in scene.bodies if b.motion != STATIC]
        self.recurring: dict[tuple, Chunk] = {}

    def static(self, entity: str, key, archetypes) -> Chunk:
        """The static row of ``archetypes()`` at ``entity``, built once per ``key`` (a
        hashable stand-in for its values): static bodies' poses, goal marker shapes (Push's
        disc, a 48-gon mesh, is slow to build), action names."""
        if (entity, key) not in self.recurring:
            if len(self.recurring) >= RECURRING_CACHE:  # values that change every episode
                self.recurring.clear()
            self.recurring[entity, key] = _static_chunk(entity, *archetypes())
        return self.recurring[entity, key]

    def blueprint_beside(self, path: Path) -> None:
        """Write the blueprint to ``<application id>.rbl`` in ``path``'s folder, once per
        folder (replacing one of an earlier run: rerun keeps one blueprint per application
        id anyway)."""
        folder = path.parent
        if folder not in self.blueprint_folders:
            _blueprint(*self.blueprint).save(self.application_id,
                                             blueprint_path(folder, self.application_id))
            self.blueprint_folders.add(folder)


def row_columns(bodies: int) -> tuple[int, int]:
    """The columns of a row of ``bodies`` bodies (``recording._Rows``) where the
    orientations start and where the reward is (step, sim_time and the positions come
    first)."""
    return 2 + 3 * bodies, 2 + 7 * bodies


def blueprint_path(folder: Path, application_id: str) -> Path:
    """Where the blueprint of ``application_id``'s files in ``folder`` is."""
    return Path(folder) / f"{application_id}.rbl"


class _File:
    """One ``.rrd`` file: chunks gathered from the messages (the scene's on creation),
    written by ``close``."""

    def __init__(self, path: Path, recording_id: str, layout: _Layout, statics: dict,
                 contacts: bool):
        self.path, self.recording_id, self.layout = path, recording_id, layout
        self.chunks = [_static_chunk("__properties", rr.archetypes.RecordingInfo(
                           start_time=time.time_ns(), name=recording_id)), *layout.scene]
        for body, pose in statics.items():
            self.chunks.append(layout.static(layout.entities[body], pose,
                                             lambda pose=pose: [_transform(*pose)]))
        if contacts:
            self.chunks += [
                layout.static("world/contacts/points", None, lambda: [rr.Points3D.from_fields(
                    radii=[0.004], colors=[CONTACT_COLOR])]),
                layout.static("world/contacts/forces", None, lambda: [rr.Arrows3D.from_fields(
                    radii=[0.002], colors=[FORCE_COLOR])])]

    def markers(self, markers: list) -> None:
        """Static goal markers: (shape, position (3,) m, orientation (4,) (w, x, y, z),
        RGBA (4,) in [0, 255]) each, as a pose and the shape's geometry in the marker's
        frame (the same entity: two static rows)."""
        for k, (shape, position, orientation, rgba) in enumerate(markers):
            entity = f"world/goals/{k}"
            self.chunks += [_static_chunk(entity, _transform(position, orientation)),
                            self.layout.static(entity, pickle.dumps((shape, rgba)),
                                               functools.partial(_geometry, shape, Pose(), rgba))]

    def rows(self, data: bytes, width: int) -> None:
        """Rows (T, width) of float64 as bytes: step, sim_time (s), every body's position
        (n x 3, m) and orientation (n x 4, w x y z), n = the scene's bodies in order; for an
        env, then the values of the layout's series in order (one per label), recorded from
        step 1 on. The moving bodies' poses are written (a static body's is written once, on
        opening)."""
        rows = np.frombuffer(data).reshape(-1, width)
        n = len(self.layout.entities)
        orientations, scalars = row_columns(n)
        steps, times = rows[:, 0], rows[:, 1]
        indexes = _indexes(steps, times)
        position = rows[:, 2:orientations].reshape(len(rows), n, 3)
        xyzw = _xyzw(rows[:, orientations:scalars].reshape(len(rows), n, 4))
        for body in self.layout.moving:
            self.chunks.append(Chunk.from_columns(
                self.layout.entities[body], indexes,
                rr.Transform3D.columns(translation=position[:, body],
                                       quaternion=xyzw[:, body])))
        after_reset = steps > 0
        stepped = rows[after_reset, scalars:]
        if stepped.shape[1] and len(stepped):
            indexes = _indexes(steps[after_reset], times[after_reset])
            start = 0
            for name, labels, _ in self.layout.series:
                values = stepped[:, start:start + len(labels)]
                start += len(labels)
                self.chunks.append(Chunk.from_columns(
                    name, indexes, rr.Scalars.columns(scalars=values.ravel())
                    .partition(lengths=np.full(len(values), len(labels)))))

    def contacts(self, steps, times, points, origins, vectors) -> None:
        """Per row: contact points (k, 3) m, force arrows' origins and vectors (p, 3) m."""
        indexes = _indexes(steps, times)
        points_column = rr.Points3D.columns(positions=np.concatenate(points))
        arrows_column = rr.Arrows3D.columns(origins=np.concatenate(origins),
                                            vectors=np.concatenate(vectors))
        self.chunks += [
            Chunk.from_columns("world/contacts/points", indexes,
                               points_column.partition(lengths=[len(p) for p in points])),
            Chunk.from_columns("world/contacts/forces", indexes,
                               arrows_column.partition(lengths=[len(o) for o in origins]))]

    def close(self) -> None:
        """Write the file (its chunks, then rerun's footer), making its folder again if it
        has gone since the file was opened, then the layout beside it. The chunks go to a
        hidden file beside it that is then renamed to the file's name, so that the name only
        ever holds a whole file: a reader never opens a half-written one, and a writer killed
        while writing leaves the hidden part, not a truncated ``.rrd`` that no reader can
        open. Raises an OSError where the file cannot be made."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        part = self.path.with_name(f".{self.path.name}.part")
        part.open("wb").close()  # rerun's own error would name neither the file nor errno
        ChunkStore.from_chunks(self.chunks).write_rrd(
            part, application_id=self.layout.application_id, recording_id=self.recording_id)
        os.replace(part, self.path)
        self.chunks = []
        self.layout.blueprint_beside(self.path)


def _static_chunk(entity: str, *archetypes) -> Chunk:
    """One static row of ``archetypes`` at ``entity``."""
    return Chunk.from_columns(entity, [], [batch.partition([len(batch.as_arrow_array())])
                                           for archetype in archetypes
                                           for batch in archetype.as_component_batches()])


def _indexes(steps, times) -> list:
    """The ``step`` (sequence) and ``sim_time`` (duration; times in s) time columns."""
    nanoseconds = np.round(np.asarray(times) * 1e9).astype(np.int64)  # not truncated
    return [rr.TimeColumn("step", sequence=np.asarray(steps, dtype=np.int64)),
            rr.TimeColumn("sim_time", duration=nanoseconds.astype("timedelta64[ns]"))]


# -- geometry and layout ------------------------------------------------------------------------

def _geometry(shape, pose: Pose, rgba: np.ndarray) -> list:
    """The archetypes that draw ``shape`` placed at ``pose`` in an entity's frame, in colour
    ``rgba`` (4,) uint8, to be logged as one static row: a Compound's parts are flattened,
    and primitives of a kind share one archetype (its instances placed by their poses)."""
    leaves = primitives(shape, pose)
    archetypes = []
    for kind, build in _ARCHETYPES:
        parts = [(s, p) for s, p in leaves if isinstance(s, kind)]
        if parts:
            archetypes.append(build(parts, rgba))
    return archetypes


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
            normal = corner_normals(vertices, mesh_triangles)
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


def _camera(eye, target, fov_deg: float) -> list:
    """The archetypes of the env camera at ``CAMERA_ENTITY``: its pose (looking from ``eye``
    (3,) m at ``target`` (3,) m, z up on screen) and a Pinhole of its vertical field of view
    ``fov_deg`` and square frames (``rigid_gym.render.Camera``'s), drawn as no more than a
    thin frustum."""
    eye, target = np.asarray(eye, dtype=np.float64), np.asarray(target, dtype=np.float64)
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)  # the camera's axes are right, down, forward (RDF)
    orientation = quat.from_matrix(np.column_stack([right, down, forward]))
    return [_transform(eye, orientation),
            rr.Pinhole(fov_y=float(np.radians(fov_deg)), aspect_ratio=1.0,
                       camera_xyz=rr.ViewCoordinates.RDF, image_plane_distance=0.05,
                       line_width=0.00002)]


def _blueprint(camera, series: tuple, grid: bool) -> rrb.Blueprint:
    """The 3D view, looking through the env's ``camera`` ((eye, target, field of view) at
    ``CAMERA_ENTITY``) if given (rerun's default eye otherwise; rerun's line grid at z = 0
    only if ``grid``: a table would hide it), beside one plot per series ((name, labels,
    colours) each); playing on ``sim_time``."""
    controls = None
    if camera is not None:
        eye, target, _ = camera
        controls = rrb.EyeControls3D(position=eye, look_target=target,
                                     tracking_entity=f"/{CAMERA_ENTITY}")
    scene = rrb.Spatial3DView(origin="/world", name="scene", eye_controls=controls,
                              line_grid=grid)
    view: rrb.Spatial3DView | rrb.Horizontal = scene
    if series:
        plots = rrb.Vertical(*(rrb.TimeSeriesView(origin=f"/{name}", name=name)
                               for name, _, _ in series))
        view = rrb.Horizontal(scene, plots, column_shares=[3, 1])
    return rrb.Blueprint(view, rrb.BlueprintPanel(state="collapsed"),
                         rrb.SelectionPanel(state="collapsed"),
                         rrb.TimePanel(timeline="sim_time", play_state="playing"))


if __name__ == "__main__":
    main()
