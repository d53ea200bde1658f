"""What a thermal engineer fits to a log of many sensors: sets of sensors and their
principal components.

Zhu (ch. 2) reviews how thermal-error models are built in practice: least
squares on temperatures at chosen "key points", the points chosen by
clustering correlated sensors and keeping from each group the one most
related to the error (correlation, or the grey relational grade); principal
components of the temperature field when many sensors move together. On a
single record these blend many sensors at once and can out-fit a named
physical effect, so they are candidates only for thermal logs
(:attr:`~.base.EffectFamily.log_only`); the log's forward validation then
chooses between them and the catalogue's named effects.

* ``sensor_least_squares`` - least squares on a set of sensors' rises (Zhu eq.
  3.12 with several sensor terms): every structure sensor, or the
  representatives of correlated groups (:func:`sensor_groups`).
* ``temperature_components`` - least squares on the first k principal
  components of the standardised temperatures; the centre, scale and
  loadings are the setting (computed on the rows the model is fitted on, and
  kept in the model so it evaluates the same columns later).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .base import Context, EffectFamily, per_component
from .physics import thermal_gain_limit_m_per_k
from .thermal import sensor_set_design, sensor_set_parameters

#: Largest number of principal components offered.
MAX_COMPONENTS = 4

#: Grey relational distinguishing coefficient (Deng's usual 0.5).
GREY_RHO = 0.5


def grey_relational_grades(reference: NDArray[np.float64], series: NDArray[np.float64],
                           rho: float = GREY_RHO) -> NDArray[np.float64]:
    """Deng's grey relational grade of each of ``series`` (S, N) to ``reference`` (N,).

    Every sequence is mapped to [0, 1] by its range; a series falling as the reference
    rises is related too, so each series is also taken reversed and the larger grade
    kept. xi_i(k) = (d_min + rho d_max) / (d_i(k) + rho d_max) with d_i(k) = |x0(k) -
    x_i(k)| and d_min, d_max over every i and k; the grade is the mean of xi_i over k.

    Parameters
    ----------
    reference : ndarray, shape (N,)
        The reference sequence (the error), any unit (each sequence is scaled by its range).
    series : ndarray, shape (S, N)
        The S compared sequences (sensor temperatures), any unit.
    rho : float, optional
        Distinguishing coefficient, dimensionless (default :data:`GREY_RHO`).

    Returns
    -------
    ndarray, shape (S,)
        Grade of each series, dimensionless in (0, 1].
    """
    def unit(values):
        values = np.asarray(values, dtype=np.float64)
        span = np.ptp(values, axis=-1, keepdims=True)
        return (values - values.min(axis=-1, keepdims=True)) / np.where(span > 0, span, 1.0)

    x0 = unit(reference)
    xs = unit(series)
    grades = []
    for candidate in (xs, 1.0 - xs):
        delta = np.abs(candidate - x0[None, :])
        d_min, d_max = float(delta.min()), float(delta.max())
        if d_max == 0:
            grades.append(np.ones(xs.shape[0]))
            continue
        grades.append(np.mean((d_min + rho * d_max) / (delta + rho * d_max), axis=1))
    return np.maximum(grades[0], grades[1])


def correlation_clusters(temperatures: NDArray[np.float64], count: int) -> NDArray[np.intp]:
    """Cluster label (S,) of each of S sensors (S, N): ``count`` groups of sensors that move
    together (average linkage on 1 - |correlation|; a constant sensor joins no one).

    Parameters
    ----------
    temperatures : ndarray, shape (S, N)
        S sensors' readings at N times, any unit (only correlations are used).
    count : int
        Number of groups wanted.

    Returns
    -------
    ndarray of int, shape (S,)
        Group label of each sensor, from 0 (each its own when S <= ``count``).
    """
    from scipy.cluster.hierarchy import fcluster, linkage
    from scipy.spatial.distance import squareform

    t = np.asarray(temperatures, dtype=np.float64)
    if t.shape[0] <= count:
        return np.arange(t.shape[0], dtype=np.intp)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = np.nan_to_num(np.corrcoef(t), nan=0.0)
    distance = np.clip(1.0 - np.abs(r), 0.0, 2.0)
    np.fill_diagonal(distance, 0.0)
    tree = linkage(squareform((distance + distance.T) / 2.0, checks=False), method="average")
    return (fcluster(tree, t=count, criterion="maxclust") - 1).astype(np.intp)


def sensor_groups(temperatures: dict[str, NDArray[np.float64]], target: NDArray[np.float64],
                  counts: range = range(2, 5)) -> dict[str, str]:
    """Key sensors as Zhu's review describes them: for each number of groups, the sensors
    clustered by correlation, and from each group the one with the largest grey relational
    grade to ``target`` (N,). Returns {variant ("a+b+c"): how it was chosen}.

    Parameters
    ----------
    temperatures : dict of str to ndarray, shape (N,)
        Sensor name -> readings [degC] (only correlations and ranges are used).
    target : ndarray, shape (N,)
        The error the sensors are graded against, any unit.
    counts : range, optional
        Numbers of groups tried (default 2, 3 and 4).

    Returns
    -------
    dict of str to str
        Variant (sensor names joined by ``+``) -> how it was chosen; empty for fewer than 3
        sensors.
    """
    names = sorted(temperatures)
    if len(names) < 3:
        return {}
    t = np.array([temperatures[n] for n in names])
    grades = grey_relational_grades(target, t)
    out: dict[str, str] = {}
    for count in counts:
        if count >= len(names):
            break
        labels = correlation_clusters(t, count)
        chosen = []
        for label in np.unique(labels):
            members = np.flatnonzero(labels == label)
            chosen.append(names[int(members[np.argmax(grades[members])])])
        variant = "+".join(sorted(chosen))
        out.setdefault(variant, f"{len(chosen)} groups of correlated sensors, each "
                       "represented by its largest grey relational grade to the error")
    return out


class SensorLeastSquares(EffectFamily):
    """Least squares on a set of sensors (Zhu eq. 3.12, several sensor terms).

    Parameters
    ----------
    chosen : dict of str to str, optional
        Variant (sensor names joined by ``+``) -> how its sensors were chosen (set by the
        log's command, e.g. from :func:`sensor_groups`).
    """

    name = "sensor_least_squares"
    group = "thermal"
    complexity = 3
    log_only = True
    summary = "a set of structure sensors together, by least squares"
    reference = "Zhu eq. 3.12 (sensor terms); key sensors by grouping, Zhu ch. 2"

    def __init__(self, chosen: dict[str, str] | None = None) -> None:
        #: variant -> how its sensors were chosen (set by the log's command)
        self.chosen = dict(chosen or {})

    def variants(self, ctx):
        """The chosen sets whose sensors are all structure sensors here.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            Variants, sensor names joined by ``+``.
        """
        sensors = set(ctx.structure_sensors())
        return [v for v in self.chosen if set(v.split("+")) <= sensors]

    def variant_complexity(self, variant: str) -> int:
        """3 for four or more sensors, else 2.

        Parameters
        ----------
        variant : str
            Sensor names joined by ``+``.

        Returns
        -------
        int
            The complexity (see :attr:`EffectFamily.complexity`).
        """
        return 3 if variant.count("+") >= 3 else 2

    def parameter_names(self, variant, setting):
        """A gain per sensor and TCP direction.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``b<x|y|z>_<sensor>`` [m/K], 3 per sensor.
        """
        return sensor_set_parameters(variant)

    def design(self, ctx, variant, setting):
        """Each sensor's rise on x, y and z (Zhu eq. 3.12, several sensor terms).

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, 3S)
            Rises [K] of the S sensors: TCP error [m] per gain [m/K].
        """
        return sensor_set_design(ctx, variant)

    def parameter_limits(self, ctx, variant, setting):
        """Free expansion of the structure per kelvin for every gain.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        dict of str to tuple of (float, str)
            Parameter name -> (bound [m/K], reason).
        """
        bound = thermal_gain_limit_m_per_k(ctx.machine)
        return {name: (bound, "free expansion of the structure per K")
                for name in self.parameter_names(variant, setting)}

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence, with how the sensors were chosen.
        """
        sensors = variant.split("+")
        how = self.chosen.get(variant, "")
        return (f"the residual follows {len(sensors)} sensors together ({', '.join(sensors)}"
                f"{'; ' + how if how else ''}) by least squares (Zhu eq. 3.12)")


class TemperatureComponents(EffectFamily):
    """Least squares on the first k principal components of the standardised sensors."""

    name = "temperature_components"
    group = "thermal"
    complexity = 3
    log_only = True
    summary = "the main patterns of the temperature field (principal components)"
    reference = "principal components of the temperatures; Zhu ch. 2"

    def variants(self, ctx):
        """The numbers of components offered: 1 up to min(4, S - 1) for S >= 3 sensors.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.

        Returns
        -------
        list of str
            ``"1"``, ``"2"`` ... (k as text).
        """
        sensors = ctx.structure_sensors()
        if len(sensors) < 3:
            return []
        return [str(k) for k in range(1, min(MAX_COMPONENTS, len(sensors) - 1) + 1)]

    def settings(self, ctx, variant):
        """The one setting: sensors, centre, scale and the first k loadings of these readings.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            k, the number of components (one of :meth:`variants`).

        Returns
        -------
        list of dict
            One setting: ``sensors`` (names joined by ``+``), ``centre`` and ``scale`` (S
            floats [degC]), ``loadings`` (k tuples of S floats, dimensionless, each signed so
            its largest loading is positive).
        """
        sensors = ctx.structure_sensors()
        t = np.column_stack([ctx.variables.temperatures[s] for s in sensors])
        centre = t.mean(axis=0)
        scale = t.std(axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        _, _, vt = np.linalg.svd((t - centre) / scale, full_matrices=False)
        k = int(variant)
        # A component's sign is arbitrary: fix it so its largest loading is positive.
        loadings = vt[:k] * np.sign(vt[:k][np.arange(k), np.argmax(np.abs(vt[:k]), axis=1)]
                                    )[:, None]
        return [{"sensors": "+".join(sensors),
                 "centre": tuple(float(v) for v in centre),
                 "scale": tuple(float(v) for v in scale),
                 "loadings": tuple(tuple(float(v) for v in row) for row in loadings)}]

    def parameter_names(self, variant, setting):
        """A gain per component and TCP direction.

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        list of str
            ``b<x|y|z>_pc<j>`` [m per unit score], 3 per component.
        """
        return [f"b{c}_pc{j + 1}" for j in range(int(variant)) for c in "xyz"]

    def scores(self, ctx: Context, setting: dict) -> NDArray[np.float64]:
        """The k component scores of the readings: standardised temperatures times the loadings.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, k)
            Scores, dimensionless.
        """
        sensors = setting["sensors"].split("+")
        t = np.column_stack([ctx.variables.temperatures[s] for s in sensors])
        z = (t - np.asarray(setting["centre"], float)) / np.asarray(setting["scale"], float)
        return z @ np.asarray(setting["loadings"], float).T

    def design(self, ctx, variant, setting):
        """Each component's score on x, y and z.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        ndarray, shape (N, 3, 3k)
            Scores (dimensionless): TCP error [m] per gain [m per unit score].
        """
        scores = self.scores(ctx, setting)
        return np.concatenate([per_component(scores[:, j]) for j in range(scores.shape[1])],
                              axis=2)

    def parameter_limits(self, ctx, variant, setting):
        # One unit of a score moves each sensor by at most its scale: the gain per unit
        # is bounded by the free expansion per K times the scales' sum.
        """Free expansion per kelvin times the sum of the sensors' scales.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        dict of str to tuple of (float, str)
            Parameter name -> (bound [m per unit score], reason).
        """
        bound = thermal_gain_limit_m_per_k(ctx.machine) * float(np.sum(setting["scale"]))
        return {name: (bound, "free expansion of the structure over the component's "
                       "temperature spread") for name in self.parameter_names(variant, setting)}

    def implied_gains(self, setting: dict, coefficients) -> NDArray[np.float64]:
        """Each sensor's gain the components' fit amounts to (S, 3) [m/K]: a score is the
        standardised temperatures times the loadings, so a gain per unit score b_j gives
        each sensor s the gain sum_j b_j loading_js / scale_s.

        Parameters
        ----------
        setting : dict
            The setting (one of :meth:`settings`).
        coefficients : sequence of float, length 3k
            The fitted gains, in :meth:`parameter_names` order [m per unit score].

        Returns
        -------
        ndarray, shape (S, 3)
            Gain of each sensor on x, y, z [m/K].
        """
        per_component = np.asarray(coefficients, float).reshape(-1, 3)      # (k, 3)
        loadings = np.asarray(setting["loadings"], float)                  # (k, S)
        return (loadings.T @ per_component) / np.asarray(setting["scale"], float)[:, None]

    def fit_problems(self, ctx, variant, setting, coefficients):
        """The per-sensor gains the fit amounts to, held to the bound a least-squares fit on
        those sensors is held to (:class:`SensorLeastSquares`): a statistical model may not
        pass where the sensors' own gains would be refused.

        Parameters
        ----------
        ctx : Context
            The machine and the variables at the N readings.
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).
        coefficients : sequence of float, length 3k
            The fitted gains [m per unit score].

        Returns
        -------
        list of str
            One sentence per sensor beyond the bound (empty: none).
        """
        bound = thermal_gain_limit_m_per_k(ctx.machine)
        gains = self.implied_gains(setting, coefficients)
        problems = []
        for sensor, row in zip(setting["sensors"].split("+"), gains):
            for axis, gain in zip("xyz", row):
                if abs(gain) > bound:
                    problems.append(f"its gain on {sensor} amounts to b{axis} = {gain:.3g} m/K, "
                                    f"beyond +-{bound:.3g} (free expansion of the structure "
                                    "per K)")
        return problems

    def describe_setting(self, setting):
        """The setting in words: ``"k of S"``.

        Parameters
        ----------
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            Number of components of number of sensors.
        """
        return f"{len(setting.get('loadings', ()))} of {setting.get('sensors', '').count('+') + 1}"

    def explanation(self, variant, setting):
        """One sentence of physics for a user (see :meth:`EffectFamily.explanation`).

        Parameters
        ----------
        variant : str
            The variant (one of :meth:`variants`).
        setting : dict
            The setting (one of :meth:`settings`).

        Returns
        -------
        str
            The sentence.
        """
        sensors = setting.get("sensors", "").split("+")
        return (f"the residual follows the first {variant} principal component(s) of "
                f"{len(sensors)} sensors - the temperature field's main patterns, the "
                "sensors' collinearity taken out")


def families() -> list[EffectFamily]:
    """The log-only families of this module, newly made.

    Returns
    -------
    list of EffectFamily
        :class:`SensorLeastSquares` (nothing chosen yet) and :class:`TemperatureComponents`.
    """
    return [SensorLeastSquares(), TemperatureComponents()]
