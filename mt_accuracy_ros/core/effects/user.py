"""User-defined effects: an expression in the model YAML, or Python through an entry point.

**Declared in the model** (no code, no package edit)::

    effects:
      screw_heat:
        expression: "k * x * lag(T_spindle, 1200)"   # see .expression for the grammar
        parameters: [k]                               # enter linearly; the workbench fits them
        acts_on: x            # x, y, z, a list of them, or an axis (X): along its motion
        values: {k: 0.0}      # optional: fitted values (the model applies it once given)
        bounds: {k: 1.0e-4}   # optional: the largest |k| its physics allows; a fit
                              # beyond it is refused (units of the parameter)

With several components in ``acts_on`` each gets its own parameters
(``k_x``, ``k_z``). Linearity in the parameters is checked numerically on
the data (f(p + q) = f(p) + f(q) and no term without a parameter); a design
collinear with an effect already in the model is refused by the workbench.

**Written in Python**: a package exposes an :class:`~.base.EffectFamily`
subclass (or instance) in the entry-point group ``mt_accuracy_ros.effects``
(see ``docs/user_effects.md`` for a worked example); it is then a candidate
everywhere a built-in family is.
"""
from __future__ import annotations

import os
import sys

import numpy as np

from ..errors import InputDataError, ParameterError
from .expression import Expression, ExpressionError, parse
from .base import Context, EffectFamily

ENTRY_POINT_GROUP = "mt_accuracy_ros.effects"
_COMPONENTS = "xyz"


def user_declaration(name: str, spec: dict) -> dict:
    """Checked, normalised declaration of a user effect (raises ParameterError naming it).

    Parameters
    ----------
    name : str
        The effect's name in the model (named in every error).
    spec : dict
        The declaration: ``expression``, ``parameters``, ``acts_on`` and optionally
        ``values``, ``bounds`` (in the parameters' own units), ``explanation`` (see the
        module docstring).

    Returns
    -------
    dict
        The declaration with the expression's text normalised, values and bounds as
        floats.

    Raises
    ------
    ParameterError
        An unknown key, a bad parameter list, a target, value or bound.
    ExpressionError
        An expression that does not parse or uses what is not allowed.
    """
    where = f"user effect {name!r}"
    if not isinstance(spec, dict):
        raise ParameterError(f"{where}: expected a mapping with expression, parameters, acts_on")
    unknown = set(spec) - {"expression", "parameters", "acts_on", "values", "explanation",
                           "family", "variant", "bounds"}
    if unknown:
        raise ParameterError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}")
    expression = parse(spec.get("expression", ""), where)
    parameters = spec.get("parameters")
    if not isinstance(parameters, list) or not parameters or \
            not all(isinstance(p, str) and p.isidentifier() for p in parameters):
        raise ParameterError(f"{where}: 'parameters' must list the names of its linear "
                             "parameters, e.g. [k]")
    missing = [p for p in parameters if p not in expression.names]
    if missing:
        raise ParameterError(f"{where}: parameter(s) {', '.join(missing)} do not appear in "
                             f"{expression.text!r}")
    acts_on = spec.get("acts_on", "x")
    targets = acts_on if isinstance(acts_on, list) else [acts_on]
    for target in targets:
        if not (isinstance(target, str) and (target in _COMPONENTS or
                                             (len(target) == 1 and target in "XYZABC"))):
            raise ParameterError(f"{where}: acts_on {target!r}: expected x, y, z (TCP "
                                 "components) or an axis letter (along its motion)")
    if len(set(targets)) != len(targets):
        raise ParameterError(f"{where}: acts_on names a component twice")
    names = [p if len(targets) == 1 else f"{p}_{t}" for t in targets for p in parameters]
    values = spec.get("values")
    if values is not None:
        if not isinstance(values, dict) or set(values) != set(names):
            raise ParameterError(f"{where}: 'values' must give every parameter "
                                 f"({', '.join(names)})")
        for key, value in values.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                    not np.isfinite(value):
                raise ParameterError(f"{where}: value of {key} must be a finite number")
        values = {k: float(v) for k, v in values.items()}
    bounds = spec.get("bounds")
    if bounds is not None:
        if not isinstance(bounds, dict) or set(bounds) - set(parameters):
            raise ParameterError(f"{where}: 'bounds' must map some of its parameters "
                                 f"({', '.join(parameters)}) to the largest |value| allowed")
        for key, value in bounds.items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or \
                    not np.isfinite(value) or value <= 0:
                raise ParameterError(f"{where}: bound of {key} must be a positive number")
        bounds = {k: float(v) for k, v in bounds.items()}
    return {"expression": expression.text, "parameters": list(parameters),
            "acts_on": targets if isinstance(acts_on, list) else targets[0],
            **({"values": values} if values is not None else {}),
            **({"bounds": bounds} if bounds is not None else {}),
            **({"explanation": str(spec["explanation"])} if "explanation" in spec else {})}


class UserExpression(EffectFamily):
    """One user effect declared as an expression; its variant is the effect's name.

    Parameters
    ----------
    effect_name : str
        The effect's name in the model (its variant).
    declaration : dict
        Its declaration (see :func:`user_declaration`).

    Raises
    ------
    ParameterError, ExpressionError
        A declaration :func:`user_declaration` refuses.
    """

    name = "user"
    group = "user"
    complexity = 1   # the user's own hypothesis comes first on a tie
    reference = "declared by the user in the model"

    def __init__(self, effect_name: str, declaration: dict) -> None:
        self.effect_name = effect_name
        self.declaration = user_declaration(effect_name, declaration)
        self.expression: Expression = parse(self.declaration["expression"],
                                            f"user effect {effect_name!r}")
        acts_on = self.declaration["acts_on"]
        self.targets = acts_on if isinstance(acts_on, list) else [acts_on]
        self.summary = self.declaration.get("explanation", f"user effect {self.expression.text}")

    def variants(self, ctx: Context) -> list[str]:
        """The one variant: the effect's name.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ``[effect_name]``.
        """
        return [self.effect_name]

    def parameter_names(self, variant, setting):
        """The declared parameters, ``<p>_<target>`` for several targets.

        Parameters
        ----------
        variant : str
            The effect's name (the one variant).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        list of str
            P names, in the units the user's expression gives them.
        """
        base = self.declaration["parameters"]
        return [p if len(self.targets) == 1 else f"{p}_{t}" for t in self.targets for p in base]

    def _values(self, ctx: Context) -> dict:
        variables = {}
        for name in self.expression.names:
            if name in self.declaration["parameters"]:
                continue
            try:
                variables[name] = ctx.variables.get(name)
            except InputDataError as exc:
                raise ParameterError(f"user effect {self.effect_name!r}: {exc}") from exc
        return variables

    def columns(self, ctx: Context) -> np.ndarray:
        """(N, P) value of the expression per unit parameter; checks linearity.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        ndarray, shape (N, P0)
            The expression at each declared parameter set to 1, the others 0, for the P0
            declared parameters; in the expression's unit (a TCP error [m] per parameter unit).

        Raises
        ------
        ParameterError
            A variable the readings do not have.
        ExpressionError
            Not linear in its parameters, or NaN/inf on these data.
        """
        values = self._values(ctx)

        def lag(variable, tau):
            return ctx.variables.lag(f"user_{variable}", values[variable], tau)

        def at(parameters):
            return np.broadcast_to(self.expression.evaluate({**values, **parameters}, lag),
                                   (ctx.n,)).astype(float)

        names = self.declaration["parameters"]
        zero = at({p: 0.0 for p in names})
        where = f"user effect {self.effect_name!r}"
        if not np.all(np.isfinite(zero)) or np.any(np.abs(zero) > 1e-12 * (1 + np.abs(zero)
                                                                          ).max()):
            raise ExpressionError(f"{where}: not linear in its parameters - a term without a "
                                  "parameter, or NaN/inf on these data")
        columns = np.column_stack([at({p: float(p == q) for p in names}) for q in names])
        if not np.all(np.isfinite(columns)):
            raise ExpressionError(f"{where}: NaN/inf on these data (e.g. log of a negative "
                                  "value or a division by zero)")
        scale = np.abs(columns).max() or 1.0
        for i, p in enumerate(names):
            doubled = at({q: 2.0 * float(q == p) for q in names})
            if not np.allclose(doubled, 2.0 * columns[:, i], atol=1e-9 * scale, rtol=1e-9):
                raise ExpressionError(f"{where}: not linear in parameter {p!r}")
        if len(names) > 1:
            together = at({p: 1.0 for p in names})
            if not np.allclose(together, columns.sum(axis=1), atol=1e-9 * scale, rtol=1e-9):
                raise ExpressionError(f"{where}: parameters multiply each other - not linear")
        return columns

    def design(self, ctx: Context, variant, setting):
        """The columns along each target: a TCP component, or an axis' motion (its EXX).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The effect's name (the one variant).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        ndarray, shape (N, 3, P)
            TCP error [m] per parameter unit, bed frame; P = P0 x number of targets.

        Raises
        ------
        ParameterError
            A target axis the machine does not have, or a missing variable.
        ExpressionError
            Not linear in its parameters, or NaN/inf on these data.
        """
        columns = self.columns(ctx)
        n_base = columns.shape[1]
        design = np.zeros((ctx.n, 3, n_base * len(self.targets)))
        for j, target in enumerate(self.targets):
            if target in _COMPONENTS:
                direction = np.zeros((ctx.n, 3))
                direction[:, _COMPONENTS.index(target)] = 1.0
            else:
                if target not in ctx.machine.axes:
                    raise ParameterError(f"user effect {self.effect_name!r}: acts_on {target}: "
                                         f"no such axis on {ctx.machine.name}")
                direction = ctx.jacobian(f"E{target}{target}")
            design[:, :, j * n_base:(j + 1) * n_base] = direction[:, :, None] * columns[:, None, :]
        return design

    def parameter_limits(self, ctx, variant, setting):
        """The bounds declared with the effect.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The effect's name (the one variant).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        dict of str to tuple of (float, str)
            Parameter name -> (bound in the parameter's unit, reason), for those declared.
        """
        bounds = self.declaration.get("bounds") or {}
        out = {}
        for name in self.parameter_names(variant, setting):
            base = name if name in bounds else name.rsplit("_", 1)[0]
            if base in bounds:
                out[name] = (bounds[base], "the bound declared with the effect")
        return out

    def explanation(self, variant, setting):
        """The declared explanation, else the expression and its targets.

        Parameters
        ----------
        variant : str
            The effect's name (the one variant).
        setting : dict
            The setting (the one empty setting).

        Returns
        -------
        str
            The sentence.
        """
        return self.declaration.get("explanation") or \
            f"the user's effect {self.effect_name}: {self.expression.text} on " \
            f"{', '.join(self.targets)}"


def _entry_point_files_may_name(group: str) -> bool:
    """Could an installed distribution declare entry points of ``group``? False only when
    no ``entry_points.txt`` of a dist-info or egg-info directory on ``sys.path`` mentions
    it (2 ms); a zip on the path, or any mention, leaves the answer to
    ``importlib.metadata`` (30 ms over a ROS venv's hundreds of distributions)."""
    for entry in sys.path:
        path = entry or "."
        if os.path.isfile(path):
            return True
        try:
            names = os.listdir(path)
        except OSError:
            continue
        for name in names:
            if not name.endswith((".dist-info", ".egg-info")):
                continue
            try:
                with open(os.path.join(path, name, "entry_points.txt"), encoding="utf-8",
                          errors="replace") as handle:
                    if group in handle.read():
                        return True
            except OSError:
                continue
    return False


def load_plugins() -> list[EffectFamily]:
    """Effect families installed by other packages (entry-point group ``mt_accuracy_ros.effects``).

    Raises ParameterError naming the entry point when one cannot be loaded or is
    not an :class:`EffectFamily`.

    Returns
    -------
    list of EffectFamily
        One instance per entry point (a class is instantiated without arguments).
    """
    if not _entry_point_files_may_name(ENTRY_POINT_GROUP):
        return []
    from importlib.metadata import entry_points

    out = []
    for point in entry_points(group=ENTRY_POINT_GROUP):
        try:
            loaded = point.load()
        except Exception as exc:  # noqa: BLE001 - any failure of foreign code, named
            raise ParameterError(f"effect plugin {point.name!r} ({point.value}): cannot be "
                                 f"loaded: {type(exc).__name__}: {exc}") from exc
        family = loaded() if isinstance(loaded, type) else loaded
        if not isinstance(family, EffectFamily):
            raise ParameterError(f"effect plugin {point.name!r} ({point.value}): not an "
                                 "EffectFamily (subclass mt_accuracy_ros.core.workbench."
                                 "catalogue.EffectFamily)")
        out.append(family)
    return out
