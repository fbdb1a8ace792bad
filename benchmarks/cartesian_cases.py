"""
The fixed, seeded set of lines and arcs of benchmarks/cartesian.py (issue 30, "Speed").

Per robot (example-robot-data's Panda, tool ``panda_hand_tcp``, and UR10, tool
``wrist_3_link``) 10 lines of 0.1-0.4 m and 5 arcs, from :data:`SEED`:

* ``away``: a start within ±0.35 rad of each joint of a nominal pose, a line in a random
  direction (or an arc on a random circle through the start, 0.1-0.4 m long), the tool
  turning by up to 0.4 rad about a random axis; goal (and interim) reachable.
* ``stretch``: the arm outward, near full stretch: a line along the shoulder-to-tool
  direction ending 5-20 mm before the end of the reach (found by walking out in 5 mm
  steps of the inverse kinematics), or an arc whose interim point is there.
* ``wrist`` (UR10): ``wrist_2`` within 0.03-0.08 rad of 0, where joints 4 and 6 align
  (the wrist singularity), the tool's orientation kept along a random line or arc.
* ``overhead`` (Panda): the tool above the shoulder, near the axis of joint 1.

Each case keeps the start's joints: both planners start from them.

Units: m, rad.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core.cartesian.rotations import rotation_exp
from traj_gen_ros.core.cartesian.tool_path import circular_path, straight_path, ToolPath
from traj_gen_ros.core.kinematics import Chain
from traj_gen_ros.core.kinematics.inverse import UnreachablePoseError

SEED = 30
LENGTHS = (0.1, 0.4)  # m: a line's length, an arc's
PANDA_READY = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
UR_HOME = np.array([0.0, -1.57, 1.57, -1.57, -1.57, 0.0])
#: Per robot: (kind, line or arc) in order, 10 lines and 5 arcs.
PLAN = {
    'panda': [('away', 'line')] * 6 + [('stretch', 'line')] * 2 + [('overhead', 'line')] * 2
    + [('away', 'arc')] * 3 + [('stretch', 'arc'), ('overhead', 'arc')],
    'ur10': [('away', 'line')] * 6 + [('stretch', 'line')] * 2 + [('wrist', 'line')] * 2
    + [('away', 'arc')] * 3 + [('stretch', 'arc'), ('wrist', 'arc')],
}
SHOULDER = {'panda': 'panda_link2', 'ur10': 'upper_arm_link'}
_STEP = 0.005  # m: the walk out to the end of the reach


@dataclass(frozen=True)
class Case:
    """One line or arc: its robot, kind, path, and the joints at its start."""

    name: str
    robot: str
    kind: str
    shape: str
    q_start: np.ndarray
    path: ToolPath

    @property
    def translation(self) -> float:
        """Return the tool's travel (m): ``|dp/ds|·S`` (constant along one line or arc)."""
        return float(np.linalg.norm(self.path.sample(0.0).velocity[0])) * self.path.length


def _unit(rng: np.random.Generator) -> np.ndarray:
    vector = rng.normal(size=3)
    return vector / np.linalg.norm(vector)


def _reachable(chain: Chain, pose: np.ndarray, seed: np.ndarray) -> np.ndarray | None:
    try:
        return chain.inverse(pose, seed).q
    except UnreachablePoseError:
        return None


def _turned(pose: np.ndarray, rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    moved = pose.copy()
    moved[:3, :3] = rotation @ pose[:3, :3]
    moved[:3, 3] = position
    return moved


def _reach(chain: Chain, q: np.ndarray, pose: np.ndarray, direction: np.ndarray,
           limit: float = 0.6) -> float:
    """Return how far (m) the tool goes along ``direction`` from ``pose`` (orientation kept)."""
    distance = 0.0
    while distance < limit:
        step = _turned(pose, np.eye(3), pose[:3, 3] + (distance + _STEP) * direction)
        try:
            q = chain.inverse(step, q).q  # seeded from the step before: the same branch
        except UnreachablePoseError:
            break
        if pose_error_mm(chain, q, step) > 0.01:
            break
        distance += _STEP
    return distance


def pose_error_mm(chain: Chain, q: np.ndarray, pose: np.ndarray) -> float:
    """Return the distance (mm) of the tool at ``q`` from ``pose``'s position."""
    return float(np.linalg.norm(chain.forward(q)[:3, 3] - pose[:3, 3])) * 1e3


def _start(robot: str, kind: str, rng: np.random.Generator, chain: Chain) -> np.ndarray:
    nominal = PANDA_READY if robot == 'panda' else UR_HOME
    q = nominal + rng.uniform(-0.35, 0.35, nominal.size)
    if kind == 'stretch':  # folded enough to walk out 0.1-0.4 m to the end of the reach
        if robot == 'panda':
            q[1], q[3] = rng.uniform(-0.3, 0.4), rng.uniform(-2.4, -1.9)
        else:
            q[1], q[2] = rng.uniform(-1.4, -1.0), rng.uniform(0.9, 1.2)
    elif kind == 'wrist':
        q[4] = rng.choice([-1.0, 1.0]) * rng.uniform(0.03, 0.08)
    return np.clip(q, chain.lower + 0.05, chain.upper - 0.05)


def _outward(chain: Chain, robot: str, q: np.ndarray) -> np.ndarray:
    offset = chain.forward(q)[:3, 3] - chain.frame_pose(SHOULDER[robot], q)[:3, 3]
    return offset / np.linalg.norm(offset)


def _overhead(chain: Chain, rng: np.random.Generator, shape: str
              ) -> tuple[np.ndarray, ToolPath] | None:
    """
    Return a start and a path of the tool (pointing down) passing by joint 1's axis.

    A line along y that passes 1-6 cm from the axis at 0.55-0.75 m high, or a horizontal
    arc of 8-15 cm radius about a centre within 3 cm of the axis.
    """
    down, height = chain.forward(PANDA_READY), rng.uniform(0.55, 0.75)
    if shape == 'line':
        length = rng.uniform(*LENGTHS)
        side = np.array([0.0, 1.0, 0.0])
        middle = np.array([rng.uniform(0.01, 0.06), 0.0, height])
        points = [middle - 0.5 * length * side, middle + 0.5 * length * side]
    else:
        radius, centre = rng.uniform(0.08, 0.15), np.array([rng.uniform(0.0, 0.03), 0.0,
                                                            height])
        angle = rng.uniform(math.pi / 3, 5 * math.pi / 6)
        points = [centre + radius * np.array([math.cos(phi), math.sin(phi), 0.0])
                  for phi in (-angle / 2, 0.0, angle / 2)]
    poses = [_turned(down, np.eye(3), point) for point in points]
    q = _reachable(chain, poses[0], PANDA_READY)
    if q is None or any(_reachable(chain, pose, q) is None for pose in poses[1:]):
        return None
    start = chain.forward(q)
    if shape == 'line':
        return q, straight_path(start, [poses[1]])
    return q, circular_path(start, points[1], poses[2])


def _line(robot: str, kind: str, rng: np.random.Generator, chain: Chain,
          q: np.ndarray) -> ToolPath | None:
    start = chain.forward(q)
    if kind == 'stretch':
        direction = _outward(chain, robot, q)
        length = _reach(chain, q, start, direction) - rng.uniform(0.005, 0.02)
        turn = np.eye(3)
    else:
        direction, length = _unit(rng), rng.uniform(*LENGTHS)
        angle = rng.uniform(0.0, 0.4) if kind == 'away' else 0.0
        turn = rotation_exp(angle * _unit(rng)[None])[0]
    if not LENGTHS[0] <= length <= LENGTHS[1]:
        return None
    goal = _turned(start, turn, start[:3, 3] + length * direction)
    if kind != 'stretch' and _reachable(chain, goal, q) is None:
        return None
    return straight_path(start, [goal])


def _arc(robot: str, kind: str, rng: np.random.Generator, chain: Chain,
         q: np.ndarray) -> ToolPath | None:
    """Return an arc through the start: centre ``r`` away, turning ``φ`` (``rφ`` in range)."""
    start = chain.forward(q)
    radius, angle = rng.uniform(0.08, 0.2), rng.uniform(math.pi / 3, math.pi)
    first, second = _unit(rng), _unit(rng)
    if kind == 'stretch':  # the circle's plane holds the outward direction: it bulges out
        second = _outward(chain, robot, q)
    second = second - (second @ first) * first
    second /= np.linalg.norm(second)
    centre = start[:3, 3] + radius * first

    def point(phi: float) -> np.ndarray:
        return centre - radius * (math.cos(phi) * first - math.sin(phi) * second)

    if not LENGTHS[0] <= radius * angle <= LENGTHS[1]:
        return None
    turn = rotation_exp(rng.uniform(0.0, 0.4) * _unit(rng)[None])[0] if kind == 'away' \
        else np.eye(3)
    interim, goal = point(angle / 2.0), _turned(start, turn, point(angle))
    if kind == 'stretch':  # move the circle out until the interim point is near the reach
        middle = _reachable(chain, _turned(start, np.eye(3), interim), q)
        if middle is None:
            return None
        reach = _reach(chain, middle, _turned(start, np.eye(3), interim), second)
        interim = interim + (reach - rng.uniform(0.005, 0.02)) * second
    for target in (_turned(start, np.eye(3), interim), goal):
        if _reachable(chain, target, q) is None:
            return None
    return circular_path(start, interim, goal)


def cases(chains: dict[str, Chain]) -> list[Case]:
    """Return the 30 lines and arcs of :data:`PLAN`, drawn from :data:`SEED` (retried)."""
    rng = np.random.default_rng(SEED)
    found = []
    for robot, plan in PLAN.items():
        chain = chains[robot]
        for index, (kind, shape) in enumerate(plan):
            for _ in range(200):
                if kind == 'overhead':
                    q, path = _overhead(chain, rng, shape) or (None, None)
                else:
                    q = _start(robot, kind, rng, chain)
                    path = (_line if shape == 'line' else _arc)(robot, kind, rng, chain, q)
                case = Case(f'{robot}-{shape}{index + 1:02d}', robot, kind, shape, q, path) \
                    if path is not None else None
                if case is not None and LENGTHS[0] <= case.translation <= LENGTHS[1]:
                    break
            else:
                raise RuntimeError(f'no {kind} {shape} found for {robot}')
            found.append(case)
    return found
