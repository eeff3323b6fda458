"""rigid_gym: an impulse-based rigid-body solver and the Gymnasium manipulation tasks built on it.

    import rigid_gym as rg
    scene = rg.Scene()
    scene.add_ground()
    scene.add_body(rg.Box((0.05, 0.05, 0.05)), mass=1.0, position=(0, 0, 0.5))
    world = rg.World(scene, dt=1 / 240)
    world.step(240)
"""

import importlib.metadata

from rigid_gym.config import SolverConfig
from rigid_gym.envs import ENV_IDS  # registers rigid_gym/Push-v0 ... with Gymnasium
from rigid_gym.inertia import MassProperties, mass_properties
from rigid_gym.render import Camera, Renderer
from rigid_gym.scene import Scene
from rigid_gym.shapes import Box, Capsule, Compound, Mesh, Plane, Pose, Sphere
from rigid_gym.world import World

__all__ = [
    "ENV_IDS", "Box", "Camera", "Capsule", "Compound", "MassProperties", "Mesh", "Plane", "Pose",
    "Renderer", "Scene", "SolverConfig", "Sphere", "World", "mass_properties",
]
__version__ = importlib.metadata.version("rigid_gym")  # pyproject.toml's
