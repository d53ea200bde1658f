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
    name = "reversal"
    group = "motion"
    complexity = 1
    summary = "backlash: the error jumps with the direction of motion"
    reference = "ISO 230-2 reversal value; Kidani section 2.4"

    def variants(self, ctx):
        return [a for a in ctx.linear_axes(moving=True) if a in ctx.variables.velocities or
                a in ctx.variables.directions]

    def parameter_names(self, variant, setting):
        return ["backlash_m"]

    def design(self, ctx, variant, setting):
        shift = -0.5 * ctx.variables.direction(variant)
        return (ctx.jacobian(f"E{variant}{variant}") * shift[:, None])[:, :, None]

    def explanation(self, variant, setting):
        return (f"the residual jumps with the direction of {variant} motion - backlash in the "
                f"{variant} drive")


class ServoLag(EffectFamily):
    name = "servo_lag"
    group = "motion"
    complexity = 1
    summary = "following error: the error is proportional to the feed"
    reference = "position-loop following error, tau = 1/K_v"

    def variants(self, ctx):
        return [a for a in ctx.linear_axes(moving=True) if a in ctx.variables.velocities and
                np.any(ctx.variables.velocities[a])]

    def parameter_names(self, variant, setting):
        return ["lag_s"]

    def design(self, ctx, variant, setting):
        shift = -ctx.variables.velocity(variant)
        return (ctx.jacobian(f"E{variant}{variant}") * shift[:, None])[:, :, None]

    def explanation(self, variant, setting):
        return (f"the residual is proportional to the {variant} feed speed - following error "
                "of its position loop")


class Acceleration(EffectFamily):
    name = "acceleration"
    group = "motion"
    complexity = 1
    summary = "inertial deflection: the error follows an axis' acceleration"
    reference = "structure compliance under inertial load"

    def variants(self, ctx):
        out = []
        for axis in ctx.linear_axes():
            try:
                if np.any(ctx.variables.acceleration(axis)):
                    out.append(axis)
            except InputDataError:  # no velocities or times: no acceleration variant
                continue
        return out

    def parameter_names(self, variant, setting):
        return ["cx_s2", "cy_s2", "cz_s2"]

    def design(self, ctx, variant, setting):
        return per_component(ctx.variables.acceleration(variant))

    def explanation(self, variant, setting):
        return (f"the residual follows the {variant} acceleration - the structure deflects "
                "under the axis' inertial load")


def families():
    return [Reversal(), ServoLag(), Acceleration()]
