"""
The speed override: the factor in force, its ramp, and the map from node time to plan time.

Two inputs set the factor asked for (:mod:`traj_gen_ros.node.speed.factor`): the
``speed_scaling`` parameter (the operator's slider) and the ``~/speed_scaling_input``
topic (what the robot or a program asks), each in ``[0, 1]``; their product is ``f*``.

A scaled plan runs on its own time ``τ``, which advances at ``f`` times the node clock
``t``: ``dτ/dt = f(t)``. What is commanded from the plan's own position ``p(τ)``,
velocity ``v(τ)``, acceleration ``a(τ)`` and jerk ``j(τ)`` is (chain rule)

* velocity ``f · v(τ)``,
* acceleration ``f² · a(τ) + ḟ · v(τ)``,
* jerk ``f³ · j(τ) + 3 f ḟ · a(τ) + f̈ · v(τ)``.

So ``f`` itself is never stepped: :class:`TimeMap` ramps the effective factor ``f(t)``
toward ``f*`` on a grid of ``STEP_NS`` and integrates the plan clock ``P(t) = ∫ f dt``
(exactly: ``f`` is a polynomial on each step). The slope ``ḟ`` on each step is the one
toward ``f*`` that the closed-form bound :func:`rate_bounds` allows for every joint at
the step's start: ``|f² a + ḟ v| <= max(σ a_max, f² |a|)`` (``σ = MARGIN``), an interval
of ``ḟ`` that always holds 0; where the plan itself uses the limit the ramp waits, where
it leaves room the ramp takes it. Under ``scurve`` (a jerk limit) ``ḟ`` is continuous:
``f̈`` is bounded by the jerk interval (:func:`jerk_bounds`) and ``ḟ`` kept inside the
acceleration interval, and a step of ``f̈`` is taken only if a brake of ``ḟ`` after it
provably keeps both limits up to ``ḟ = 0``, looking ahead into the plan's own jerk
phases (:mod:`traj_gen_ros.node.speed.look_ahead`); else the ramp waits or brakes.

**How long a pause takes.** Pausing (``f* = 0``), ``ḟ <= 0`` is as steep as the binding
joint allows, so that joint's commanded acceleration is ``-σ a_max`` (against its
velocity) all along: its commanded speed ``f |v|`` falls at ``σ a_max``. For a plan whose
joints move in step (a goal from rest, a synchronised goal, via points of one joint) the
binding joint does not change, so from full speed the pause takes at most
``T <= max_j v_max_j / (σ a_max_j)`` (plus one step; under ``scurve`` the jerk-limited
start and end of the slope add about ``a_max / j_max``, and the ramp may first wait for
the plan's jerk phases in progress to end). Where the plan already brakes at its limit,
the plan itself comes to rest first.

No ROS here. Units: rad (or m), rad/s, rad/s², rad/s³, s; ns where named.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
import math

import numpy as np
from traj_gen_ros.node.speed.factor import check_factor
from traj_gen_ros.node.speed.look_ahead import brake_rate, first_feasible, ramp_candidates
from traj_gen_ros.node.speed.plan_window import PlanWindow
from traj_gen_ros.node.speed.ramp_bounds import jerk_bounds, MARGIN, rate_bounds, RESTING

#: The ramp's grid (ns): ``ḟ`` (or ``f̈``) is constant on each step.
STEP_NS = 1_000_000
#: Before this node time (ns) a question sets no origin (the schedule's "since forever").
EARLIEST_NS = -(2 ** 61)
#: ``f`` within this of ``f*`` is settled exactly there (under a jerk limit, with ``|ḟ|``
#: within ``SETTLED_RATE`` 1/s: a step of ``ḟ`` that small changes the commanded
#: acceleration by at most ``SETTLED_RATE · v_max``).
SETTLED = 1e-6
SETTLED_RATE = 1e-5
#: Under a jerk limit, at rest (``ḟ = 0``) the chunked check is tried every this many steps.
RETRY = 4
#: ``|ḟ|`` this close (relative) to the verified brake's curve to ``f*`` counts as on it:
#: the brake is followed, and stops short of ``f*`` by about this times its distance.
ON_CURVE = 1e-3

#: The scaled plan in effect at node time ``t`` (ns), as a :class:`PlanWindow`, and its
#: own time ``τ`` (s) at the plan clock ``P`` (s); None where nothing scaled moves.
PlanState = Callable[[int, float], tuple[PlanWindow, float] | None]


@dataclass(frozen=True)
class Knot:
    """
    The ramp at a grid time and on the step after it.

    ``clock`` is ``P`` (s of plan time since the node clock's zero), ``factor`` is ``f``,
    ``rate`` is ``ḟ`` there (1/s) and ``curvature`` ``f̈`` (1/s²) on the whole step after
    it: ``f`` is a polynomial of degree <= 2 on each step, ``P`` of degree <= 3.
    """

    time_ns: int
    clock: float
    factor: float
    rate: float = 0.0
    curvature: float = 0.0
    #: Under a jerk limit, ``K`` (1/s²) of the brake verified from this knot's state
    #: (:func:`~traj_gen_ros.node.speed.look_ahead.first_feasible`), and of the one from the next;
    #: each with the plan window it was verified against (None: not verified).
    brake: float = 0.0
    next_brake: float = 0.0
    verified: object = None
    next_verified: object = None

    def at(self, time_ns: int) -> tuple[float, float, float, float]:
        """``(P, f, ḟ, f̈)`` at ``time_ns`` within the step after this knot (exact)."""
        d = (time_ns - self.time_ns) * 1e-9
        f, r, c = self.factor, self.rate, self.curvature
        return (self.clock + f * d + r * d * d / 2.0 + c * d ** 3 / 6.0,
                f + r * d + c * d * d / 2.0, r + c * d, c)

    @property
    def still(self) -> bool:
        """Whether ``f`` is constant from here (``ḟ = f̈ = 0``)."""
        return self.rate == 0.0 and self.curvature == 0.0


class TimeMap:
    """
    The plan clock ``P(t) = ∫ f dt`` with ``f`` ramped toward the factor asked for.

    Deterministic: ``P`` at a time is the same whoever asks first, as long as the factor
    asked for and the plans do not change (:attr:`version` counts the changes of the
    former; :meth:`forget` is told the latter). What is settled (``f = f*``, ``ḟ = 0``)
    is a straight line, computed at once; a ramp is stepped on ``STEP_NS`` and its knots
    are kept until a change. Nothing before the committed knot is asked again (the
    stream commits the time it published). Not thread-safe (the stream's lock guards it).
    """

    def __init__(self, max_acceleration: np.ndarray, max_jerk: np.ndarray | None = None,
                 factor: float = 1.0, step_ns: int = STEP_NS,
                 origin_ns: int | None = None) -> None:
        """
        Start with ``f = f* = factor`` and ``P = 0`` at ``origin_ns`` (the node's start).

        So ``P`` stays small and ``P(t) - P(s)`` exact to ~1e-12 s for hours. ``None``:
        at the first question about a time after ``EARLIEST_NS``. A question about a
        time before the origin is answered as at the origin.
        """
        self.max_acceleration = np.asarray(max_acceleration, dtype=float)
        self.max_jerk = None if max_jerk is None else np.asarray(max_jerk, dtype=float)
        self.target = check_factor(factor)
        self.step_ns = step_ns
        self.version = 0
        self._base: Knot | None = None
        if origin_ns is not None:
            self._base = Knot(origin_ns - origin_ns % step_ns, 0.0, self.target)
        self._ahead: list[Knot] = []

    def set_limits(self, max_acceleration: np.ndarray, max_jerk: np.ndarray | None) -> None:
        """Ramp within new limits from the next step on (``max_jerk`` None: no jerk bound)."""
        self.max_acceleration = np.asarray(max_acceleration, dtype=float)
        self.max_jerk = None if max_jerk is None else np.asarray(max_jerk, dtype=float)
        self.forget()

    def forget(self) -> None:
        """
        Drop the knots computed ahead of the committed one (the plans changed).

        The brake verified from the next knot was verified against the old plans: it is
        no longer taken for verified (the next step's candidates are checked afresh).
        """
        self._ahead.clear()
        if self._base is not None and self._base.next_verified is not None:
            self._base = replace(self._base, next_brake=0.0, next_verified=None)

    def set_target(self, factor: float, from_ns: int, plan_state: PlanState) -> None:
        """Ramp toward ``factor`` (in [0, 1]) from the first grid time at or after ``from_ns``."""
        factor = check_factor(factor)
        self.commit(from_ns, plan_state)
        self._ahead.clear()
        if factor == self.target:
            return
        self.target = factor
        self.version += 1
        if self._base.time_ns >= from_ns:  # on the grid: its step is decided again
            self._base = self._decide(self._base, plan_state)

    @property
    def settled(self) -> bool:
        """Whether ``f`` is at the factor asked for, at rest (at the committed knot)."""
        return self._base is None or self._is_settled(self._base)

    def commit(self, time_ns: int, plan_state: PlanState) -> None:
        """Fix the ramp up to the last grid time at or before ``time_ns``."""
        knot = self._knot_before(time_ns, plan_state)
        self._ahead = [k for k in self._ahead if k.time_ns > knot.time_ns]
        self._base = knot

    def at(self, time_ns: int, plan_state: PlanState) -> tuple[float, float, float, float]:
        """``(P (s), f, ḟ (1/s), f̈ (1/s²))`` at node time ``time_ns`` (ns, >= committed)."""
        knot = self._knot_before(time_ns, plan_state)
        return knot.at(max(time_ns, knot.time_ns))

    def _is_settled(self, knot: Knot) -> bool:
        return knot.factor == self.target and knot.still

    def _knot_before(self, time_ns: int, plan_state: PlanState) -> Knot:
        if self._base is None:
            if time_ns < EARLIEST_NS:  # "since forever": no origin from that
                return Knot(time_ns, 0.0, self.target)
            self._base = Knot(time_ns - time_ns % self.step_ns, 0.0, self.target)
        time_ns = max(time_ns, self._base.time_ns)
        grid = max(self._base.time_ns, time_ns - time_ns % self.step_ns)
        knot = self._base
        for ahead in self._ahead:
            if ahead.time_ns > grid:
                return knot
            knot = ahead
        while knot.time_ns < grid:
            if self._is_settled(knot):  # a straight line to the grid time
                return Knot(grid, knot.clock + knot.factor * (grid - knot.time_ns) * 1e-9,
                            knot.factor)
            clock, factor, rate, _ = knot.at(knot.time_ns + self.step_ns)
            factor = min(max(factor, 0.0), 1.0)
            slow = self.max_jerk is None or abs(rate) <= SETTLED_RATE
            if slow and abs(self.target - factor) <= SETTLED:
                factor, rate = self.target, 0.0
            knot = Knot(knot.time_ns + self.step_ns, clock, factor, rate,
                        brake=knot.next_brake, verified=knot.next_verified)
            knot = self._decide(knot, plan_state)
            self._ahead.append(knot)
        return knot

    def _decide(self, knot: Knot, plan_state: PlanState) -> Knot:
        """``knot`` with the slope (``ḟ``, or ``f̈`` under a jerk limit) of its step."""
        h = self.step_ns * 1e-9
        error = self.target - knot.factor
        if error == 0.0 and knot.rate == 0.0:
            return Knot(knot.time_ns, knot.clock, knot.factor)
        found = plan_state(knot.time_ns, knot.clock)
        if found is not None:
            window, tau = found
            velocity, acceleration, jerk = window.state(tau)
        if self.max_jerk is None or found is None:
            low, high = (-math.inf, math.inf) if found is None else rate_bounds(
                knot.factor, velocity, acceleration, self.max_acceleration)
            return Knot(knot.time_ns, knot.clock, knot.factor, min(max(error / h, low), high))
        curvature, brake, checked = self._curvature(
            knot, window, tau, (velocity, acceleration, jerk), error, h)
        return Knot(knot.time_ns, knot.clock, knot.factor, knot.rate, curvature,
                    knot.brake, brake, knot.verified, checked)

    def _curvature(self, knot: Knot, window: PlanWindow, tau: float,
                   state: tuple[np.ndarray, np.ndarray, np.ndarray], error: float, h: float
                   ) -> tuple[float, float, PlanWindow | None]:
        """
        ``(f̈, K, window)`` on the step after ``knot`` under a jerk limit; ``K``: the brake then.

        ``window`` is the plan window ``K`` was verified against (None: not verified). A
        brake verified against another window (the plan before a splice) is not followed.

        Candidates for ``K`` are ``K₀ 4⁻ⁱ`` (``K₀ = σ min j_max / |v|`` over the moving
        joints): each asks for the slope ``ḟ`` whose grid brake at ``K`` ends at ``f*``
        (:func:`~traj_gen_ros.node.speed.look_ahead.brake_rate`), kept in the acceleration
        interval, and moves ``ḟ`` toward it within ``±K`` and the jerk interval. The first
        whose step and brake keep the limits all along (first of all the landing: this step
        and one more to rest at ``f*`` exactly)
        (:func:`~traj_gen_ros.node.speed.look_ahead.first_feasible`) is taken; if none, the brake
        verified from ``knot`` (``f̈ = -sign(ḟ) min(K, |ḟ|/h)``; at ``ḟ = 0``: ``f̈ = 0``).
        """
        velocity, acceleration, jerk = state
        f, rate = knot.factor, knot.rate
        own = knot.brake if knot.verified is window else 0.0  # verified against this plan
        if own > 0.0 and rate * error > 0.0 and abs(rate) > 2.0 * own * h and \
                abs(rate) >= (1.0 - ON_CURVE) * brake_rate(abs(error), own, h):
            # On (or past) the verified brake's curve to f*: follow it (its tail is
            # verified, no check needed); a stronger brake might land a little sooner.
            # Its last two steps are chosen afresh: the landing puts f on f* at rest.
            return -math.copysign(min(own, abs(rate) / h), rate), own, window
        moving = np.abs(velocity) > RESTING
        strongest = (MARGIN * float(np.min(self.max_jerk[moving] / np.abs(velocity[moving])))
                     if moving.any() else 1.0 / (h * h))
        candidates = ramp_candidates(knot.factor, knot.rate, state, error, h, strongest,
                                     self.max_jerk, self.max_acceleration)
        # Waiting at ḟ = 0 is safe for ever: then the dearer chunked check is made only on
        # every RETRY-th step (a ramp starts at most RETRY - 1 steps later for it); over
        # pieces of a higher degree than 3 (Bernstein bounds), never.
        retry = rate != 0.0 or (knot.time_ns // self.step_ns) % RETRY == 0
        # A plan that jerks harder than max_jerk itself (an action goal: executed as given)
        # is held to its own peak, never to less: else no step could pass.
        jerk_limit = np.maximum(self.max_jerk, window.peak_jerk)
        chosen = first_feasible(window, tau, f, rate, candidates, h, self.max_acceleration,
                                jerk_limit, retry and window.cubic)
        if chosen is not None:
            return *chosen, window
        if rate == 0.0:
            return 0.0, 0.0, None
        if own > 0.0:  # the verified brake goes on
            return -math.copysign(min(own, abs(rate) / h), rate), own, window
        # None verified against this plan (one just spliced in, new limits): toward the
        # strongest brake as far as the jerk bound at the step's start allows (it holds
        # f̈ = 0), bounded at its start only; every next step is checked again.
        low, high = jerk_bounds(f, rate, velocity, acceleration, jerk, jerk_limit, 1.0)
        brake = -math.copysign(min(strongest, abs(rate) / h), rate)
        return min(max(brake, low), high), strongest, None
