"""
The blend of a corner between two straight segments: a tangent arc, C¹ in ``s``.

The corner is at ``s_k`` (its pose ``p_c``, ``R_c``); the segment before it moves
``u1`` (unit) at ``v1 = L1 / S1`` metres and ``ω1`` rad per unit of path, the one after it
``u2``, ``v2``, ``ω2`` (both constant along a segment, :mod:`.tool_path`). With the blend
radius ``r`` the blend starts and ends ``d = min(r, L1/2, L2/2)`` metres from the corner
along each segment, at ``B1 = p_c − d u1`` and ``B2 = p_c + d u2``, and it takes the ``s``
of the corner it cuts away: ``d1 = d / v1`` before ``s_k`` and ``d2 = d / v2`` after it,
``D = d1 + d2``; ``σ = (s − s_k + d1) / D`` runs from 0 to 1 and ``t = s − s_k``.

Position: the circle tangent to both segments at ``B1`` and ``B2``: for the turn
``β = ∠(u1, u2)`` its curvature is ``κ = tan(β/2) / d`` and its length ``Λ = β / κ``
(``2d`` on a straight corner, ``κ = 0``). By its arc length ``λ`` from ``B1``, with
``φ = κλ`` and ``n⊥`` the unit normal towards the turn,
``p = B1 + λ (sin φ/φ · u1 + (1 − cos φ)/φ · n⊥)``, tangent ``T = cos φ u1 + sin φ n⊥``,
``dT/dλ = κ (−sin φ u1 + cos φ n⊥)``. ``λ(σ)`` must leave and meet the segments at their
speeds, ``dλ/dσ = m0 = v1 D`` at 0 and ``m1 = v2 D`` at 1, cover ``Λ`` and never turn
back. It is the polynomial whose derivative has the Bernstein coefficients
``(m0, c, …, c, m1)`` of degree ``n``:
``λ' = m0 (1−σ)ⁿ + m1 σⁿ + c (1 − (1−σ)ⁿ − σⁿ)``, ``c = ((n+1)Λ − m0 − m1) / (n − 1)``,
with the least ``n >= 2`` that makes ``c >= 0``: then ``λ' > 0`` throughout
(``m0 (1−σ)ⁿ + m1 σⁿ > 0`` and the rest is not negative). ``n = 2`` is the cubic
Hermite; a sharp corner, whose arc is short beside ``D``, needs a higher ``n`` (its speed
along the arc dips in the middle). Beyond :data:`MAX_DEGREE` the corner is not blended. So
``dp/ds = T λ'/D`` and ``d²p/ds² = κ N (λ'/D)² + T λ''/D²``; ``dp/ds`` is continuous at
both ends, ``d²p/ds²`` steps there (the arc's curvature, and ``λ''``).

Orientation: both segments' slerps pass through ``R_c`` at ``s_k`` and are there
``R_i(s) = exp(t ω_i) R_c`` (extended past their ends); the blend turns at the blended
rate, ``R = exp(t g(σ)) R_c``, ``g = (1 − w) ω1 + w ω2``, with the quintic smoothstep
``w = 10σ³ − 15σ⁴ + 6σ⁵`` (``w' = w'' = 0`` at both ends). At the ends it is ``R_1`` and
``R_2`` with their rates and (zero) angular accelerations, so the orientation is C² in
``s``. It equals ``slerp(R_1(s), R_2(s), w)`` when ``ω1 ∥ ω2`` and differs from it by
``O(t²)`` otherwise. Rates by :func:`.rotations.exp_rates` with ``v = t g``,
``v' = g + t w'/D (ω2 − ω1)``, ``v'' = (2 w'/D + t w''/D²)(ω2 − ω1)``.

Within the blend ``s`` is this parameter, not the combined length of its curve (the arc is
shorter than the two legs it replaces). Units: m, rad, per unit of path.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
import math

import numpy as np
from traj_gen_ros.core.cartesian.rotations import exp_rates, rodrigues_coefficients, rotation_exp

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
    One corner's blend (module formulas).

    :ivar corner_s: ``s_k``, the corner's ``s`` on the unblended path.
    :ivar start: ``s_k − d1``, where the blend leaves the first segment.
    :ivar span: ``D = d1 + d2``.
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

    corner_s: float
    start: float
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

    @property
    def end(self) -> float:
        """Return ``s_k + d2``, where the blend joins the second segment."""
        return self.start + self.span


def corner_blend(corner_s: float, position: np.ndarray, rotation: np.ndarray,
                 before: Leg, after: Leg, radius: float) -> CornerBlend | None:
    """
    Return the blend of the corner at ``position``/``rotation`` (``s = corner_s``), or None.

    None when the corner turns back (within :data:`REVERSAL_ANGLE` of π) or so sharply,
    for its speeds, that ``dλ/dσ`` would need a degree above :data:`MAX_DEGREE`. Both legs
    must translate (``L > 0``) and ``radius`` (m) be positive.
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
    before_s, after_s = distance / before.speed, distance / after.speed
    span = before_s + after_s
    first, last = before.speed * span, after.speed * span
    degree = max(2, math.ceil((first + last) / arc - 1.0 - 1e-12))
    if degree > MAX_DEGREE:
        return None
    middle = max(((degree + 1) * arc - first - last) / (degree - 1), 0.0)
    return CornerBlend(
        float(corner_s), float(corner_s - before_s), span, distance,
        np.asarray(position, dtype=float) - distance * u1, np.asarray(u1, dtype=float),
        inward, curvature, degree, (first, middle, last), np.asarray(rotation, dtype=float),
        np.array([before.rate, after.rate], dtype=float))


class CornerBlends:
    """Several corners' blends, stacked, sampled together."""

    def __init__(self, blends: Sequence[CornerBlend]) -> None:
        self.blends = tuple(blends)

        def stack(name: str) -> np.ndarray:
            return np.array([getattr(blend, name) for blend in self.blends], dtype=float)

        self._corner_s, self._start, self._span = (stack(name) for name in (
            'corner_s', 'start', 'span'))
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
        t = (s - self._corner_s[rows])[:, None]
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
        # Orientation: exp(t g(σ)) R_c, g blending the two segments' rates.
        w = sigma ** 3 * (10.0 + sigma * (-15.0 + 6.0 * sigma))
        w_rate = 30.0 * (sigma * rest) ** 2 / span
        w_rate_rate = 60.0 * sigma * rest * (1.0 - 2.0 * sigma) / span ** 2
        rate_before, change = self._rates[rows, 0], self._rates[rows, 1] - self._rates[rows, 0]
        blended = rate_before + w * change
        vector = t * blended
        vector_rate = blended + t * w_rate * change
        vector_rate_rate = (2.0 * w_rate + t * w_rate_rate) * change
        angular, angular_acceleration = exp_rates(vector, vector_rate, vector_rate_rate)
        rotation = rotation_exp(vector) @ self._rotation[rows]
        return position, rotation, velocity, acceleration, angular, angular_acceleration
