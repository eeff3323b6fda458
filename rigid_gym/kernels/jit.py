"""The one place that sets how kernels are compiled.

``cache=True`` so a fresh process loads compiled code from ``__pycache__`` instead of compiling;
``fastmath=False`` so results are IEEE-exact and runs are bit-for-bit repeatable;
``error_model="numpy"`` so a division by zero gives inf/nan (caught by validation upstream)
rather than a Python exception inside a parallel loop.
"""

import numba

JIT_FLAGS = dict(cache=True, fastmath=False, nogil=True, error_model="numpy")


def kernel(fn=None, *, parallel: bool = False):
    """Compile ``fn`` with the project's flags; ``parallel=True`` enables ``numba.prange``."""

    def wrap(f):
        return numba.njit(parallel=parallel, **JIT_FLAGS)(f)

    return wrap(fn) if fn is not None else wrap


prange = numba.prange
