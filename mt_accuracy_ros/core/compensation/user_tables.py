"""User effects in a CNC's per-axis compensation tables.

A per-axis table holds error motions of one axis as functions of that axis' position
(ISO 230-1 E_XX(x), E_YX(x), ...). A fitted user effect (an expression in the model)
belongs there when it depends on one linear axis' position alone: its TCP error is
then converted to the translational error motions of that axis, e = J^-1 v, with J
the axis' translational sensitivities (:meth:`Context.jacobian`). The conversion is
checked, not assumed: it must give the same error motions with the other axes
anywhere in their travel (a twist that depends on two positions, or a direction that
turns with a rotary axis, is not a per-axis error and is refused by export).

An effect of temperatures, time, feeds or the spindle is a real-time effect, like the
catalogue's thermal effects: it stays in the real-time stream and export says so.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..effects import Context
from ..effects.expression import parse
from ..effects.user import UserExpression
from ..effects.variables import Variables

_CONFIGURATIONS = 3       # other-axis configurations the conversion must agree over
_AGREEMENT = 1e-9         # relative


def fitted_user_effects(model) -> dict[str, dict]:
    """The model's user effects that have fitted values (name -> declaration).

    Parameters
    ----------
    model : ErrorModel
        The model.

    Returns
    -------
    dict of str to dict
        Effect name -> its declaration (``expression``, ``parameters``, ``values`` ...).
    """
    return {name: entry for name, entry in model.effects.items()
            if isinstance(entry, dict) and "expression" in entry and "values" in entry}


def _variables(model, name: str, entry: dict) -> tuple[list[str], list[str]]:
    """(linear axes whose positions the effect uses, its other variables)."""
    variables = parse(entry["expression"], f"user effect {name!r}").names - \
        set(entry["parameters"])
    linear = {a.lower(): a for a in model.machine.axis_order
              if not model.machine.axes[a].is_rotary}
    return ([linear[v] for v in variables if v in linear],
            sorted(v for v in variables if v not in linear))


def table_axis(model, name: str, entry: dict) -> tuple[str | None, str]:
    """(axis, "") when the user effect is a function of one linear axis' position alone,
    else (None, why it is not a per-axis table effect).

    Parameters
    ----------
    model : ErrorModel
        The model (its machine's axes).
    name : str
        Effect name, quoted in messages.
    entry : dict
        The effect's declaration.

    Returns
    -------
    axis : str or None
        The linear axis, or None.
    why : str
        "" or the reason.
    """
    positions, others = _variables(model, name, entry)
    if others:
        return None, (f"depends on {', '.join(others)}: not a position error, it stays in the "
                      "real-time stream")
    if len(positions) != 1:
        what = "no position" if not positions else f"{len(positions)} axes' positions"
        return None, f"depends on {what}: a per-axis table cannot hold it"
    return positions[0], ""


def refuse_untabled(model) -> None:
    """Raise ParameterError naming every fitted user effect of positions alone that no
    per-axis table can hold (export must not leave a geometric effect out silently);
    effects of temperatures, time or feeds stay real-time and are not refused.

    Parameters
    ----------
    model : ErrorModel
        The model about to be exported.

    Raises
    ------
    ParameterError
        One or more such effects (all named).
    """
    from ..errors import ParameterError

    problems = []
    for name, entry in fitted_user_effects(model).items():
        axis, why = table_axis(model, name, entry)
        if axis is None and not _variables(model, name, entry)[1]:   # positions alone
            problems.append(f"user effect {name!r} {why}")
    if problems:
        raise ParameterError("; ".join(problems) + " - export refused (a controller's tables "
                             "would leave it out; compensate it in real time)")


def _tcp_and_sensitivity(model, name: str, entry: dict, axis: str, grid: NDArray,
                         rng: np.random.Generator) -> tuple[NDArray, NDArray]:
    positions = {}
    for other in model.machine.axis_order:
        low, high = model.machine.axes[other].stroke
        positions[other] = grid if other == axis else rng.uniform(low, high, grid.size)
    ctx = Context(model.machine, Variables(positions), model.kinematics)
    family = UserExpression(name, entry)
    coefficients = np.array([entry["values"][p] for p in family.parameter_names(name, {})])
    tcp = family.design(ctx, name, {}) @ coefficients                       # (N, 3)
    sensitivity = np.stack([ctx.jacobian(f"E{c}{axis}") for c in "XYZ"], axis=2)   # (N, 3, 3)
    return tcp, sensitivity


def user_motion_errors(model, axis: str, grid: ArrayLike, *, strict: bool = True,
                       seed: int = 0) -> dict[str, NDArray[np.float64]]:
    """Error motions of ``axis`` (ISO name -> values [m] on ``grid``) equivalent to the
    model's fitted user effects of that axis' position.

    Parameters
    ----------
    model : ErrorModel
        The model.
    axis : str
        Linear axis letter.
    grid : array_like, shape (K,)
        Positions of ``axis`` [m].
    strict : bool, optional
        Refuse (True) or leave out (False) an effect that is not a per-axis error motion.
    seed : int, optional
        Seed of the other axes' random configurations.

    Returns
    -------
    dict of str to ndarray, shape (K,)
        ``E<X|Y|Z><axis>`` -> translational error motion [m] (non-zero ones only).

    Raises
    ------
    ParameterError
        (``strict``) A user effect of this axis' position whose TCP error is not a
        per-axis error motion (the conversion disagrees between configurations of the
        other axes). Not strict, such an effect is left out (it stays real-time).
    """
    from ..errors import ParameterError

    grid = np.atleast_1d(np.asarray(grid, dtype=np.float64))
    rng = np.random.default_rng(seed)
    out: dict[str, NDArray[np.float64]] = {}
    for name, entry in fitted_user_effects(model).items():
        if table_axis(model, name, entry)[0] != axis:
            continue
        motions = []
        for _ in range(_CONFIGURATIONS):
            tcp, sensitivity = _tcp_and_sensitivity(model, name, entry, axis, grid, rng)
            motions.append(np.linalg.solve(sensitivity, tcp[..., None])[..., 0])
        scale = max(float(np.max(np.abs(motions[0]))), 1e-300)
        if any(np.max(np.abs(m - motions[0])) > _AGREEMENT * scale for m in motions[1:]):
            if not strict:
                continue
            raise ParameterError(f"user effect {name!r}: its TCP error is not an error motion "
                                 f"of {axis} alone (it changes with the other axes' "
                                 "positions): a per-axis table cannot hold it")
        for c, component in enumerate("XYZ"):
            if np.any(motions[0][:, c]):
                key = f"E{component}{axis}"
                out[key] = out.get(key, 0.0) + motions[0][:, c]
    return out


def user_tcp_error(model, positions: dict[str, ArrayLike]) -> NDArray[np.float64]:
    """(N, 3) TCP error [m] of the model's fitted user effects that go into the tables,
    computed from the expressions directly (the round trip's independent reference).

    Parameters
    ----------
    model : ErrorModel
        The model.
    positions : dict of str to array_like, shape (N,)
        Axis commands [m] (rotary [rad]), every axis.

    Returns
    -------
    ndarray, shape (N, 3)
        TCP error [m], bed frame.
    """
    q = {a: np.atleast_1d(np.asarray(positions[a], dtype=np.float64))
         for a in model.machine.axis_order}
    n = next(iter(q.values())).size
    total = np.zeros((n, 3))
    ctx = Context(model.machine, Variables(q), model.kinematics)
    for name, entry in fitted_user_effects(model).items():
        if table_axis(model, name, entry)[0] is None:
            continue
        family = UserExpression(name, entry)
        coefficients = np.array([entry["values"][p] for p in family.parameter_names(name, {})])
        total += family.design(ctx, name, {}) @ coefficients
    return total
