// One world's joints (joints.h) as the step sees them: J rows of the model, shared by every
// world, and per-world rows of limits, motors, accumulated and reported impulses and the
// global solve's scratch, each listed once in a table (base/span.h) from which the batch's
// buffers (JointBuffers, world.h) are allocated and viewed.
#pragma once

#include <cmath>
#include <cstdint>

#include "base/math.h"
#include "base/span.h"

namespace rg {

// One constraint row of a joint: its rate is la.V_a + aa.omega_a + lb.V_b + ab.omega_b;
// error: its positional error (m or rad) at the poses it was built for.
struct JointRow {
    Vec3 la, aa, lb, ab;
    double error;
};

// Up to this many rows a joint: a fixed joint's 6, or 5 and its free coordinate's.
constexpr int MAX_JOINT_ROWS = 6;

// The model, the same in every world (set once: Batch::set_joints). j: joints, k: joined
// pairs, c: components.
#define RG_JOINT_MODEL_ROWS(X)                                                                 \
    X(int32_t, kind, j, 0)             /* JointKind */                                        \
    X(int32_t, body_a, j, 0)           /* dynamic */                                          \
    X(int32_t, body_b, j, 0)           /* any body, or WORLD_BODY */                          \
    X(Vec3, anchor_a, j, Vec3{})       /* m, in a's frame (from its centre of mass) */        \
    X(Vec3, anchor_b, j, Vec3{})       /* m, in b's frame (world frame for WORLD_BODY) */     \
    X(Vec3, axis_a, j, Vec3{})         /* unit, a's frame: the rotation or slide axis */      \
    X(Vec3, axis_b, j, Vec3{})         /* unit, b's frame */                                  \
    X(Quat, reference, j, Quat{})      /* a's orientation in b's frame at coordinate 0 */     \
    X(int64_t, joined_keys, k, 0)      /* the joined pairs' broad-phase keys a n + b, sorted */ \
    X(int32_t, order, j, 0)            /* the joints by component (bodies joined through */   \
                                       /* joints; a static, kinematic or world body joins */  \
                                       /* nothing), in index order within each */             \
    X(int64_t, component_start, c + 1, 0) /* each component's first in order */

// Per world, j joints: what Python sets (limits, motors) and reads (impulses).
#define RG_JOINT_WORLD_ROWS(X)                                                                 \
    X(double, lower, j, -INFINITY)     /* rad or m; -inf: none */                             \
    X(double, upper, j, INFINITY)      /* rad or m; +inf: none */                             \
    X(double, motor_speed, j, 0.0)     /* rad/s or m/s, a relative to b along the axis */     \
    X(double, max_motor, j, 0.0)       /* N m or N; 0: no motor */                            \
    X(double, accumulated, 3 * j, 0.0) /* N m s or N s: the motor's and the limits' */        \
                                       /* impulses of the last velocity solve, and unused */  \
    X(Vec3, impulse, j, Vec3{})        /* N s on body a over the last step (b: the opposite) */ \
    X(Vec3, angular_impulse, j, Vec3{}) /* N m s on body a about its centre of mass */

// Per world, scratch of the global solve: r = MAX_JOINT_ROWS j rows, n bodies.
#define RG_JOINT_SOLVE_ROWS(X)                                                                 \
    X(JointRow, rows, r, JointRow{})   /* the rows, at the poses their errors are for */      \
    X(JointRow, along, r, JointRow{})  /* the same rows at the current poses */               \
    X(Vec3, turn_a, r, Vec3{})         /* I_a(t)^-1 aa of each row of the system's columns */ \
    X(Vec3, turn_b, r, Vec3{})         /* I_b(t)^-1 ab (0 where b takes no impulse) */        \
    X(int32_t, row_joint, r, 0)        /* each row's joint */                                 \
    X(int32_t, row_role, r, 0)         /* EQUALITY or the free coordinate's condition */      \
    X(double, target, r, 0.0)          /* m/s or rad/s, each row's wanted rate */             \
    X(double, rhs, r, 0.0)             /* the system's right-hand side */                     \
    X(uint8_t, held, r, 0)             /* a row held at its bound, out of the system */       \
    X(double, matrix, r * (r + 1), 0.0) /* the system and its right-hand side */              \
    X(double, lambda, r, 0.0)          /* N s or N m s */                                     \
    X(int32_t, column_of, r, 0)        /* elimination bookkeeping */                          \
    X(Vec3, saved, (j > 0 ? 3 * n : 0), Vec3{}) /* the jointed bodies' V, L and omega */      \
                                       /* before a Newton step of pre-stabilisation */

struct JointRows {
    RG_JOINT_MODEL_ROWS(RG_CONST_SPAN_FIELD)
    RG_JOINT_WORLD_ROWS(RG_SPAN_FIELD)
    RG_JOINT_SOLVE_ROWS(RG_SPAN_FIELD)

    int64_t size() const { return kind.size; }
};

}  // namespace rg
