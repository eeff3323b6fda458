"""The ``rigid-gym`` command.

    rigid-gym demo [--steps N] [--dt S] [--order {1,2,3}]

``demo`` runs a few scenes (tumbling bodies of every shape, a ten-cube tower, a bouncing ball,
a sliding box) and prints each result next to its closed form.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def timed_steps(world, steps: int) -> float:
    """Step ``world`` ``steps`` times; return steps/s, the first step (which may compile the
    kernels on a fresh install) left out of the timing."""
    world.step(1)
    start = time.perf_counter()
    world.step(steps - 1)
    return (steps - 1) / (time.perf_counter() - start)


def demo(steps: int, dt: float, order: int) -> int:
    """Run a few scenes and print each result next to its closed form."""
    import rigid_gym as rg
    from rigid_gym import analytic
    from rigid_gym.meshes import l_shape_mesh

    print(f"rigid_gym demo (dt = {dt:g} s)")
    # 1. free flight: every shape tumbling; L and energy are invariants, the centre falls exactly
    scene = rg.Scene(gravity=(0.0, 0.0, -9.81))
    shapes = [rg.Box((0.1, 0.2, 0.3)), rg.Sphere(0.1), rg.Capsule(0.05, 0.2), l_shape_mesh()]
    for k, shape in enumerate(shapes):
        scene.add_body(shape, density=500.0, position=(k, 0.0, 10.0), velocity=(0.0, 1.0, 5.0),
                       angular_velocity=(3.0, 0.1 * k, 5.0), name=type(shape).__name__.lower())
    world = rg.World(scene, dt=dt, config=rg.SolverConfig.for_scene(scene, rotation_order=order))

    def rotational_energy():
        return 0.5 * np.sum(world.body_angular_momentum * world.angular_velocity, axis=-1)

    momentum0, energy0 = world.body_angular_momentum.copy(), rotational_energy()
    rate = timed_steps(world, steps)
    x, _ = analytic.free_fall_discrete(scene.bodies[0].position, scene.bodies[0].velocity,
                                       scene.gravity, dt, steps)
    print(f"  free flight, 4 shapes tumbling for {steps * dt:g} s ({rate:,.0f} steps/s):")
    print(f"    box centre vs discrete free fall        {np.abs(world.position[0] - x).max():.1e} m")
    print(f"    angular momentum change                 "
          f"{np.abs(world.body_angular_momentum - momentum0).max():.1e} kg m^2/s")
    print(f"    rotational energy change (rotation order {order})  "
          f"{np.max(np.abs(rotational_energy() / energy0 - 1.0)):.1e}")
    # 2. a ten-cube tower standing on the ground
    scene = rg.Scene()
    scene.add_ground(friction=0.5)
    for k in range(10):
        scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0.0, 0.0, 0.05 + 0.1 * k))
    world = rg.World(scene, dt=dt)
    top = world.position[10].copy()
    rate = timed_steps(world, steps)
    print(f"  ten-cube tower, {steps * dt:g} s ({rate:,.0f} steps/s): top cube moved "
          f"{np.linalg.norm(world.position[10] - top):.1e} m, deepest overlap "
          f"{world.contacts().depth.max(initial=0.0):.1e} m")
    # 3. a ball bouncing with restitution 0.8, and a box sliding to a stop
    scene = rg.Scene()
    scene.add_ground(restitution=0.8, friction=0.4)
    scene.add_body(rg.Sphere(0.05), mass=1.0, position=(0.0, 0.0, 1.05), restitution=0.8)
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(1.0, 0.0, 0.05),
                   velocity=(2.0, 0.0, 0.0), friction=0.4)
    world = rg.World(scene, dt=dt)
    apex, rising = 0.0, False
    while not (rising and world.velocity[1, 2] <= 0.0) or apex == 0.0:
        rising = world.velocity[1, 2] > 0.0
        world.step()
        if rising and world.velocity[1, 2] <= 0.0:
            apex = world.position[1, 2] - 0.05
    world.step(max(0, int(2.0 / dt) - world.steps))
    slide = world.position[2, 0] - 1.0
    print(f"  ball dropped from 1 m, e = 0.8: first apex {apex:.4f} m (e^2 h0 = 0.6400 m)")
    print(f"  box sliding at 2 m/s, mu = 0.4: stops after {slide:.4f} m "
          f"(v0^2 / (2 mu g) = {2.0 ** 2 / (2 * 0.4 * 9.81):.4f} m)")
    return 0


def bounded(kind, low, high):
    """An argparse type: ``kind`` (int or float) within [low, high], else a clear error."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {kind.__name__}, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be in [{low}, {high}], got {text}")
        return value

    return parse


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rigid-gym", description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    p = commands.add_parser("demo", help="run a few scenes and compare them with closed forms")
    p.add_argument("--steps", type=bounded(int, 2, 10**7), default=2400,
                   help="number of steps, 2 to 1e7 (default 2400)")
    p.add_argument("--dt", type=bounded(float, 1e-6, 0.1), default=1 / 240,
                   help="time step, s, 1e-6 to 0.1 (default 1/240)")
    p.add_argument("--order", type=int, default=2, choices=(1, 2, 3), help="rotation order")
    args = parser.parse_args(argv)
    if args.command == "demo":
        return demo(args.steps, args.dt, args.order)
    return 2


if __name__ == "__main__":
    sys.exit(main())
