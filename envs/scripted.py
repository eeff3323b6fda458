"""Hand-written policies for every task: baselines that need no training, used by the tests,
the benchmarks and ``rigid-gym record --policy scripted``.

Each policy is a function of the observation dict alone (no memory), so it can resume from
any state; it reads the observation's fields by name (the task's ``observation_layout``):

    policy = scripted_policy(env)          # env: any rigid_gym env, wrapped or not
    action = policy(observation)

An env made with ``effector="gripper"`` gets the two-finger gripper's policies (the ``*_fingers``
functions): approach open, descend around the object, close until both pads press it, lift,
carry, put down and open (Throw: open in flight, one step after the launch).
"""

from __future__ import annotations

import functools

import numpy as np

from .base import RigidGymEnv
from .effector import PAD_HALF_EXTENTS, STEP_DISTANCE
from .flip import (
    PUSH_DIRECTIONS,
    ROLLS,
    TILTED,
    nearest_rotation,
    nearest_target,
    roll_table,
    rotation_matrices,
    tilt,
)
from .gripper import FINGER_DROP, MAX_OPENING, TOP_GRASP
from .insert import CLEARANCE, HOLE_DEPTH, HOLE_HALF, PEG_HALF_EXTENTS, Insert
from .observation import Layout
from .slide import PUCK_FRICTION, PUCK_RADIUS
from .task import CUBE_HALF, FRICTION, STEP_TIME

PAD_HALF_HEIGHT = PAD_HALF_EXTENTS[2]
CRUISE_HEIGHT = 0.12
"""m: pad centre height for moving over cubes."""
ALIGNED = 0.006
"""m: x, y error under which the pad counts as above (or behind) its mark."""
G = 9.81
STRIKE_GAP = 0.005
"""m between the pad and the puck before Slide's strike."""
STAGING = 0.02
"""m back along the line from Slide's strike position where the pad descends."""
FLIP_PUSH_DEPTH = 0.005
"""m: Flip's pad pushes with its bottom this far below the cube's top (the top of a face)."""
FLIP_PUSH_SPEED = 0.3
"""Flip's push, in action units (0.015 m per step)."""
FLIP_ROLL_SHIFT = 0.06
"""m a roll moves the cube, about (for choosing rolls that keep it in the middle)."""
INSERT = Insert()
"""Insert's goal test, which the policy reads from the observation's goals."""
OPEN, CLOSE = 1.0, -1.0
"""The gripper's finger commands: full speed open, full speed closed (pressing with the full
grip force once the pads meet the object)."""
FINGER_CLEARANCE = 0.01
"""m: the gripper's finger tips stop this far above the bottom of the object they take."""
GRIPPER_CRUISE = 0.15
"""m: hand centre height for moving over cubes empty (the finger tips 8 cm up)."""
GRIPPER_CARRY = GRIPPER_CRUISE + 0.02
"""m: hand centre height for carrying a cube over the others (its bottom 9.5 cm up)."""
FIRM = 0.001
"""m: the gripper holds firmly once its opening is within this of the object's width."""
THROW_LAUNCH = (0.15, 0.2)
"""m: x and hand centre height of the gripper's launch point: from there the launch step and
the release step each move the hand up to 5 cm in x and z and stay in its workspace (x up to
0.25 m), and the hand's palm stays above the rising cube."""


def scripted_policy(env):
    """The scripted policy for ``env``'s task: a function observation dict -> action."""
    task = env.unwrapped
    if not isinstance(task, RigidGymEnv):
        raise ValueError(f"scripted_policy: expected a rigid_gym env, got {type(task).__name__}")
    if task.task.effector == "gripper":
        policy = {"StackEnv": _tower_fingers, "TowerEnv": _tower_fingers,
                  "PickAndPlaceEnv": _pick_and_place_fingers, "ThrowEnv": _throw_fingers,
                  "InsertEnv": _insert_fingers}[type(task).__name__]
    else:
        policy = {"PushEnv": _push, "StackEnv": _stack, "ThrowEnv": _throw,
                  "ReachEnv": _reach, "PickAndPlaceEnv": _pick_and_place, "SlideEnv": _slide,
                  "FlipEnv": _flip,
                  "TowerEnv": _tower, "InsertEnv": _insert}[type(task).__name__]
    return functools.partial(policy, task.task.observation_layout)


def _toward(pad: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The motion part of an action that moves the pad toward ``target`` (full speed when far)."""
    return np.clip((target - pad) / STEP_DISTANCE, -1.0, 1.0)


def _field(layout: Layout, observation: dict, name: str) -> np.ndarray:
    """Field ``name`` of ``observation["observation"]``, as float64."""
    return observation["observation"][layout.slice(name)].astype(np.float64)


def _held(layout: Layout, observation: dict) -> bool:
    """Whether the observation's ``holding`` flag says the pad holds a cube."""
    return bool(observation["observation"][layout.slice("holding")][0] > 0.5)


def _above(pad, point, height) -> np.ndarray:
    """Motion to reach (point x, y, height): rise first if low and not yet above it."""
    target = np.array([point[0], point[1], height])
    if np.linalg.norm(pad[:2] - point[:2]) > ALIGNED and pad[2] < height - 0.02:
        target = np.array([pad[0], pad[1], height])
    return _toward(pad, target)


def _push(layout: Layout, observation: dict) -> np.ndarray:
    """Get behind the cube on the line from the target through it, then push along that line."""
    pad = _field(layout, observation, "pad.position")
    cube = _field(layout, observation, "cube0.position")
    goal = observation["desired_goal"].astype(np.float64)
    line = goal[:2] - cube[:2]
    distance = np.linalg.norm(line)
    if distance < 0.01:
        return np.zeros(3)
    direction = np.append(line / distance, 0.0)
    # stand off by the cube's widest half (its diagonal, whatever its turn) plus the pad's
    # half width along the line (the pad never turns)
    standoff = np.sqrt(2) * CUBE_HALF + PAD_HALF_EXTENTS[0] * np.abs(direction).sum() + 0.005
    behind = cube - direction * standoff
    behind[2] = cube[2]
    off_line = np.linalg.norm(pad[:2] - behind[:2]) > 2 * ALIGNED
    if off_line:
        if pad[2] < 2 * cube[2] + PAD_HALF_HEIGHT + 0.01:
            return _toward(pad, np.array([pad[0], pad[1], CRUISE_HEIGHT]))  # clear the cube
        return _above(pad, behind, CRUISE_HEIGHT)
    if pad[2] > cube[2] + 0.01:
        return _toward(pad, behind)  # descend behind the cube
    # push no faster than the cube can slide to a stop at the target: v^2 = 2 mu g d
    speed = 0.7 * np.sqrt(2.0 * FRICTION * G * distance)
    return _toward(pad, behind + direction * min(speed * STEP_TIME, STEP_DISTANCE))


def _carry(pad, cube, target, held, half_height: float = CUBE_HALF,
           cruise: float = CRUISE_HEIGHT, carry: float = CRUISE_HEIGHT + 0.02) -> np.ndarray:
    """Pick ``cube`` (of half height ``half_height``, m) up by its top and put it down with its
    centre at ``target``: (motion, grip). The pad moves over things at ``cruise`` m (its
    centre) while empty and at ``carry`` m while holding."""
    if not held:
        top = cube + np.array([0.0, 0.0, half_height + PAD_HALF_HEIGHT])
        if np.linalg.norm(pad[:2] - top[:2]) > ALIGNED:
            return np.append(_above(pad, top, cruise), -1.0)
        return np.append(_toward(pad, top - np.array([0, 0, 0.01])), 1.0)
    offset = pad - cube
    goal_pad = target + offset
    if np.linalg.norm(cube[:2] - target[:2]) > ALIGNED:
        return np.append(_above(pad, goal_pad, carry), 1.0)
    if cube[2] > target[2] + 0.002:
        return np.append(_toward(pad, goal_pad), 1.0)
    return np.append(np.zeros(3), -1.0)


def _stack(layout: Layout, observation: dict) -> np.ndarray:
    """Carry cube 0 to the tower's base, then cube 1 onto it; then let go and rise."""
    pad, held = _field(layout, observation, "pad.position"), _held(layout, observation)
    goal = observation["desired_goal"].astype(np.float64)
    cubes = [_field(layout, observation, f"cube{k}.position") for k in (0, 1)]
    for k in (0, 1):
        target = goal[3 * k:3 * k + 3]
        if np.linalg.norm(cubes[k] - target) > 0.01:
            holding_other = held and np.linalg.norm(pad[:2] - cubes[1 - k][:2]) < 0.01
            if holding_other:
                return np.append(np.zeros(3), -1.0)
            return _carry(pad, cubes[k], target, held)
    return np.array([0.0, 0.0, 1.0, -1.0])


def _tower(layout: Layout, observation: dict) -> np.ndarray:
    """Carry each cube in turn, cube 0 first, onto the tower's top, moving over the tower built
    so far; then let go and rise."""
    pad, held = _field(layout, observation, "pad.position"), _held(layout, observation)
    goal = observation["desired_goal"].astype(np.float64).reshape(-1, 3)
    cubes = [_field(layout, observation, f"cube{k}.position") for k in range(len(goal))]
    for k, (cube, target) in enumerate(zip(cubes, goal)):
        if np.linalg.norm(cube - target) > 0.01:
            if held and not _under(pad, cube):
                return np.append(np.zeros(3), -1.0)  # holding another cube: let it go
            top = target[2] - CUBE_HALF  # of the tower built so far
            return _carry(pad, cube, target, held,
                          cruise=max(CRUISE_HEIGHT, top + PAD_HALF_HEIGHT + 0.02),
                          carry=max(CRUISE_HEIGHT + 0.02,
                                    top + 2 * CUBE_HALF + PAD_HALF_HEIGHT + 0.02))
    return np.array([0.0, 0.0, 1.0, -1.0])


def _under(pad: np.ndarray, cube: np.ndarray) -> bool:
    """Whether ``cube``'s top touches the pad's bottom, under its centre (the cube it holds)."""
    return bool(np.linalg.norm(pad[:2] - cube[:2]) < 0.01
                and abs(pad[2] - cube[2] - CUBE_HALF - PAD_HALF_HEIGHT) < 0.005)


def _insert(layout: Layout, observation: dict) -> np.ndarray:
    """Take the peg by its top and lift it clear of the block; over the block, line it up with
    the hole and lower it; in the hole, push it down to the floor, let go and rise. Every
    branch reads where the peg is now, so it recovers from a push off line: a peg lowered off
    the hole stops on the block (the force limit) and is lined up again there."""
    pad, held = _field(layout, observation, "pad.position"), _held(layout, observation)
    peg = _field(layout, observation, "cube0.position")
    goal = observation["desired_goal"].astype(np.float64)
    half_length = PEG_HALF_EXTENTS[2]
    if not held:
        if INSERT.goal_reached(peg, goal):
            return np.array([0.0, 0.0, 1.0, -1.0])  # in: rise clear
        return _carry(pad, peg, goal, False, half_length)  # take it by its top
    goal_pad = goal + (pad - peg)
    error = np.abs(peg[:2] - goal[:2]).max()  # of its axis from the hole's, along x or y
    below_top = peg[2] - half_length < HOLE_DEPTH - 0.001  # its bottom below the block's top
    if below_top and error < HOLE_HALF:  # in the hole: down to the floor, then let go
        if peg[2] > goal[2] + 0.002:
            return np.append(_toward(pad, goal_pad), 1.0)
        return np.append(np.zeros(3), -1.0)
    if below_top:  # beside the block: up and over, clear of it
        return np.append(_above(pad, goal_pad, HOLE_DEPTH + 2 * half_length
                                + PAD_HALF_HEIGHT + 0.03), 1.0)
    if error > CLEARANCE:  # over the block: line up at this height
        return np.append(_toward(pad, np.array([goal_pad[0], goal_pad[1], pad[2]])), 1.0)
    return np.append(_toward(pad, goal_pad), 1.0)


def _throw(layout: Layout, observation: dict) -> np.ndarray:
    """Pick the cube up, carry it to the launch point, release it on a ballistic arc to the bin."""
    pad, held = _field(layout, observation, "pad.position"), _held(layout, observation)
    cube = _field(layout, observation, "cube0.position")
    goal = observation["desired_goal"].astype(np.float64)
    if not held:
        if cube[2] > 0.03 or np.linalg.norm(cube[:2]) > 0.3:  # in flight or thrown:
            return np.array([-1.0, 0.0, 1.0, -1.0])  # follow through up and back, out of its way
        return _carry(pad, cube, cube, False)
    # launch as far forward as the release step's motion stays unclipped (a clipped move would
    # change the release velocity; from x = 0.15 the far bins were out of range), and low
    # enough that the pad, which stops at the workspace's top, stays above the rising cube
    launch = np.array([0.2, np.clip(goal[1] * 0.5, -0.2, 0.2), 0.2])
    if np.linalg.norm(pad - launch) > 0.01:
        return np.append(_toward(pad, launch), 1.0)
    velocity = _launch_velocity(cube, goal)
    return np.append(np.clip(velocity * STEP_TIME / STEP_DISTANCE, -1.0, 1.0), -1.0)


def _launch_velocity(start: np.ndarray, goal: np.ndarray, vertical: float = 1.25,
                     carried: float = 0.0) -> np.ndarray:
    """Velocity (3,) m/s with vertical component ``vertical`` that carries a point from
    ``start`` to ``goal``: first in a straight line at that velocity for ``carried`` s (the
    gripper's launch step, still closed), then under gravity (descending branch of the
    parabola)."""
    drop = start[2] + vertical * carried - goal[2]
    time = (vertical + np.sqrt(vertical ** 2 + 2 * G * drop)) / G + carried
    return np.array([(goal[0] - start[0]) / time, (goal[1] - start[1]) / time, vertical])


def _reach(layout: Layout, observation: dict) -> np.ndarray:
    """Move the pad straight to the target."""
    pad = _field(layout, observation, "pad.position")
    return _toward(pad, observation["desired_goal"].astype(np.float64))


def _pick_and_place(layout: Layout, observation: dict) -> np.ndarray:
    """Pick the cube up; put it down at a target on the table, or hold it at one in the air."""
    pad, held = _field(layout, observation, "pad.position"), _held(layout, observation)
    cube = _field(layout, observation, "cube0.position")
    target = observation["desired_goal"].astype(np.float64)
    on_table = target[2] < CUBE_HALF + 0.005
    if not held:
        if np.linalg.norm(cube - target) < 0.01:  # put down: stay clear
            return np.array([0.0, 0.0, 1.0, -1.0])
        return _carry(pad, cube, target, False)
    if on_table:
        return _carry(pad, cube, target, True)
    if cube[2] < CUBE_HALF + 0.02 and np.linalg.norm(cube[:2] - target[:2]) > ALIGNED:
        return np.array([0.0, 0.0, 1.0, 1.0])  # lift clear of the table first
    return np.append(_toward(pad, target + pad - cube), 1.0)  # then hold it at the target


def _slide(layout: Layout, observation: dict) -> np.ndarray:
    """Get behind the puck on the line from the target through it, then strike it in one step
    at the speed from which friction stops it at the target, and stand still."""
    pad = _field(layout, observation, "pad.position")
    puck = _field(layout, observation, "cube0.position")
    if np.linalg.norm(_field(layout, observation, "cube0.velocity")) > 0.02:
        return np.zeros(3)  # sliding: keep out of its way
    goal = observation["desired_goal"].astype(np.float64)
    line = goal[:2] - puck[:2]
    distance = np.linalg.norm(line)
    if distance < 0.01:
        return np.zeros(3)
    direction = np.append(line / distance, 0.0)
    radius = PUCK_RADIUS * puck[2]  # the puck's centre height is its half height
    # strike with the pad's vertical edge on the line: a round puck is pushed along the normal
    # at the contact, which a face would keep to x or y whatever the line
    corner = np.append(np.where(direction[:2] >= 0.0, 1.0, -1.0) * PAD_HALF_EXTENTS[:2], 0.0)
    behind = puck - direction * (radius + STRIKE_GAP) - corner
    behind[2] = puck[2]
    along = np.dot(pad[:2] - behind[:2], direction[:2])  # < 0: back from it on the line
    across = np.linalg.norm(pad[:2] - behind[:2] - along * direction[:2])
    on_line = across < 2 * ALIGNED and -STAGING - 2 * ALIGNED < along < ALIGNED
    if not (on_line and pad[2] <= puck[2] + 0.005):
        # descend STAGING back along the line: the arm's force limit takes the puck for its
        # bounding box, which a pad's corner just behind a round puck overlaps on a diagonal
        staging = behind - direction * STAGING
        if np.linalg.norm(pad[:2] - staging[:2]) > 2 * ALIGNED:
            if pad[2] < 2 * puck[2] + PAD_HALF_HEIGHT + 0.01:
                return _toward(pad, np.array([pad[0], pad[1], CRUISE_HEIGHT]))  # clear it
            return _above(pad, staging, CRUISE_HEIGHT)
        return _toward(pad, staging)  # descend
    if along < -ALIGNED:
        return _toward(pad, behind)  # close up to the strike's gap, low
    # the puck moves with the pad for the rest of the strike step (v STEP_TIME - STRIKE_GAP),
    # then slides v^2 / (2 mu g): the speed v that adds up to the distance
    a, b, c = 1.0 / (2.0 * PUCK_FRICTION * G), STEP_TIME, -(distance + STRIKE_GAP)
    speed = (-b + np.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    return np.clip(direction * speed * STEP_TIME / STEP_DISTANCE, -1.0, 1.0)


def _flip(layout: Layout, observation: dict) -> np.ndarray:
    """Roll the cube a quarter turn at a time (pushed at the top of a face it tips over its far
    edge), along a fewest-rolls path to the resting orientation nearest the target, choosing
    among equally short paths the roll that keeps the cube nearest the middle."""
    pad = _field(layout, observation, "pad.position")
    if _held(layout, observation):
        return np.array([0.0, 0.0, 1.0, -1.0])
    cube = _field(layout, observation, "cube0.position")
    rotation = rotation_matrices(_field(layout, observation, "cube0.orientation")[None])[0]
    angle = tilt(rotation[None])[0]
    half = CUBE_HALF
    push_height = 2 * half + PAD_HALF_HEIGHT - FLIP_PUSH_DEPTH
    if angle > TILTED:  # mid-roll: push on while it leans away from the pad, then let it fall
        up = rotation[:, np.argmax(np.abs(rotation[2]))]
        lean = np.sign(up[2]) * up[:2]
        ahead = np.dot(cube[:2] - pad[:2], lean) > 0 and pad[2] < 2 * half + PAD_HALF_HEIGHT
        if ahead and angle < np.deg2rad(35.0):
            step = np.zeros(3)
            step[np.argmax(np.abs(lean))] = np.sign(lean[np.argmax(np.abs(lean))])
            return np.append(step * FLIP_PUSH_SPEED, -1.0)
        return np.zeros(4)
    after, rolls = roll_table()
    current = nearest_rotation(rotation)
    target = nearest_target(observation["desired_goal"].astype(np.float64))
    left = rolls[current, target]
    if left == 0:
        return np.array([0.0, 0.0, 1.0, -1.0])  # done: rise out of the way
    moves = [k for k in range(len(after[current])) if rolls[after[current, k], target] < left]
    directions = [np.array(PUSH_DIRECTIONS[d]) for d in ROLLS]
    move = min(moves, key=lambda k: np.linalg.norm(cube[:2] + FLIP_ROLL_SHIFT * directions[k]))
    direction = np.append(directions[move], 0.0)
    behind = cube - direction * (half + PAD_HALF_EXTENTS[0] + 0.008)
    behind[2] = push_height
    clear = 2 * half + PAD_HALF_HEIGHT + 0.02
    if np.linalg.norm(pad[:2] - behind[:2]) > 2 * ALIGNED:
        if pad[2] < clear - 0.005:
            return np.array([0.0, 0.0, 1.0, -1.0])  # clear the cube
        return np.append(_above(pad, behind, clear), -1.0)
    if pad[2] > push_height + 0.003:
        return np.append(_toward(pad, behind), -1.0)  # descend behind the cube
    return np.append(direction * FLIP_PUSH_SPEED, -1.0)


# -- the two-finger gripper (effector="gripper") ---------------------------------------------

def _firmly_held(layout: Layout, observation: dict, half_width: float) -> bool:
    """Whether the gripper holds an object of half width ``half_width`` (m, along the fingers'
    axis) with both pads pressing it: the holding flag, and the opening closed to within FIRM
    of the object's width (the flag comes a little earlier, as the pads arrive)."""
    width = observation["observation"][layout.slice("fingers.width")][0]
    return _held(layout, observation) and bool(width <= 2.0 * half_width + FIRM)


def _grasp_height(obj: np.ndarray, half_height: float) -> float:
    """The hand's centre height at which the fingers take an object centred at ``obj`` of half
    height ``half_height`` (m): the tips FINGER_CLEARANCE above its bottom, or, for an object
    taller than the fingers take (Insert's peg), around its top TOP_GRASP."""
    tips = max(obj[2] - half_height + FINGER_CLEARANCE, obj[2] + half_height - TOP_GRASP)
    return tips + FINGER_DROP


def _take(hand: np.ndarray, obj: np.ndarray, half_height: float, cruise: float) -> np.ndarray:
    """Approach ``obj`` open at ``cruise`` (the hand's centre, m), descend around it, then
    close on it (and stay still while the fingers close): the action."""
    grasp = np.array([obj[0], obj[1], _grasp_height(obj, half_height)])
    if np.linalg.norm(hand[:2] - grasp[:2]) > ALIGNED:
        return np.append(_above(hand, grasp, cruise), OPEN)
    if hand[2] > grasp[2] + 0.003:
        return np.append(_toward(hand, grasp), OPEN)
    return np.append(np.zeros(3), CLOSE)


def _put(hand: np.ndarray, obj: np.ndarray, target: np.ndarray, carry: float) -> np.ndarray:
    """Carry the held ``obj`` at ``carry`` (the hand's centre, m) over ``target``, lower it
    until its centre is there (a table or a cube below stops it: the force limit), and open:
    the action."""
    goal_hand = target + hand - obj
    if np.linalg.norm(obj[:2] - target[:2]) > ALIGNED:
        return np.append(_above(hand, goal_hand, carry), CLOSE)
    if obj[2] > target[2] + 0.002:
        return np.append(_toward(hand, goal_hand), CLOSE)
    return np.append(np.zeros(3), OPEN)


def _between(hand: np.ndarray, cube: np.ndarray) -> bool:
    """Whether ``cube`` lies between the fingers about where ``_take`` grasps it (the cube
    held): along y anywhere between the open pads (a held cube slides along the fingers'
    axis when the hand's velocity jumps)."""
    return bool(abs(hand[0] - cube[0]) < 0.01 and abs(hand[1] - cube[1]) < 0.5 * MAX_OPENING
                and abs(hand[2] - _grasp_height(cube, CUBE_HALF)) < 0.015)


def _tower_fingers(layout: Layout, observation: dict) -> np.ndarray:
    """Stack and Tower with the gripper: take each cube in turn, cube 0 first, carry it over
    the tower built so far and put it on top; then open and rise."""
    hand = _field(layout, observation, "hand.position")
    goal = observation["desired_goal"].astype(np.float64).reshape(-1, 3)
    cubes = [_field(layout, observation, f"cube{k}.position") for k in range(len(goal))]
    for cube, target in zip(cubes, goal):
        if np.linalg.norm(cube - target) > 0.01:
            if _held(layout, observation) and not _between(hand, cube):
                return np.append(np.zeros(3), OPEN)  # holding another cube: let it go
            top = target[2] - CUBE_HALF  # of the tower built so far
            if not _firmly_held(layout, observation, CUBE_HALF):
                return _take(hand, cube, CUBE_HALF,
                             max(GRIPPER_CRUISE, top + FINGER_DROP + 0.02))
            return _put(hand, cube, target,
                        max(GRIPPER_CARRY, top + CUBE_HALF + 0.02 + hand[2] - cube[2]))
    return np.array([0.0, 0.0, 1.0, OPEN])


def _pick_and_place_fingers(layout: Layout, observation: dict) -> np.ndarray:
    """PickAndPlace with the gripper: take the cube; put it down at a target on the table, or
    hold it at one in the air."""
    hand = _field(layout, observation, "hand.position")
    cube = _field(layout, observation, "cube0.position")
    target = observation["desired_goal"].astype(np.float64)
    if not _firmly_held(layout, observation, CUBE_HALF):
        if np.linalg.norm(cube - target) < 0.01 and not _held(layout, observation):
            return np.array([0.0, 0.0, 1.0, OPEN])  # put down: stay clear
        return _take(hand, cube, CUBE_HALF, GRIPPER_CRUISE)
    if target[2] < CUBE_HALF + 0.005:  # on the table
        return _put(hand, cube, target, GRIPPER_CARRY)
    if cube[2] < CUBE_HALF + 0.02 and np.linalg.norm(cube[:2] - target[:2]) > ALIGNED:
        return np.array([0.0, 0.0, 1.0, CLOSE])  # lift clear of the table first
    return np.append(_toward(hand, target + hand - cube), CLOSE)  # then hold it at the target


def _throw_fingers(layout: Layout, observation: dict) -> np.ndarray:
    """Throw with the gripper: take the cube, carry it to the launch point, swing it at the
    launch velocity for one step still closed, then open while the hand keeps that velocity
    (so the cube leaves with it), and follow through up and back out of its way."""
    hand = _field(layout, observation, "hand.position")
    cube = _field(layout, observation, "cube0.position")
    goal = observation["desired_goal"].astype(np.float64)
    if not _held(layout, observation):
        if cube[2] > 0.03 or np.linalg.norm(cube[:2]) > 0.3:  # in flight or thrown
            return np.array([-1.0, 0.0, 1.0, OPEN])
        return _take(hand, cube, CUBE_HALF, GRIPPER_CRUISE)
    if not _firmly_held(layout, observation, CUBE_HALF):
        return _take(hand, cube, CUBE_HALF, GRIPPER_CRUISE)  # still closing
    launch = np.array([THROW_LAUNCH[0], np.clip(goal[1] * 0.5, -0.2, 0.2), THROW_LAUNCH[1]])
    if hand[0] > launch[0] + 0.005 and hand[2] > launch[2] + 0.005:  # launched: let go
        velocity = _field(layout, observation, "hand.velocity")
        return np.append(velocity * STEP_TIME / STEP_DISTANCE, OPEN)
    if np.linalg.norm(hand - launch) > 0.01:
        return np.append(_toward(hand, launch), CLOSE)
    velocity = _launch_velocity(cube, goal, carried=STEP_TIME)
    return np.append(np.clip(velocity * STEP_TIME / STEP_DISTANCE, -1.0, 1.0), CLOSE)


def _insert_fingers(layout: Layout, observation: dict) -> np.ndarray:
    """Insert with the gripper: take the peg around its top and lift it clear of the block;
    over the block, line it up with the hole and lower it to the floor; open and rise. Every
    branch reads where the peg is now, as the pad's policy does."""
    hand = _field(layout, observation, "hand.position")
    peg = _field(layout, observation, "cube0.position")
    goal = observation["desired_goal"].astype(np.float64)
    half_length = PEG_HALF_EXTENTS[2]
    cruise = 2.0 * half_length + FINGER_DROP + 0.02  # the tips clear a standing peg
    if not _firmly_held(layout, observation, PEG_HALF_EXTENTS[1]):
        if INSERT.goal_reached(peg, goal) and not _held(layout, observation):
            return np.array([0.0, 0.0, 1.0, OPEN])  # in: rise clear
        return _take(hand, peg, half_length, cruise)
    goal_hand = goal + (hand - peg)
    error = np.abs(peg[:2] - goal[:2]).max()  # of its axis from the hole's, along x or y
    below_top = peg[2] - half_length < HOLE_DEPTH - 0.001  # its bottom below the block's top
    if below_top and error < HOLE_HALF:  # in the hole: down to the floor, then let go
        if peg[2] > goal[2] + 0.002:
            return np.append(_toward(hand, goal_hand), CLOSE)
        return np.append(np.zeros(3), OPEN)
    if below_top:  # beside the block: up and over, clear of it
        return np.append(_above(hand, goal_hand, HOLE_DEPTH + half_length + 0.03
                                + hand[2] - peg[2]), CLOSE)
    if error > CLEARANCE:  # over the block: line up at this height
        return np.append(_toward(hand, np.array([goal_hand[0], goal_hand[1], hand[2]])), CLOSE)
    return np.append(_toward(hand, goal_hand), CLOSE)
