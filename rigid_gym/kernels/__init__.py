"""Numba kernels: the only package that imports numba.

Kernels work on plain float64/int32 arrays and scalars, write into buffers they are given and
allocate nothing in their hot loops. The Python API around them is in ``rigid_gym.world`` and
``rigid_gym.pipeline``.
"""
