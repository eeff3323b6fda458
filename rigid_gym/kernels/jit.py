"""The one place that sets how kernels are compiled.

``cache=True`` so a fresh process loads compiled code from ``__pycache__`` instead of compiling;
``fastmath=False`` so results are IEEE-exact and runs are bit-for-bit repeatable;
``error_model="numpy"`` so a division by zero gives inf/nan (caught by validation upstream)
rather than a Python exception inside a parallel loop.

Kernels are compiled without reference counting and small helpers are inlined (``kernel``):
both remove per-call costs that dominated the step (docs/architecture.md, "Speed").

A kernel compiled with ``parallel=True`` (a ``prange`` over worlds) also carries a serial twin,
``kernel.serial``: with a single world, waking numba's thread pool costs more than the work
(about 8 ms per call when another process keeps the cores busy). ``World.step`` calls the
whole-step kernel ``kernels.step.step_world`` directly for a single world; the phase-by-phase
pipeline (``World(profile=True)``) uses the twins for the light kernels and runs the solver
phases' parallel code on the calling thread alone (``calling_thread_only``).
"""

import contextlib
import types

import numba

JIT_FLAGS = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")


def kernel(fn=None, *, parallel: bool = False, allocates: bool = False, inline: bool = False):
    """Compile ``fn`` with the project's flags.

    Kernels do not reference-count arrays (numba's ``_nrt=False``): numba otherwise increments
    and decrements, atomically, the count of every array a call receives, a namedtuple's
    members included, at every call that is not inlined; with the geometry's 21 arrays, that
    made a plane's distance cost 300 ns instead of 20 (measured). Such kernels cannot allocate:
    ``allocates=True`` keeps reference counting for those that do (outside the step).
    ``inline=True`` inlines the kernel into its callers (numba IR). For a small hot helper that
    takes namedtuples of arrays, since a call passes every member's fields as separate
    arguments (the geometry alone is ~180): a box's 8 corners against a plane took 981 ns,
    446 inlined. And required for a kernel that returns views of its arguments: inlined, the
    views are counted exactly when the caller counts (a view returned uncounted to a counting
    caller would be released twice: heap corruption, seen). ``parallel=True`` enables
    ``numba.prange`` (with counting, as numba's parallel loops need) and adds the serial twin
    ``.serial``."""

    def wrap(f):
        if inline:
            return numba.njit(**JIT_FLAGS, inline="always")(f)
        if not parallel:
            return numba.njit(**JIT_FLAGS, _nrt=allocates)(f)
        compiled = numba.njit(parallel=True, **JIT_FLAGS)(f)
        # a distinct name keeps the twin's on-disk cache apart from the parallel one
        twin = types.FunctionType(f.__code__, f.__globals__, f.__name__ + "_serial",
                                  f.__defaults__, f.__closure__)
        twin.__qualname__ = f.__qualname__ + "_serial"
        twin.__doc__ = f.__doc__
        compiled.serial = numba.njit(**JIT_FLAGS)(twin)
        return compiled

    return wrap(fn) if fn is not None else wrap


def for_worlds(compiled, num_worlds: int):
    """The variant of a parallel kernel to call for ``num_worlds`` worlds."""
    return compiled.serial if num_worlds == 1 else compiled


@contextlib.contextmanager
def calling_thread_only(active: bool = True):
    """Within the block (when ``active``), parallel kernels run on the calling thread alone.

    For one world there is nothing to share out, and the thread pool's wake-up costs more than
    the work; worse, its threads then compete for the cores with other pools that spin while
    idle (PyTorch's, during training): SAC on Push ran at 37 env steps/s with numba's pool and
    121 without (2 cores). numba's thread count is per calling thread, so this is thread-safe.
    """
    if not active:
        yield
        return
    previous = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(previous)


prange = numba.prange
