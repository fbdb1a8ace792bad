"""
The circle through three points, and the arc along it from the first through the second.

For points ``P0`` (start), ``P1`` (interim), ``P2`` (goal) and ``a = P0 − P2``,
``b = P1 − P2``, the circumcentre is (the vector form of the circumscribed circle's
centre, e.g. Wikipedia, "Circumcircle", "Higher dimensions")

    ``c = P2 + ((|a|² b − |b|² a) × (a × b)) / (2 |a × b|²)``,

the radius ``ρ = |P0 − c|`` and the plane's normal ``n = (a × b) / |a × b|``; the triangle
``P0 P1 P2`` turns positively about ``n``, so going round ``n`` from ``P0`` meets ``P1``
before ``P2``. In the plane's axes ``e1 = (P0 − c) / ρ``, ``e2 = n × e1`` the arc is
``p(φ) = c + ρ (cos φ e1 + sin φ e2)``, ``0 <= φ <= Φ``, ``Φ`` the angle of ``P2``
(``0 < Φ < 2π``), with ``dp/dφ = ρ (−sin φ e1 + cos φ e2)`` and
``d²p/dφ² = −ρ (cos φ e1 + sin φ e2)``.

Refused, as Pilz's CIRC is, when two of the points are within :data:`MIN_SEPARATION` or
the three lie on a line within :data:`MIN_OFFSET` (the triangle's smallest height,
``|a × b|`` over its longest side). Units: m, rad.
"""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

#: Two of the three points closer than this (m) leave the circle undetermined.
MIN_SEPARATION = 1e-3
#: Three points off one line by less than this (m: the triangle's smallest height) neither.
MIN_OFFSET = 1e-4
_NAMES = ('start', 'interim', 'goal')


@dataclass(frozen=True)
class Circle:
    """
    The arc from the start through the interim to the goal (module formulas).

    :ivar centre: ``(3,)`` m.
    :ivar radius: ``ρ``, m.
    :ivar first: ``(3,)`` ``e1``, unit, from the centre to the start.
    :ivar second: ``(3,)`` ``e2 = n × e1``, unit: the direction of travel at the start.
    :ivar normal: ``(3,)`` ``n``, unit: the arc turns positively about it.
    :ivar angle: ``Φ``, rad: the goal's angle, ``0 < Φ < 2π``.
    :ivar interim_angle: the interim's angle, rad, ``0 < φ1 < Φ``.
    """

    centre: np.ndarray
    radius: float
    first: np.ndarray
    second: np.ndarray
    normal: np.ndarray
    angle: float
    interim_angle: float

    @property
    def length(self) -> float:
        """Return the arc's length ``ρ Φ`` (m)."""
        return self.radius * self.angle

    def points(self, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return ``p``, ``dp/dφ``, ``d²p/dφ²`` at ``angles`` ``(n,)`` (rad), ``(n, 3)`` each."""
        angles = np.asarray(angles, dtype=float)[:, None]
        radial = np.cos(angles) * self.first + np.sin(angles) * self.second
        tangent = np.cos(angles) * self.second - np.sin(angles) * self.first
        return (self.centre + self.radius * radial, self.radius * tangent,
                -self.radius * radial)


def circle_through(start: np.ndarray, interim: np.ndarray, goal: np.ndarray) -> Circle:
    """
    Return the arc from ``start`` through ``interim`` to ``goal`` (``(3,)`` positions, m).

    :raises ValueError: two points within :data:`MIN_SEPARATION`, or all three on a line
        within :data:`MIN_OFFSET`, saying which and by how much.
    """
    points = [np.asarray(point, dtype=float) for point in (start, interim, goal)]
    sides = {}
    for i, j in ((0, 1), (1, 2), (0, 2)):
        sides[i, j] = float(np.linalg.norm(points[j] - points[i]))
        if sides[i, j] < MIN_SEPARATION:
            raise ValueError(
                f'circular path: the {_NAMES[i]} and {_NAMES[j]} positions are '
                f'{sides[i, j] * 1e3:.3g} mm apart; a circle needs its three points at '
                f'least {MIN_SEPARATION * 1e3:g} mm apart')
    a, b = points[0] - points[2], points[1] - points[2]
    normal = np.cross(a, b)
    twice_area = float(np.linalg.norm(normal))
    offset = twice_area / max(sides.values())
    if offset < MIN_OFFSET:
        raise ValueError(
            f'circular path: the start, interim and goal positions lie on one line within '
            f'{offset * 1e3:.3g} mm; a circle needs them at least {MIN_OFFSET * 1e3:g} mm '
            f'off a line')
    centre = points[2] + np.cross(a @ a * b - b @ b * a, normal) / (2.0 * twice_area ** 2)
    radius = float(np.linalg.norm(points[0] - centre))
    normal = normal / twice_area
    first = (points[0] - centre) / radius
    second = np.cross(normal, first)

    def angle_of(point: np.ndarray) -> float:
        offset = point - centre
        return math.atan2(float(offset @ second), float(offset @ first)) % (2.0 * math.pi)

    return Circle(centre, radius, first, second, normal, angle_of(points[2]),
                  angle_of(points[1]))
