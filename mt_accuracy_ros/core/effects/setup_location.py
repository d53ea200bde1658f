"""Where the work or the tool was located at the set-up: an error that turns with it.

An R-test's sphere, a probed sphere or a part is *located* at the set-up pose (ISO
10791-6; a probing cycle of the KinematicsOpt kind): the machine's own error there - its
linear axes' errors at that position, the tool's length as it was measured - goes into
where the sphere (or the tool) is believed to be. That belief is a point of the
workpiece frame (of the tool frame, when the head carries rotary axes and the tool was
set up in it), so what it holds turns with the rotary axes of that side. With the error
v it absorbed (bed frame, at the set-up pose), the instrument then reads, besides the
changes the other effects give,

    e(q) = (I - R_S(q) R_S(q_s)^T) v                      (ISO 10791-6 set-up; zero at q_s)

R_S the nominal rotation of the side's last frame (workpiece or tool) in the bed frame.
An instrument that measures the tool's direction (two spheres) located that too: its
change w at the set-up is read as du(q) = -R_S(q) R_S(q_s)^T w (the direction rows are
absolute, so the constant is not taken out). The workbench's other effects are known only
up to a constant (an instrument has no zero
of its own): their value at the set-up, which this term carries, is not. So it is a
candidate of its own, never forced: on the poses surveyed it moves the readings as the
line offsets of that side's rotary axes do (both turn with them), and the output says so
when both could be named (:mod:`mt_accuracy_ros.core.workbench.separability`).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .base import Context, EffectFamily

#: The sides a located point can belong to, and the branch whose end frame it turns with.
_BRANCH = {"work": "workpiece", "tool": "tool"}


def side_rotations(ctx: Context, side: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """((N, 3, 3) R_S(q) at the readings, (3, 3) R_S(q_s) at the set-up pose): the nominal
    rotation of the ``side``'s end frame in the bed frame (linear axes do not turn it).

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings (the result is kept in its cache).
    side : str
        ``work`` or ``tool``.

    Returns
    -------
    tuple of ndarray
        R_S(q), shape (N, 3, 3), and R_S(q_s), shape (3, 3): rotations, dimensionless.
    """
    key = ("side_rotations", side)
    if key not in ctx.cache:
        machine = ctx.machine
        positions = {a: ctx.variables.positions[a] for a in machine.axis_order}
        setup = {a: np.array([machine.setup_angle(a) if machine.axes[a].is_rotary else 0.0])
                 for a in machine.axis_order}
        branch = _BRANCH[side]
        turned = ctx.kinematics.branch(branch, positions, errors=False,
                                       check_stroke=False)[:, :3, :3]
        at_setup = ctx.kinematics.branch(branch, setup, errors=False,
                                         check_stroke=False)[0, :3, :3]
        ctx.cache[key] = (turned, at_setup)
    return ctx.cache[key]


def located_design(ctx: Context, side: str) -> NDArray[np.float64]:
    """(N, 3, 3) [m per m]: the readings' change per component of v, (I - R_S R_S(q_s)^T).

    Parameters
    ----------
    ctx : Context
        The machine and the variables at the N readings.
    side : str
        ``work`` or ``tool``.

    Returns
    -------
    ndarray, shape (N, 3, 3)
        TCP reading's change [m] per component of v [m], bed frame (ISO 10791-6 set-up).
    """
    turned, at_setup = side_rotations(ctx, side)
    return np.eye(3)[None] - turned @ at_setup.T


class SetupLocation(EffectFamily):
    """The machine's error at the set-up, located into the work (or the tool) and turning
    with it (module docstring)."""

    name = "setup_location"
    group = "rotary"
    # As much as a rotary axis' line offsets together: the same circles, fewer parameters.
    complexity = 2
    summary = ("the machine's error where the work (or the tool) was set up, located into "
               "it and turning with its rotary axes")
    reference = "ISO 10791-6 (R-test set-up); ISO 230-7 (rotary axes' location)"

    def variants(self, ctx: Context) -> list[str]:
        """The sides whose branch holds a rotary axis that moved.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ``work`` and/or ``tool``.
        """
        machine = ctx.machine
        out = []
        # The work side turns with its rotary axes; the tool's own set-up matters only when
        # the head carries rotary axes (else what it absorbed is located in the work).
        for side, axes in (("work", machine.workpiece_branch), ("tool", machine.tool_branch)):
            if any(machine.axes[a].is_rotary and ctx.moves(a) for a in axes):
                out.append(side)
        return out

    def settings(self, ctx: Context, variant: str) -> list[dict]:
        # An instrument that measured the tool's direction located it too (two spheres).
        """``{"direction": True}`` when the instrument measured the tool's direction, else empty.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The side.

        Returns
        -------
        list of dict
            The one setting.
        """
        return [{"direction": True}] if ctx.orientation_lever_m is not None else [{}]

    def parameter_names(self, variant: str, setting: dict) -> list[str]:
        """v, and w when the direction was located too.

        Parameters
        ----------
        variant : str
            The side, ``work`` or ``tool`` (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``v_x, v_y, v_z`` [m] and, with ``direction``, ``w_x, w_y, w_z`` (change of the
            tool's unit direction, dimensionless ~ [rad]).
        """
        return ["v_x", "v_y", "v_z"] + (["w_x", "w_y", "w_z"] if setting.get("direction")
                                        else [])

    def parameter_limits(self, ctx: Context, variant: str, setting: dict
                         ) -> dict[str, tuple[float, str]]:
        """The machine's own error where it was set up is no larger than the largest
        squareness any machine has over its reach: v within LARGEST_SQUARENESS_RAD times
        :func:`~.geometric.machine_reach` [m], w within LARGEST_SQUARENESS_RAD. A fit
        beyond is a direction the poses barely see (the located error along the rotary
        axes' own lines), its number the noise divided by a vanishing column.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The side, ``work`` or ``tool``.
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        dict of str to tuple of (float, str)
            Name -> (bound [m] or [rad], reason).
        """
        from .geometric import LARGEST_SQUARENESS_RAD, machine_reach  # (imports this module)

        reach = machine_reach(ctx)
        moved = (LARGEST_SQUARENESS_RAD * reach,
                 f"the machine's error at the set-up, at most {LARGEST_SQUARENESS_RAD * 1e3:g} "
                 f"mm per metre of its {reach:.2f} m reach")
        turned = (LARGEST_SQUARENESS_RAD, "the tool's direction at the set-up, turned by at "
                                          "most the largest squareness of any machine")
        return {name: turned if name.startswith("w_") else moved
                for name in self.parameter_names(variant, setting)}

    def design(self, ctx: Context, variant: str, setting: dict) -> NDArray[np.float64]:
        """(I - R_S R_S(q_s)^T) on v; w moves no TCP position.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The side, ``work`` or ``tool`` (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, P)
            TCP error [m] per parameter (P = 3, or 6 with zero columns for w), bed frame.
        """
        design = located_design(ctx, variant)
        if setting.get("direction"):
            design = np.concatenate([design, np.zeros_like(design)], axis=2)
        return design

    def orientation_design(self, ctx: Context, variant: str, setting: dict
                           ) -> NDArray[np.float64] | None:
        """The tool direction's turn u x du, du = -R_S R_S(q_s)^T w, when the direction was located.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The side, ``work`` or ``tool`` (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, 6), or None
            Tool-orientation error [rad] per parameter (zero columns for v), bed frame; None
            without ``direction``.
        """
        if not setting.get("direction"):
            return None
        # The tool direction's change w at the set-up (bed frame), located with it: the
        # instrument reads du(q) - R_S R_S(q_s)^T w, a turn u x du across the tool axis.
        turned, at_setup = side_rotations(ctx, variant)
        change = -(turned @ at_setup.T)
        axis = ctx.tool_axis()
        turn = np.cross(axis[:, :, None], change, axisa=1, axisb=1, axisc=1)
        return np.concatenate([np.zeros_like(turn), turn], axis=2)

    def explanation(self, variant: str, setting: dict) -> str:
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The side, ``work`` or ``tool`` (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        what = "the work (the sphere or part)" if variant == "work" else "the tool"
        return (f"{what} was located at the set-up pose with the machine's own error there "
                "(v, bed frame), and that error turns with the "
                f"{'table' if variant == 'work' else 'head'}'s rotary axes "
                "(ISO 10791-6 set-up)")


def families() -> list[EffectFamily]:
    """The family of this module, newly made.

    Returns
    -------
    list of EffectFamily
        :class:`SetupLocation`.
    """
    return [SetupLocation()]
