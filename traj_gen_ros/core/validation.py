"""
Input checks shared by every profile, done before any math runs.

Each function returns clean float64 arrays or raises ``ValueError`` saying what is wrong,
where (which argument, joint or point) and what would be valid.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from decimal import Decimal
import functools
import math
import sys
from typing import Literal, TypeVar

import numpy as np

ArrayLike = float | Sequence[float] | np.ndarray
Planner = TypeVar('Planner', bound=Callable)


def refuses_overflow(caller: str) -> Callable[[Planner], Planner]:
    """
    Make a public planner refuse inputs whose arithmetic leaves float64, never return junk.

    The planner runs with numpy's overflow, division by zero and invalid results raised
    (code that expects them says so with its own ``np.errstate``); one of them, or a
    Python ``OverflowError``, becomes a ``ValueError`` naming ``caller`` and why. Extreme
    magnitudes (positions or durations near 1e308, limits near 1e-308) are then refused
    instead of giving a plan that is silently wrong.
    """
    def decorate(planner: Planner) -> Planner:
        @functools.wraps(planner)
        def guarded(*args: object, **kwargs: object) -> object:
            try:
                with np.errstate(over='raise', divide='raise', invalid='raise'):
                    return planner(*args, **kwargs)
            except (FloatingPointError, OverflowError) as error:
                raise ValueError(
                    f'{caller}: the inputs leave the range of float64 ({error}); use '
                    'smaller positions and velocities, or durations and limits closer to '
                    'each other') from None
        return guarded  # type: ignore[return-value]
    return decorate


def every(mask: np.ndarray) -> bool:
    """
    Tell whether every entry of a boolean array is true.

    ``np.count_nonzero`` skips the ufunc-reduction set-up of ``mask.all()``: on the few
    joints of a plan it is several times faster, and a node may plan at kHz rates.
    """
    return np.count_nonzero(mask) == mask.size


def round_up(value: float, digits: int) -> str:
    """
    Print ``value`` rounded up to ``digits`` significant digits, so the printed number works.

    A limit named in a refusal (a minimum duration, s) is printed rounded *up*: passing
    the printed number back is then never too short. Values that are not finite and > 0
    are printed as they are; a value whose rounding up passes the largest float is
    printed exactly (``1.798e+308``) rather than as ``inf``.
    """
    if not math.isfinite(value) or value <= 0.0:
        return f'{value:g}'
    exact = Decimal(value)  # the float's exact value: no overflow, no underflow
    exponent = exact.adjusted() - digits + 1
    # (1 - 1e-15): a value that is already a round number is not pushed up by its rounding.
    mantissa = math.ceil(exact.scaleb(-exponent) * (1 - Decimal('1e-15')))
    rounded = Decimal(mantissa).scaleb(exponent)
    if rounded <= Decimal(sys.float_info.max):
        return f'{float(rounded):.{digits}g}'
    return format(rounded, f'.{digits}g')


def _describe_bad(values: np.ndarray, item: str = 'joint') -> str:
    """Name the first non-finite entry (index and value); ``item`` names a 1-D index."""
    index = tuple(int(i) for i in np.argwhere(~np.isfinite(values))[0])
    if len(index) == 2:
        return f'point {index[0]}, joint {index[1]} is {values[index]}'
    return f'{item} {index[0]} is {values[index]}' if index else f'it is {values}'


def finite_array(name: str, value: ArrayLike, max_ndim: int, item: str = 'joint') -> np.ndarray:
    """
    Return ``value`` as a float array of at most ``max_ndim`` dimensions, all finite.

    ``item`` names what a 1-D array is indexed by (joint, point, segment, sample) in the
    error message.
    """
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError(f'{name} must be numbers: {error}') from None
    if array.ndim > max_ndim:
        raise ValueError(f'{name} has {array.ndim} dimensions; at most {max_ndim} allowed')
    if not every(np.isfinite(array)):
        raise ValueError(f'{name} must be finite: {_describe_bad(array, item)}')
    return array


def joint_count_of(**values: np.ndarray) -> int:
    """
    Return the joint count that scalars and 1-D per-joint arrays agree on.

    The first 1-D array (the positions, or the path) sets the count; a disagreeing one is
    named with its length and the count expected.
    """
    sizes = {name: array.size for name, array in values.items() if array.ndim == 1}
    if not sizes:
        return 1
    reference, count = next(iter(sizes.items()))
    for name, size in sizes.items():
        if size != count:
            raise ValueError(f'{name} has {size} values for {count} joints (as {reference}); '
                             'give one value, or one per joint')
    if count == 0:
        raise ValueError('no joints: per-joint arrays are empty')
    return count


def duration_of(value: float, name: str = 'duration') -> float:
    """Return ``value`` as a finite, strictly positive duration in seconds."""
    if isinstance(value, int | float) and 0.0 < value < np.inf:
        return float(value)
    array = finite_array(name, value, max_ndim=0)
    if array <= 0.0:
        raise ValueError(f'{name} must be > 0 s, got {float(array)}')
    return float(array)


Sign = Literal['positive', 'non-negative', 'any']
_VALID = {('positive', False): 'finite and > 0', ('non-negative', False): 'finite and >= 0',
          ('any', False): 'finite', ('positive', True): '> 0 (inf: no limit)',
          ('non-negative', True): '>= 0 (inf: no limit)',
          ('any', True): 'a number, not NaN (+-inf: no limit)'}


def per_joint(name: str, value: object, joint_count: int, sign: Sign = 'positive',
              infinite: bool = False, joints: Sequence[str] | None = None) -> np.ndarray:
    """
    Return a per-joint value given as one number for all joints or one per joint.

    The one broadcaster of the package: the core's limits, the node's parameters, the
    URDF merge and the command line's options all go through it.

    :param name: the argument or parameter, named in the error message.
    :param value: a number, or a sequence of one or ``joint_count`` numbers.
    :param joint_count: how many joints.
    :param sign: ``'positive'`` (> 0), ``'non-negative'`` (>= 0) or ``'any'``.
    :param infinite: whether ±inf is allowed (meaning: no limit); NaN never is.
    :param joints: the joints' names, to name the first joint out of range by its name
        (else by its index, from 0).
    :return: ``(joint_count,)`` floats, in the unit of ``value``.
    :raises ValueError: naming ``name`` and what is valid: not numbers, a count that is
        neither 1 nor ``joint_count``, or a value out of range (naming the first joint).
    """
    if isinstance(value, int | float) and not isinstance(value, bool):
        array = np.full(joint_count, float(value))
    else:
        if isinstance(value, bool | str) or value is None:
            raise ValueError(f'{name} must be a number or one number per joint, got {value!r}')
        try:
            array = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f'{name} must be a number or one number per joint, '
                             f'got {value!r}') from None
        if array.ndim > 1:
            raise ValueError(f'{name} must be a number or one number per joint, '
                             f'got shape {array.shape}')
        if array.size == 1:
            array = np.full(joint_count, float(array.reshape(-1)[0]))
        elif array.size != joint_count:
            raise ValueError(f'{name} has {array.size} values but there are {joint_count} '
                             'joints: give one value for all joints or one per joint')
    if sign == 'positive':
        valid = array > 0.0
    elif sign == 'non-negative':
        valid = array >= 0.0
    else:
        valid = ~np.isnan(array)
    if not infinite:
        valid &= np.isfinite(array)
    if not every(valid):
        joint = int(np.argmin(valid))
        which = f'joint {joint}' if joints is None else f'joint {joints[joint]!r}'
        raise ValueError(f'{name} must be {_VALID[sign, infinite]}; {which} has '
                         f'{array[joint]}')
    return array


def require_positive(rows: np.ndarray, names: tuple[str, ...]) -> None:
    """Check that every entry of the per-joint ``rows`` named ``names`` is > 0."""
    if np.count_nonzero(rows > 0.0) != rows.size:
        row, joint = (int(index) for index in np.argwhere(rows <= 0.0)[0])
        raise ValueError(f'{names[row]} must be finite and > 0; joint {joint} has '
                         f'{rows[row, joint]}')


def path_points(points: ArrayLike) -> np.ndarray:
    """Via points shaped ``(points,)`` or ``(points, joints)`` as ``(points, joints)``."""
    array = finite_array('points', points, max_ndim=2)
    if array.ndim == 0:
        raise ValueError('points must be a sequence of at least 2 positions, got a scalar')
    if array.ndim == 1:
        array = array[:, None]
    if array.shape[0] < 2:
        raise ValueError(f'points needs at least 2 points (start and goal), got {len(array)}')
    if array.shape[1] == 0:
        raise ValueError('points has no joints')
    return array


def segment_durations(durations: ArrayLike, segment_count: int) -> np.ndarray:
    """One finite, strictly positive duration per segment, ``(segments,)``."""
    array = np.atleast_1d(finite_array('durations', durations, max_ndim=1, item='segment'))
    if array.size != segment_count:
        raise ValueError(f'durations has {array.size} entries for {segment_count} segments '
                         f'({segment_count + 1} points); give one per segment')
    bad = np.flatnonzero(array <= 0.0)
    if bad.size:
        raise ValueError(f'durations must be > 0 s; segment {bad[0]} has {array[bad[0]]}')
    return array


def per_point(name: str, value: ArrayLike, shape: tuple[int, int]) -> np.ndarray:
    """Return a value at every path point as ``(points, joints)``."""
    array = finite_array(name, value, max_ndim=2, item='point')
    if array.ndim == 1 and shape[1] == 1:
        array = array[:, None]
    if array.shape != shape:
        raise ValueError(f'{name} is shaped {array.shape}; expected {shape} '
                         '(one value per point and joint)')
    return array


def per_joint_rows(like: np.ndarray | None = None, **values: ArrayLike) -> np.ndarray:
    """
    Stack scalars or per-joint 1-D arrays as rows, ``(len(values), joints)``.

    The joint count is the one the 1-D arrays agree on (or ``like.size``); scalars apply
    to every joint. One finiteness check covers all rows; a failure names the argument.
    Numpy arrays of one 1-D shape, all finite (the usual call), are stacked in one step.
    """
    shape = None
    for value in values.values():
        if type(value) is not np.ndarray or value.shape != (shape or value.shape):
            break
        shape = value.shape
    else:
        if shape and len(shape) == 1 and shape[0] and (like is None or like.size == shape[0]):
            try:
                rows = np.array(list(values.values()), dtype=float)
            except (TypeError, ValueError):  # not numbers: the checks below say so
                rows = None
            if rows is not None and every(np.isfinite(rows)):
                return rows
    arrays = []
    sizes = set() if like is None else {like.size}
    for name, value in values.items():
        if not isinstance(value, float):
            try:
                value = np.asarray(value, dtype=float)
            except (TypeError, ValueError) as error:
                raise ValueError(f'{name} must be numbers: {error}') from None
            if value.ndim:
                sizes.add(value.shape[0] if value.ndim == 1 else -1)
        arrays.append(value)
    if len(sizes) > 1 or 0 in sizes or -1 in sizes:
        named = zip(values, arrays, strict=True)
        _explain_rows(like, {name: np.asarray(array) for name, array in named})
    rows = np.empty((len(arrays), sizes.pop() if sizes else 1))
    for row, array in enumerate(arrays):
        rows[row] = array
    if not every(np.isfinite(rows)):
        for name, array in zip(values, arrays, strict=True):
            finite_array(name, array, max_ndim=1)
    return rows


def _explain_rows(like: np.ndarray | None, arrays: dict[str, np.ndarray]) -> None:
    """Raise the ``ValueError`` that says why per-joint arrays cannot be stacked."""
    for name, array in arrays.items():
        if array.ndim > 1:
            raise ValueError(f'{name} must be a scalar or one value per joint, '
                             f'got shape {array.shape}')
    if like is not None:
        arrays = {'points': np.asarray(like).reshape(-1), **arrays}
    joint_count_of(**arrays)
