// Velocity and position updates, rotation, attachments (integrate.h).
#include "solver/integrate.h"

#include <algorithm>
#include <cmath>

namespace rg {

namespace {

constexpr double QUARTER_TURN = 0.5 * 3.14159265358979323846;
// Newton steps that put a rotated body back on its energy (they stop once it is reached).
constexpr int ENERGY_NEWTON_STEPS = 32;
// Relative size below which an energy error, or a gradient along the sphere, is round-off.
constexpr double ENERGY_ROUND_OFF = 1e-15;

// omega_bar for one (sub)step of length h (s): Buss's update of the given order (1, 2 or 3),
// from R at the start of the step, angular momentum L and torque tau.
Vec3 effective_angular_velocity(const Mat3& r, Vec3 inverse_moments, Vec3 l, Vec3 tau, double h,
                                int order) {
    const Vec3 o = apply_inverse_inertia(r, inverse_moments, l);
    if (order == 1) {
        return o;
    }
    // alpha = d omega/dt = I^-1 (L x omega + tau)
    const Vec3 m = add(cross(l, o), tau);
    const Vec3 a = apply_inverse_inertia(r, inverse_moments, m);
    const Vec3 b = {o.x + 0.5 * h * a.x, o.y + 0.5 * h * a.y, o.z + 0.5 * h * a.z};
    if (order == 2) {
        return b;
    }
    // omega'' = omega x alpha - I^-1 (omega x M) + I^-1 (tau x omega + L x alpha), M = L x omega + tau
    const Vec3 p1 = cross(o, a);
    const Vec3 wm = cross(o, m);
    const Vec3 tw = cross(tau, o);
    const Vec3 la = cross(l, a);
    const Vec3 s = {tw.x + la.x - wm.x, tw.y + la.y - wm.y, tw.z + la.z - wm.z};
    const Vec3 p2 = apply_inverse_inertia(r, inverse_moments, s);
    const Vec3 dd = add(p1, p2);
    // the Magnus commutator term alpha x omega
    const Vec3 c = cross(a, o);
    const double c6 = h * h / 6.0;
    const double c12 = h * h / 12.0;
    return {b.x + c6 * dd.x + c12 * c.x, b.y + c6 * dd.y + c12 * c.y, b.z + c6 * dd.z + c12 * c.z};
}

// Rotational kinetic energy L_b . (I^-1 L_b) / 2 of body-frame angular momentum L_b, J.
double rotational_energy(Vec3 lb, Vec3 inverse_moments) {
    return 0.5 * (lb.x * lb.x * inverse_moments.x + lb.y * lb.y * inverse_moments.y +
                  lb.z * lb.z * inverse_moments.z);
}

// The orientation q (rotation r) turned by the smallest body-frame rotation after which the
// rotational energy of world angular momentum l is `energy` again (it was before the rotation
// update; the update keeps |L| exactly, L being the stored state). On the sphere |L_b| =
// |L| the energy's gradient is g = I^-1 L_b minus its radial part; Newton steps along g find
// the nearest L_b of that energy (the polhode through the start), and the rotation carrying
// it onto the current L_b is applied on the body side (a projection method, Hairer, Lubich &
// Wanner, Geometric Numerical Integration, IV.4: the update keeps its order). A body spinning
// about a principal axis has g = 0 there and keeps its energy already.
Quat restore_energy(Quat q, const Mat3& r, Vec3 l, Vec3 inverse_moments, double energy) {
    const Vec3 start = rotate_inverse(r, l);
    const double size = length(start);
    if (size == 0.0) {
        return q;
    }
    Vec3 lb = start;
    for (int k = 0; k < ENERGY_NEWTON_STEPS; ++k) {
        const double error = rotational_energy(lb, inverse_moments) - energy;
        const Vec3 gradient = {lb.x * inverse_moments.x, lb.y * inverse_moments.y,
                               lb.z * inverse_moments.z};
        const Vec3 g = sub(gradient, scale(dot(gradient, lb) / (size * size), lb));
        const double g2 = dot(g, g);
        // done at round-off; and where g is round-off of the gradient (an isotropic body,
        // whose energy is the same all over the sphere), there is nothing to move along
        if (!(std::fabs(error) > ENERGY_ROUND_OFF * energy) ||
            !(g2 > ENERGY_ROUND_OFF * dot(gradient, gradient))) {
            break;
        }
        lb = add(lb, scale(-error / g2, g));
        lb = scale(size / length(lb), lb);
    }
    // body-frame rotation taking lb onto start: q' = q d with d lb = start
    const Vec3 a = scale(1.0 / size, lb), b = scale(1.0 / size, start);
    const Vec3 axis = cross(a, b);
    const Quat d = normalize({1.0 + dot(a, b), axis.x, axis.y, axis.z});
    return normalize(multiply(q, d));
}

}  // namespace

int symmetry_axis(Vec3 inverse_moments) {
    const double x = inverse_moments.x, y = inverse_moments.y, z = inverse_moments.z;
    if (x == y && y != z) {
        return 2;
    }
    if (y == z && z != x) {
        return 0;
    }
    return x == z && x != y ? 1 : -1;
}

Quat symmetric_rotation(Quat q, const Mat3& r, Vec3 l, Vec3 inverse_moments, int axis, double h) {
    const double equal = inverse_moments[(axis + 1) % 3];  // 1 / I1
    const double size = length(l);
    if (size == 0.0) {
        return q;
    }
    const double turn = 0.5 * size * equal * h;  // half angles
    const double spin = 0.5 * (inverse_moments[axis] - equal) * rotate_inverse(r, l)[axis] * h;
    const double st = std::sin(turn) / size, ss = std::sin(spin);
    const Quat world = {std::cos(turn), st * l.x, st * l.y, st * l.z};
    const Quat body = {std::cos(spin), axis == 0 ? ss : 0.0, axis == 1 ? ss : 0.0,
                       axis == 2 ? ss : 0.0};
    return normalize(multiply(multiply(world, q), body));
}

Quat turned(Quat q, const Mat3& r, Vec3 l, Vec3 omega, Vec3 inverse_moments, double h) {
    const int axis = symmetry_axis(inverse_moments);
    return axis >= 0 ? symmetric_rotation(q, r, l, inverse_moments, axis, h)
                     : rotate_by_angular_velocity(q, omega, h);
}

Vec3 turn_between(Quat from, Quat to) {
    Quat d = multiply(to, {from.w, -from.x, -from.y, -from.z});
    if (d.w < 0.0) {
        d = {-d.w, -d.x, -d.y, -d.z};
    }
    const double s = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    if (s == 0.0) {
        return {0.0, 0.0, 0.0};
    }
    const double angle = 2.0 * std::atan2(s, d.w);
    return {angle * d.x / s, angle * d.y / s, angle * d.z / s};
}

int rotation_substeps(double speed, double dt) {
    const double turns = std::ceil(speed * dt / QUARTER_TURN);
    // compared as a double: a huge (or NaN) speed must not reach the conversion to int
    if (!(turns > 1.0)) {
        return 1;
    }
    return turns >= MAX_ROTATION_SUBSTEPS ? MAX_ROTATION_SUBSTEPS : static_cast<int>(turns);
}

void refresh_rotation_and_angular_velocity(const BodyStates& bodies, const BodyModel& model) {
    for (int64_t i = 0; i < bodies.position.size; ++i) {
        bodies.rotation[i] = rotation_from_quaternion(bodies.orientation[i]);
        if (model.motion[i] == DYNAMIC) {
            bodies.angular_velocity[i] = apply_inverse_inertia(
                bodies.rotation[i], model.inverse_moments[i], bodies.angular_momentum[i]);
        }
    }
}

void refresh_inverse_inertia(const BodyStates& bodies, const BodyModel& model,
                             Span<const uint8_t> kept) {
    for (int64_t i = 0; i < bodies.position.size; ++i) {
        if (kept.size > 0 && kept[i]) {
            continue;
        }
        bodies.inverse_inertia[i] = model.motion[i] == DYNAMIC
                                        ? inverse_inertia(bodies.rotation[i], model.inverse_moments[i])
                                        : Mat3{};
    }
}

void update_velocities(const BodyStates& bodies, const BodyModel& model, double dt,
                       Span<const uint8_t> asleep) {
    const Vec3 g = model.gravity;
    for (int64_t i = 0; i < bodies.position.size; ++i) {
        if (model.motion[i] != DYNAMIC || (asleep.size > 0 && asleep[i])) {
            continue;
        }
        const Vec3 f = bodies.force[i], tau = bodies.torque[i];
        const double inverse_mass = model.inverse_mass[i];
        Vec3& v = bodies.velocity[i];
        Vec3& l = bodies.angular_momentum[i];
        v = {v.x + dt * (g.x + f.x * inverse_mass), v.y + dt * (g.y + f.y * inverse_mass),
             v.z + dt * (g.z + f.z * inverse_mass)};
        l = {l.x + dt * tau.x, l.y + dt * tau.y, l.z + dt * tau.z};
        bodies.angular_velocity[i] = rotate(bodies.inverse_inertia[i], l);
    }
}

void update_positions(const BodyStates& bodies, const BodyModel& model, double dt, int order,
                      bool keep_energy, bool exact_symmetric, Span<const int64_t> acting,
                      Span<const uint8_t> asleep) {
    for (int64_t i = 0; i < bodies.position.size; ++i) {
        if (model.motion[i] == STATIC || (asleep.size > 0 && asleep[i])) {
            continue;
        }
        Vec3& x = bodies.position[i];
        const Vec3 v = bodies.velocity[i];
        x = {x.x + dt * v.x, x.y + dt * v.y, x.z + dt * v.z};
        Quat& q = bodies.orientation[i];
        Mat3& r = bodies.rotation[i];
        const Vec3 w = bodies.angular_velocity[i];
        if (model.motion[i] == KINEMATIC) {
            q = rotate_by_angular_velocity(q, w, dt);
            r = rotation_from_quaternion(q);
            continue;
        }
        // a body that took an impulse keeps its torque in L alone (integrate.h says why)
        const bool free = acting[i] == 0;
        const Vec3 l = bodies.angular_momentum[i];
        const Vec3 tau = free ? bodies.torque[i] : Vec3{0.0, 0.0, 0.0};
        const Vec3 inverse_moments = model.inverse_moments[i];
        const int axis = exact_symmetric ? symmetry_axis(inverse_moments) : -1;
        if (axis >= 0 && tau.x == 0.0 && tau.y == 0.0 && tau.z == 0.0) {
            q = symmetric_rotation(q, r, l, inverse_moments, axis, dt);
            r = rotation_from_quaternion(q);
            bodies.angular_velocity[i] = apply_inverse_inertia(r, inverse_moments, l);
            continue;
        }
        const double speed = std::sqrt(w.x * w.x + w.y * w.y + w.z * w.z);
        const int substeps = rotation_substeps(speed, dt);
        const double h = dt / substeps;
        const double energy = rotational_energy(rotate_inverse(r, l), inverse_moments);
        for (int k = 0; k < substeps; ++k) {
            // Buss's update starts each sub-step from its own L: the torque acted on L over the
            // whole step already (update_velocities), so sub-step k starts dt - k h of it back
            const Vec3 lk = order == 1 ? l : sub(l, scale(dt - k * h, tau));
            const Vec3 bar = effective_angular_velocity(r, inverse_moments, lk, tau, h, order);
            q = rotate_by_angular_velocity(q, bar, h);
            r = rotation_from_quaternion(q);
        }
        if (keep_energy && speed > 0.0 && free) {
            q = restore_energy(q, r, l, inverse_moments, energy);
            r = rotation_from_quaternion(q);
        }
        bodies.angular_velocity[i] = apply_inverse_inertia(r, inverse_moments, l);
    }
}

void place_attached(const BodyStates& bodies, const Attachments& attached) {
    for (int64_t i = 0; i < bodies.position.size; ++i) {
        const int p = attached.parent[i];
        if (p < 0) {
            continue;
        }
        bodies.position[i] = to_world(bodies.position[p], bodies.rotation[p],
                                      attached.offset_position[i]);
        bodies.velocity[i] = bodies.velocity[p];
        bodies.angular_velocity[i] = {0.0, 0.0, 0.0};
        bodies.angular_momentum[i] = {0.0, 0.0, 0.0};
        bodies.orientation[i] =
            normalize(multiply(bodies.orientation[p], attached.offset_orientation[i]));
        bodies.rotation[i] = rotation_from_quaternion(bodies.orientation[i]);
    }
}

}  // namespace rg
