"""What physics allows a fitted effect on the machine at hand.

A least-squares fit returns whatever numbers make the residual smallest; on
a short record a sensor that barely moved takes a gain of millimetres per
kelvin to follow noise. Such a fit is not a finding, and live it would move
the machine by that gain times every later temperature change. Each family
therefore declares the range its physics allows
(:meth:`~.base.EffectFamily.parameter_limits`), and every fitted effect must
also be **consistent with the residual it explains**: its own spread at the
readings may not exceed a small multiple of the residual's (an effect twice
as large as what it explains is cancelling against another term, not
describing the machine).

Bounds are generous on purpose - they refuse the absurd, never a real
machine's effect:

* thermal gains [m/K]: free expansion of the structure between a sensor and
  the tool, ``GENEROUS_CTE_PER_K`` (aluminium is 23e-6, steel 11.5e-6, cast
  iron 10e-6) times the structure's length (the machine description's
  ``structure_length_m``, else the sum of the chain's strokes, offsets, tool
  and workpiece) - Zhu eq. 3.12 with the largest plausible coefficient;
* gradients and tilts: that expansion times a lever of ``BENDING_LEVER``
  (a link's slenderness L/h, Zhu Table 4.2: deflection alpha dT L^2 / 2h);
* heat sources: the gain times the fastest driver seen may not exceed the
  free expansion over ``MAX_RISE_K``;
* a relative expansion coefficient [1/K] (Zhu eq. 3.13): ``GENEROUS_CTE_PER_K``;
* user effects: the ``bounds`` they declare in the model YAML.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Largest thermal expansion coefficient any machine structure has [1/K].
GENEROUS_CTE_PER_K = 30e-6
#: Slenderness of a link bent by a gradient (deflection per K of difference over
#: the free expansion per K).
BENDING_LEVER = 10.0
#: Largest steady temperature rise a heat source drives in a structure [K].
MAX_RISE_K = 30.0
#: An effect's spread at the readings may be at most this times the residual's RMS
#: (plus twice the instrument's noise) in every component it acts on.
CONSISTENCY_FACTOR = 2.0


def structure_length_m(machine) -> float:
    """Length of structure that can expand between a sensor and the tool [m].

    Parameters
    ----------
    machine : MachineDescription
        The machine (its ``structure_length_m``, else strokes [m], offsets, tool and
        workpiece [m]).

    Returns
    -------
    float
        Length [m], at least 0.1.
    """
    if getattr(machine, "structure_length_m", None):
        return float(machine.structure_length_m)
    length = float(np.linalg.norm(machine.tool) + np.linalg.norm(machine.workpiece))
    for axis in machine.axis_order:
        spec = machine.axes[axis]
        if not spec.is_rotary:
            length += spec.stroke[1] - spec.stroke[0]
        length += float(np.linalg.norm(spec.offset))
    return max(length, 0.1)


def thermal_gain_limit_m_per_k(machine) -> float:
    """Largest TCP displacement per kelvin of one sensor's rise [m/K].

    Parameters
    ----------
    machine : MachineDescription
        The machine.

    Returns
    -------
    float
        :data:`GENEROUS_CTE_PER_K` x :func:`structure_length_m` [m/K].
    """
    return GENEROUS_CTE_PER_K * structure_length_m(machine)


def limit_problems(names: list[str], values: NDArray[np.float64],
                   limits: dict[str, tuple[float, str]]) -> list[str]:
    """Parameters beyond their declared limits, each named with its limit and reason.

    Parameters
    ----------
    names : list of str
        P parameter names.
    values : ndarray, shape (P,)
        Their fitted values, in their units.
    limits : dict of str to tuple of (float, str)
        Name -> (bound in the same unit, reason) (:meth:`~.base.EffectFamily.parameter_limits`).

    Returns
    -------
    list of str
        One sentence per parameter beyond its bound or not finite.
    """
    out = []
    for name, value in zip(names, np.asarray(values, dtype=float)):
        if name not in limits:
            continue
        bound, why = limits[name]
        if not np.isfinite(value) or abs(value) > bound:
            out.append(f"{name} = {value:.3g} exceeds +-{bound:.3g} ({why})")
    return out


#: Measured components: the TCP position's (x, y, z) and the tool direction's, about
#: x, y and z (a, b, c; scaled to metres, :class:`~.base.Context`).
COMPONENT_NAMES = "xyzabc"


def consistency_allowances(residual: NDArray[np.float64], mask: NDArray[np.bool_],
                           noise_sigma: float) -> dict[str, float]:
    """Per measured component, the largest spread [m] an effect may have at the readings:
    :data:`CONSISTENCY_FACTOR` x the residual's spread + 2 sigma of noise.

    Parameters
    ----------
    residual : ndarray, shape (N, C)
        Residual at the readings [m], C = 3 (TCP) or 6 (with the tool direction scaled to
        metres).
    mask : ndarray of bool, shape (N, C)
        Components measured.
    noise_sigma : float
        The instrument's noise, standard deviation [m].

    Returns
    -------
    dict of str to float
        Component (``x`` ... ``c``) -> largest spread allowed [m], for components measured.
    """
    out = {}
    for c, component in enumerate(COMPONENT_NAMES[:residual.shape[1]]):
        rows = mask[:, c]
        if rows.any():
            r = residual[rows, c]
            out[component] = CONSISTENCY_FACTOR * float(np.sqrt(np.mean((r - r.mean()) ** 2))) \
                + 2.0 * noise_sigma
    return out


def spread_problems(spreads: dict[str, float], allowances: dict[str, float],
                    orientation_lever_m: float | None = None,
                    carried: dict[str, float] | None = None) -> list[str]:
    """Components where an effect's own spread [m] exceeds its allowance
    (:func:`consistency_allowances`); a direction component (a, b, c: scaled by
    ``orientation_lever_m``) is said in urad.

    An effect fitted beside others may move a component more than the residual there
    shows, by what the others move it the other way: their sum is what the residual
    saw. So the allowance grows by the others' spread ``carried`` (triangle inequality),
    by at most the allowance itself: the others are held to it too, and two stand-ins
    that cancel each other beyond it are still refused.

    Parameters
    ----------
    spreads : dict of str to float
        Component -> the effect's RMS spread about its mean at the readings [m].
    allowances : dict of str to float
        Component -> largest spread allowed [m] (:func:`consistency_allowances`).
    orientation_lever_m : float, optional
        Lever that scaled a direction component to metres [m]; with it, a, b, c are said
        in urad.
    carried : dict of str to float, optional
        Component -> the RMS spread at the readings of what the other effects of the same
        joint fit move [m]; none when the effect stands alone.

    Returns
    -------
    list of str
        One sentence per component beyond its allowance.
    """
    out = []
    carried = carried or {}
    for component, allowed in allowances.items():
        spread = spreads.get(component, 0.0)
        if spread == 0.0:
            continue
        allowed = allowed + min(carried.get(component, 0.0), allowed)
        if not np.isfinite(spread) or spread > allowed:
            if component in "abc" and orientation_lever_m:
                what, factor, unit = (f"the tool's direction about {'xyz'['abc'.index(component)]}",
                                      1e6 / orientation_lever_m, "urad")
            else:
                what, factor, unit = component, 1e6, "um"
            beside = " beside what the other named effects move there" \
                if carried.get(component, 0.0) > 0.0 else ""
            out.append(f"it would move {what} by {spread * factor:.3g} {unit} RMS at the "
                       f"readings, more than the {allowed * factor:.3g} {unit} the residual "
                       f"there allows{beside}")
    return out


def consistency_problems(contribution: NDArray[np.float64], residual: NDArray[np.float64],
                         mask: NDArray[np.bool_], noise_sigma: float) -> list[str]:
    """Components where an effect's own spread (N, 3) is larger than the residual allows.

    Parameters
    ----------
    contribution : ndarray, shape (N, 3)
        The effect's TCP error at the readings [m].
    residual : ndarray, shape (N, 3)
        The residual it explains [m].
    mask : ndarray of bool, shape (N, 3)
        Components measured.
    noise_sigma : float
        The instrument's noise, standard deviation [m].

    Returns
    -------
    list of str
        One sentence per component beyond its allowance (see :func:`spread_problems`).
    """
    spreads = {}
    for c, component in enumerate("xyz"):
        own = contribution[mask[:, c], c]
        if own.size:
            spreads[component] = float(np.sqrt(np.mean((own - own.mean()) ** 2)))
    return spread_problems(spreads, consistency_allowances(residual, mask, noise_sigma))
