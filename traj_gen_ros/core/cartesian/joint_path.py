"""
The joint path that follows an ideal tool path: :func:`follow`.

The joint path is the continuation of the inverse kinematics from the joint positions at
the start (:mod:`.continuation`): at grid points ``s_i`` (every knot of the path among
them) ``q_i`` is on the path pose, ``dq/ds = J⁺ x'`` and ``d²q/ds² = J⁺ (x'' − J̇q')``;
between them ``q(s)`` is the quintic Hermite interpolant of those states
(:func:`~traj_gen_ros.core.polynomial.quintic_hermite`, one per interval, each side's
derivatives at a knot), the grid chosen so that the tool stays within
:data:`~.continuation.TOLERANCE` of the ideal path. On a 7-joint arm it is the least
joint motion: every rate and correction is the minimum-norm one. A path that the joints
cannot follow is refused whole (:mod:`.path_checks`, :class:`~.path_refusal.PathRefusal`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from traj_gen_ros.core.cartesian.continuation import Continuation, pose_error, Run
from traj_gen_ros.core.cartesian.path_checks import PathChecks
from traj_gen_ros.core.cartesian.path_refusal import start_refusal
from traj_gen_ros.core.cartesian.samples import IdealPath, JointPath
from traj_gen_ros.core.polynomial import quintic_hermite
from traj_gen_ros.core.trajectory import Trajectory

#: How far (m, rad) ``q_start`` may put the tool from the path's start.
START_TOLERANCE = (1e-5, 1e-4)


def _limits(chain: Any, values: Sequence[float] | None, default: np.ndarray,
            what: str) -> np.ndarray:
    if values is None:
        return np.asarray(default, dtype=float)
    array = np.asarray(values, dtype=float)
    if array.shape != (len(chain.joints),) or np.isnan(array).any():
        raise ValueError(f'{what} limits must be {len(chain.joints)} numbers (rad or m, '
                         f'±inf: none), one per joint of {", ".join(chain.joints)}')
    return array


def _start(chain: Any, path: IdealPath, q_start: Sequence[float], lower: np.ndarray,
           upper: np.ndarray) -> np.ndarray:
    """Return ``q_start`` checked: one finite value per joint, in limits, on the start."""
    q = np.array(q_start, dtype=float).reshape(-1)
    if q.shape != (len(chain.joints),) or not np.isfinite(q).all():
        raise ValueError(f'q_start must be {len(chain.joints)} finite numbers, one per joint '
                         f'of {", ".join(chain.joints)}; got {q_start!r}')
    if float(path.length) <= 0.0:
        raise ValueError(f'the tool path has length {path.length}: it must be > 0')
    for joint in range(q.size):
        for side, bound, out in (('lower', lower[joint], q[joint] < lower[joint]),
                                 ('upper', upper[joint], q[joint] > upper[joint])):
            if out:
                raise start_refusal(chain.joints, chain.angular, joint, side, bound,
                                    float(path.length), q)
    start = path.sample(0.0, 'right')
    _, distance, angle = pose_error(start.rotation[0], start.position[0], chain.forward(q))
    if distance > START_TOLERANCE[0] or angle > START_TOLERANCE[1]:
        raise ValueError(
            f'q_start puts {chain.tool_frame!r} {distance * 1e3:.4g} mm and {angle * 1e3:.4g} '
            f'mrad from the start of the tool path: it must be within '
            f'{START_TOLERANCE[0] * 1e3:g} mm and {START_TOLERANCE[1] * 1e3:g} mrad (give the '
            'joint positions at the start pose, e.g. from the inverse kinematics)')
    return q


def joint_trajectory(run: Run) -> Trajectory | None:
    """Return ``q(s)`` over the grid points of ``run``: quintic pieces, None if there are none."""
    breakpoints, coefficients = [], []
    for span in run.spans:
        if len(span) < 2:
            continue
        s = np.array([point.s for point in span])
        curvature = np.array([point.curvature for point in span])
        piece = quintic_hermite(s, np.array([point.q for point in span]),
                                np.array([point.rate for point in span]),
                                curvature[:-1], curvature[1:])
        breakpoints.append(s if not breakpoints else s[1:])  # the knots exactly
        coefficients.append(piece.coefficients)
    if not coefficients:
        return None
    return Trajectory(np.concatenate(breakpoints), np.concatenate(coefficients))


def follow(chain: Any, path: IdealPath, q_start: Sequence[float], *,
           lower: Sequence[float] | None = None,
           upper: Sequence[float] | None = None) -> JointPath:
    """
    Return the joint path that moves ``chain``'s tool along ``path`` from ``q_start``.

    :param chain: a :class:`~traj_gen_ros.core.kinematics.chain.Chain`; the path is in its
        ``base_frame``, of its ``tool_frame``.
    :param path: the ideal tool path (:class:`~.samples.IdealPath`).
    :param q_start: ``(joints,)`` rad or m: where the joints are at the path's start; the
        tool must be there within :data:`START_TOLERANCE`.
    :param lower: lower joint limits ``(joints,)``; None: ``chain.lower``.
    :param upper: upper joint limits ``(joints,)``; None: ``chain.upper``.
    :return: the :class:`~.samples.JointPath`: ``q(s)`` with ``path``'s knots, stops and
        length.
    :raises PathRefusal: the joints cannot follow the path: a point out of reach, a joint
        limit, a singularity that needs more than 100 rad per unit of path, or a
        configuration flip (where, which joint, how much: see
        :class:`~.path_refusal.PathRefusal`), found on the whole path before any motion.
    :raises ValueError: ``q_start`` not one finite value per joint, not on the path's
        start (saying how far), or limits that are not one number per joint.
    """
    lower = _limits(chain, lower, chain.lower, 'lower')
    upper = _limits(chain, upper, chain.upper, 'upper')
    crossed = np.flatnonzero(lower > upper)
    if crossed.size:
        joint = int(crossed[0])
        raise ValueError(f'joint {chain.joints[joint]!r}: lower limit {lower[joint]:g} > upper '
                         f'limit {upper[joint]:g}')
    q = _start(chain, path, q_start, lower, upper)
    continuation = Continuation(chain, path, lower, upper)
    first = continuation.start(0.0, q, 'right')
    checks = PathChecks(continuation, lower, upper)
    if first is None:
        raise checks.unbounded_start(q)
    run = continuation.run(first)
    trajectory = joint_trajectory(run)
    refusal = checks.refusal(run, trajectory)
    if refusal is not None:
        raise refusal
    return JointPath(trajectory, np.asarray(path.knots, dtype=float).copy(),
                     np.asarray(path.stops, dtype=float).copy(), float(path.length))
