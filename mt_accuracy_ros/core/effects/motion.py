"""Motion effect families, per axis: backlash, servo lag, acceleration.

* ``reversal`` - lost motion at a reversal (backlash, Kidani's reversal value
  B of ISO 230-2): the axis stands b/2 short in the direction it last moved,
  e = -dir b / 2 along the axis.
* ``servo_lag`` - following error of the position loop, e = -v tau along the
  axis (tau = 1 / K_v).
* ``acceleration`` - inertial deflection of the structure under the axis'
  acceleration, e = c a, in every direction (a column tilting as it starts).
"""
from __future__ import annotations

import numpy as np

from ..errors import InputDataError
from .base import EffectFamily, per_component


class Reversal(EffectFamily):
    """Backlash: lost motion at a reversal, e = -dir b / 2 along the axis."""

    name = "reversal"
    group = "motion"
    complexity = 1
    summary = "backlash: the error jumps with the direction of motion"
    reference = "ISO 230-2 reversal value; Kidani section 2.4"

    def variants(self, ctx):
        """The linear axes that moved and whose velocity or direction of motion is known.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Axis letters.
        """
        return [a for a in ctx.linear_axes(moving=True) if a in ctx.variables.velocities or
                a in ctx.variables.directions]

    def parameter_names(self, variant, setting):
        """The reversal value B.

        Parameters
        ----------
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        list of str
            ``backlash_m`` [m].
        """
        return ["backlash_m"]

    def design(self, ctx, variant, setting):
        """-dir / 2 along the axis' positioning error EXX (ISO 230-2 reversal value).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        ndarray, shape (N, 3, 1)
            TCP error [m] per backlash [m]: the sensitivity to E<axis><axis> [m/m]
            times -dir / 2 (dir +1 / -1 / 0, dimensionless).
        """
        shift = -0.5 * ctx.variables.direction(variant)
        return (ctx.jacobian(f"E{variant}{variant}") * shift[:, None])[:, :, None]

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        str
            The sentence.
        """
        return (f"the residual jumps with the direction of {variant} motion - backlash in the "
                f"{variant} drive")


class ServoLag(EffectFamily):
    """Following error of the position loop, e = -v tau along the axis."""

    name = "servo_lag"
    group = "motion"
    complexity = 1
    summary = "following error: the error is proportional to the feed"
    reference = "position-loop following error, tau = 1/K_v"

    def variants(self, ctx):
        """The linear axes that moved with a known, not all zero velocity.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Axis letters.
        """
        return [a for a in ctx.linear_axes(moving=True) if a in ctx.variables.velocities and
                np.any(ctx.variables.velocities[a])]

    def parameter_names(self, variant, setting):
        """The lag tau = 1 / K_v.

        Parameters
        ----------
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        list of str
            ``lag_s`` [s].
        """
        return ["lag_s"]

    def design(self, ctx, variant, setting):
        """-v along the axis' positioning error EXX (following error e = -v tau).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        ndarray, shape (N, 3, 1)
            TCP error [m] per lag [s]: the sensitivity to E<axis><axis> [m/m]
            times -v [m/s].
        """
        shift = -ctx.variables.velocity(variant)
        return (ctx.jacobian(f"E{variant}{variant}") * shift[:, None])[:, :, None]

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        str
            The sentence.
        """
        return (f"the residual is proportional to the {variant} feed speed - following error "
                "of its position loop")


class Acceleration(EffectFamily):
    """Inertial deflection under an axis' acceleration, e = c a."""

    name = "acceleration"
    group = "motion"
    complexity = 1
    summary = "inertial deflection: the error follows an axis' acceleration"
    reference = "structure compliance under inertial load"

    def variants(self, ctx):
        """The linear axes with a known, not all zero acceleration (given, or from velocities
        and times).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Axis letters.
        """
        out = []
        for axis in ctx.linear_axes():
            try:
                if np.any(ctx.variables.acceleration(axis)):
                    out.append(axis)
            except InputDataError:  # no velocities or times: no acceleration variant
                continue
        return out

    def parameter_names(self, variant, setting):
        """A compliance per TCP direction.

        Parameters
        ----------
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        list of str
            ``cx_s2, cy_s2, cz_s2`` [s^2] (TCP error [m] per [m/s^2]).
        """
        return ["cx_s2", "cy_s2", "cz_s2"]

    def design(self, ctx, variant, setting):
        """The axis' acceleration on x, y and z (e = c a).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        ndarray, shape (N, 3, 3)
            Acceleration [m/s^2]: TCP error [m] per compliance [s^2].
        """
        return per_component(ctx.variables.acceleration(variant))

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The axis (one of :meth:`variants`).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        str
            The sentence.
        """
        return (f"the residual follows the {variant} acceleration - the structure deflects "
                "under the axis' inertial load")


def families():
    """The motion families of this module, newly made.

    Returns
    -------
    list of EffectFamily
        :class:`Reversal`, :class:`ServoLag` and :class:`Acceleration`.
    """
    return [Reversal(), ServoLag(), Acceleration()]
