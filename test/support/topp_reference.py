"""
An independent time-optimal timing of a path: the phase plane on 10,000+ points.

The oracle (sharing nothing with the package's timing) is the classical method (Bobrow,
Dubowsky & Gibson 1985; Shin & McKay 1985) in its numerical form: the maximum-velocity
curve ``x_mvc(s)`` (velocity limits, and where the acceleration limits leave no ``s̈``:
bisection), then forward integration at the largest ``s̈`` and backward integration at
the smallest, each capped by the curve, the profile their minimum. The constraints are
taken at single points from the joints' ``q(s)`` and the tool's exact acceleration norm
(an ellipse in ``(s̈, ṡ²)``), explicit Euler in ``x = ṡ²``.
"""

import math

import numpy as np

POINTS = 10_000


def _u_range(dq, ddq, amax, tool, x):
    """Smallest and largest s̈ at ṡ² = x at one point (Python floats)."""
    lo, hi = -math.inf, math.inf
    for rate, bend, limit in zip(dq, ddq, amax, strict=True):
        if rate != 0.0:
            one, two = (limit - bend * x) / rate, (-limit - bend * x) / rate
            lo, hi = max(lo, min(one, two)), min(hi, max(one, two))
    if tool is not None:
        aa, ab, cross, limit = tool
        disc = aa * limit ** 2 - cross ** 2 * x ** 2
        if disc < -1e-9 * aa * limit ** 2:
            return math.inf, -math.inf
        disc = max(disc, 0.0)  # on the curve itself, rounding must not make it infeasible
        root = math.sqrt(disc)
        lo, hi = max(lo, (-ab * x - root) / aa), min(hi, (-ab * x + root) / aa)
    return lo, hi


def reference_duration(path, states, vmax, amax, tool, points=POINTS):
    """
    Return the time-optimal duration (s) of ``path`` whose joints ``states(s)`` give.

    ``states(s)`` returns ``(q, dq/ds, d²q/ds²)``, ``(n, joints)`` each; ``tool`` has
    ``max_linear_velocity``, ``max_linear_acceleration``, ``max_angular_velocity``.
    """
    s = np.union1d(np.linspace(0.0, path.length, points + 1), path.knots)
    _, dq, ddq = states(s)
    count = dq.shape[1]
    vmax, amax = np.broadcast_to(vmax, (count,)), np.broadcast_to(amax, (count,))
    sides = {}
    for side in ('right', 'left'):
        sample = path.sample(s, side)
        rate, bend = sample.velocity, sample.acceleration
        terms = np.stack([(rate * rate).sum(1), (rate * bend).sum(1),
                          np.linalg.norm(np.cross(rate, bend), axis=1)], axis=1)
        with np.errstate(divide='ignore'):
            speed = np.minimum(np.min((vmax / np.abs(dq)) ** 2, axis=1),
                               (tool.max_linear_velocity / np.linalg.norm(rate, axis=1)) ** 2)
            speed = np.minimum(speed, (tool.max_angular_velocity
                                       / np.linalg.norm(sample.angular, axis=1)) ** 2)
        sides[side] = (terms, speed)
    finite_tool = math.isfinite(tool.max_linear_acceleration)
    dq_list, ddq_list, amax_list = dq.tolist(), ddq.tolist(), amax.tolist()

    def tool_terms(side, k):
        if not finite_tool:
            return None
        aa, ab, cross = sides[side][0][k].tolist()
        return aa, ab, cross, tool.max_linear_acceleration

    def feasible(side, x):  # every point at once: U_lo(x) <= U_hi(x)
        with np.errstate(divide='ignore', invalid='ignore'):
            one, two = (amax - ddq * x[:, None]) / dq, (-amax - ddq * x[:, None]) / dq
            hi = np.where(dq != 0.0, np.maximum(one, two), np.inf).min(axis=1)
            lo = np.where(dq != 0.0, np.minimum(one, two), -np.inf).max(axis=1)
        if finite_tool:
            aa, ab, cross = sides[side][0].T
            disc = aa * tool.max_linear_acceleration ** 2 - cross ** 2 * x ** 2
            root = np.sqrt(np.maximum(disc, 0.0))
            hi = np.where(disc < 0.0, -np.inf, np.minimum(hi, (-ab * x + root) / aa))
            lo = np.maximum(lo, (-ab * x - root) / aa)
        return lo <= hi

    mvc = np.minimum(np.minimum(sides['right'][1], sides['left'][1]), 1e4)
    for side in ('right', 'left'):
        low, top = np.zeros_like(mvc), mvc.copy()
        for _ in range(60):
            mid = 0.5 * (low + top)
            good = feasible(side, mid)
            low, top = np.where(good, mid, low), np.where(good, top, mid)
        mvc = np.where(feasible(side, mvc), mvc, low)
    mvc = mvc.tolist()
    for k in np.flatnonzero(np.isin(s, path.stops)):
        mvc[k] = 0.0
    h = np.diff(s).tolist()
    forward = [0.0] * len(s)
    for k, step in enumerate(h):
        _, hi = _u_range(dq_list[k], ddq_list[k], amax_list, tool_terms('right', k), forward[k])
        forward[k + 1] = max(min(mvc[k + 1], forward[k] + 2.0 * step * hi), 0.0)
    backward = [0.0] * len(s)
    for k in range(len(h) - 1, -1, -1):
        lo, _ = _u_range(dq_list[k + 1], ddq_list[k + 1], amax_list,
                         tool_terms('left', k + 1), backward[k + 1])
        backward[k] = max(min(mvc[k], backward[k + 1] - 2.0 * h[k] * lo), 0.0)
    speed = np.sqrt(np.minimum(forward, backward))
    return float(np.sum(2.0 * np.diff(s) / (speed[:-1] + speed[1:])))
