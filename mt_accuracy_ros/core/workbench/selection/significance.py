"""Whether a candidate's gain is chance: p-values and the max-T adjustment.

A candidate is tested on the fraction of the out-of-fold squared error it removes in
each of B contiguous time blocks (:func:`block_gains`), one-sided over the blocks
(:func:`gain_p_value`), adjusted for every candidate tried by Westfall-Young max-T
(:func:`max_t_adjusted`); its full-data coefficients are tested by
:func:`coefficient_p_value`. Whether a candidate is accepted is one rule,
:class:`PassRule`, which the selection and the commands that judge a candidate on
their own (a log's runs) both ask.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError
from ..distributions import t_sf

#: Sign patterns drawn for the max-T adjustment (the smallest adjusted p is 1 / (K + 1)).
MAX_T_DRAWS = 4000


def coefficient_p_value(coefficients: NDArray[np.float64], standard: NDArray[np.float64],
                        readings: int) -> float:
    """Two-sided p-value that the largest |coefficient| / standard error of one term is chance.

    Parameters
    ----------
    coefficients : ndarray, shape (P,)
        The term's coefficients (any units).
    standard : ndarray, shape (P,)
        Their standard errors (the same units); a zero one is left out.
    readings : int
        The rows fitted (t has ``readings`` - P degrees of freedom).

    Returns
    -------
    float
        Bonferroni over the term's usable coefficients; 1 when none is usable.
    """
    coefficients = np.asarray(coefficients, dtype=np.float64)
    standard = np.asarray(standard, dtype=np.float64)
    usable = standard > 0
    if not usable.any():
        return 1.0
    largest = float(np.max(np.abs(coefficients[usable]) / standard[usable]))
    dof = max(1, readings - coefficients.size)
    return min(1.0, 2.0 * t_sf(largest, dof) * int(usable.sum()))


def gain_p_value(gain: NDArray[np.float64]) -> float:
    """One-sided t-test p-value that the blocks' mean gain is above zero.

    Parameters
    ----------
    gain : ndarray, shape (B,)
        The fraction of each held-out block's squared error removed (dimensionless).

    Returns
    -------
    float
        P(t >= observed) with B - 1 degrees of freedom (0 or 1 when every block gains
        alike).
    """
    spread = float(np.std(gain, ddof=1))
    if spread == 0:
        return 0.0 if np.mean(gain) > 0 else 1.0
    return t_sf(float(np.mean(gain)) / (spread / np.sqrt(gain.size)), gain.size - 1)


def block_gains(block_of_sample: NDArray[np.intp], n_test_blocks: int,
                base_sq: NDArray[np.float64], per_sample: NDArray[np.float64]
                ) -> NDArray[np.float64]:
    """Per held-out block, the fraction of its squared error a candidate removes.

    Scale-free, so a trend whose error sits in the end blocks counts as much as a
    uniform one.

    Parameters
    ----------
    block_of_sample : ndarray of int, shape (N,)
        Each reading's test block, 0..``n_test_blocks`` (the last: readings not judged).
    n_test_blocks : int
        B, the blocks tested.
    base_sq : ndarray, shape (N,)
        The current model's out-of-fold squared error per reading [m^2].
    per_sample : ndarray, shape (N,)
        The candidate's [m^2].

    Returns
    -------
    ndarray, shape (B,)
        1 - (the candidate's error) / (the base's), per block.
    """
    blocks = n_test_blocks + 1
    base_blocks = np.bincount(block_of_sample, weights=base_sq, minlength=blocks)
    gain = 1.0 - np.bincount(block_of_sample, weights=per_sample, minlength=blocks) / \
        np.maximum(base_blocks, 1e-300)
    return gain[:n_test_blocks]


def max_t_adjusted(gains: NDArray[np.float64], draws: int = MAX_T_DRAWS,
                   seed: int = 28) -> NDArray[np.float64]:
    """Westfall-Young max-T adjusted p-values of one-sided t-tests over blocks.

    Parameters
    ----------
    gains : ndarray, shape (M, B)
        Each of M candidates' gain in each of B held-out blocks.
    draws : int
        K, the sign patterns drawn.
    seed : int
        Of the sign patterns: the same data give the same answer.

    Returns
    -------
    ndarray, shape (M,)
        P(max over candidates of t >= candidate's t) when no candidate helps: every
        block's gains keep their sign or flip it together (a block's gains are symmetric
        about zero then), so the candidates' correlation is kept.
    """
    m, b = gains.shape
    if b < 2:
        return np.ones(m)
    mean = gains.mean(axis=1)
    spread = gains.std(axis=1, ddof=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        observed = np.where(spread > 0, mean / (spread / np.sqrt(b)),
                            np.where(mean > 0, np.inf, -np.inf))
    flips = np.random.default_rng(seed).choice([-1.0, 1.0], size=(draws, b))
    first = flips @ gains.T / b                                    # (K, M) means
    second = np.mean(gains ** 2, axis=1)                           # (M,) unchanged by flips
    variance = np.maximum(second - first ** 2, 0.0) * b / (b - 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(variance > 0, first / np.sqrt(variance / b), -np.inf)
    largest = np.sort(t.max(axis=1))
    exceed = draws - np.searchsorted(largest, observed, side="left")
    return (1.0 + exceed) / (draws + 1.0)


@dataclass(frozen=True)
class Evidence:
    """What the acceptance rule reads of one candidate, fitted against the current model.

    Attributes
    ----------
    refusal : str
        Why physics refuses its full-data fit ("" if it does not).
    adjusted_p : float
        The held-out block test's p-value, adjusted for every candidate tried (max-T).
    reduction : float
        The fraction of the out-of-fold RMSE it cuts (negative: it raises it).
    share_of_excess : float
        The fraction of the out-of-fold error above the instrument's noise it removes.
    coefficients : ndarray, shape (P,)
        Its full-data coefficients (any units).
    standard_errors : ndarray, shape (P,)
        Their standard errors (the same units; NaN where unknown).
    coefficient_p : float
        Its full-data coefficients' p-value, adjusted for every candidate and setting
        tried, where the candidate may pass on them instead of the block test (the one
        the held-out data rank first, not on a log validated forward); 1 otherwise.
    """

    refusal: str
    adjusted_p: float
    reduction: float
    share_of_excess: float
    coefficients: NDArray[np.float64]
    standard_errors: NDArray[np.float64]
    coefficient_p: float = 1.0


@dataclass(frozen=True)
class PassRule:
    """The one rule that accepts a candidate as a missing effect.

    A candidate passes when physics allows its fit, it is no chance winner (its held-out
    block test, or its full-data coefficients where it may pass on them, below
    ``alpha`` after adjusting for every candidate tried), it cuts the out-of-fold RMSE
    by ``min_reduction``, removes ``min_share`` of what lies above the noise (a wrong
    family that trims a little is not an explanation) and carries a parameter above
    ``sigmas`` standard errors.

    Parameters
    ----------
    alpha : float
        Level of the held-out test (adjusted p-values).
    min_reduction : float
        Least fraction of the out-of-fold RMSE cut, >= 0.
    min_share : float
        Least fraction of the error above noise removed.
    block_test : bool
        False leaves the held-out test out (a log's caller judges on whole later runs
        instead).
    sigmas : float
        A parameter must exceed this many standard errors.

    Raises
    ------
    ParameterError
        ``min_reduction`` below 0 (a candidate that raises the held-out error is never
        an explanation).
    """

    alpha: float = 0.05
    min_reduction: float = 0.05
    min_share: float = 0.25
    block_test: bool = True
    sigmas: float = 3.0

    def __post_init__(self) -> None:
        if not self.min_reduction >= 0:
            raise ParameterError(f"min_reduction {self.min_reduction}: must be >= 0")

    def refusal(self, candidate: Evidence) -> str:
        """Which test refuses ``candidate``, with its numbers; "" when it passes them all.

        Parameters
        ----------
        candidate : Evidence
            What the candidate's fit showed.

        Returns
        -------
        str
            The first test that fails, in the order physics, the held-out test, the
            out-of-fold reduction, the share above noise, the parameters' strength.
        """
        if candidate.refusal:
            return f"physics refuses its fit ({candidate.refusal})"
        if self.block_test and not (candidate.adjusted_p < self.alpha or
                                    candidate.coefficient_p < self.alpha):
            return (f"the held-out block test: p = {candidate.adjusted_p:.3g} after adjusting "
                    f"for every candidate tried (max-T), above {self.alpha:g}")
        if candidate.reduction < 0:
            return f"it raises the CV error by {-100 * candidate.reduction:.1f} %"
        if not candidate.reduction >= self.min_reduction:
            return (f"it cuts the CV error by {100 * candidate.reduction:.1f} %, below "
                    f"{100 * self.min_reduction:.0f} %")
        if not candidate.share_of_excess >= self.min_share:
            return (f"it removes {100 * candidate.share_of_excess:.0f} % of the error above "
                    f"the noise, below {100 * self.min_share:.0f} %")
        values = np.abs(np.asarray(candidate.coefficients, dtype=np.float64))
        errors = np.asarray(candidate.standard_errors, dtype=np.float64)
        if not np.any(values > self.sigmas * errors):
            return f"no parameter is above {self.sigmas:g} standard errors"
        return ""

    def passes(self, candidate: Evidence) -> bool:
        """Does ``candidate`` pass every test?

        Parameters
        ----------
        candidate : Evidence
            What the candidate's fit showed.

        Returns
        -------
        bool
            :meth:`refusal` is "".
        """
        return not self.refusal(candidate)
