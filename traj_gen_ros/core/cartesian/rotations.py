"""
Rotations as rotation vectors: SO(3)'s exponential and logarithm, slerp, and their rates.

A rotation vector ``v = θ n`` (rad, unit axis ``n``) stands for the rotation by ``θ`` about
``n``. With ``[v]×`` the cross-product matrix (``[v]× x = v × x``):

* exponential (Rodrigues): ``exp(v) = I + A [v]× + B [v]×²``, ``A = sin θ / θ``,
  ``B = (1 − cos θ) / θ²``;
* logarithm: the inverse with ``θ ∈ [0, π]``, read off the unit quaternion (Shepperd's
  method, accurate near 0 and π alike): ``θ = 2 atan2(|q_xyz|, q_w)``, ``n = q_xyz / |q_xyz|``;
* slerp (Shoemake, "Animating rotation with quaternion curves", SIGGRAPH 1985): from
  ``R0`` to ``R1`` by the fraction ``f``, ``R(f) = exp(f · log(R1 R0ᵀ)) R0``: the rotation
  at a constant rate about one fixed axis (in base axes), the shorter way round;
* the rates of ``R(s) = exp(v(s)) R0``: with ``dR/ds = [ω]× R``, ``ω = J(v) v'`` where
  ``J(v) = I + B [v]× + C [v]×²``, ``C = (θ − sin θ) / θ³``, is SO(3)'s left Jacobian
  (Chirikjian, *Stochastic Models, Information Theory, and Lie Groups* vol. 2, §10.6), so
  ``ω = v' + B v × v' + C v × (v × v')`` and, differentiating once more with
  ``dθ/ds = v·v' / θ``,
  ``ω' = v'' + B v × v'' + C (v' × (v × v') + v × (v × v''))
  + (v·v') (B̃ v × v' + C̃ v × (v × v'))``, ``B̃ = B'(θ) / θ``, ``C̃ = C'(θ) / θ``.

Below :data:`SERIES_ANGLE` the coefficients come from their Taylor series (the closed forms
cancel there). Units: rad; rates per whatever ``s`` is (per unit of path in this room).
"""

from __future__ import annotations

from math import factorial

import numpy as np

#: Below this angle (rad) the Rodrigues coefficients are summed from their series.
SERIES_ANGLE = 0.5
_TERMS = range(9)
# Series in x = θ²: A, B, C, B̃ = B'/θ, C̃ = C'/θ; e.g. A = Σ (−1)ᵏ xᵏ / (2k + 1)!.
_SERIES = np.array([
    [(-1) ** k / factorial(2 * k + 1) for k in _TERMS],
    [(-1) ** k / factorial(2 * k + 2) for k in _TERMS],
    [(-1) ** k / factorial(2 * k + 3) for k in _TERMS],
    [(-1) ** (k + 1) * 2 * (k + 1) / factorial(2 * k + 4) for k in _TERMS],
    [(-1) ** (k + 1) * 2 * (k + 1) / factorial(2 * k + 5) for k in _TERMS],
])


def rodrigues_coefficients(angle: np.ndarray, count: int = 5) -> np.ndarray:
    """
    Return ``(count, ...)``: the first of ``A, B, C, B̃, C̃`` at ``angle`` (rad, >= 0).

    ``A = sin θ/θ``, ``B = (1 − cos θ)/θ²``, ``C = (θ − sin θ)/θ³``,
    ``B̃ = (θ sin θ − 2(1 − cos θ))/θ⁴``, ``C̃ = (θ(1 − cos θ) − 3(θ − sin θ))/θ⁵``; each
    from its series (Horner in ``θ²``) below :data:`SERIES_ANGLE`, so finite and accurate
    at ``θ = 0``.
    """
    shape = np.shape(angle)
    angle = np.asarray(angle, dtype=float).reshape(-1)
    small = angle < SERIES_ANGLE
    theta = np.where(small, 1.0, angle)
    sine, versine, square = np.sin(theta), 1.0 - np.cos(theta), theta * theta
    closed = [lambda: sine / theta, lambda: versine / square,
              lambda: (theta - sine) / (theta * square),
              lambda: (theta * sine - 2.0 * versine) / (square * square),
              lambda: (theta * versine - 3.0 * (theta - sine)) / (theta * square * square)]
    coefficients = np.stack([closed[i]() for i in range(count)])
    if small.any():
        square = angle[small] ** 2
        series = np.zeros((count, square.size))
        for term in _SERIES[:count, ::-1].T:
            series = series * square + term[:, None]
        coefficients[:, small] = series
    return coefficients.reshape((count, *shape))


def cross(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Return ``first × second`` of ``(n, 3)`` arrays (np.cross without its axis handling)."""
    a0, a1, a2 = first[:, 0], first[:, 1], first[:, 2]
    b0, b1, b2 = second[:, 0], second[:, 1], second[:, 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=1)


def rotation_exp(vectors: np.ndarray) -> np.ndarray:
    """Return the rotations ``(..., 3, 3)`` of rotation vectors ``(..., 3)`` (Rodrigues)."""
    vectors = np.asarray(vectors, dtype=float)
    x, y, z = vectors[..., 0], vectors[..., 1], vectors[..., 2]
    angle = np.sqrt(x * x + y * y + z * z)
    a, b = rodrigues_coefficients(angle, 2)
    # I + A [v]× + B [v]×² = cos θ I + A [v]× + B v vᵀ, entry by entry.
    cos, ax, ay, az = np.cos(angle), a * x, a * y, a * z
    bxy, bxz, byz = b * x * y, b * x * z, b * y * z
    entries = [cos + b * x * x, bxy - az, bxz + ay, bxy + az, cos + b * y * y, byz - ax,
               bxz - ay, byz + ax, cos + b * z * z]
    return np.stack(entries, axis=-1).reshape((*angle.shape, 3, 3))


def rotation_log(rotation: np.ndarray) -> np.ndarray:
    """
    Return the rotation vector ``(3,)`` of one rotation matrix, its angle in ``[0, π]``.

    Through the unit quaternion, taken from the largest of the trace and the diagonal
    (Shepperd's method); at exactly π either axis direction is the same rotation, this
    one has its largest component positive.
    """
    r = np.asarray(rotation, dtype=float)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    choice = int(np.argmax([trace, r[0, 0], r[1, 1], r[2, 2]]))
    vee = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    if choice == 0:
        w = 0.5 * np.sqrt(max(1.0 + trace, 0.0))
        xyz = vee / (4.0 * w)
    else:
        i = choice - 1
        j, k = (i + 1) % 3, (i + 2) % 3
        xyz = np.zeros(3)
        xyz[i] = 0.5 * np.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 0.0))
        xyz[j] = (r[j, i] + r[i, j]) / (4.0 * xyz[i])
        xyz[k] = (r[k, i] + r[i, k]) / (4.0 * xyz[i])
        w = vee[i] / (4.0 * xyz[i])
        if w < 0.0:
            xyz, w = -xyz, -w
    sine = float(np.linalg.norm(xyz))
    if sine == 0.0:
        return np.zeros(3)
    return xyz * (2.0 * np.arctan2(sine, w) / sine)


def slerp(first: np.ndarray, second: np.ndarray, fraction: np.ndarray) -> np.ndarray:
    """
    Return ``(n, 3, 3)``: Shoemake's slerp from ``first`` to ``second`` at ``fraction`` ``(n,)``.

    ``exp(f · log(second firstᵀ)) first``: the shorter way round, uniform in angle.
    """
    turn = rotation_log(np.asarray(second, dtype=float) @ np.asarray(first, dtype=float).T)
    fraction = np.atleast_1d(np.asarray(fraction, dtype=float))
    return rotation_exp(fraction[:, None] * turn) @ first


def exp_rates(vector: np.ndarray, rate: np.ndarray,
              rate_rate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return ``(ω, dω/ds)``, ``(n, 3)`` each, of ``R(s) = exp(v(s)) R0`` (base axes).

    From ``v``, ``v' = dv/ds`` and ``v'' = d²v/ds²``, ``(n, 3)`` each, by the module's
    left-Jacobian formulas; ``R0`` is constant and does not enter.
    """
    v, dv, ddv = (np.asarray(x, dtype=float) for x in (vector, rate, rate_rate))
    _, b, c, b_tilde, c_tilde = rodrigues_coefficients(np.linalg.norm(v, axis=-1))[..., None]
    v_dv = cross(v, dv)
    v_v_dv = cross(v, v_dv)
    omega = dv + b * v_dv + c * v_v_dv
    along = np.sum(v * dv, axis=-1)[..., None]
    v_ddv = cross(v, ddv)
    omega_rate = (ddv + b * v_ddv + c * (cross(dv, v_dv) + cross(v, v_ddv))
                  + along * (b_tilde * v_dv + c_tilde * v_v_dv))
    return omega, omega_rate
