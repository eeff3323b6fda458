"""The one place that sets how kernels are compiled.

``cache=True`` so a fresh process loads compiled code from ``__pycache__`` instead of compiling;
``fastmath=False`` so results are IEEE-exact and runs are bit-for-bit repeatable;
``error_model="numpy"`` so a division by zero gives inf/nan (caught by validation upstream)
rather than a Python exception inside a parallel loop; ``nogil=True`` so that threads can run
kernels side by side (``rigid_gym.pipeline`` shares a batch's worlds out that way).

Kernels are compiled without reference counting and small helpers are inlined (``kernel``):
both remove per-call costs that dominated the step (docs/architecture.md, "Speed").
"""

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
    ``numba.prange`` (with counting, as numba's parallel loops need), for kernels over many
    independent points outside the step (the mesh's distance fields)."""

    def wrap(f):
        if inline:
            return numba.njit(**JIT_FLAGS, inline="always")(f)
        if parallel:
            return numba.njit(parallel=True, **JIT_FLAGS)(f)
        return numba.njit(**JIT_FLAGS, _nrt=allocates)(f)

    return wrap(fn) if fn is not None else wrap


prange = numba.prange


def compiled_entry(dispatcher, *args):
    """The compiled code of kernel ``dispatcher`` for the types of ``args`` (compiled, or
    loaded from the cache, if it is not yet), to be called with arguments of exactly these
    types again and again: a call through it skips numba's dispatch, which works out the type
    of every argument at every call. For the step's namedtuples of ~110 arrays that was
    ~10 us of a ~13 us call (measured). The entry does not check the types it is given."""
    return dispatcher.compile(tuple(dispatcher.typeof_pyval(a) for a in args))
