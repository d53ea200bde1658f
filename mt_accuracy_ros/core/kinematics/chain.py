"""Kinematic (rigid-body) error model of a machine tool from its description.

Each joint j of a branch contributes, following Khan & Chen eq. 8,

    T_j = T_p . T_pe . T_s(q_j) . T_se(q_j) [. T_thermal]

with T_p the nominal position of the joint frame in its parent (the previous
axis' ``offset``, Kidani's L_*), T_pe the location errors (squareness, offsets,
zero errors), T_s the commanded motion, T_se the six position-dependent error
motions (exact product, or Kidani eq. 2.7 to first order) and an optional
thermal-link HTM (Zhu eq. 4.2). A rotary joint turns about its *actual* axis
line (ISO 230-7): its location errors L (offsets and tilts of the line, the
zero) act as

    T_pe T_s(q) -> L . T_s(q - q_s) . L^-1 . T_s(q_s)

with q_s the set-up command (``MachineDescription.setup_pose``, default 0): the
body is where the set-up found it at q_s and turns about the actual line from
there, so an offset d of a C line moves the work by (I - R_C) d, a tilt by the
tilt times the radius, and the zero error is taken out by the set-up. The tool
branch (Khan & Chen's M loop) carries the tool vector t, the workpiece branch (N
loop) the workpiece point w, and the
TCP error is

    e = (P_t - P_w)_actual - (P_t - P_w)_nominal          (Kidani eq. 2.10, Khan & Chen eq. 17)

in the bed (reference) frame.

**The machining point.** Kidani eqs. 2.9-2.10 take w as "the target position
on the work surface", the machining point; Khan & Chen eq. 17 relates the
cutter contact point to the workpiece. So by default w is, for every
configuration, the nominal tool point expressed in the workpiece frame
(:meth:`KinematicModel.machining_point`): the material the tool is cutting, and
the nominal tool-to-work vector is zero. A table's tilt then acts through the
arm from the table's frame to the tool, which changes with the other axes. An
instrument whose target is fixed on the workpiece side (an R-test sphere, a
probed sphere, a retroreflector) passes its point as ``work_point`` (in the
workpiece frame, the frame the description's ``workpiece`` is given in) and the
error is taken there. The description's ``workpiece`` is the workpiece
*reference* point (the work offset): :meth:`KinematicModel.nominal_relative`
gives the tool relative to it, the commanded geometry.

Two independent formulations are provided:

* :meth:`KinematicModel.tcp_error` - the full matrix products (exact, or with
  the first-order error matrices);
* :meth:`KinematicModel.tcp_error_linear` - the first-order sum
  ``sum_j R_j (d_j + eps_j x r_j)`` of every joint's error twist moved to the
  TCP through its nominal lever arm r_j; no error matrix is multiplied.

Everything is vectorised over N configurations: positions are dicts of arrays.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ..errors import MachineDescriptionError
from ..validation import as_samples
from .htm import (cross, identity, rotation, rotation_matrix_first_order, rotation_matrix_xyz,
                  rotation_vector, translation)
from .machine import COMPONENTS, MachineDescription, location_error_name, motion_error_name

Positions = dict[str, NDArray[np.float64]]


@dataclass
class ErrorOverrides:
    """Error values to use instead of (or on top of) the description's.

    ``motion[name]`` : array (N,) or scalar replacing the function of e.g. 'ECX'.
    ``location[name]`` : scalar or (N,) replacing e.g. 'EC0Y'.
    ``thermal[axis]`` : (N, 6) or (6,) small-displacement twist (dx, dy, dz, ex, ey, ez)
    of the body carried by ``axis`` (or ``'bed_tool'`` / ``'bed_work'``), a thermal link.
    ``scale`` : multiplies every error (for order-of-magnitude checks).

    Parameters
    ----------
    motion : dict of str to float or ndarray, shape (N,)
        Motion error name (``ECX``) -> value [m] (EX., EY., EZ.) or [rad] (EA., EB., EC.).
    location : dict of str to float or ndarray, shape (N,)
        Location error name (``EC0Y``) -> value [m] or [rad].
    thermal : dict of str to ndarray, shape (6,) or (N, 6)
        Axis (or ``bed_tool`` / ``bed_work``) -> twist: dx, dy, dz [m], ex, ey, ez [rad].
    scale : float
        Dimensionless factor on every error.
    use_description : bool
        False: errors not overridden are zero instead of the description's.
    """

    motion: dict[str, object] = field(default_factory=dict)
    location: dict[str, object] = field(default_factory=dict)
    thermal: dict[str, object] = field(default_factory=dict)
    scale: float = 1.0
    use_description: bool = True


class KinematicModel:
    """HTM chain model built from a :class:`MachineDescription`.

    Parameters
    ----------
    machine : MachineDescription
        The machine: chain, offsets [m], strokes, error functions.
    """

    def __init__(self, machine: MachineDescription) -> None:
        self.machine = machine

    # ----------------------------------------------------------------- inputs
    def _n(self, positions: Positions) -> int:
        sizes = {np.asarray(v).size for v in positions.values()}
        if len(sizes) > 1:
            raise MachineDescriptionError(f"axis position arrays differ in length: {sorted(sizes)}")
        return sizes.pop() if sizes else 1

    def _positions(self, positions: Positions, check_stroke: bool) -> tuple[Positions, int]:
        missing = [a for a in self.machine.axis_order if a not in positions]
        if missing:
            raise MachineDescriptionError(f"positions missing for axis {', '.join(missing)}")
        if check_stroke:
            self.machine.check_positions(positions)
        else:
            unknown = set(positions) - set(self.machine.axis_order)
            if unknown:
                raise MachineDescriptionError(f"unknown axis {sorted(unknown)[0]!r}")
        n = self._n(positions)
        return {a: as_samples(positions[a], n) for a in self.machine.axis_order}, n

    def motion_errors(self, axis: str, q: NDArray, overrides: ErrorOverrides) -> NDArray:
        """(N, 6) error motions (dx, dy, dz, ex, ey, ez) of ``axis`` at positions ``q``.

        Parameters
        ----------
        axis : str
            Axis letter.
        q : ndarray, shape (N,)
            Positions of ``axis`` [m] (rotary [rad]).
        overrides : ErrorOverrides
            Error values replacing or adding to the description's (none by default).

        Returns
        -------
        ndarray, shape (N, 6)
            dx, dy, dz [m] and ex, ey, ez [rad], times ``overrides.scale``.
        """
        spec = self.machine.axes[axis]
        out = np.zeros((q.size, 6))
        for i, component in enumerate(COMPONENTS):
            name = motion_error_name(component, axis)
            if name in overrides.motion:
                # A value or an (N,) array: the assignment broadcasts (and refuses others).
                out[:, i] = np.asarray(overrides.motion[name], float)
            elif overrides.use_description:
                out[:, i] = spec.motion_errors[component](q)
        return out * overrides.scale

    def location_errors(self, axis: str, n: int, overrides: ErrorOverrides) -> NDArray:
        """(N, 6) location errors (EX0., EY0., EZ0., EA0., EB0., EC0.) of ``axis``.

        Parameters
        ----------
        axis : str
            Axis letter.
        n : int
            Number of configurations N.
        overrides : ErrorOverrides
            Error values replacing or adding to the description's (none by default).

        Returns
        -------
        ndarray, shape (N, 6)
            Offsets [m] and tilts / zero [rad], undeclared ones zero, times ``overrides.scale``.
        """
        spec = self.machine.axes[axis]
        out = np.zeros((n, 6))
        for i, component in enumerate(COMPONENTS):
            name = location_error_name(component, axis)
            if name in overrides.location:
                out[:, i] = np.asarray(overrides.location[name], float)
            elif overrides.use_description:
                out[:, i] = spec.location_errors.get(component, 0.0)
        return out * overrides.scale

    def _thermal(self, key: str, n: int, overrides: ErrorOverrides) -> NDArray | None:
        if key not in overrides.thermal:
            return None
        twist = np.broadcast_to(np.asarray(overrides.thermal[key], dtype=np.float64), (n, 6))
        return twist * overrides.scale

    # ----------------------------------------------------------------- chains
    def _motion(self, axis: str, q: NDArray) -> NDArray:
        spec = self.machine.axes[axis]
        value = spec.sign * q
        if spec.is_rotary:
            return rotation("xyz"[spec.direction], value)
        d = np.zeros((q.size, 3))
        d[:, spec.direction] = value
        return translation(d[:, 0], d[:, 1], d[:, 2])

    def branch(self, which: str, positions: Positions, *, errors: bool = True,
               first_order: bool = False, overrides: ErrorOverrides | None = None,
               check_stroke: bool = True, end_point: NDArray | None = None) -> NDArray:
        """(N, 4, 4) HTM from the bed to the branch's end point frame.

        ``which`` is ``"tool"`` (M loop, ending at the tool vector) or
        ``"workpiece"`` (N loop, ending at the workpiece point); the returned
        frame's origin is that point. ``end_point`` ((3,) or (N, 3) [m], in the
        branch's last frame) replaces the description's tool vector or workpiece
        reference point.

        Parameters
        ----------
        which : {"tool", "workpiece"}
            The branch.
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        errors : bool, optional
            Include the error HTMs (False: the nominal chain).
        first_order : bool, optional
            First-order error matrices (Kidani eq. 2.7) instead of the exact products.
        overrides : ErrorOverrides, optional
            Error values replacing or adding to the description's (none by default).
        check_stroke : bool, optional
            Refuse positions outside an axis' stroke.
        end_point : array_like, shape (3,) or (N, 3), optional
            End point [m] in the branch's last frame.

        Returns
        -------
        ndarray, shape (N, 4, 4)
            Bed-to-end-point HTMs, translation in [m].

        Raises
        ------
        MachineDescriptionError
            Missing or unknown axes, arrays of different lengths, or (``check_stroke``)
            positions outside the stroke.
        """
        rot, pos = self._branch_rp(which, positions, errors, first_order,
                                   overrides or ErrorOverrides(), check_stroke, end_point)
        out = identity((rot.shape[0],))
        out[:, :3, :3] = rot
        out[:, :3, 3] = pos
        return out

    def _branch_rp(self, which: str, positions: Positions, errors: bool, first_order: bool,
                   overrides: ErrorOverrides, check_stroke: bool,
                   end_point: NDArray | None = None) -> tuple[NDArray, NDArray]:
        """The branch product kept as rotation (N, 3, 3) and translation (N, 3).

        Composing T1 T2 as (R1 R2, R1 p2 + p1) skips the constant last row of
        every 4x4 product and lets linear motions add a column instead of
        multiplying a matrix.
        """
        q, n = self._positions(positions, check_stroke)
        axes = self.machine.tool_branch if which == "tool" else self.machine.workpiece_branch
        if end_point is None:
            end_point = self.machine.tool if which == "tool" else self.machine.workpiece
        end = np.asarray(end_point, dtype=np.float64)
        rotation_of = rotation_matrix_first_order if first_order else rotation_matrix_xyz
        rot = np.zeros((n, 3, 3))
        rot[:, (0, 1, 2), (0, 1, 2)] = 1.0
        pos = np.zeros((n, 3))

        def apply_error(twist):
            # The error HTM D_X D_Y D_Z D_A D_B D_C (or Kidani eq. 2.7) as (R_e, d).
            nonlocal rot, pos
            pos = pos + np.einsum("nij,nj->ni", rot, twist[:, :3])
            rot = rot @ rotation_of(twist[:, 3], twist[:, 4], twist[:, 5])

        def apply(htm):
            nonlocal rot, pos
            pos = pos + np.einsum("nij,nj->ni", rot, htm[:, :3, 3])
            rot = rot @ htm[:, :3, :3]

        def undo_error(twist):
            # The inverse of apply_error's (R_e, d): (R_e^T, -R_e^T d).
            nonlocal rot, pos
            turn = np.swapaxes(rotation_of(twist[:, 3], twist[:, 4], twist[:, 5]), 1, 2)
            rot = rot @ turn
            pos = pos - np.einsum("nij,nj->ni", rot, twist[:, :3])

        thermal = self._thermal("bed_tool" if which == "tool" else "bed_work", n, overrides)
        if errors and thermal is not None:
            apply_error(thermal)
        parent_offset = np.zeros(3)
        for axis in axes:
            pos = pos + rot @ parent_offset
            spec = self.machine.axes[axis]
            location = self.location_errors(axis, n, overrides) if errors else None
            located = location is not None and np.any(location)
            if located and spec.is_rotary:
                # ISO 230-7: the body turns about the actual axis line L from where it was
                # set up, L R(q - q_s) L^-1 R(q_s): at the set-up pose it is where the
                # set-up found it; an offset line d moves it by (I - R) d.
                setup = spec.sign * self.machine.setup_angle(axis)
                apply_error(location)
                apply(rotation("xyz"[spec.direction], spec.sign * q[axis] - setup))
                undo_error(location)
                if setup:
                    apply(rotation("xyz"[spec.direction], np.full(n, setup)))
            elif spec.is_rotary:
                apply(rotation("xyz"[spec.direction], spec.sign * q[axis]))
            else:
                if located:
                    apply_error(location)
                pos = pos + rot[:, :, spec.direction] * (spec.sign * q[axis])[:, None]
            if errors:
                apply_error(self.motion_errors(axis, q[axis], overrides))
                thermal = self._thermal(axis, n, overrides)
                if thermal is not None:
                    apply_error(thermal)
            parent_offset = spec.offset
        if end.ndim == 1:
            pos = pos + rot @ (parent_offset + end)
        else:
            pos = pos + rot @ parent_offset + np.einsum("nij,nj->ni", rot, end)
        return rot, pos

    # ------------------------------------------------------ the machining point
    def machining_point(self, positions: Positions, check_stroke: bool = False) -> NDArray:
        """(N, 3) [m] the nominal tool point expressed in the workpiece frame.

        The workpiece frame is the one the description's ``workpiece`` is given
        in (the last workpiece axis' frame moved by its ``offset``; the bed for a
        machine whose workpiece branch is empty). This is the w of Kidani eqs.
        2.9-2.10 ("the target position on the work surface"): the material the
        tool is cutting in this configuration.

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        check_stroke : bool, optional
            Refuse positions outside an axis' stroke.

        Returns
        -------
        ndarray, shape (N, 3)
            Machining point [m], workpiece frame.
        """
        q, _ = self._positions(positions, check_stroke)
        return self._machining_point(q)

    def _machining_point(self, q: Positions) -> NDArray:
        none = ErrorOverrides()
        _, tool_p = self._branch_rp("tool", q, False, False, none, False)
        work_r, work_o = self._branch_rp("workpiece", q, False, False, none, False,
                                         np.zeros(3))
        return np.einsum("nji,nj->ni", work_r, tool_p - work_o)

    def _work_point(self, q: Positions, n: int, work_point) -> NDArray:
        """(N, 3) the work point in the workpiece frame: the machining point for None."""
        if work_point is None:
            return self._machining_point(q)
        point = np.asarray(work_point, dtype=np.float64)
        if point.shape not in ((3,), (n, 3)):
            raise MachineDescriptionError(
                f"work_point must have shape (3,) or ({n}, 3), not {point.shape}")
        if not np.all(np.isfinite(point)):
            raise MachineDescriptionError("work_point is not finite")
        return np.broadcast_to(point, (n, 3))

    # ------------------------------------------------------------- the error
    def tcp_error(self, positions: Positions, *, first_order: bool = False,
                  overrides: ErrorOverrides | None = None,
                  check_stroke: bool = True, work_point: NDArray | None = None
                  ) -> dict[str, NDArray]:
        """TCP position and tool-orientation error from the matrix products.

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        first_order : bool, optional
            First-order error matrices (Kidani eq. 2.7) instead of the exact products.
        overrides : ErrorOverrides, optional
            Error values replacing or adding to the description's (none by default).
        check_stroke : bool, optional
            Refuse positions outside an axis' stroke.
        work_point : (3,) or (N, 3) [m], optional
            The workpiece-side point the error is taken at, in the workpiece frame
            (a fixed instrument target: an R-test or probed sphere). Default: the
            machining point (:meth:`machining_point`), so the nominal
            tool-to-work vector is zero.

        Returns
        -------
        dict with ``position`` (N, 3) [m] = (P_t - P_w)_actual - (P_t - P_w)_nominal
        (Kidani eq. 2.10) and ``orientation`` (N, 3) [rad], the rotation vector of
        the actual tool orientation relative to the workpiece against the nominal
        one, in the bed frame.

        Raises
        ------
        MachineDescriptionError
            Missing or unknown axes, arrays of different lengths, positions outside the
            stroke (``check_stroke``), or a malformed ``work_point``.
        """
        overrides = overrides or ErrorOverrides()
        q, n = self._positions(positions, check_stroke)
        # The nominal branches once: the machining point comes from them (checked once).
        args = (overrides, False)
        tool0_r, tool0_p = self._branch_rp("tool", q, False, False, *args)
        work0_r, work0_origin = self._branch_rp("workpiece", q, False, False, *args,
                                                np.zeros(3))
        if work_point is None:
            point = np.einsum("nji,nj->ni", work0_r, tool0_p - work0_origin)
        else:
            point = self._work_point(q, n, work_point)
        work0_p = work0_origin + np.einsum("nij,nj->ni", work0_r, point)
        tool_r, tool_p = self._branch_rp("tool", q, True, first_order, *args)
        work_r, work_p = self._branch_rp("workpiece", q, True, first_order, *args, point)
        position = (tool_p - work_p) - (tool0_p - work0_p)
        # Orientation error: (work rotation error)^T (tool rotation error), both as
        # R_actual R_nominal^T in the bed frame.
        tool_rot = tool_r @ np.swapaxes(tool0_r, 1, 2)
        work_rot = work_r @ np.swapaxes(work0_r, 1, 2)
        relative = np.swapaxes(work_rot, 1, 2) @ tool_rot
        return {"position": position, "orientation": rotation_vector(relative)}

    def tcp_error_linear(self, positions: Positions, *, overrides: ErrorOverrides | None = None,
                         check_stroke: bool = True, work_point: NDArray | None = None
                         ) -> dict[str, NDArray]:
        """First-order TCP error as a sum of joint error twists (independent of the matrices).

        For every error HTM in a branch, with R the nominal rotation of the frame
        it acts in and r the nominal vector from that frame's origin to the branch
        end point (both in the bed frame): dP = R d + (R eps) x r, dTheta = R eps.
        The workpiece branch enters with a minus sign; its end point is the
        machining point (the nominal tool point itself) unless ``work_point`` is
        given (see :meth:`tcp_error`).

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        overrides : ErrorOverrides, optional
            Error values replacing or adding to the description's (none by default).
        check_stroke : bool, optional
            Refuse positions outside an axis' stroke.
        work_point : array_like, shape (3,) or (N, 3), optional
            Workpiece-side point [m] in the workpiece frame the error is taken at
            (default: the machining point).

        Returns
        -------
        dict of str to ndarray
            ``position`` (N, 3) [m] and ``orientation`` (N, 3) [rad], bed frame, to first
            order in the errors.
        """
        overrides = overrides or ErrorOverrides()
        q, n = self._positions(positions, check_stroke)
        position = np.zeros((n, 3))
        orientation = np.zeros((n, 3))
        tool_end = self.branch("tool", q, errors=False, check_stroke=False)[:, :3, 3]
        for which, sign in (("tool", 1.0), ("workpiece", -1.0)):
            axes = self.machine.tool_branch if which == "tool" else self.machine.workpiece_branch
            if which == "tool" or work_point is None:
                end = tool_end
            else:
                end = self.branch("workpiece", q, errors=False, check_stroke=False,
                                  end_point=self._work_point(q, n, work_point))[:, :3, 3]
            # (frame, twist) pairs in chain order, frames nominal.
            frames_and_twists = []
            frame = identity((n,))
            thermal = self._thermal("bed_tool" if which == "tool" else "bed_work", n, overrides)
            if thermal is not None:
                frames_and_twists.append((frame.copy(), thermal))
            parent_offset = np.zeros(3)
            for axis in axes:
                frame = frame @ translation(*parent_offset)
                location = self.location_errors(axis, n, overrides)
                frames_and_twists.append((frame.copy(), location))
                if self.machine.axes[axis].is_rotary:
                    # Turning about the actual line from the set-up pose: the twist, and
                    # its opposite in the frame turned by q - q_s (chain docstring).
                    frames_and_twists.append((frame @ self._turn_from_setup(axis, q[axis]),
                                              -location))
                frame = frame @ self._motion(axis, q[axis])
                frames_and_twists.append((frame.copy(), self.motion_errors(axis, q[axis],
                                                                           overrides)))
                thermal = self._thermal(axis, n, overrides)
                if thermal is not None:
                    frames_and_twists.append((frame.copy(), thermal))
                parent_offset = self.machine.axes[axis].offset
            for frame, twist in frames_and_twists:
                rot = frame[:, :3, :3]
                d = np.einsum("nij,nj->ni", rot, twist[:, :3])
                eps = np.einsum("nij,nj->ni", rot, twist[:, 3:])
                lever = end - frame[:, :3, 3]
                position += sign * (d + cross(eps, lever))
                orientation += sign * eps
        return {"position": position, "orientation": orientation}

    def error_frames(self, positions: Positions, check_stroke: bool = False,
                     work_point: NDArray | None = None
                     ) -> dict[str, tuple[float, NDArray, NDArray]]:
        """Where every motion and location error acts: name -> (sign, R, lever).

        ``R`` (N, 3, 3) is the nominal rotation of the frame the error twist acts
        in, ``lever`` (N, 3) [m] the nominal vector from that frame's origin to
        the branch end point, both in the bed frame, and ``sign`` +1 for the
        tool branch, -1 for the workpiece branch. The workpiece branch ends at
        the machining point (the nominal tool point), or at ``work_point`` when
        given (see :meth:`tcp_error`). A unit error in component c
        then moves the TCP by ``sign * R[:, :, c]`` (translations) or
        ``sign * (R[:, :, c-3] x lever)`` (rotations): the same first-order
        terms as :meth:`tcp_error_linear`, so a sensitivity costs one cross
        product instead of a chain of matrix products. Frames of linear axes
        share one rotation array (a linear motion does not turn the frame).

        A rotary axis' location error turns its body about the actual line from
        the set-up pose (ISO 230-7), so its ``R`` is ``R_p (I - R(q - q_s))``,
        R_p the frame before the turn: not a rotation, but the consumers above
        take its columns linearly. Its zero error (EC0C for C) and the offset along
        its own line then move nothing: the set-up takes them out.

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        check_stroke : bool, optional
            Refuse positions outside an axis' stroke.
        work_point : array_like, shape (3,) or (N, 3), optional
            Workpiece-side point [m] in the workpiece frame the error is taken at
            (default: the machining point).

        Returns
        -------
        dict of str to tuple of (float, ndarray, ndarray)
            Every motion and location error name of every axis -> (sign, R shape (N, 3, 3),
            lever shape (N, 3) [m]).
        """
        q, n = self._positions(positions, check_stroke)
        frames: dict[str, tuple[float, NDArray, NDArray]] = {}
        tool_end = None
        for which, sign in (("tool", 1.0), ("workpiece", -1.0)):
            axes = self.machine.tool_branch if which == "tool" else self.machine.workpiece_branch
            rot = np.broadcast_to(np.eye(3), (n, 3, 3))
            pos = np.zeros((n, 3))
            origins = []
            parent_offset = np.zeros(3)
            for axis in axes:
                pos = pos + rot @ parent_offset
                spec = self.machine.axes[axis]
                if spec.is_rotary:
                    # A unit location error acts as R (I - R(q - q_s)): not a rotation,
                    # but every consumer takes its columns linearly (see the docstring).
                    turned = self._turn_from_setup(axis, q[axis])[:, :3, :3]
                    origins.append((axis, "location", rot - rot @ turned, pos))
                else:
                    origins.append((axis, "location", rot, pos))
                if spec.is_rotary:
                    rot = rot @ rotation("xyz"[spec.direction], spec.sign * q[axis])[:, :3, :3]
                else:
                    pos = pos + rot[:, :, spec.direction] * (spec.sign * q[axis])[:, None]
                origins.append((axis, "motion", rot, pos))
                parent_offset = spec.offset
            if which == "tool":
                end = pos + rot @ (parent_offset + self.machine.tool)
                tool_end = end
            elif work_point is None:
                end = tool_end
            else:
                point = self._work_point(q, n, work_point)
                end = pos + rot @ parent_offset + np.einsum("nij,nj->ni", rot, point)
            for axis, kind, frame_rot, origin in origins:
                name_of = location_error_name if kind == "location" else motion_error_name
                lever = end - origin
                for component in COMPONENTS:
                    frames[name_of(component, axis)] = (sign, frame_rot, lever)
        return frames

    def located_sensitivities(self, positions: Positions, names: list[str],
                              work_point: NDArray | None = None
                              ) -> dict[str, tuple[NDArray, NDArray]]:
        """What an instrument located at the set-up reads of unit location errors.

        A sphere (an R-test's, a probed one) is located at the set-up pose by a
        translation of the workpiece frame - a sphere has no orientation to find - and,
        when the head carries rotary axes, the tool by a translation of the tool frame
        (ISO 10791-6). A rotary body turns about its actual line by its command (ISO
        230-7, ``L R(q) L^-1``: no set-up in the turn), so a unit error moving the
        target by s(q) (position, bed frame) and the tool's direction by du(q) reads

            s(q) - R_S(q) R_S(q_s)^T s(q_s),   du(q) - R_S(q) R_S(q_s)^T du(q_s)

        with R_S the nominal rotation of the located side's end frame (the tool's for an
        error of a head that carries rotary axes, else the workpiece's). For the last
        axis of a side this is :meth:`error_frames`' ``R_p (I - R(q - q_s))``; for an outer
        axis whose inner axes leave their set-up, and for the tool's direction, it is not
        (the set-up moved the target, not the body: the body's tilt at the set-up stays).

        Parameters
        ----------
        positions : axis -> (N,) commands [m, rad]
        names : location error names (``EX0C``, ``EA0B`` ...)
        work_point : (3,) or (N, 3) [m], optional
            The target, workpiece frame (default: the machining point of each reading,
            located where it is at the set-up).

        Returns
        -------
        name -> (position (N, 3) [m per unit], orientation (N, 3) [rad per unit]): the
        orientation is the body's turn less the located change's turn across the tool
        axis, u x R_S R_S(q_s)^T du(q_s) (what an instrument sees is its part across u).
        The linear axes keep the readings' commands at the set-up (they do not turn a
        side's frame; an arm they lengthen downstream of a rotary axis is neglected).
        """
        q, n = self._positions(positions, False)
        raw = KinematicModel(replace(self.machine, setup_pose={}))
        setup = {a: np.full(n, self.machine.setup_angle(a)) if self.machine.axes[a].is_rotary
                 else q[a] for a in self.machine.axis_order}
        point = self._machining_point(q) if work_point is None else \
            self._work_point(q, n, work_point)
        frames = raw.error_frames(q, work_point=point)
        at_setup = raw.error_frames(setup, work_point=point)
        turned = {}
        for side in ("tool", "workpiece"):
            now = raw.branch(side, q, errors=False, check_stroke=False)[:, :3, :3]
            then = raw.branch(side, setup, errors=False, check_stroke=False)[:, :3, :3]
            turned[side] = now @ np.swapaxes(then, 1, 2)
        tool_axis, tool_axis_setup = raw.tool_axis(q), raw.tool_axis(setup)
        head = any(self.machine.axes[a].is_rotary for a in self.machine.tool_branch)
        out = {}
        for name in names:
            axis = name[3]
            side = "tool" if head and axis in self.machine.tool_branch else "workpiece"
            # A zero error (EC0C) turns the body to q + e about its line (ISO 230-7): the
            # axis' constant angular positioning error, which a turn about the line itself
            # (L R L^-1, L about the line) cannot make.
            source = motion_error_name(axis, axis) if name[1] == axis else name
            moved = _unit_motion(frames[source], source)
            moved_then = _unit_motion(at_setup[source], source)
            position = moved[0] - np.einsum("nij,nj->ni", turned[side], moved_then[0])
            # The direction's change at the set-up, located with the side: its turn across
            # the tool axis comes off the body's own turn (kept whole: at a set-up where the
            # line errors move nothing, the chain's).
            located = np.einsum("nij,nj->ni", turned[side],
                                cross(moved_then[1], tool_axis_setup))
            out[name] = (position, moved[1] - cross(tool_axis, located))
        return out

    def _turn_from_setup(self, axis: str, q: NDArray) -> NDArray:
        """(N, 4, 4) the nominal turn of rotary ``axis`` from its set-up command to ``q``."""
        spec = self.machine.axes[axis]
        return rotation("xyz"[spec.direction], spec.sign * (q - self.machine.setup_angle(axis)))

    def tool_axis(self, positions: Positions) -> NDArray:
        """(N, 3) unit vector of the tool axis in the bed frame, nominal chain (the tool
        vector's direction; +z of the spindle frame for a zero tool vector).

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.

        Returns
        -------
        ndarray, shape (N, 3)
            Unit vectors (dimensionless), bed frame.
        """
        tool = self.branch("tool", positions, errors=False, check_stroke=False)
        vector = np.asarray(self.machine.tool, dtype=np.float64)
        norm = float(np.linalg.norm(vector))
        local = vector / norm if norm > 0 else np.array([0.0, 0.0, 1.0])
        return tool[:, :3, :3] @ local

    def nominal_relative(self, positions: Positions, check_stroke: bool = False,
                         work_point: NDArray | None = None) -> NDArray:
        """(N, 3) nominal tool point relative to a workpiece point, bed frame.

        The point is the description's workpiece reference point (the work
        offset) or ``work_point`` ((3,) or (N, 3) [m], workpiece frame): the
        commanded geometry, whose derivative maps axis moves to TCP moves.

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        check_stroke : bool, optional
            Refuse positions outside an axis' stroke.
        work_point : array_like, shape (3,) or (N, 3), optional
            Workpiece point [m], workpiece frame (default: the description's ``workpiece``).

        Returns
        -------
        ndarray, shape (N, 3)
            Nominal tool point minus workpiece point [m], bed frame.
        """
        q, n = self._positions(positions, check_stroke)
        point = None if work_point is None else self._work_point(q, n, work_point)
        none = ErrorOverrides()
        _, tool0 = self._branch_rp("tool", q, False, False, none, False)
        _, work0 = self._branch_rp("workpiece", q, False, False, none, False, point)
        return tool0 - work0

    # ----------------------------------------------------------- compensation
    def compensate(self, positions: Positions, *, iterations: int = 4,
                   overrides: ErrorOverrides | None = None) -> dict[str, object]:
        """Modified linear-axis commands that cancel the TCP position error.

        One step is Kidani eq. 2.2, p2 = p1 - e(p1), mapped to the axes through
        the nominal kinematics; further steps evaluate e at the modified command
        (the error varies with position): p_{i+1} = p1 - e(p_i). Rotary axes
        keep their commands here (see :meth:`compensate_orientation`).

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        iterations : int, optional
            Number of fixed-point steps (at least one).
        overrides : ErrorOverrides, optional
            Error values replacing or adding to the description's (none by default).

        Returns
        -------
        dict: ``positions`` (corrected commands), ``residual`` (N, 3) TCP error
        left after compensation [m], ``initial`` (N, 3) the error before [m].

        Raises
        ------
        MachineDescriptionError
            Positions outside the stroke, or a machine without exactly three linear axes.
        """
        q, n = self._positions(positions, check_stroke=True)
        linear = [a for a in self.machine.axis_order if not self.machine.axes[a].is_rotary]
        # The material to cut stays the one nominally under the tool at the command.
        point = self._machining_point(q)
        jacobian = self._linear_jacobian(q, linear)
        initial = self.tcp_error(q, overrides=overrides, check_stroke=False,
                                 work_point=point)["position"]
        current = dict(q)

        def off_target(command):
            return self.nominal_relative(command, work_point=point) + self.tcp_error(
                command, overrides=overrides, check_stroke=False, work_point=point)["position"]

        for _ in range(max(1, int(iterations))):
            step = np.linalg.solve(jacobian, (-off_target(current))[..., None])[..., 0]
            for i, axis in enumerate(linear):
                current[axis] = current[axis] + step[:, i]
        return {"positions": current, "residual": off_target(current), "initial": initial}

    def _linear_jacobian(self, q: Positions, linear: list[str]) -> NDArray:
        if len(linear) != 3:
            raise MachineDescriptionError("position compensation needs exactly three linear axes")
        base = self.nominal_relative(q)
        jac = np.empty((base.shape[0], 3, 3))
        for i, axis in enumerate(linear):
            shifted = dict(q)
            shifted[axis] = q[axis] + 1e-3
            jac[:, :, i] = (self.nominal_relative(shifted) - base) / 1e-3
        return jac

    def compensate_orientation(self, positions: Positions, *, iterations: int = 3,
                               overrides: ErrorOverrides | None = None) -> dict[str, object]:
        """Rotary-axis corrections that cancel the tool-orientation error where possible.

        The tool orientation relative to the workpiece, R_rel = R_w^T R_t, is
        driven back to its nominal value at the original command by least squares
        on the numeric Jacobian of the nominal R_rel w.r.t. the rotary axes;
        components no rotary axis can produce (e.g. a rotation about the tool
        axis) remain in ``residual`` (rotation vectors in the workpiece frame [rad]).

        Parameters
        ----------
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]), every axis of the machine.
        iterations : int, optional
            Number of Gauss-Newton steps (at least one).
        overrides : ErrorOverrides, optional
            Error values replacing or adding to the description's (none by default).

        Returns
        -------
        dict
            ``positions`` (corrected commands, dict of str to ndarray (N,), [m] / [rad]),
            ``initial`` and ``residual`` (N, 3) orientation errors [rad] before and after.

        Raises
        ------
        MachineDescriptionError
            Positions outside the stroke, or a machine without a rotary axis.
        """
        q, n = self._positions(positions, check_stroke=True)
        rotary = [a for a in self.machine.axis_order if self.machine.axes[a].is_rotary]
        if not rotary:
            raise MachineDescriptionError("this machine has no rotary axis to correct orientation")
        target = self._relative_rotation(q, errors=False)

        def error_at(command):
            actual = self._relative_rotation(command, errors=True, overrides=overrides)
            return rotation_vector(actual @ np.swapaxes(target, 1, 2))

        initial = error_at(q)
        current = dict(q)
        for _ in range(max(1, int(iterations))):
            error = error_at(current)
            base = self._relative_rotation(current, errors=False)
            jac = np.empty((n, 3, len(rotary)))
            for i, axis in enumerate(rotary):
                nudged = dict(current)
                nudged[axis] = current[axis] + 1e-6
                moved = self._relative_rotation(nudged, errors=False) @ np.swapaxes(base, 1, 2)
                jac[:, :, i] = rotation_vector(moved) / 1e-6
            step = np.stack([np.linalg.lstsq(jac[k], -error[k], rcond=None)[0] for k in range(n)])
            for i, axis in enumerate(rotary):
                current[axis] = current[axis] + step[:, i]
        return {"positions": current, "initial": initial, "residual": error_at(current)}

    def _relative_rotation(self, q: Positions, errors: bool = False,
                           overrides: ErrorOverrides | None = None) -> NDArray:
        """R_w^T R_t: tool orientation in the workpiece frame, (N, 3, 3)."""
        tool = self.branch("tool", q, errors=errors, overrides=overrides, check_stroke=False)
        work = self.branch("workpiece", q, errors=errors, overrides=overrides, check_stroke=False)
        return np.swapaxes(work[:, :3, :3], 1, 2) @ tool[:, :3, :3]

    # ------------------------------------------------------------- inventory
    def error_inventory(self) -> dict[str, list[str]]:
        """Potential and considered error parameters (Khan & Chen section 5).

        Potential: six position-dependent errors per joint; location errors of
        each joint (linear: two orientations and the zero position; rotary: two
        positions, two orientations and the zero angle); three of the machine
        coordinate system. Considered: every position-dependent error plus the
        location errors the description declares.
        """
        potential: list[str] = []
        considered: list[str] = []
        for axis in self.machine.axis_order:
            spec = self.machine.axes[axis]
            names = [motion_error_name(c, axis) for c in COMPONENTS]
            potential += names
            considered += names
            direction = "XYZ"[spec.direction]
            others = [c for c in "XYZ" if c != direction]
            rot_of = {"X": "A", "Y": "B", "Z": "C"}
            if spec.is_rotary:
                location = ([location_error_name(c, axis) for c in others]
                            + [location_error_name(rot_of[c], axis) for c in others]
                            + [location_error_name(rot_of[direction], axis)])
            else:
                location = ([location_error_name(rot_of[c], axis) for c in others]
                            + [location_error_name(direction, axis)])
            potential += location
            considered += [location_error_name(c, axis) for c in spec.location_errors]
        potential += ["machine coordinate system: " + n for n in ("EA0M", "EB0M", "EC0M")]
        return {"potential": potential, "considered": considered}


def _unit_motion(frame: tuple[float, NDArray, NDArray], name: str) -> tuple[NDArray, NDArray]:
    """(position (N, 3), orientation (N, 3)) a unit error ``name`` gives through its
    :meth:`KinematicModel.error_frames` entry (sign, R, lever)."""
    sign, rotation, lever = frame
    component = COMPONENTS.index(name[1])
    if component < 3:
        return sign * rotation[:, :, component], np.zeros_like(lever)
    turn = sign * rotation[:, :, component - 3]
    return cross(turn, lever), turn


def volumetric_map(model: KinematicModel, positions: Positions, *, chunk: int = 100_000,
                   overrides_factory=None, first_order: bool = False) -> dict[str, NDArray]:
    """TCP position and orientation errors at many configurations, in chunks.

    ``positions`` maps each axis to an (N,) array. Chunks bound the memory of the
    (chunk, 4, 4) temporaries. ``overrides_factory(slice)`` may return the
    :class:`ErrorOverrides` for a chunk.

    Parameters
    ----------
    model : KinematicModel
        The model.
    positions : dict of str to ndarray, shape (N,)
        Axis commands [m] (rotary [rad]).
    chunk : int, optional
        Configurations per chunk.
    overrides_factory : callable, optional
        ``slice -> ErrorOverrides or None`` for each chunk.
    first_order : bool, optional
        First-order error matrices instead of the exact products.

    Returns
    -------
    dict of str to ndarray
        ``position`` (N, 3) [m] and ``orientation`` (N, 3) [rad], as
        :meth:`KinematicModel.tcp_error`.
    """
    n = len(next(iter(positions.values())))
    position = np.empty((n, 3))
    orientation = np.empty((n, 3))
    for start in range(0, n, chunk):
        part = slice(start, min(n, start + chunk))
        overrides = overrides_factory(part) if overrides_factory else None
        out = model.tcp_error({a: np.asarray(v)[part] for a, v in positions.items()},
                              overrides=overrides, first_order=first_order)
        position[part] = out["position"]
        orientation[part] = out["orientation"]
    return {"position": position, "orientation": orientation}
