"""One context for every look at the same readings: its designs are built once, not once
per look.

``check --auto`` looks at a survey twice: once with the model as given, once with the
named effects added. Both looks see the same readings through the same nominal chain,
so every candidate's design is the same in both: the kinematic sensitivities
(:meth:`Context.jacobian`), the families' bases in ``Context.cache`` and what the
selection derives from them (:class:`~.selection.Selector`'s designs, their products
with themselves, where each term acts). Only the residual differs. A
:class:`ContextMemo` hands the second look the first look's :class:`Context` when
everything a design depends on is equal; anything else gets a new context.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..effects.base import Context
from ..effects.variables import Variables
from ..kinematics.chain import KinematicModel
from ..kinematics.machine import MachineDescription


def _same_array(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and bool(np.array_equal(a, b))


def _same_arrays(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(_same_array(a[k], b[k]) for k in a)


def same_variables(a: Variables, b: Variables) -> bool:
    """Do ``a`` and ``b`` hold the same readings (every array equal, the same reference
    temperatures and runs)? Live lag states are never shared.

    Parameters
    ----------
    a, b : Variables
        The two sets of readings.

    Returns
    -------
    bool
        True when every array and setting is equal and neither keeps live lag states.
    """
    if a is b:
        return a.lag_states is None
    return (a.lag_states is None and b.lag_states is None and a.n == b.n and
            _same_arrays(a.positions, b.positions) and
            _same_arrays(a.velocities, b.velocities) and
            _same_arrays(a.accelerations, b.accelerations) and
            _same_arrays(a.directions, b.directions) and
            _same_arrays(a.temperatures, b.temperatures) and
            a.reference_temperatures_c == b.reference_temperatures_c and
            _same_array(a.time_s, b.time_s) and
            _same_array(a.spindle_speed_rad_s, b.spindle_speed_rad_s) and
            _same_array(a.run_starts, b.run_starts))


class ContextMemo:
    """The last context built for a set of readings, handed out again when asked for the
    same readings on the same machine (see the module docstring)."""

    def __init__(self) -> None:
        self._kept: tuple | None = None
        #: How many contexts were served from the memo (for tests and benches).
        self.reused = 0

    def context(self, machine: MachineDescription, variables: Variables,
                kinematics: KinematicModel, orientation: NDArray[np.float64] | None, *,
                orientation_lever_m: float | None,
                work_point: NDArray[np.float64] | None,
                zero_rows: NDArray[np.intp] | None, located_readings: bool = False
                ) -> Context:
        """A :class:`Context` of these arguments: the kept one if they are the kept
        context's (the machine the same object, every array equal), else a new one.

        Parameters
        ----------
        machine : MachineDescription
            The machine (compared by identity).
        variables : Variables
            The N readings.
        kinematics : KinematicModel
            The nominal chain of ``machine``.
        orientation : ndarray, shape (N, 3), or None
            The model's tool-orientation error [rad].
        orientation_lever_m : float or None
            Set when the readings measured the tool's direction: the instrument's
            position noise over its direction noise [m per rad].
        work_point : ndarray, shape (3,) or (N, 3), or None
            Fixed target [m], workpiece frame.
        zero_rows : ndarray of int, shape (N,), or None
            The row each reading's instrument was zeroed at.
        located_readings : bool, optional
            An instrument's readings, located at the set-up (:class:`Context`).

        Returns
        -------
        Context
            The kept context or a new one (then kept).
        """
        if self._kept is not None:
            ctx = self._kept
            if (ctx.machine is machine and ctx.kinematics.machine is machine and
                    same_variables(ctx.variables, variables) and
                    _same_array(ctx.orientation, orientation) and
                    ctx.orientation_lever_m == orientation_lever_m and
                    _same_array(ctx.work_point, work_point) and
                    _same_array(ctx.zero_rows, zero_rows) and
                    ctx.located_readings == located_readings):
                self.reused += 1
                return ctx
        ctx = Context(machine, variables, kinematics, orientation,
                      orientation_lever_m=orientation_lever_m, work_point=work_point,
                      zero_rows=zero_rows, located_readings=located_readings)
        self._kept = ctx
        return ctx
