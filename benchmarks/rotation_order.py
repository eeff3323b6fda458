"""Error order of the rotation updates on the torque-free asymmetric top.

For each update (1: the notes' exact rotation with omega at the step start; 2 and 3: Buss's
second and third order) and each dt, simulates I = (1, 2, 3) kg m^2 started at
omega = (0.3, 0, 1) rad/s (body frame) for 10 s and prints:
  energy error   max over the run of |E/E0 - 1|   (L is exact, so E = L.omega/2 measures the
                 orientation error)
  omega error    max |omega_body - exact| against the Jacobi-elliptic solution, rad/s
  ratio          error at 2 dt / error at dt: 2^p for a method of order p
  us/step        wall time per World.step, timed over a whole run without queries
                 (median of 3 runs)

    python benchmarks/rotation_order.py
"""

import time

import numpy as np

import rigid_gym as rg
from rigid_gym import analytic
from rigid_gym.report.scenes import spinning_body

MOMENTS = (1.0, 2.0, 3.0)
OMEGA0 = (0.3, 0.0, 1.0)
DURATION = 10.0
DTS = (1 / 25, 1 / 50, 1 / 100, 1 / 200, 1 / 400)


def run(order: int, dt: float) -> tuple[float, float, float]:
    world = rg.World(spinning_body(MOMENTS, OMEGA0), dt=dt, config=rg.SolverConfig(rotation_order=order))
    steps = round(DURATION / dt)
    exact = analytic.torque_free_angular_velocity(MOMENTS, OMEGA0, dt * np.arange(1, steps + 1))
    e0 = world.kinetic_energy()
    energy_error = omega_error = 0.0
    for k in range(steps):
        world.step()
        energy_error = max(energy_error, abs(world.kinetic_energy() / e0 - 1.0))
        body_omega = world.rotation[0].T @ world.angular_velocity[0]
        omega_error = max(omega_error, float(np.abs(body_omega - exact[k]).max()))
    world.reset()
    start = time.perf_counter()
    world.step(steps)
    return energy_error, omega_error, (time.perf_counter() - start) / steps


def main() -> None:
    run(1, 0.1)  # warm-up
    print("| order | dt (s) | energy error | ratio | omega error (rad/s) | ratio | us/step |")
    print("|---|---|---|---|---|---|---|")
    for order in (1, 2, 3):
        previous = None
        for dt in DTS:
            results = [run(order, dt) for _ in range(3)]
            energy, omega = results[0][0], results[0][1]
            micros = 1e6 * float(np.median([r[2] for r in results]))
            ratios = ("", "") if previous is None else (
                f"{previous[0] / energy:.2f}", f"{previous[1] / omega:.2f}")
            print(f"| {order} | 1/{round(1 / dt)} | {energy:.3e} | {ratios[0]} | {omega:.3e} | "
                  f"{ratios[1]} | {micros:.1f} |")
            previous = (energy, omega)


if __name__ == "__main__":
    main()
