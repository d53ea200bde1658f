"""The effect catalogue: every physical effect the workbench can name, as a registry.

Families by group (each a small class with its physics in the docstring):

* geometric (:mod:`.geometric`): positioning / straightness / angular errors of
  every linear axis, smooth and periodic; squareness of each axis pair;
  cross-axis twist; Abbe offset;
* rotary (:mod:`.geometric`): position-dependent errors and location errors of
  rotary axes (Khan & Chen); (:mod:`.setup_location`) the machine's error where the
  work or the tool was located at the set-up, turning with them;
* thermal (:mod:`.thermal`): drift, lag, gradient, heat sources,
  position-dependent expansion, thermal squareness (Zhu ch. 3-4);
* motion (:mod:`.motion`): reversal, servo lag, acceleration per axis;
* thermal logs only (:mod:`.log_models`): least squares on sets of sensors and on
  the temperatures' principal components;
* user (:mod:`.user`): expressions declared in the model, and families other
  packages install under the entry-point group ``mt_accuracy_ros.effects``.

A fitted candidate is stored in an error model as an effect entry
``{family, variant, setting, coefficients}`` and applied by
:func:`catalogue_error`, so an added effect acts in the model monitor, the
compensation broadcaster and the reports exactly as in the workbench.
"""
from __future__ import annotations

import copy

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from . import geometric, log_models, motion, setup_location, thermal
from .base import Context, EffectFamily, along, per_component
from .user import ENTRY_POINT_GROUP, UserExpression, load_plugins, user_declaration

__all__ = ["Context", "EffectFamily", "ENTRY_POINT_GROUP", "UserExpression", "along",
           "builtin_families", "catalogue_error", "catalogue_orientation", "families",
           "family_named", "is_catalogue_entry", "load_plugins", "per_component",
           "user_declaration"]


def builtin_families() -> list[EffectFamily]:
    """Every family this package defines, newly made.

    Returns
    -------
    list of EffectFamily
        Geometric, set-up location, thermal, motion and log-only families.
    """
    return geometric.families() + setup_location.families() + thermal.families() + \
        motion.families() + log_models.families()


_PLUGINS: list[EffectFamily] | None = None
#: Built-in family name -> the family, made once (:func:`family_named` hands out copies).
_BUILTIN_BY_NAME: dict[str, EffectFamily] | None = None


def families(user_effects: dict[str, dict] | None = None, *, plugins: bool = True
             ) -> list[EffectFamily]:
    """Built-in families, installed plugins, and one family per declared user effect.

    Parameters
    ----------
    user_effects : dict of str to dict, optional
        Effect name -> declaration (``expression``, ``parameters`` ...; see
        :func:`user_declaration`) of the user effects declared in a model.
    plugins : bool, optional
        Include families installed under :data:`ENTRY_POINT_GROUP` (default True).

    Returns
    -------
    list of EffectFamily
        The families, built-in ones first.

    Raises
    ------
    ParameterError
        A plugin family named like a built-in one.
    """
    global _PLUGINS
    out = builtin_families()
    if plugins:
        if _PLUGINS is None:
            _PLUGINS = load_plugins()
        names = {f.name for f in out}
        for family in _PLUGINS:
            if family.name in names:
                raise ParameterError(f"effect plugin family {family.name!r} clashes with a "
                                     "built-in family of that name")
            out.append(family)
    for name, declaration in (user_effects or {}).items():
        out.append(UserExpression(name, declaration))
    return out


def family_named(name: str, *, user: tuple[str, dict] | None = None) -> EffectFamily:
    """The family called ``name``, or the user expression ``user``.

    Parameters
    ----------
    name : str
        A family's :attr:`~EffectFamily.name`.
    user : tuple of (str, dict), optional
        (name, declaration) of a user effect: that family is made instead.

    Returns
    -------
    EffectFamily
        A new instance.

    Raises
    ------
    ParameterError
        No family of that name.
    """
    global _BUILTIN_BY_NAME
    if user is not None:
        return UserExpression(*user)
    if _BUILTIN_BY_NAME is None:
        # Made once (families() refuses a plugin that clashes with a built-in first): a
        # model names its families at every evaluation, a node's at every message, and
        # making every family to find one was a tenth of a five-axis evaluation's cost.
        _BUILTIN_BY_NAME = {}
        for family in families()[:len(builtin_families())]:
            _BUILTIN_BY_NAME.setdefault(family.name, family)
    if name in _BUILTIN_BY_NAME:
        # A copy: each caller gets an instance of its own, as a newly made one.
        return copy.copy(_BUILTIN_BY_NAME[name])
    for family in families():
        if family.name == name:
            return family
    raise ParameterError(f"unknown effect family {name!r}; known: "
                         f"{', '.join(sorted({f.name for f in families()}))}")


def is_catalogue_entry(parameters) -> bool:
    """A model effect entry that the catalogue evaluates (fitted family, or user expression).

    Parameters
    ----------
    parameters : object
        A model's entry for one effect.

    Returns
    -------
    bool
        True for a dict with ``family`` or ``expression``.
    """
    return isinstance(parameters, dict) and ("family" in parameters or "expression" in parameters)


def catalogue_error(name: str, entry: dict, ctx: Context) -> NDArray[np.float64]:
    """(N, 3) TCP error [m] of one fitted catalogue or user effect in a model.

    Parameters
    ----------
    name : str
        The effect's name in the model.
    entry : dict
        Its entry: ``{family, variant, setting, coefficients}`` (SI, in the family's
        parameter units), or a user declaration with ``expression`` and fitted ``values``.
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    ndarray, shape (N, 3)
        TCP error [m], bed frame (zeros for a user effect not fitted yet).

    Raises
    ------
    ParameterError
        An unknown family.
    """
    if "expression" in entry:
        if "values" not in entry:
            return np.zeros((ctx.n, 3))  # declared, not fitted yet
        family = UserExpression(name, entry)
        coefficients = np.array([entry["values"][p] for p in
                                 family.parameter_names(name, {})])
        return family.design(ctx, name, {}) @ coefficients
    family, variant, setting, coefficients = _fitted(entry)
    return family.design(ctx, variant, setting) @ coefficients


def _fitted(entry: dict) -> tuple[EffectFamily, str, dict, NDArray[np.float64]]:
    """(family, variant, setting, coefficients in parameter order) of a fitted entry."""
    family = family_named(entry["family"])
    variant, setting = entry.get("variant", ""), entry.get("setting") or {}
    names = family.parameter_names(variant, setting)
    return family, variant, setting, np.array([entry["coefficients"][p] for p in names])


def catalogue_orientation(name: str, entry: dict, ctx: Context) -> NDArray[np.float64]:
    """(N, 3) tool-orientation error [rad] of one fitted catalogue effect in a model: what
    a tilted rotary axis or a pitching guideway turns (zero for a translation and for
    user expressions, which declare a TCP error).

    Parameters
    ----------
    name : str
        The effect's name in the model.
    entry : dict
        Its entry ``{family, variant, setting, coefficients}`` (or a user declaration).
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    ndarray, shape (N, 3)
        Tool-orientation error [rad], bed frame.

    Raises
    ------
    ParameterError
        An unknown family.
    """
    if "family" not in entry:
        return np.zeros((ctx.n, 3))
    family, variant, setting, coefficients = _fitted(entry)
    design = family.orientation_design(ctx, variant, setting)
    return np.zeros((ctx.n, 3)) if design is None else design @ coefficients
