"""The virtual machine's own rigid-body truth: where every body really is.

The simulator must not judge the model with the model's own physics, so this
module shares no code with :mod:`mt_accuracy_ros.core.kinematics` beyond the
machine description (data: the chain, strokes, offsets, tool vector). Poses are
kept as (rotation matrix, origin) pairs built with :mod:`scipy.spatial.transform`
and composed body by body, from the bed outwards, in the order the machine is
assembled (ISO 230-1): the body sits at its parent's ``offset``, is out of
place by its location errors, moves by its command, and is disturbed by its
six error motions and a thermal twist. A rotary body turns about its actual
axis line (ISO 230-7): where the set-up found it at the machine's set-up pose,
and from there about the line its location errors put elsewhere.

An error twist (dx, dy, dz, ex, ey, ez) is the pose "shift by d, then turn by
the XYZ-intrinsic angles (ex, ey, ez)" - the reading of an error motion that
ISO 230-1 and Kidani eq. 2.7 use (the translation measured at the body's
origin, the rotation about its own axes).

The truth the simulator reports is what a machinist cares about: the tool
point against the workpiece point under it, in the bed frame. The point under
the tool is the material the *command* puts the tool on (the nominal tool point
expressed in the nominal workpiece frame), unless an instrument fixes its own
target on the workpiece side (an R-test sphere, a probed sphere).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

_UNIT = np.eye(3)


@dataclass
class BodyErrors:
    """Error twists of the virtual machine's bodies at N instants.

    Every value is (N, 6) [m, m, m, rad, rad, rad] or broadcastable to it:
    ``motion[axis]`` the six error motions of the body an axis moves,
    ``location[axis]`` its location errors, ``thermal[key]`` a thermal twist of
    the body carried by ``axis`` or of the bed under either branch
    (``"bed_tool"``, ``"bed_work"``).
    """

    motion: dict[str, NDArray] = field(default_factory=dict)
    location: dict[str, NDArray] = field(default_factory=dict)
    thermal: dict[str, NDArray] = field(default_factory=dict)

    def add(self, kind: str, axis: str, component: int, value, n: int) -> None:
        """Add ``value`` ((N,) or scalar) to one component of one twist."""
        table = getattr(self, kind)
        twist = table.setdefault(axis, np.zeros((n, 6)))
        twist[:, component] += np.broadcast_to(np.asarray(value, dtype=np.float64), (n,))


@dataclass
class Pose:
    """Rigid poses of N instants: ``rotation`` (N, 3, 3) and ``origin`` (N, 3) [m],
    the body frame in the bed frame."""

    rotation: NDArray[np.float64]
    origin: NDArray[np.float64]

    @classmethod
    def identity(cls, n: int) -> "Pose":
        return cls(np.repeat(_UNIT[None], n, axis=0), np.zeros((n, 3)))

    def then(self, rotation: NDArray | None, shift: NDArray | None) -> "Pose":
        """This pose followed by a local shift (N, 3) and then a local turn (N, 3, 3)."""
        origin = self.origin
        if shift is not None:
            origin = origin + np.einsum("nij,nj->ni", self.rotation, shift)
        turned = self.rotation if rotation is None else np.einsum("nij,njk->nik",
                                                                   self.rotation, rotation)
        return Pose(turned, origin)

    def point(self, local: NDArray) -> NDArray[np.float64]:
        """(N, 3) bed coordinates of a point given in this frame ((3,) or (N, 3))."""
        local = np.broadcast_to(np.asarray(local, dtype=np.float64), self.origin.shape)
        return self.origin + np.einsum("nij,nj->ni", self.rotation, local)

    def local(self, point: NDArray) -> NDArray[np.float64]:
        """(N, 3) coordinates in this frame of a bed point (N, 3)."""
        return np.einsum("nji,nj->ni", self.rotation, point - self.origin)


def _twist(twist: NDArray, n: int) -> tuple[NDArray, NDArray]:
    twist = np.broadcast_to(np.asarray(twist, dtype=np.float64), (n, 6))
    return Rotation.from_euler("XYZ", twist[:, 3:]).as_matrix().reshape(n, 3, 3), twist[:, :3]


def _disturb(pose: Pose, twist: NDArray | None, n: int) -> Pose:
    if twist is None:
        return pose
    rotation, shift = _twist(twist, n)
    return pose.then(rotation, shift)


def _turn(angle: NDArray, unit: NDArray, n: int) -> NDArray:
    return Rotation.from_rotvec(np.asarray(angle)[:, None] * unit).as_matrix().reshape(n, 3, 3)


def _turn_about_actual_line(pose: Pose, angle: NDArray, unit: NDArray,
                            location: NDArray | None, setup: float, n: int) -> Pose:
    """A rotary body turned by ``angle`` [rad] about its actual axis line.

    The line's place and direction are the nominal frame moved by the location twist
    (ISO 230-7). The body was set up at ``setup``: there it is where the set-up found
    it, and from there it turns about the actual line - so a point at the frame's
    nominal position p goes to c + R (p - c) for a line through c.
    """
    if location is None:
        return pose.then(_turn(angle, unit, n), None)
    line_rotation, line_shift = _twist(location, n)
    on_line = pose.then(line_rotation, line_shift)
    turned = on_line.then(_turn(angle - setup, unit, n), None)
    # Back from the actual line's frame: the inverse of "shift, then turn".
    back = turned.then(np.swapaxes(line_rotation, 1, 2), None).then(None, -line_shift)
    return back.then(_turn(np.full(n, setup), unit, n), None)


def body_pose(machine, branch: str, positions: dict[str, NDArray],
              errors: BodyErrors | None = None) -> Pose:
    """Pose of the last body of a branch (``"tool"`` or ``"workpiece"``), at its
    mounting point (the last axis' ``offset``), for axis positions (N,) each.

    Without ``errors`` the nominal pose.
    """
    axes = machine.tool_branch if branch == "tool" else machine.workpiece_branch
    n = int(np.size(next(iter(positions.values()))))
    pose = Pose.identity(n)
    if errors is not None:
        pose = _disturb(pose, errors.thermal.get("bed_tool" if branch == "tool" else "bed_work"),
                        n)
    mount = np.zeros(3)
    for axis in axes:
        spec = machine.axes[axis]
        pose = pose.then(None, np.broadcast_to(mount, (n, 3)))
        value = spec.sign * np.broadcast_to(np.asarray(positions[axis], float), (n,))
        unit = _UNIT[spec.direction]
        location = None if errors is None else errors.location.get(axis)
        if spec.is_rotary:
            pose = _turn_about_actual_line(pose, value, unit, location,
                                           spec.sign * machine.setup_angle(axis), n)
        else:
            pose = _disturb(pose, location, n)
            pose = pose.then(None, value[:, None] * unit)
        if errors is not None:
            pose = _disturb(pose, errors.motion.get(axis), n)
            pose = _disturb(pose, errors.thermal.get(axis), n)
        mount = np.asarray(spec.offset, dtype=np.float64)
    return pose.then(None, np.broadcast_to(mount, (n, 3)))


def point_under_tool(machine, command: dict[str, NDArray]) -> NDArray[np.float64]:
    """(N, 3) the workpiece point the command puts the tool on, workpiece frame [m]."""
    tool = body_pose(machine, "tool", command).point(np.asarray(machine.tool, float))
    return body_pose(machine, "workpiece", command).local(tool)


def tool_against_work(machine, actual: dict[str, NDArray], command: dict[str, NDArray],
                      errors: BodyErrors | None, work_point: NDArray | None = None
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The tool against the workpiece, truth.

    Parameters
    ----------
    actual, command : axis -> (N,)
        Where the axes are and where the CNC commanded them.
    errors : BodyErrors or None
        The bodies' error twists at those instants.
    work_point : (3,) or (N, 3) [m], optional
        A fixed target on the workpiece side, in the workpiece frame; default
        the point under the tool at the command.

    Returns
    -------
    position : (N, 3) [m]
        Actual tool point minus the actual place of the work point, less the
        same at the command (zero for the point under the tool), bed frame.
    orientation : (N, 3) [rad]
        Rotation vector of the tool's actual orientation relative to the
        workpiece against the commanded one, bed frame.
    """
    tool_vector = np.asarray(machine.tool, dtype=np.float64)
    tool = body_pose(machine, "tool", actual, errors)
    work = body_pose(machine, "workpiece", actual, errors)
    tool0 = body_pose(machine, "tool", command)
    work0 = body_pose(machine, "workpiece", command)
    target = work0.local(tool0.point(tool_vector)) if work_point is None else work_point
    position = (tool.point(tool_vector) - work.point(target)) \
        - (tool0.point(tool_vector) - work0.point(target))
    # The tool in the workpiece frame, actual against commanded, shown in the bed frame
    # through the commanded workpiece pose.
    actual_rel = np.einsum("nji,njk->nik", work.rotation, tool.rotation)
    nominal_rel = np.einsum("nji,njk->nik", work0.rotation, tool0.rotation)
    change = np.einsum("nij,nkj->nik", actual_rel, nominal_rel)
    in_bed = np.einsum("nij,njk,nlk->nil", work0.rotation, change, work0.rotation)
    n = position.shape[0]
    return position, Rotation.from_matrix(in_bed).as_rotvec().reshape(n, 3)
