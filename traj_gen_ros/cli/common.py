"""
What ``traj-gen``'s offline and ROS commands share: exit codes, errors, joint names, reports.

Used by :mod:`traj_gen_ros.cli.main` and :mod:`traj_gen_ros.cli.ros`. Its own module so that
``ros`` needs nothing from ``main`` (``main`` imports ``ros`` only when a ROS command runs,
so the offline commands need no ROS).
"""

from __future__ import annotations

import json
import math

EXIT_OK = 0
EXIT_REFUSED = 1
EXIT_USAGE = 2
EXIT_NO_ANSWER = 3
EXIT_INTERNAL = 4


class NoAnswerError(Exception):
    """Nothing arrived from ROS in time: one line on stderr, exit status 3."""


class UsageError(Exception):
    """Bad arguments or a plan the solver refuses: one line on stderr, exit status 2."""

    def __init__(self, message: str, prog: str | None = None) -> None:
        """Keep ``message`` and the program (``traj-gen goal`` ...) it is about."""
        super().__init__(message)
        self.prog = prog


def finite_number(text: str, what: str) -> float:
    """Read a finite number from the command line; :class:`UsageError` naming ``what``."""
    try:
        value = float(text)
    except ValueError:
        raise UsageError(f"{what}: '{text}' is not a number") from None
    if not math.isfinite(value):
        raise UsageError(f"{what}: '{text}' must be finite")
    return value


def joint_names(count: int) -> list[str]:
    """
    Return the names ``traj-gen`` gives ``count`` joints: ``joint_1``, ``joint_2``, ….

    The node's convention (its default ``joints`` parameter), so that a plan solved
    offline and one recorded from the node name their joints alike.
    """
    return [f'joint_{index}' for index in range(1, count + 1)]


def report_plot(info: dict, as_json: bool) -> None:
    """Print where the PNG went (and its size and panels with ``--json``)."""
    if as_json:
        print(json.dumps(info, indent=2, ensure_ascii=False))
    else:
        print(f"wrote {info['output']} ({info['width']}x{info['height']} px, "
              f"{len(info['panels'])} panels)")
