// Contacts on jointed bodies: the articulated response of a body whose joints hold it to
// immovable bodies (Mirtich 1996, "Impulse-based dynamic simulation of rigid body systems",
// ch. 5; Weinstein, Teran & Fedkiw 2006, sec. 6).
//
// A contact's impulse on a free body moves it by M^-1 f (f = [j; r x j + m], M = diag(M 1,
// I(t))). A body held by joints moves only as its joints let it: a finger on a prismatic
// joint to a kinematic hand slides along the axis and nothing else. Sized with M^-1, the
// impulse is the free body's: friction that should hold a cube in a gripper drags the light
// finger along with the cube, and the joint stage puts the finger back only after the cube
// has slipped. The response with the joints is
//     P = M^-1 - M^-1 J^T (J M^-1 J^T)^+ J M^-1 = M^-1 G,   G = 1 - J^T (J M^-1 J^T)^+ J M^-1,
// J the joints' equality rows (joint_rows.h) on the body: the velocity change within the
// rows' null space that the impulse gives, the joints taking the rest (J^T lambda). G f is
// the part of a wrench that moves the body (its Mobility, base/body.h); P is symmetric.
//
// Exact for an articulated body: a dynamic body whose every joint holds it to a static or
// kinematic body or the world frame (a leaf on an immovable base: BodyModel::articulated).
// Its joint rows do not change within the impulse stages (the poses do not move and the base
// takes no impulse), so G is formed once a step, for a body in a listed pair
// (form_joint_mobility, joints.h): prismatic,
// translation along the axis; revolute, rotation about the axis through the anchor (linear
// and angular coupled); fixed, none. The free coordinate's rows, the motor and the limits,
// are left free: the joint velocity stage applies the motor (within max_motor dt) and
// pre-stabilisation the limits. A body jointed to another dynamic body keeps the free body's
// response, its joints restoring it in the joint stages: the exact response there is the
// Schur complement of the component's joint rows (Weinstein et al. 2006), which moves every
// body of the component with each contact impulse, not only the pair's two.
//
// The stage order gives a squeezed cube its equilibrium within each step: the joint velocity
// stage (before the contact stage) drives each finger inwards with its motor's F dt, the
// contact stage stops the fingers against the cube with a normal impulse of F dt a face (the
// fingers move only along their axes; both faces at once, squeeze.h), and friction on each
// face, up to mu F dt over the step, is taken by the joints from the hand: the cube is held
// while m (g + a) < 2 mu F and slides at 2 mu F / m - g otherwise (the report's grasp case).
//
// Where both bodies of a pair move only along fewer than three directions at the contact
// point (an articulated body against an immovable one), K is singular: impulse.h's
// jointed_contact_impulse.
#pragma once

#include "base/body.h"
#include "base/span.h"
#include "solver/joint_rows.h"

namespace rg {

// out = G for a body of inverse mass inverse_mass and I(t)^-1 inverse_inertia held by the
// equality rows `rows` (their a sides: la, aa), by Gram-Schmidt in the M^-1 inner product:
// rows dependent on the ones before (a fixed joint's 6 and a revolute's 5 give rank 6 and 5,
// two joints may repeat a row) add nothing.
void form_mobility(double inverse_mass, const Mat3& inverse_inertia, const JointRow* rows,
                   int count, Mobility& out);

// The wrench (j, l) on body i (N s, N m s about its centre of mass) as it moves the body: g
// (j, l) for an articulated body, unchanged for another.
void admit(const BodyStates& bodies, const BodyModel& model, int i, Vec3& j, Vec3& l);

// The change of articulated body i's velocity V (m/s) and angular velocity omega (rad/s)
// that the wrench (j, l) makes: M^-1 G (j, l).
void articulated_response(const BodyStates& bodies, const BodyModel& model, int i, Vec3 j,
                          Vec3 l, Vec3& dv, Vec3& dw);

// k += the change of articulated body i's velocity at lever r per unit impulse there
// (add_point_mass_matrix of impulse.h, with the joints).
void add_articulated_point_matrix(const BodyStates& bodies, const BodyModel& model, int i,
                                  Vec3 r, Mat3& k);

// big += [dv at r; d omega] per unit [j; m] (j at lever r, plus the angular impulse m) for
// articulated body i (patch.cpp's add_body_wrench_matrix, with the joints).
void add_articulated_wrench_matrix(const BodyStates& bodies, const BodyModel& model, int i,
                                   Vec3 r, double big[6][6]);

}  // namespace rg
