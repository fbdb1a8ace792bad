"""
The blend of a corner between two straight segments: a tangent arc, C¹ in ``s``.

The corner's pose is ``p_c``, ``R_c``; the segment before it moves ``u1`` (unit) at
``v1 = L1 / S1`` metres and ``ω1`` rad per unit of path, the one after it ``u2``, ``v2``,
``ω2`` (both constant along a segment, :mod:`.tool_path`; ``v² + (ℓ|ω|)² = 1``,
``ℓ`` = :data:`.samples.ROTATION_LENGTH`). With the blend radius ``r`` the blend starts and
ends ``d = min(r, L1/2, L2/2)`` metres from the corner along each segment, at
``B1 = p_c − d u1`` and ``B2 = p_c + d u2``: it cuts away the last ``d1 = d / v1`` of the
first segment's ``s`` and the first ``d2 = d / v2`` of the second's, ``D = d1 + d2``.

Its own ``s``-range is its combined length (:mod:`.samples`): ``Δ = √(Λ² + (ℓΘ)²)``,
``Λ`` the arc's length and ``Θ = d1|ω1| + d2|ω2|`` the rotation of the two legs it cuts
(not the angle between its ends' orientations: the orientation may turn one way and back
across a blend); the pieces after it move up by ``D − Δ``. ``Δ <= D`` (the arc is no
longer than the legs, ``Λ <= 2d = v1 d1 + v2 d2``, and Minkowski's inequality), and
``Δ = Λ`` when the tool does not turn. ``σ = (s − s_b) / Δ`` runs from 0 to 1 across it
(``s_b`` its first ``s``).

Position: the circle tangent to both segments at ``B1`` and ``B2``: for the turn
``β = ∠(u1, u2)`` its curvature is ``κ = tan(β/2) / d`` and its length ``Λ = β / κ``
(``2d`` on a straight corner, ``κ = 0``). By its arc length ``λ`` from ``B1``, with
``φ = κλ`` and ``n⊥`` the unit normal towards the turn,
``p = B1 + λ (sin φ/φ · u1 + (1 − cos φ)/φ · n⊥)``, tangent ``T = cos φ u1 + sin φ n⊥``,
``dT/dλ = κ (−sin φ u1 + cos φ n⊥)``. ``λ(σ)`` must leave and meet the segments at their
speeds, ``dλ/dσ = m0 = v1 Δ`` at 0 and ``m1 = v2 Δ`` at 1, cover ``Λ`` and never turn
back. It is the polynomial whose derivative has the Bernstein coefficients
``(m0, c, …, c, m1)`` of degree ``n``:
``λ' = m0 (1−σ)ⁿ + m1 σⁿ + c (1 − (1−σ)ⁿ − σⁿ)``, ``c = ((n+1)Λ − m0 − m1) / (n − 1)``,
with the least ``n >= 2`` that puts ``c`` within a factor 2 of the mean ``Λ``
(``Λ/2 <= c <= 2Λ``: ``n >= 2(m0 + m1)/Λ − 3`` and ``n >= 3 − (m0 + m1)/Λ``). A
Bernstein polynomial lies between its least and greatest coefficients, so ``λ' > 0`` and
``|dp/ds| = λ'/Δ`` stays between ``min(v1, v2, Λ/2Δ)`` and ``max(v1, v2, 2Λ/Δ)``. Without
rotation ``m0 = m1 = Λ``, so ``n = 2``, ``λ' = Λ`` and ``|dp/ds| = 1`` all along (``s`` is
the arc length, at any turn); where the tool turns much while its arc is short the tool
point slows in the middle (the orientation takes over) and ``n`` grows. Beyond
:data:`MAX_DEGREE` the corner is not blended. So ``dp/ds = T λ'/Δ`` and
``d²p/ds² = κ N (λ'/Δ)² + T λ''/Δ²``; ``dp/ds`` is continuous at both ends, ``d²p/ds²``
steps there (the arc's curvature, and ``λ''``).

Orientation: both segments' slerps pass through ``R_c`` at the corner and are there
``R_i(t) = exp(t ω_i) R_c``, ``t`` the unblended path's ``s`` from the corner (extended
past their ends). The blend maps its fraction to that ``t`` and turns at the blended rate,
``R = exp(t(σ) g(σ)) R_c``, ``t(σ) = −d1 + Δσ + (D − Δ) w``, ``g = (1 − w) ω1 + w ω2``,
with the quintic smoothstep ``w = 10σ³ − 15σ⁴ + 6σ⁵`` (``w' = w'' = 0`` at both ends): so
``t`` runs from ``−d1`` to ``d2``, ``dt/ds = 1 + (D/Δ − 1) w' >= 1`` is 1 at both ends and
``d²t/ds²`` 0 there, and at the ends ``R`` is ``R_1`` and ``R_2`` with their rates and
(zero) angular accelerations: the orientation is C² in ``s``. It equals
``slerp(R_1(t), R_2(t), w)`` when ``ω1 ∥ ω2`` and differs from it by ``O(t²)`` otherwise.
Rates by :func:`.rotations.exp_rates` with ``v = t g``, ``v' = t' g + t g'``,
``v'' = t'' g + 2 t' g' + t g''`` (``'`` by ``s``: ``w'/Δ``, ``w''/Δ²`` for ``w``'s).

Units: m, rad, per unit of path.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core.cartesian.rotations import (
    exp_rates,
    rodrigues_coefficients,
    rotation_exp,
)
from traj_gen_ros.core.cartesian.samples import ROTATION_LENGTH

#: The highest degree of ``dλ/dσ`` a blend may take; a sharper corner is not blended.
MAX_DEGREE = 12
#: A turn within this of π (rad) is a reversal: never blended.
REVERSAL_ANGLE = 1e-6


@dataclass(frozen=True)
class Leg:
    """
    One segment as its corner's blend sees it.

    :ivar direction: ``(3,)`` unit direction of its translation.
    :ivar length: its translation ``L``, m.
    :ivar speed: ``v = L / S``, m per unit of path.
    :ivar rate: ``(3,)`` ``ω``, rad per unit of path.
    """

    direction: np.ndarray
    length: float
    speed: float
    rate: np.ndarray


@dataclass(frozen=True)
class CornerBlend:
    """
    One corner's blend (module formulas), wherever on the path it starts.

    :ivar cut: ``(d1, d2)``: the ``s`` it cuts from the segment before and after the corner.
    :ivar span: ``Δ``, its own ``s``-range: its combined length.
    :ivar distance: ``d``, m from the corner along each segment.
    :ivar entry: ``(3,)`` ``B1``, m.
    :ivar direction: ``(3,)`` ``u1``.
    :ivar inward: ``(3,)`` ``n⊥``, unit (zero on a straight corner).
    :ivar curvature: ``κ``, 1/m.
    :ivar degree: ``n`` of ``dλ/dσ``.
    :ivar speeds: ``(m0, c, m1)``, m per unit of ``σ``.
    :ivar rotation: ``(3, 3)`` ``R_c``.
    :ivar rates: ``(2, 3)`` ``ω1``, ``ω2``.
    """

    cut: tuple[float, float]
    span: float
    distance: float
    entry: np.ndarray
    direction: np.ndarray
    inward: np.ndarray
    curvature: float
    degree: int
    speeds: tuple[float, float, float]
    rotation: np.ndarray
    rates: np.ndarray


def corner_blend(position: np.ndarray, rotation: np.ndarray, before: Leg, after: Leg,
                 radius: float) -> CornerBlend | None:
    """
    Return the blend of the corner at ``position``/``rotation``, or None.

    None when the corner turns back (within :data:`REVERSAL_ANGLE` of π) or so sharply,
    for how much the tool turns across it, that ``dλ/dσ`` would need a degree above
    :data:`MAX_DEGREE`. Both legs must translate (``L > 0``) and ``radius`` (m) be positive.
    """
    u1, u2 = before.direction, after.direction
    turn = math.atan2(float(np.linalg.norm(np.cross(u1, u2))), float(u1 @ u2))
    if turn > math.pi - REVERSAL_ANGLE:
        return None
    distance = min(radius, before.length / 2.0, after.length / 2.0)
    inward = u2 - (u1 @ u2) * u1
    sine = float(np.linalg.norm(inward))
    if sine < 1e-12:
        inward, curvature, arc = np.zeros(3), 0.0, 2.0 * distance
    else:
        inward = inward / sine
        curvature = math.tan(turn / 2.0) / distance
        arc = turn / curvature
    cut = (distance / before.speed, distance / after.speed)
    rates = np.array([before.rate, after.rate], dtype=float)
    turned = cut[0] * float(np.linalg.norm(rates[0])) + cut[1] * float(np.linalg.norm(rates[1]))
    span = math.hypot(arc, ROTATION_LENGTH * turned)
    first, last = before.speed * span, after.speed * span
    ratio = (first + last) / arc
    degree = max(2, math.ceil(2.0 * ratio - 3.0 - 1e-9), math.ceil(3.0 - ratio - 1e-9))
    if degree > MAX_DEGREE:
        return None
    middle = max(((degree + 1) * arc - first - last) / (degree - 1), 0.0)
    return CornerBlend(
        cut, span, distance, np.asarray(position, dtype=float) - distance * u1,
        np.asarray(u1, dtype=float), inward, curvature, degree, (first, middle, last),
        np.asarray(rotation, dtype=float), rates)


class CornerBlends:
    """Several corners' blends, each from its first ``s``, stacked, sampled together."""

    def __init__(self, blends: Sequence[CornerBlend], starts: Sequence[float]) -> None:
        self.blends = tuple(blends)

        def stack(name: str) -> np.ndarray:
            return np.array([getattr(blend, name) for blend in self.blends], dtype=float)

        self._start = np.array(starts, dtype=float)
        self._cut, self._span = stack('cut').reshape(-1, 2), stack('span')
        self._entry, self._direction, self._inward = (stack(name) for name in (
            'entry', 'direction', 'inward'))
        self._curvature, self._degree, self._speeds = (stack(name) for name in (
            'curvature', 'degree', 'speeds'))
        self._rotation, self._rates = stack('rotation'), stack('rates')

    def sample(self, rows: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, ...]:
        """
        Return position, rotation, dp/ds, d²p/ds², ω_s, dω_s/ds at ``s`` of blends ``rows``.

        ``rows`` and ``s`` are ``(n,)``; the arrays ``(n, 3)`` (rotation ``(n, 3, 3)``).
        """
        span = self._span[rows][:, None]
        sigma = np.clip((s - self._start[rows]) / self._span[rows], 0.0, 1.0)[:, None]
        # Position: λ(σ) along the tangent arc.
        n = self._degree[rows][:, None]
        first, middle, last = (self._speeds[rows, i][:, None] for i in range(3))
        rest = 1.0 - sigma
        rest_n, sigma_n = rest ** n, sigma ** n
        arc = ((first - middle) * (1.0 - rest_n * rest) + (last - middle) * sigma_n * sigma
               ) / (n + 1.0) + middle * sigma
        arc_rate = first * rest_n + last * sigma_n + middle * (1.0 - rest_n - sigma_n)
        arc_rate_rate = n * ((middle - first) * rest ** (n - 1.0)
                             + (last - middle) * sigma ** (n - 1.0))
        curvature = self._curvature[rows][:, None]
        angle = curvature * arc
        sinc, versine = rodrigues_coefficients(angle[:, 0])[:2, :, None]
        u, inward = self._direction[rows], self._inward[rows]
        position = self._entry[rows] + arc * (sinc * u + angle * versine * inward)
        tangent = np.cos(angle) * u + np.sin(angle) * inward
        normal = np.cos(angle) * inward - np.sin(angle) * u
        speed = arc_rate / span
        velocity = tangent * speed
        acceleration = curvature * speed ** 2 * normal + tangent * (arc_rate_rate / span ** 2)
        # Orientation: exp(t(σ) g(σ)) R_c, g blending the two segments' rates.
        w = sigma ** 3 * (10.0 + sigma * (-15.0 + 6.0 * sigma))
        w_rate = 30.0 * (sigma * rest) ** 2 / span
        w_rate_rate = 60.0 * sigma * rest * (1.0 - 2.0 * sigma) / span ** 2
        lead, cut = self._cut[rows, :1], self._cut[rows].sum(axis=1)[:, None]
        t = span * sigma - lead + (cut - span) * w
        t_rate = 1.0 + (cut - span) * w_rate
        t_rate_rate = (cut - span) * w_rate_rate
        rate_before, change = self._rates[rows, 0], self._rates[rows, 1] - self._rates[rows, 0]
        blended = rate_before + w * change
        vector = t * blended
        vector_rate = t_rate * blended + t * w_rate * change
        vector_rate_rate = (t_rate_rate * blended
                            + (2.0 * t_rate * w_rate + t * w_rate_rate) * change)
        angular, angular_acceleration = exp_rates(vector, vector_rate, vector_rate_rate)
        rotation = rotation_exp(vector) @ self._rotation[rows]
        return position, rotation, velocity, acceleration, angular, angular_acceleration
