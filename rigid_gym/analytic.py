"""Exact answers the solver is checked against (tests, benchmarks and the report).

Each function is a closed form from mechanics, with its source in the docstring.
"""

from __future__ import annotations

import numpy as np


def free_fall_discrete(x0, v0, gravity, dt: float, steps: int) -> tuple[np.ndarray, np.ndarray]:
    """Position (3,) m and velocity (3,) m/s after ``steps`` symplectic-Euler steps of ``dt``.

    v_n = v0 + n dt g;  x_n = x0 + dt sum_{k=1..n} v_k = x0 + n dt v0 + dt^2 g n (n + 1) / 2.
    """
    x0, v0, g = (np.asarray(a, dtype=np.float64) for a in (x0, v0, gravity))
    n = float(steps)
    return x0 + n * dt * v0 + dt * dt * g * n * (n + 1.0) / 2.0, v0 + n * dt * g


def free_fall_continuous(x0, v0, gravity, t: float) -> tuple[np.ndarray, np.ndarray]:
    """x(t) = x0 + v0 t + g t^2 / 2 and v(t) = v0 + g t (exact ballistic motion)."""
    x0, v0, g = (np.asarray(a, dtype=np.float64) for a in (x0, v0, gravity))
    return x0 + v0 * t + 0.5 * g * t * t, v0 + g * t


def _top_parameters(moments, omega0):
    """Amplitudes (A, B, C), rate lambda, parameter m and the branch (True when
    L^2 > 2 E I2) of the torque-free solution started at omega0 = (w1, 0, w3)."""
    i1, i2, i3 = (float(x) for x in moments)
    if not i1 < i2 < i3:
        raise ValueError(f"torque-free top: need I1 < I2 < I3, got {moments!r}")
    w1, w2, w3 = (float(x) for x in omega0)
    if w2 != 0.0 or w1 == 0.0 or w3 == 0.0:
        raise ValueError(f"torque-free top: need omega0 = (w1, 0, w3) with w1, w3 != 0, got {omega0!r}")
    two_e = i1 * w1 * w1 + i3 * w3 * w3
    l2 = (i1 * w1) ** 2 + (i3 * w3) ** 2
    a = np.sqrt((two_e * i3 - l2) / (i1 * (i3 - i1)))
    c = np.sqrt((l2 - two_e * i1) / (i3 * (i3 - i1)))
    high = l2 > two_e * i2
    if high:
        b = np.sqrt((two_e * i3 - l2) / (i2 * (i3 - i2)))
        lam = np.sqrt((i3 - i2) * (l2 - two_e * i1) / (i1 * i2 * i3))
        m = (i2 - i1) * (two_e * i3 - l2) / ((i3 - i2) * (l2 - two_e * i1))
    else:
        b = np.sqrt((l2 - two_e * i1) / (i2 * (i2 - i1)))
        lam = np.sqrt((i2 - i1) * (two_e * i3 - l2) / (i1 * i2 * i3))
        m = (i3 - i2) * (l2 - two_e * i1) / ((i2 - i1) * (two_e * i3 - l2))
    return (a, b, c), lam, m, high


def torque_free_angular_velocity(moments, omega0, t) -> np.ndarray:
    """Body-frame angular velocity of a torque-free asymmetric rigid body at times ``t`` (s).

    moments: principal moments (I1, I2, I3), kg m^2, with I1 < I2 < I3.
    omega0: body-frame angular velocity at t = 0, rad/s, with omega0[1] == 0 (start on the
        omega_2 = 0 section, where every trajectory passes) and omega0[0], omega0[2] != 0.
    Returns (len(t), 3) rad/s.

    Landau & Lifshitz, Mechanics §37: with 2E = sum I_i w_i^2 and L^2 = sum (I_i w_i)^2,
    for L^2 > 2 E I2:  w1 = A cn(lt), w2 = B sn(lt), w3 = C dn(lt);
    for L^2 < 2 E I2:  w1 = A dn(lt), w2 = B sn(lt), w3 = C cn(lt)
    (Jacobi elliptic functions of parameter m, ``scipy.special.ellipj``). Signs: w1 and w3
    keep their initial signs, w2 carries sgn(w1 w3) (a symmetry of Euler's equations).
    """
    from scipy.special import ellipj

    (a, b, c), lam, m, high = _top_parameters(moments, omega0)
    t = np.atleast_1d(np.asarray(t, dtype=np.float64))
    sn, cn, dn, _ = ellipj(lam * t, m)
    out = np.stack([a * cn, b * sn, c * dn] if high else [a * dn, b * sn, c * cn], axis=-1)
    s1, s3 = np.sign(omega0[0]), np.sign(omega0[2])
    return out * np.array([s1, s1 * s3, s3])


def torque_free_flip_period(moments, omega0) -> float:
    """Time between reversals of omega_2 (the intermediate-axis 'Dzhanibekov' flip), s:
    half the period 4 K(m) / lambda of the body-frame angular velocity."""
    from scipy.special import ellipk

    _, lam, m, _ = _top_parameters(moments, omega0)
    return float(2.0 * ellipk(m) / lam)


def pendulum_period(pivot_inertia: float, mass: float, distance: float, gravity: float,
                    amplitude: float) -> float:
    """Period (s) of a rigid (physical) pendulum released from rest at ``amplitude`` (rad):
    moment of inertia ``pivot_inertia`` (kg m^2) about the pivot, ``mass`` (kg), centre of
    mass ``distance`` (m) from the pivot, |g| ``gravity`` (m/s^2).

    T = 4 sqrt(I / (m g d)) K(k), k = sin(amplitude / 2) (complete elliptic integral of the
    first kind, ``scipy.special.ellipk`` of m = k^2); 2 pi sqrt(I / (m g d)) at small
    amplitude, and a simple pendulum's 4 sqrt(L / g) K(k) for I = m L^2, d = L."""
    from scipy.special import ellipk

    k = np.sin(0.5 * amplitude)
    return float(4.0 * np.sqrt(pivot_inertia / (mass * gravity * distance)) * ellipk(k * k))


def arm_speed_past_motor(pivot_inertia: float, mass: float, distance: float, gravity: float,
                         torque: float, angle: float) -> float:
    """Angular speed (rad/s) of an arm released horizontal from rest and turning down about a
    horizontal pivot against a constant opposing torque ``torque`` (N m), once it is ``angle``
    (rad) below horizontal. Energy: I w^2 / 2 = m g d sin(angle) - torque angle."""
    work = mass * gravity * distance * np.sin(angle) - torque * angle
    return float(np.sqrt(2.0 * work / pivot_inertia))
