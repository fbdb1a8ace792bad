"""
Pinocchio, imported only when a robot description becomes a chain, and the model it builds.

``import traj_gen_ros`` does not import Pinocchio (≈ 0.09 s beyond numpy, measured with
``python -X importtime``, its C++ libraries included): the
first :func:`build_model` does. The Pinocchio API this room uses, the same in Pinocchio
3.x and 4.x (checked with the PyPI ``pin`` 3.4.0 and 4.1.0): ``buildModelFromXML(xml)``
(mimic joints come out as independent joints in both; see
:mod:`~traj_gen_ros.core.kinematics.configuration`), ``Model.getJointId``,
``Model.getFrameId(name, FrameType.BODY)``, ``Model.joints[i].idx_q/idx_v/nq/nv``,
``Model.createData``, ``neutral``, ``forwardKinematics``, ``updateFramePlacement``,
``computeJointJacobians``, ``getFrameJacobian`` with
``ReferenceFrame.LOCAL_WORLD_ALIGNED``, ``SE3.rotation/translation/homogeneous/actInv``
and ``log3``.

Pinocchio reads the URDF with urdfdom, which prints why it refuses a document to the
process's standard error and raises only "The XML stream does not contain a valid URDF
model". :func:`build_model` catches those lines (file descriptor 2, for the few
milliseconds of the parse) to put them in its ``ValueError``, and writes everything else it
caught back to standard error.
"""

from __future__ import annotations

from contextlib import contextmanager
import os
import sys
import tempfile
import threading
from types import ModuleType
from typing import Any

#: The PyPI release pinned in requirements.txt; a ROS install may bring a 3.x instead.
PINNED = '4.1.0'
_STDERR = threading.Lock()


def pinocchio() -> ModuleType:
    """Import and return Pinocchio, saying how to install it where it is missing."""
    try:
        import pinocchio as pin  # noqa: PLC0415 - imported only where a chain is built
    except ImportError as error:
        raise ImportError(f'kinematics needs Pinocchio: pip install pin=={PINNED} (the '
                          'venv: requirements.txt) or the rosdep key pinocchio (ROS: '
                          f'ros-<distro>-pinocchio); importing it failed: {error}') from error
    return pin


@contextmanager
def _stderr_into(sink: Any):
    """Send file descriptor 2 to ``sink`` (a file) inside the block, one thread at a time."""
    with _STDERR:
        try:
            sys.stderr.flush()
            saved = os.dup(2)
        except (AttributeError, OSError, ValueError):  # no usable stderr: nothing to catch
            saved = None
        if saved is not None:
            os.dup2(sink.fileno(), 2)
        try:
            yield
        finally:
            if saved is not None:
                os.dup2(saved, 2)
                os.close(saved)


def _urdfdom_reasons(text: str) -> tuple[list[str], str]:
    """Split urdfdom's ``Error:`` lines (and their ``at line`` lines) from other output."""
    reasons, rest, lines = [], [], text.splitlines(keepends=True)
    for line in lines:
        stripped = line.strip()
        if stripped.startswith('Error:'):
            reasons.append(stripped[len('Error:'):].strip())
        elif not (stripped.startswith('at line ') and reasons):
            rest.append(line)
    return reasons, ''.join(rest)


def build_model(urdf_text: str) -> tuple[ModuleType, Any]:
    """
    Build Pinocchio's model of a URDF document.

    :return: ``(pinocchio, model)``.
    :raises ValueError: Pinocchio (urdfdom) cannot read the document; the message gives
        urdfdom's reasons, e.g. ``Malformed parent origin element for joint [imu_joint]``.
    :raises ImportError: Pinocchio is not installed.
    """
    pin = pinocchio()
    with tempfile.TemporaryFile() as sink:
        failure = None
        with _stderr_into(sink):
            try:
                model = pin.buildModelFromXML(urdf_text)
            except Exception as error:  # noqa: BLE001 - any refusal of the C++ parser
                failure = error
        sink.seek(0)
        caught = sink.read().decode(errors='replace')
    reasons, rest = _urdfdom_reasons(caught) if failure is not None else ([], caught)
    if rest and sys.stderr is not None:
        sys.stderr.write(rest)
        sys.stderr.flush()
    if failure is not None:
        why = '; '.join(reasons) or ' '.join(str(failure).split())
        raise ValueError(f'invalid URDF: Pinocchio cannot read it: {why}') from None
    return pin, model
