"""The ``rigid-gym`` command.

    rigid-gym demo [--steps N] [--dt S] [--order {1,2,3}]

``demo`` simulates a few tumbling bodies of every shape in free flight and prints how well the
invariants hold (world angular momentum, energy) against the closed forms.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def demo(steps: int, dt: float, order: int) -> int:
    import rigid_gym as rg
    from rigid_gym import analytic
    from rigid_gym.meshes import l_shape_mesh

    scene = rg.Scene(gravity=(0.0, 0.0, -9.81))
    shapes = [rg.Box((0.1, 0.2, 0.3)), rg.Sphere(0.1), rg.Capsule(0.05, 0.2), l_shape_mesh()]
    for k, shape in enumerate(shapes):
        scene.add_body(shape, density=500.0, position=(k, 0.0, 10.0), velocity=(0.0, 1.0, 5.0),
                       angular_velocity=(3.0, 0.1 * k, 5.0), name=type(shape).__name__.lower())
    world = rg.World(scene, dt=dt, config=rg.SolverConfig(rotation_order=order))

    def rotational_energy():
        return 0.5 * np.sum(world.body_angular_momentum * world.angular_velocity, axis=-1)

    momentum0, energy0 = world.body_angular_momentum.copy(), rotational_energy()
    start = time.perf_counter()
    world.step(steps)
    seconds = time.perf_counter() - start
    x, v = analytic.free_fall_discrete(scene.bodies[0].position, scene.bodies[0].velocity,
                                       scene.gravity, dt, steps)
    print(f"rigid_gym demo: {len(shapes)} bodies tumbling in free flight, {steps} steps of "
          f"dt = {dt:g} s, rotation order {order}: {steps / seconds:,.0f} steps/s")
    print(f"  box centre vs discrete free fall:   {np.abs(world.position[0] - x).max():.1e} m")
    print(f"  box velocity vs discrete free fall: {np.abs(world.velocity[0] - v).max():.1e} m/s")
    print(f"  angular momentum change (max):      "
          f"{np.abs(world.body_angular_momentum - momentum0).max():.1e} kg m^2/s")
    print(f"  rotational energy change (max rel): "
          f"{np.max(np.abs(rotational_energy() / energy0 - 1.0)):.1e}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="rigid-gym", description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    p = commands.add_parser("demo", help="simulate tumbling bodies and check the invariants")
    p.add_argument("--steps", type=int, default=2400, help="number of steps (default 2400)")
    p.add_argument("--dt", type=float, default=1 / 240, help="time step, s (default 1/240)")
    p.add_argument("--order", type=int, default=2, choices=(1, 2, 3), help="rotation order")
    args = parser.parse_args(argv)
    if args.command == "demo":
        return demo(args.steps, args.dt, args.order)
    return 2


if __name__ == "__main__":
    sys.exit(main())
