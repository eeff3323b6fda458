"""SolverConfig: which phases of the step run and how.

``SolverConfig.for_scene(scene)`` derives the cheapest configuration for a scene: phases it
cannot need are off, and the collision phase where every restitution is 0
(docs/architecture.md); any field can be given to override it, and ``dataclasses.replace``
changes one later.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np

from rigid_gym import _core
from rigid_gym._core import DYNAMIC
from rigid_gym.checks import in_range, integer
from rigid_gym.fast_motion import can_move_far

if TYPE_CHECKING:
    from rigid_gym.scene import Scene

ROTATION_ORDERS = (1, 2, 3)
CORE_DEFAULTS = _core.Settings()
"""The core's defaults of the settings it takes (``src/solver/settings.h``): SolverConfig's."""


@dataclass(frozen=True)
class SolverConfig:
    """Switches and counts for the step (``step_world`` in ``src/solver/step.cpp``).

    collision_passes: sweeps of the collision phase (real restitution, old velocities); 0
        switches the phase off. Where every restitution is 0 an impact is left to the contact
        phase, which ends at e = 0 as well but can spread it differently through bodies in
        contact (the report's struck row: speeds within 5.0e-9 of the closed form without
        the phase, 6.8e-9 with it, at dt = 1/240; 7.9e-6 and 7.7e-9 without
        ``contact_patches``).
    contact_passes: sweeps of the contact phase (restitution ramping from -0.9 to 0).
    shock_sweeps: sweeps per level of shock propagation; 0 switches it off. It only matters
        where a body can rest on another (or on the ground) under gravity; resting contact
        is made exact there (``src/solver/patch.h``).
    rotation_order: 1 = the exact rotation through omega dt, omega taken at the start
        of the step (first order); 2 = Buss's second-order update (omega + h/2 alpha);
        3 = Buss's third-order update. Cost grows slightly with the order.
    box_edge_segments: each box edge carries this many - 1 surface samples between its
        corners, so that edge-edge crossings with meshes are detected once they are deeper
        than about edge length / (2 box_edge_segments) (benchmarks/box_edge_samples.py).
    sweep: broad phase by sort-and-sweep (True) or brute force (False); None chooses
        sort-and-sweep from ``collision.SWEEP_MIN_BODIES`` bounded bodies.
    sleep: skip an island of bodies in contact (a stack, a cube on the table) while its step
        is a fixed point (``src/solver/sleep.h``); exact, so off only to measure what it saves.
    sleep_speed: m/s, 0 to 10; above 0 (and with ``sleep``), an island whose every point
        has moved slower than this for 0.5 s is stopped (its velocities zeroed)
        and sleeps until something touches or pushes it, as Box2D and MuJoCo sleep: what a
        settled pile or pyramid needs, whose round-off motion is no exact fixed point. It
        changes trajectories (a body creeping slower than it stops), so it is off (0) by
        default; 0.01 stops piles within a second of settling (docs/architecture.md).
    keep_energy: after each rotation update, turn a dynamic body's orientation by the smallest
        body-frame rotation that gives it back the rotational kinetic energy it had (L is the
        stored state, so |L| is exact anyway): a free body then keeps |L| and E to round-off
        at any dt, a projection that keeps the rotation order's accuracy (``src/solver/integrate.h``).
        Off, the rotation order's energy error shows (what the order studies measure).
    overlap_correction: after the impulse phases, push apart contacts that overlap by more
        than 0.1 mm by this fraction of the excess per step (translations only, split by
        inverse mass: no orientation changes, and velocities only as ``overlap_energy``
        says; ``src/solver/overlap.h``); 0
        switches it off (GBF as published: overlap once made stays). The default, 1, removes
        the excess within the step that made it: overlap the velocity-level phases cannot
        see (the corner of a fast-turning box sweeping into a neighbour and out of it again
        within the step, separating at the predicted pose) is gone before anyone looks.
    overlap_energy: a body that the overlap correction lifts against gravity, where only
        static bodies touch it and no joint holds it, ends the step with no more energy
        (kinetic plus potential) than it began with plus the work of its applied forces:
        what the lift would add is taken from its kinetic energy, its velocity and angular
        momentum scaled by one factor (to rest where that is not enough). The scaled motion
        approaches no support it did not approach, so its contacts stay resolved
        (``src/solver/overlap.h``). Off, a lift is free: a top spinning on its tip, whose
        axis nutates within a step and sinks its tip ~0.14 mm each step at dt = 1/240,
        gained 0.5% of its energy in 2 s (on: 8e-6 less than it started with).
    joint_passes: rounds of each joint stage (``src/solver/joints.h``), which solve every
        joint's rows at once: the velocity solve's rounds of holding a motor or limit at its
        bound, and pre-stabilisation's Newton steps (until every joint holds to 1e-12 m or
        rad); 0 switches the joint stages off, where a scene has no joint.
    continuous: where a pair moves further in a step than the thinner body's half thickness
        and the end-of-step prediction would carry it past a mid-plane, find its contacts
        where the bodies meet (time of impact) rather than at the end of the step
        (``src/solver/continuous.h``): a fast body stops at a thin wall instead of jumping
        it, a falling plate lands on a table top instead of sinking through. Other pairs
        are found as before, bit for bit. ``for_scene`` leaves it out where nothing can
        move that far (``rigid_gym.fast_motion``).
    contact_patches: in the contact and shock phases, a face or edge patch between two movable
        bodies gets the patch wrench of ``src/solver/patch.h`` (brought exactly to rest or to
        sliding without rocking) as a patch against an immovable one does; off, one impulse at
        the approaching points' centroid, which leaves a light body on a far heavier one
        rocking (a 1 mm cube on a 1 m cube, mass ratio 1e9, moved at 1.5e-5 m/s after 1 s at
        dt = 1/60); and a body touching only static and kinematic bodies is resolved against
        all of them at once, as shock propagation does (pair by pair, the impulse that stopped
        a plank at one of two bars lifted it at the other, and it rocked for good).
    patch_reactions: each patch's impulse is booked to the pairs behind it by the lever
        rule (``World.contacts`` then reports each support's reaction; off, the
        whole patch's impulse goes to one pair), and passes what a sliding patch or a single
        impulse applies across gravity against a dynamic support on to that support as its
        reaction, then resolves the levels again (off, that reaction is lost: a block pulled
        under another on a frictionless floor gained 1.2% momentum beyond F T; a static patch
        wrench's is still lost, see docs/architecture.md, and so is one against a support
        that moves more at the contact than the body on it, where the rounds diverge: a
        0.5 kg ball dropped on a 10 g box's edge sent the box off at 36 m/s).
    exact_symmetric: a body with exactly two equal principal moments, free of torque in a
        position update, turns by its exact torque-free motion (a turn about L and a spin
        about its axis, ``symmetric_rotation`` in ``src/solver/integrate.h``) instead of the
        rotation update of ``rotation_order``, at any dt, and the contact stages predict its
        pose by the same motion; off, a fast flat top on its tip (|omega| dt = 1.25) precessed
        at 250 times the closed-form rate.
    detect_every_pass: run the narrow phase again at the predicted poses in every pass of
        every impulse phase (the original GBF formulation) instead of finding each pair's
        contacts once per step and carrying their separations through the passes
        (``src/solver/contacts.h``); kept to measure what the difference costs and changes.
    """

    collision_passes: int = CORE_DEFAULTS.collision_passes
    contact_passes: int = CORE_DEFAULTS.contact_passes
    shock_sweeps: int = CORE_DEFAULTS.shock_sweeps
    rotation_order: int = CORE_DEFAULTS.rotation_order
    box_edge_segments: int = 4
    sweep: bool | None = None
    sleep: bool = CORE_DEFAULTS.sleep
    sleep_speed: float = CORE_DEFAULTS.sleep_speed
    detect_every_pass: bool = CORE_DEFAULTS.detect_every_pass
    keep_energy: bool = CORE_DEFAULTS.keep_energy
    overlap_correction: float = CORE_DEFAULTS.overlap_correction
    overlap_energy: bool = CORE_DEFAULTS.overlap_energy
    joint_passes: int = CORE_DEFAULTS.joint_passes
    continuous: bool = CORE_DEFAULTS.continuous
    contact_patches: bool = CORE_DEFAULTS.contact_patches
    patch_reactions: bool = CORE_DEFAULTS.patch_reactions
    exact_symmetric: bool = CORE_DEFAULTS.exact_symmetric

    def __post_init__(self):
        for name, low, high in (("collision_passes", 0, 1000), ("contact_passes", 0, 1000),
                                ("shock_sweeps", 0, 1000), ("box_edge_segments", 1, 64),
                                ("joint_passes", 0, 1000)):
            integer(getattr(self, name), f"SolverConfig.{name}", low, high)
        if isinstance(self.overlap_correction, bool) or not isinstance(
                self.overlap_correction, (int, float, np.floating)):
            raise ValueError("SolverConfig.overlap_correction: expected a number, got "
                             f"{self.overlap_correction!r}")
        in_range(self.overlap_correction, 0.0, 1.0, "SolverConfig.overlap_correction")
        if isinstance(self.sleep_speed, bool) or not isinstance(
                self.sleep_speed, (int, float, np.floating)):
            raise ValueError("SolverConfig.sleep_speed: expected a number of m/s, got "
                             f"{self.sleep_speed!r}")
        in_range(self.sleep_speed, 0.0, 10.0, "SolverConfig.sleep_speed")
        if self.rotation_order not in ROTATION_ORDERS:
            raise ValueError(f"SolverConfig.rotation_order must be one of {ROTATION_ORDERS}, "
                             f"got {self.rotation_order!r}")
        if self.sweep not in (None, True, False):
            raise ValueError(f"SolverConfig.sweep must be None, True or False, got {self.sweep!r}")
        for name in ("sleep", "detect_every_pass", "keep_energy", "overlap_energy", "continuous",
                     "contact_patches", "patch_reactions", "exact_symmetric"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"SolverConfig.{name} must be True or False, got "
                                 f"{getattr(self, name)!r}")

    @classmethod
    def for_scene(cls, scene: Scene, dt: float | None = None, **overrides) -> SolverConfig:
        """The default configuration with what ``scene`` cannot need switched off (no shock
        propagation without gravity or when nothing can rest on anything: no dynamic body, or
        one alone in empty space; no continuous collision where nothing can move far in a
        step of ``dt`` s, or, without ``dt``, nothing can move: ``fast_motion.can_move_far``),
        no collision phase when every restitution is 0 (impacts are then the contact phase's
        alone; ``collision_passes``) and no joint stages without a joint (``joint_passes``
        0). ``overrides`` (any field) win over all."""
        known = {f.name for f in fields(cls)}
        unknown = set(overrides) - known
        if unknown:
            raise ValueError(f"SolverConfig.for_scene: unknown option(s) {sorted(unknown)}; "
                             f"allowed: {sorted(known)}")
        derived = {}
        if all(b.restitution == 0.0 for b in scene.bodies):
            derived["collision_passes"] = 0
        dynamic = sum(b.motion == DYNAMIC for b in scene.bodies)
        supports = len(scene.bodies) - dynamic
        if not np.any(scene.gravity) or dynamic == 0 or (dynamic == 1 and supports == 0):
            derived["shock_sweeps"] = 0
        if not scene.joints:
            derived["joint_passes"] = 0
        derived["continuous"] = can_move_far(scene, dt)
        return cls(**{**derived, **overrides})

    def settings(self, sweep: bool = False) -> _core.Settings:
        """The core's view of this config (``Settings`` in ``src/solver/settings.h``), the broad
        phase by sort and sweep or not (``sweep`` as ``collision.uses_sweep`` decides it)."""
        s = _core.Settings()
        for name in ("collision_passes", "contact_passes", "shock_sweeps", "rotation_order",
                     "sleep", "detect_every_pass", "keep_energy", "overlap_energy", "joint_passes",
                     "continuous", "contact_patches", "patch_reactions", "exact_symmetric"):
            setattr(s, name, getattr(self, name))
        s.sleep_speed = float(self.sleep_speed)
        s.overlap_correction = float(self.overlap_correction)
        s.sweep = bool(sweep)
        return s

    def phases(self, gravity: bool = True, joints: bool = True) -> dict[str, bool]:
        """Which stages of the step run, by name, in step order (the core's rules:
        ``_core.stage_rules``). Shock propagation orders bodies along gravity, so without
        gravity (``gravity=False``) it never runs; the joint stages run only where the scene
        has joints (``joints``)."""
        return dict(zip(_core.STAGES, _core.stage_rules(self.settings(), bool(gravity),
                                                        bool(joints))))
