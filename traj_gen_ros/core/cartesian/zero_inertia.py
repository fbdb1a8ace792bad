"""
The timing grid cut finer around zero-inertia points, where the discrete timing dents.

A joint's acceleration along the path is ``q̈ = q' s̈ + q'' ṡ²``. Where ``q'`` passes
zero (a *zero-inertia point*; Shiller & Lu, ASME J. Mech. Des. 114(1), 1992) its limit
bounds ``ṡ²`` alone, ``ṡ² <= a / |q''|``, and the time-optimal ``s̈`` passes it smoothly.
The timing holds every limit at both ends of each interval with ``s̈`` constant between
(:mod:`.path_constraints`). In the squared speeds ``(x_i, x_{i+1})`` a row ``q' u + q''
x <= a`` at an interval's start reads ``(q'' - q'/2Δ) x_i + (q'/2Δ) x_{i+1} <= a`` (its
mirror at the end): both coefficients are positive, so raising one point's speed lowers
the other's, exactly where the *gain* ``2Δ |q''| / |q'|`` exceeds 1, within about two
intervals of the zero. Everywhere else the set of feasible profiles is closed under the
pointwise maximum, and the greedy pass of :mod:`.reachability` gives the largest ``ṡ²``
at every point, the discrete optimum; here it is not, and neither the greedy profile
nor the discrete optimum (a linear program over the same rows, weighting each point's
``ṡ²`` by its share of the time, dents alike) is smooth: on
the Panda's 5 cm blend of docs/cli.md (erd-panda to panda_hand_tcp) ``s̈`` went 3.21,
2.67, 3.62, 3.62, 3.80, 3.80 (per unit of path and s²) where a grid ten times finer
gives 3.22 … 3.29, 3.35, 3.40 smoothly, and panda_joint2's acceleration jumped by 0.8
rad/s² for one interval and back while panda_joint7 held its limit. Whether it happens
depends on where the zero falls in its interval: on 7 of 13 grids 3 % coarser to 3 %
finer than the default.

:func:`refine` cuts each interval where a joint's gain reaches :data:`GAIN` at either
end into :data:`SPLIT` equal parts, if that joint's limit can bind there (``|q''|`` times
the largest ``ṡ²`` the velocity limits allow reaches :data:`BIND` of its acceleration
limit: a joint that barely bends is left alone). The intervals left as they were all
have a gain below :data:`GAIN`, and the region of gain above 1 shrinks
:data:`SPLIT`-fold about the zero; the pinched steps of ``s̈`` it leaves are as many
times shorter and, measured, much smaller. On that blend the largest excursion of a
joint's acceleration beyond both neighbouring intervals' falls from 0.33-0.41 of the
limit (on the 7 grids) to at most 0.013 on all 13, the total variation of ``s̈`` from
28.5 to 27.4 (27.5 on a grid twice as fine). It costs a few intervals per zero that can
bind (962 → 1,109 on that path, 601 → 739 on the arc of docs/cli.md, none on a straight
0.3 m line of the Panda) and the time to sample them again; the durations only shorten
(measured: by 4e-6 relative there, up to 4e-4 on the synthetic paths of the tests). Cutting the
whole grid as fine would cost ``SPLIT`` times the intervals; a pass smoothing ``s̈`` after
the greedy one would trade the exactness of its rows for a heuristic.
"""

from __future__ import annotations

import numpy as np

#: Parts each interval near a zero-inertia point is cut into.
SPLIT = 4
#: ``2Δ |q''| / |q'|`` at either end of an interval from which it is cut.
GAIN = 0.5
#: ``|q''| ṡ²_max / a`` from which a joint's limit counts as able to bind at a point.
BIND = 0.25


def refine(s: np.ndarray, rates: np.ndarray, curvatures: np.ndarray, squared_speed: np.ndarray,
           max_acceleration: np.ndarray) -> np.ndarray:
    """
    Return the grid ``s`` with the intervals near a zero-inertia point cut finer.

    :param s: ``(n + 1,)`` the grid, ascending (every point stays).
    :param rates: ``(2, n, joints)`` ``dq/ds`` at each interval's start and end (the
        sides of the interval), rad per unit of path.
    :param curvatures: ``(2, n, joints)`` ``d²q/ds²`` there.
    :param squared_speed: ``(n + 1,)`` the largest ``ṡ²`` the velocity limits allow at
        each point (:func:`.path_constraints.speed_bounds`).
    :param max_acceleration: ``(joints,)`` rad/s².
    """
    delta = np.diff(s)
    size = np.abs(rates)
    bend = np.abs(curvatures)
    ends = np.stack([squared_speed[:-1], squared_speed[1:]])[..., None]  # (2, n, 1)
    near = 2.0 * delta[None, :, None] * bend >= GAIN * size
    with np.errstate(invalid='ignore'):  # inf · 0: a joint that does not bend
        binds = bend * ends >= BIND * max_acceleration
    cut = np.any(near & binds & (bend > 0.0), axis=(0, 2))
    if not cut.any():
        return s
    parts = np.where(cut, SPLIT, 1)
    starts = np.repeat(s[:-1], parts)
    steps = np.repeat(delta / parts, parts)
    offsets = np.arange(len(starts)) - np.repeat(np.cumsum(parts) - parts, parts)
    return np.concatenate([starts + offsets * steps, s[-1:]])
