// The impulse stages of the step (Guendelman, Bridson & Fedkiw 2003).
//
// All three work at *predicted* poses: each body is moved ahead by dt with its current
// velocity (X + dt V, q turned by omega dt), contacts are found there, and impulses change
// velocities only. The collision stage, which runs before gravity is added, also moves
// dynamic bodies by dt^2 g when predicting (but still judges approach and sizes impulses
// with the old velocities): a collision that gravity completes within the step then bounces
// instead of being caught by the inelastic contact stage, and a body resting on an incline
// still sees no approach.
//
// * resolve_world_contacts(COLLISION): passes over every candidate pair with the pair's real
//   restitution max(e_a, e_b), until a pass applies no impulse.
// * resolve_world_contacts(CONTACT): the same with restitution ramping from about -0.9
//   (negative e only slows the approach) to 0 on the last pass, which stops rattling.
// * propagate_world_shock (shock.cpp): builds the contact graph, orders it into levels from
//   the ground up (levels.h), and resolves level by level with everything below frozen
//   (infinite mass). Leftover approach can then only push upper bodies: a stack cannot sink.
//
// Within a pair, contacts are grouped into patches of similar normal, each resolved at once
// (resolve_patches): against an immovable partner by the wrench of patch.h, and against a
// movable one too with Settings::contact_patches, otherwise by one impulse at its centroid;
// with contact_patches the contact stage resolves a body touching only static and kinematic
// bodies against all of them at once, and a body squeezed between articulated bodies (a cube
// between a gripper's fingers) its pairs with them at once (squeeze.h). Shock propagation
// combines a body's contacts with all its frozen supports into such patches. Coulomb's limit applies to each pair's impulse over
// the whole step (StepContext::pair_impulse).
#pragma once

#include "solver/patch.h"
#include "solver/world.h"

namespace rg {

enum ImpulseMode { COLLISION, CONTACT, SHOCK };

// The collision (COLLISION) or contact (CONTACT) stage: up to `passes` sweeps over the first
// `pairs` listed pairs, stopping early when a sweep applies no impulse.
//
// In the contact stage, a pair whose movable bodies are in no other pair (a cube on the
// table, two boxes meeting in the air) skips the restitution ramp: the ramp shares impulses
// out among contacts that disturb each other, and such a pair disturbs nothing. Its passes
// run at e = 0 once the other pairs' passes are done (they share no movable body, so the
// order between the two does not matter), until one applies nothing. That e = 0 stops the
// approach without leaving the body hanging short of its support: as in every pass of the
// contact and shock stages, a gap that gravity would close within the step is closed
// (speculative contact, closable in patch.h), which a ramp's early passes did only by chance.
void resolve_world_contacts(StepContext& w, int64_t pairs, double dt, ImpulseMode mode, int passes);

// The shock-propagation stage over the first `pairs` listed pairs (shock.cpp).
void propagate_world_shock(StepContext& w, int64_t pairs, double dt);

// w.pairs_of: in how many of the first `pairs` listed pairs each body is.
void count_pairs_of_bodies(StepContext& w, int64_t pairs);

// w.pairs_of: in how many of the first `pairs` listed pairs each body took an impulse this
// step (w.pair_impulse not zero): the pairs that acted on its motion. A pair listed because
// two fast bodies' grown boxes meet, whose bodies never touch, does not count.
void count_acting_pairs_of_bodies(StepContext& w, int64_t pairs);

// What the collision stage moves dynamic bodies by when predicting their poses: dt^2 g (m).
Vec3 collision_lookahead(const BodyModel& model, double dt);

// Resolve the contacts of listed pair k at their predicted poses (contacts.h, then
// resolve_patches, from its body a's side); returns the number of impulses applied.
// COLLISION uses the pair's restitution, CONTACT ramp_e, SHOCK 0.
int resolve_pair(StepContext& w, int64_t k, double dt, Vec3 lookahead, ImpulseMode mode,
                 double ramp_e, Movable movable);

// Resolve body a's contacts in `set` (normals towards a; each against the body set.partner[i])
// in stage `mode`; returns the number of impulses applied (solver.cpp says how).
// reactions (shock propagation's resolves against frozen bodies): where given, with
// Settings::patch_reactions, what a sliding patch wrench or a single impulse applied against
// a frozen dynamic partner across gravity is held back for it reversed (w.reaction), and
// *reactions counts how often (the caller applies them and resolves the levels again).
// memo: where set holds one pair's kept contacts (contacts.h), the pair's patch memo
// (patch_memo.h), or nullptr to keep nothing.
int resolve_patches(StepContext& w, int a, Movable movable, const ContactSet& set, int64_t count,
                    double dt, ImpulseMode mode, double ramp_e, int* reactions = nullptr,
                    PatchMemo* memo = nullptr);

}  // namespace rg
