"""The impulse at one contact (Guendelman, Bridson & Fedkiw 2003), checked formula by formula."""

import numpy as np
import pytest
from rigid_gym._core import add_point_mass_matrix, contact_impulse

from rigid_gym import quaternion as quat

N = np.array([0.0, 0.0, 1.0])


def impulse(k, v, e, mu):
    return np.array(contact_impulse(np.asarray(k, dtype=float), v, N, e, mu))


def test_point_mass_matrix_of_a_unit_cube_corner():
    """K = (1/M) 1 + r*^T I^-1 r*, built column by column by the core, equals the
    matrix product for a unit-mass cube of edge 1 (I = M/6) at the corner r = (1/2, 1/2, -1/2)."""
    k = np.zeros((3, 3))
    inverse_moments = np.full(3, 6.0)
    r = np.array([0.5, 0.5, -0.5])
    k = np.array(add_point_mass_matrix(1.0, np.eye(3), inverse_moments, r, k))
    star = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    np.testing.assert_allclose(k, np.eye(3) + star.T @ np.diag(inverse_moments) @ star, atol=1e-15)


def test_frictionless_impulse():
    """j = -(1 + e) v_n / (n^T K n) n."""
    k = np.diag([2.0, 3.0, 4.0])
    j = impulse(k, (0.3, -0.2, -1.0), 0.5, 0.0)
    np.testing.assert_allclose(j, [0, 0, 1.5 * 1.0 / 4.0], atol=1e-15)


def test_static_friction_inside_the_cone():
    """j = K^-1 (-v - e v_n n) when |j_t| <= mu j_n: the relative velocity becomes -e v_n n."""
    k = np.array([[2.0, 0.1, 0.2], [0.1, 3.0, 0.0], [0.2, 0.0, 4.0]])
    v = np.array([0.1, 0.05, -2.0])
    j = impulse(k, v, 0.5, 1.0)
    np.testing.assert_allclose(k @ j, -v - 0.5 * v[2] * N, atol=1e-14)
    assert np.linalg.norm(j[:2]) <= 1.0 * j[2]


def test_sliding_friction_outside_the_cone():
    """|j_t| would exceed mu j_n: j = j_n (n - mu T), T along the tangential velocity,
    j_n = -(1 + e) v_n / (n^T K (n - mu T)); the normal velocity then becomes -e v_n."""
    k = np.diag([1.0, 1.0, 1.0])
    v = np.array([3.0, 0.0, -1.0])
    e, mu = 0.2, 0.3
    j = impulse(k, v, e, mu)
    t = np.array([1.0, 0.0, 0.0])
    jn = -(1 + e) * v[2] / (N @ k @ (N - mu * t))
    np.testing.assert_allclose(j, jn * (N - mu * t), atol=1e-15)
    assert (v + k @ j) @ N == pytest.approx(-e * v[2])


def test_non_positive_sliding_denominator_leaves_the_static_impulse():
    """A large mu with a coupled K makes n^T K (n - mu T) <= 0 (a Painleve-type case: the
    sliding formula would pull). In the (t, n) plane that needs K_nt >= K_nn / mu, while the
    static impulse leaving the cone would need K_nt > mu K_tt; together K_nt^2 > K_tt K_nn,
    impossible for a positive definite K. So the static impulse is returned and stops the
    contact (the core's guard also returns it should the sliding branch ever meet such a
    denominator)."""
    k = np.array([[1.0, 0.0, 0.5], [0.0, 1.0, 0.0], [0.5, 0.0, 1.0]])  # SPD: eigenvalues 0.5, 1, 1.5
    v = np.array([1.0, 0.0, -1.0])
    mu = 5.0
    t = np.array([1.0, 0.0, 0.0])
    assert N @ k @ (N - mu * t) <= 0.0
    static = np.linalg.solve(k, -v)
    assert np.linalg.norm(static[:2]) <= mu * static[2]
    j = impulse(k, v, 0.0, mu)
    np.testing.assert_allclose(j, static, atol=1e-14)
    np.testing.assert_allclose(v + k @ j, 0.0, atol=1e-14)


def test_speeds_whose_squares_underflow_keep_the_friction_direction():
    """A resting cube pinched between the table and a kinematic pad once met v ~ 1e-202 m/s
    with a pulling static impulse: |u|^2 underflowed to 0, and the fallback direction divided
    0 by 0 (the step turned NaN). The arguments are the ones recorded then."""
    k = np.array([[39.99999999999998, 8.570883641437328, 8.570883641437334],
                  [8.570883641437328, 29.897336426337205, -14.99999999999999],
                  [8.570883641437334, -14.999999999999991, 29.897336426337187]])
    v = (8.165126103939127e-202, -1.168030658331746e-204, 1.1680306583317453e-204)
    n = (-5.350036542037848e-19, -2.4283442764624865e-19, -1.0)
    j = np.array(contact_impulse(k, v, n, 0.0, 0.5))
    assert np.all(np.isfinite(j))
    # scaled up by 1e200 the same contact is ordinary: the answers must agree, scaled back
    big = np.array(contact_impulse(k, 1e200 * np.array(v), n, 0.0, 0.5))
    np.testing.assert_allclose(j * 1e200, big, rtol=1e-12)


def test_no_impact_with_friction_adds_kinetic_energy():
    """Random eccentric impacts of a unit cube's corner on the ground at e = 1, mu = 0.5: with
    K coupling normal and tangent, Newton's restitution with Coulomb friction in one impulse
    gains energy for some of them (Kane & Levinson), so the core falls back to the
    frictionless impulse there (src/solver/impulse.h). The energy change j.v + j.K j / 2 must never
    be positive (beyond round-off), and where friction is kept it is the combined impulse."""
    rng = np.random.default_rng(7)
    kept = 0
    for _ in range(2000):
        axis = rng.normal(size=3)
        rotation = quat.to_matrix(np.concatenate([[np.cos(0.5)], np.sin(0.5) * axis / np.linalg.norm(axis)]))
        r = rotation @ (0.5 * rng.choice([-1.0, 1.0], 3))
        k = np.array(add_point_mass_matrix(1.0, rotation, np.full(3, 6.0), r, np.zeros((3, 3))))
        v = np.concatenate([rng.normal(size=2), [-abs(rng.normal()) - 0.1]])
        j = impulse(k, v, 1.0, 0.5)
        change = j @ v + 0.5 * j @ k @ j
        assert change <= 1e-12 * (v @ np.linalg.solve(k, v)), (k, v, j)
        kept += abs(j[0]) + abs(j[1]) > 0.0
    assert kept > 500  # friction is kept wherever it removes energy
