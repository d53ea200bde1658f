"""Forward selection of missing effects, judged only on readings the fit did not see.

Given the residual r = measured - model at N readings (time order) and the
catalogue's candidate terms, each step

1. scores every candidate by **time-blocked K-fold cross-validation**: the
   readings are cut into K contiguous blocks; each block is predicted by the
   terms already selected plus the candidate, fitted on the other blocks, with
   the candidate's setting (order, period, time constant) chosen **inside the
   fold** from the training blocks only - so a searched period or time
   constant cannot fit the held-out noise;
2. takes the candidate with the smallest out-of-fold error and **tests** it:
   the fraction of the out-of-fold squared error it removes is taken in each
   of ``n_blocks`` contiguous blocks (blocks against the residual's
   autocorrelation; fractions so that a trend whose error sits in the end
   blocks weighs like a uniform one) on the components the candidate moves, and tested
   one-sided (t-test), the p-value adjusted for every candidate tried by Westfall-Young
   max-T (:func:`max_t_adjusted`: the best of M is not a chance winner), and it
   (a weak effect spread evenly moves each block too little for that test: the
   candidate ranked first by the held-out data may pass instead on its full-data
   coefficients, Bonferroni over every candidate and setting tried - not on a log
   validated forward, whose slow residual breaks the test's independence); it
   must also cut the out-of-fold RMSE by ``min_reduction``, remove at least
   ``min_share`` of what lies above the instrument's noise (a wrong family
   that trims a little is not an explanation), and carry a parameter above
   3 standard errors;
   Candidates whose held-out error is within ``tie`` (2 % in mean square) of the
   best cannot be told apart by these data: the simplest of them (fewest
   assumptions, :attr:`EffectFamily.complexity`) is taken - Occam's razor;
   a candidate whose full-data fit physics does not allow (beyond its
   family's :meth:`~..effects.base.EffectFamily.parameter_limits`, or larger
   at the readings than the residual it explains - :mod:`..effects.physics`)
   is **refused**, with the reason, and the next one is considered;
3. if it passes, adds it (setting chosen on all readings), refits every
   selected term jointly, re-tests every earlier term against the ones before it
   and the newest (one the newest explains is dropped: :meth:`Selector.no_longer_needed`),
   and looks again; otherwise stops, and takes out a term the others together leave
   with every number inside its expanded uncertainty (:meth:`Selector.carrying_nothing`);
4. refits every named term jointly: one physics refuses there goes - unless a term named
   after it broke its fit (without that one physics accepts the model, which predicts the
   held-out readings better than without the refused term), which then goes instead; a
   term that passed only beside a refused one goes with it; and the search goes on from
   what remains, without what went.

The false-alarm rate of this rule on data with nothing missing is measured
in ``bench/workbench_catalogue.py`` (docs/results.md).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray

from ...errors import InsufficientDataError
from ...effects.base import Context
from ...effects.geometric import located_turns
from ...effects.physics import consistency_allowances, limit_problems, spread_problems
from ..distributions import chi2_sf
from ..line_search import minimise_bounded
from .designs import ReadingDesigns, Term, _BaseStatistics, penalty_of
from .folds import time_blocks
from .linalg import (BATCH_BYTES, penalise, penalised_fit, products_fit, products_fits,
                     same_shape_batches, solve_normal, solve_normal_grouped)
from .significance import (Evidence, PassRule, block_gains, coefficient_p_value,
                           gain_p_value, max_t_adjusted)


#: How often the search goes on after physics refused a named term in the joint fit.
_RESUMED_SEARCHES = 2

#: How far down the first step's ranking a simpler first term is sought
#: (:meth:`Selector._simpler_start`). Below the leader may rank several flexible terms that
#: each stand in for two effects: the work's located set-up error beside a tilt's lever
#: holds an offset of the C line (ISO 230-7) and an offset of the A line that carries it.
SIMPLER_START_RANKS = 6

#: The coverage factor of an expanded uncertainty (GUM, ISO 14253-1: k = 2), by which a
#: coefficient is told from zero when the selection is pruned.
COVERAGE = 2.0


@dataclass
class Scored:
    """A candidate's cross-validated score at one selection step."""

    term: Term
    cv_rmse: float
    reduction: float
    p_value: float
    adjusted_p: float
    share_of_excess: float
    setting: dict
    #: Held-out squared error per reading and component, (N, 3) (kept for the best few
    #: candidates only).
    per_sample_sq: NDArray[np.float64] | None = field(repr=False)
    significant: bool = False
    coefficients: NDArray[np.float64] | None = None
    standard_errors: NDArray[np.float64] | None = None
    parameter_names: list[str] = field(default_factory=list)
    #: Why physics refuses its full-data fit ("" if it does not).
    refusal: str = ""
    #: The measured components its design moves (it is tested on these alone).
    components: str = "xyz"
    #: Its full-data coefficients' p-value, adjusted for every candidate setting tried
    #: (set for the step's first candidate only; 1 otherwise).
    coefficient_p: float = 1.0
    #: The second term of the pair it was named in (:meth:`Selector.pair_lookahead`): it
    #: passed only beside that one ("" when it passed on its own).
    paired_with: str = ""

    def evidence(self, on_coefficients: bool = False) -> Evidence:
        """What :class:`.significance.PassRule` reads of this candidate.

        Parameters
        ----------
        on_coefficients : bool
            It may pass on its full-data coefficients (:attr:`coefficient_p`) instead of
            the held-out block test.

        Returns
        -------
        Evidence
        """
        return Evidence(self.refusal, self.adjusted_p, self.reduction, self.share_of_excess,
                        self.coefficients, self.standard_errors,
                        self.coefficient_p if on_coefficients else 1.0)


def simplicity(candidate: Scored) -> tuple[int, int]:
    """How much a candidate assumes, for Occam's tie-break (smaller is simpler).

    Parameters
    ----------
    candidate : Scored
        A scored candidate (its full-data coefficients set).

    Returns
    -------
    tuple of int
        Its family's :meth:`~..effects.base.EffectFamily.variant_complexity`, then its
        number of fitted parameters (of two equally assuming families, the one that fits
        fewer numbers: an offset of the tool where it was located before a rotary line
        offset and its two tilts).
    """
    parameters = 0 if candidate.coefficients is None else int(candidate.coefficients.size)
    return candidate.term.family.variant_complexity(candidate.term.variant), parameters


def still_rotary_axes(candidate: Scored, ctx) -> int:
    """How many rotary axes of a candidate's line errors stood still over the readings
    (zero for any other family): Occam's first tie-break, a turning line before a still
    one that moves the readings alike.

    Parameters
    ----------
    candidate : Scored
        A scored candidate.
    ctx : Context
        The machine and the variables at the N readings.

    Returns
    -------
    int
        The number of its variant's rotary axes whose positions never changed.
    """
    if candidate.term.family.name != "rotary_location":
        return 0
    return sum(not ctx.moves(axis) for axis in candidate.term.variant)


@dataclass
class Step:
    """One selection step: the ranking and, if one passed, the term added."""

    base_cv_rmse: float
    ranking: list[Scored]
    added: Scored | None



@dataclass(frozen=True)
class SimplerStart:
    """The search began from a simpler first term than the first step's leader, because
    that whole selection predicts the held-out readings as well with fewer numbers
    (:meth:`Selector._simpler_start`)."""

    started_from: str
    leader: str
    parameters: int
    leader_parameters: int
    #: Out-of-fold RMS of each whole selection (the residual's unit: [m]).
    held_out_rms: float
    leader_held_out_rms: float

    def sentence(self) -> str:
        """What the output says of it, beside the term the search began from."""
        return (f"the search began from {self.started_from}, which assumes less than "
                f"{self.leader} (the first step's leader): that whole selection predicts the "
                f"held-out readings as well ({self.held_out_rms * 1e6:.3g} against "
                f"{self.leader_held_out_rms * 1e6:.3g} um RMS) with {self.parameters} numbers "
                f"instead of {self.leader_parameters}")


class Selector(ReadingDesigns):
    """Forward selection over ``terms`` for the residual (N, K) at ``ctx``'s readings.

    K = ``ctx.width``: 3 (the TCP position, [m]) or 6 (and the tool's direction,
    scaled to metres by ``ctx.orientation_lever_m``: every row has the same noise).
    """

    def __init__(self, ctx: Context, residual: NDArray[np.float64], mask: NDArray[np.bool_],
                 noise_sigma: float, *, folds: int = 5, n_blocks: int = 20,
                 alpha: float = 0.05, min_reduction: float = 0.05, min_share: float = 0.25,
                 tie: float = 0.02, forward: bool = False,
                 blocks: NDArray[np.intp] | None = None) -> None:
        n = residual.shape[0]
        if blocks is None and n < 4 * folds:
            raise InsufficientDataError(f"{n} reference readings; need >= {4 * folds}")
        #: Forward chaining (a log whose model will predict the future): the record is cut
        #: into folds + 1 blocks, each block is predicted by a fit on the blocks *before*
        #: it only, and the first block is never judged (nothing precedes it).
        self.forward = bool(forward)
        #: Set by :meth:`run` when the selection kept began from a simpler first term.
        self.simpler_start: SimplerStart | None = None
        folds = folds + 1 if self.forward else folds
        if blocks is not None:
            # Given blocks (a log of many runs: whole runs, never cut): 0, 1, ... in order.
            blocks = np.asarray(blocks, dtype=np.intp)
            if blocks.shape != (n,) or blocks[0] != 0 or np.any(np.diff(blocks) < 0) or \
                    np.any(np.diff(blocks) > 1) or blocks[-1] < 1:
                raise ValueError("blocks: (N,) non-decreasing 0, 1, ... with at least two")
            folds = int(blocks[-1]) + 1
        width = ctx.width
        if residual.shape != (n, width) or mask.shape != (n, width):
            raise ValueError(f"residual {residual.shape} and mask {mask.shape} must be "
                             f"({n}, {width}) for this context")
        self._set_readings(ctx, residual, mask,
                           time_blocks(n, folds) if blocks is None else blocks, folds,
                           self.forward)
        self.allowances = consistency_allowances(residual, mask, noise_sigma)
        #: Whether the effects' moves at the set-up were located as one sum that turns with
        #: the rotary axes (:func:`.geometric.located_turns`): then what one term moves
        #: through that sum, the others may cancel (:meth:`physics_refusal`).
        self.shared_located = located_turns(ctx)
        # Rows judged: all, or (forward) those after the first block.
        first_judged = self.fold_bounds[1][0] if self.forward else 0
        self.judged_row = np.arange(self.rows.size) >= first_judged
        judged_sample = np.zeros(n, dtype=bool)
        judged_sample[self.sample_of_row[self.judged_row]] = True
        self.judged_mask = mask & judged_sample[:, None]
        self.n_test_blocks = max(4, min(n_blocks, int(judged_sample.sum()) // 6))
        # Unjudged readings go to one extra block the test leaves out.
        self.block_of_sample = np.full(n, self.n_test_blocks)
        self.block_of_sample[judged_sample] = time_blocks(int(judged_sample.sum()),
                                                          self.n_test_blocks)
        self.noise_sigma = float(noise_sigma)
        self.alpha, self.min_reduction, self.min_share = alpha, min_reduction, min_share
        #: The one acceptance rule (:class:`.significance.PassRule`).
        self.rule = PassRule(alpha, min_reduction, min_share)
        self.tie = tie
        #: How many of a step's best candidates keep their per-reading errors.
        self.keep_errors = 3
        self.selected: list[tuple[Term, dict]] = []
        #: Terms taken out again because a later one explains them: (dropped, by).
        self.dropped: list[tuple[Scored, Scored]] = []
        #: Terms taken out because the others together leave them nothing to carry:
        #: (dropped, the names of the terms kept) (:meth:`carrying_nothing`).
        self.dropped_jointly: list[tuple[Scored, list[str]]] = []
        #: Terms named beside one physics refused in the joint fit, taken out when they do
        #: not pass without it: (dropped, the refused term's name) (:meth:`_without_refused`).
        self.dropped_with_refused: list[tuple[Scored, str]] = []
        #: Terms named after one they made physics refuse in the joint fit, taken out so
        #: that it stands: (dropped, the earlier term's name, why physics refused it) -
        #: (:meth:`_later_break`).
        self.dropped_for_refusal: list[tuple[Scored, str, str]] = []

    def physics_refusal(self, term: Term, setting: dict, coefficients: NDArray[np.float64],
                        own_square_sum: float | None = None,
                        others: NDArray[np.float64] | None = None) -> str:
        """Why physics refuses ``term`` fitted with ``coefficients``.

        Parameters
        ----------
        term : Term
            The candidate.
        setting : dict
            Its setting.
        coefficients : ndarray, shape (P,)
            Its fitted parameters (SI).
        own_square_sum : float, optional
            c'X'Xc, the sum of the term's own contribution squared over the rows fitted
            [m^2] (from the products at hand). Every component's spread is at most
            sqrt(that / its rows); when that bound lies within every allowance, no
            spread can exceed one and the contribution itself is not made.
        others : ndarray, shape (R,), optional
            What the other named terms of the same joint fit move on the rows fitted [m].
            Where the set-up was located as one sum that turns with the rotary axes
            (:attr:`shared_located`), part of the term's spread may cancel theirs there
            (:func:`.physics.spread_problems`); elsewhere each term is held to the
            residual alone (two stand-ins of one period cancelling each other's arm).

        Returns
        -------
        str
            Its limits, its family's own checks and its spread per component against
            the residual's allowances, "; "-joined; "" if it may stand.
        """
        names = term.family.parameter_names(term.variant, setting)
        problems = limit_problems(names, coefficients,
                                  term.family.parameter_limits(self.ctx, term.variant, setting))
        coefficients = np.asarray(coefficients, float)
        problems += term.family.fit_problems(self.ctx, term.variant, setting, coefficients)
        if own_square_sum is not None and self._spreads_within_allowances(own_square_sum):
            return "; ".join(problems)
        spreads = self._spreads(self.prediction_rows(term, setting, coefficients))
        carried = None if others is None or not self.shared_located else \
            self._spreads(others)
        problems += spread_problems(spreads, self.allowances, self.ctx.orientation_lever_m,
                                    carried)
        return "; ".join(problems)

    def joint_refusals(self, terms: list[tuple[Term, dict]],
                       coefficients: list[NDArray[np.float64]],
                       judged: list[int] | None = None) -> list[str]:
        """:meth:`physics_refusal` of each of ``terms`` fitted jointly with ``coefficients``,
        beside what the others move.

        Parameters
        ----------
        terms : list of (Term, dict)
            The jointly fitted terms and their settings.
        coefficients : list of ndarray
            Each term's coefficients in that fit (SI).
        judged : list of int, optional
            The indices of the terms judged (default: all).

        Returns
        -------
        list of str
            Per judged term, why physics refuses it ("" where it may stand).
        """
        judged = range(len(terms)) if judged is None else judged
        if not self.shared_located:
            return [self.physics_refusal(terms[k][0], terms[k][1], coefficients[k])
                    for k in judged]
        predictions = [self.prediction_rows(t, s, c) for (t, s), c in zip(terms, coefficients)]
        total = np.sum(predictions, axis=0)
        return [self.physics_refusal(terms[k][0], terms[k][1], coefficients[k],
                                     others=total - predictions[k]) for k in judged]

    def prediction_rows(self, term: Term, setting: dict, coefficients: NDArray[np.float64]
                        ) -> NDArray[np.float64]:
        """(R,) what ``term`` at ``setting`` with ``coefficients`` moves on the rows fitted [m]."""
        coefficients = np.asarray(coefficients, float)
        basis = self.basis_rows(term, setting)
        return self.design_rows(term, setting) @ coefficients if basis is None else \
            self._separable_prediction(term, basis, coefficients)

    def _spreads(self, rows: NDArray[np.float64]) -> dict[str, float]:
        """Each judged component's spread about its mean of ``rows`` (R,) [m], from the rows
        that measured it."""
        if self.all_rows:
            # (Column reductions by products: numpy's strided std is several times slower.)
            per_sample = rows.reshape(-1, self.width)
            centred = per_sample - (self._ones @ per_sample) / per_sample.shape[0]
            spread = np.sqrt(np.einsum("ij,ij->j", centred, centred) / per_sample.shape[0])
        else:
            count = np.bincount(self.component_of_row, minlength=self.width)
            mean = np.bincount(self.component_of_row, weights=rows, minlength=self.width) / \
                np.maximum(count, 1)
            spread = np.sqrt(np.bincount(self.component_of_row,
                                         weights=(rows - mean[self.component_of_row]) ** 2,
                                         minlength=self.width) / np.maximum(count, 1))
        return {component: float(spread[c]) for c, component in enumerate(self.components)
                if component in self.allowances}

    def _named_prediction(self, base: NDArray[np.float64], coefficients: NDArray[np.float64]
                          ) -> NDArray[np.float64]:
        """(R,) what the selected terms among the model's columns ``base`` (R, q) move with
        their ``coefficients`` (q,) of a joint fit [m] (the offsets left out: they are the
        datum, no effect)."""
        start = self.offsets.shape[1]
        return base[:, start:] @ np.asarray(coefficients, float)[start:]

    def _spreads_within_allowances(self, own_square_sum: float) -> bool:
        """Can no component's spread of a contribution whose squares sum to
        ``own_square_sum`` over the rows fitted exceed its allowance? (A spread about the
        mean of n_c rows is at most sqrt(sum / n_c); a margin of 1e-9 covers the rounding
        of a sum taken from products.)"""
        if not np.isfinite(own_square_sum) or own_square_sum < 0:
            return False
        for c, component in enumerate(self.components):
            allowed = self.allowances.get(component)
            rows = self._rows_per_component[c]
            if allowed is None or rows == 0:
                continue
            if not np.sqrt(own_square_sum / rows) * (1.0 + 1e-9) <= allowed:
                return False
        return True

    # ------------------------------------------------------------ scoring
    # Every fold's fit is solved from normal equations: the training blocks' products
    # are the whole record's minus the held-out block's, and each block's products are
    # computed once per design (the selected model's once per step). A candidate then
    # costs one pass over its own columns instead of a refit per fold and setting.
    def _train(self, per_fold: NDArray[np.float64]) -> NDArray[np.float64]:
        """Per-fold sums -> each fold's training sums: every other fold's, or (forward)
        the earlier folds' only (:meth:`.folds.Folds.training_sums`)."""
        return self.cv.training_sums(per_fold)

    def _per_sample(self, squared_rows: NDArray[np.float64]) -> NDArray[np.float64]:
        """Squared errors of the judged rows -> (N, 3) per reading and component."""
        if self.forward:
            squared_rows = np.where(self.judged_row, squared_rows, 0.0)
        if self.all_rows:
            # Every component of every reading fitted: the rows are the readings' already.
            return squared_rows.reshape(self.n, self.width)
        return np.bincount(self.rows, weights=squared_rows,
                           minlength=self.mask.size).reshape(self.n, self.width)

    def _held_out_errors(self, x: NDArray[np.float64], coefficients: NDArray[np.float64]
                         ) -> NDArray[np.float64]:
        """(R,) each row's squared error under its fold's ``coefficients`` (F, p) of
        ``x`` (R, p)."""
        residual, _ = self.cv.held_out_residuals(x, self.y, lambda fold: coefficients[fold])
        return residual ** 2

    def out_of_fold(self, stats: _BaseStatistics, term: Term | None,
                    fold_fits: tuple[list[dict], dict] | None = None
                    ) -> tuple[NDArray[np.float64], dict]:
        """Out-of-fold squared errors of the current model (+ ``term``).

        Parameters
        ----------
        stats : _BaseStatistics
            The current model's per-fold products (:meth:`base_statistics`).
        term : Term or None
            A candidate, its setting chosen inside each fold (:meth:`choose_settings`);
            None: the current model alone.
        fold_fits : (list of dict, dict), optional
            ``term``'s :meth:`fold_fits`, when already made (a step makes every
            candidate's together).

        Returns
        -------
        per_sample : ndarray, shape (N, K)
            Squared held-out errors per reading and component [m^2] (0 where not judged).
        settings : dict
            Fold -> the setting it chose (empty for None).
        """
        if term is None:
            q = stats.base.shape[1]
            coefficients = solve_normal(self._train(stats.products[:, :q, :q]),
                                        self._train(stats.products[:, :q, q]))
            return self._per_sample(self._held_out_errors(stats.base, coefficients)), {}
        settings, fits = self.fold_fits([term], stats)[0] if fold_fits is None else fold_fits
        squared = np.empty(self.y.size)
        q = stats.base.shape[1]
        for key, coefficients in fits.items():
            setting = dict(key)
            basis = self.basis_rows(term, setting)
            design = self.design_rows(term, setting) if basis is None else None
            for fold, (a, b) in enumerate(self.fold_bounds):
                if settings[fold] == setting:
                    own = design[a:b] @ coefficients[fold, q:] if basis is None else \
                        self._separable_prediction(term, basis, coefficients[fold, q:], a, b)
                    squared[a:b] = (stats.base[a:b] @ coefficients[fold, :q] + own -
                                    self.y[a:b]) ** 2
        return self._per_sample(squared), dict(enumerate(settings))

    def fold_fits(self, terms: list[Term], stats: _BaseStatistics
                  ) -> list[tuple[list[dict], dict[tuple, NDArray[np.float64]]]]:
        """Each candidate's in-fold settings and the folds' fits of the settings chosen.

        The fits the choice of settings compared already (the same products,
        unpenalised) are taken from it; the others are solved together, the normal
        matrices of one size of every candidate in batched calls
        (:func:`.linalg.same_shape_batches`; each fit is its own call's, bit for bit).

        Parameters
        ----------
        terms : list of Term
            The candidates.
        stats : _BaseStatistics
            The current model's per-fold products.

        Returns
        -------
        list of (settings, fits)
            Per candidate, in order: the setting each fold chooses (:meth:`choose_settings`,
            length F) and, per setting chosen by its sorted items, every fold's fit of
            base + candidate on its training blocks (F, q + p).
        """
        q = stats.base.shape[1]
        plans, pending = [], []
        for index, (term, (settings, compared)) in enumerate(
                zip(terms, self._settings_and_fits_of(terms, stats))):
            fits = {}
            for key in dict.fromkeys(tuple(sorted(s.items())) for s in settings):
                fits[key] = compared.get(key)
                if fits[key] is None:
                    pending.append((index, key, term, self._products_of(stats, term, dict(key))))
            plans.append((settings, fits))
        # The training blocks' matrices are made per batch: all at once, they would be a
        # copy of every candidate's products.
        for batch in same_shape_batches([products[0].shape for *_, products in pending]):
            grams, rhs = [], []
            for i in batch:
                _, key, term, (gram, right, _) = pending[i]
                grams.append(penalise(self._train(gram), q, gram.shape[1],
                                      penalty_of(term, dict(key))))
                rhs.append(self._train(right))
            solved = solve_normal(np.stack(grams), np.stack(rhs))
            for k, i in enumerate(batch):
                index, key, _, _ = pending[i]
                plans[index][1][key] = solved[k]
        return plans

    def choose_settings(self, term: Term, stats: _BaseStatistics) -> list[dict]:
        """The setting each fold's training blocks choose (preselection or BIC).

        Parameters
        ----------
        term : Term
            The candidate.
        stats : _BaseStatistics
            The current model's per-fold products.

        Returns
        -------
        list of dict, length F
            One of ``term.settings`` per fold; a penalised family's strength is
            validated inside the fold (:meth:`_choose_penalty`).
        """
        return self._settings_and_fits(term, stats)[0]

    def _settings_and_fits(self, term: Term, stats: _BaseStatistics
                           ) -> tuple[list[dict], dict[tuple, NDArray[np.float64]]]:
        """:meth:`choose_settings`, and each fold's fit (F, p) of the settings compared by
        BIC, by the setting's sorted items (empty when none was compared: one setting, a
        preselection for every fold, a penalised family)."""
        return self._settings_and_fits_of([term], stats)[0]

    def _settings_and_fits_of(self, terms: list[Term], stats: _BaseStatistics
                              ) -> list[tuple[list[dict], dict[tuple, NDArray[np.float64]]]]:
        """:meth:`_settings_and_fits` of each of ``terms``, the fits BIC compares solved
        for several candidates together (:func:`.linalg.solve_normal_grouped`), a few
        MB of training matrices at a time."""
        out: list = [None] * len(terms)
        waiting: list = []
        held = 0
        for index, term in enumerate(terms):
            chosen, trained = self._settings_before_bic(term, stats)
            if trained is None:
                out[index] = chosen, {}
                continue
            waiting.append((index, term, chosen, trained))
            held += sum(gram.nbytes for gram, _, _ in trained)
            if held > BATCH_BYTES:
                self._choose_by_bic(waiting, out)
                waiting, held = [], 0
        self._choose_by_bic(waiting, out)
        return out

    def _settings_before_bic(self, term: Term, stats: _BaseStatistics
                             ) -> tuple[list[dict | None], list[tuple] | None]:
        """``term``'s settings per fold where no BIC is needed (trained None), else the folds
        a preselection chose (None where it did not) and each setting's training products
        (X'X, X'y, y'y per fold) for BIC to compare."""
        if len(term.settings) == 1:
            return [term.settings[0]] * self.folds, None
        if getattr(term.family, "penalty_setting", None):
            return self._choose_penalty(term, stats), None
        chosen: list[dict | None] = [None] * self.folds
        if term.family.preselects:
            if stats.after_base is None:
                q = stats.base.shape[1]
                base_coefficients = solve_normal(self._train(stats.products[:, :q, :q]),
                                                 self._train(stats.products[:, :q, q]))
                trains = np.ones((self.folds, self.n), dtype=bool)
                after_base = np.zeros((self.folds, self.mask.size))
                for fold, (a, b) in enumerate(self.fold_bounds):
                    if self.forward:
                        # The readings before the fold; the first (never judged) fold
                        # chooses on itself.
                        first = self.sample_of_row[a]
                        trains[fold] = np.arange(self.n) < first if first > 0 else \
                            np.isin(np.arange(self.n), self.sample_of_row[a:b])
                        continue
                    trains[fold, self.sample_of_row[a:b]] = False
                    after_base[fold, self.rows] = self.y - stats.base @ base_coefficients[fold]
                stats.after_base = (trains, after_base.reshape(self.folds, -1, self.width))
            trains, after_base = stats.after_base
            # A family chooses its setting from the TCP position's rows (its own design's).
            chosen = term.family.preselect_folds(self.ctx, term.variant, term.settings,
                                                 after_base[:, :, :3], self.mask[:, :3], trains)
        if all(c is not None for c in chosen):
            return chosen, None
        return chosen, [tuple(self._train(a) for a in self._products_of(stats, term, setting))
                        for setting in term.settings]

    def _choose_by_bic(self, waiting: list, out: list) -> None:
        """Each waiting (index, term, chosen, trained) of :meth:`_settings_before_bic`: its
        settings' fold fits solved (together), the folds no preselection chose given the
        setting of least BIC, into ``out[index]``."""
        solved = iter(solve_normal_grouped([gram for *_, trained in waiting
                                            for gram, _, _ in trained],
                                           [rhs for *_, trained in waiting
                                            for _, rhs, _ in trained]))
        counts = np.array([max(a, 1) if self.forward else self.y.size - (b - a)
                           for a, b in self.fold_bounds], float)
        for index, term, chosen, trained in waiting:
            # (refused by physics, BIC): a fold takes a setting whose fit its family's
            # physics refuses (a pivot beyond the machine's reach) only when all are.
            best_key = np.full((self.folds, 2), np.inf)
            best = [term.settings[0]] * self.folds
            fits = {}
            for setting, (gram, rhs, yy) in zip(term.settings, trained):
                coefficients = next(solved)
                rss = np.maximum(yy - np.einsum("fi,fi->f", coefficients, rhs), 1e-300)
                bic = counts * np.log(rss / counts) + gram.shape[1] * np.log(counts)
                key = np.column_stack([self._refused_in_folds(term, setting, coefficients),
                                       bic])
                for fold in range(self.folds):
                    if tuple(key[fold]) < tuple(best_key[fold]):
                        best_key[fold], best[fold] = key[fold], setting
                if penalty_of(term, setting) <= 0:
                    fits[tuple(sorted(setting.items()))] = coefficients
            out[index] = [c if c is not None else b for c, b in zip(chosen, best)], fits

    def _refused_in_folds(self, term: Term, setting: dict,
                          coefficients: NDArray[np.float64]) -> NDArray[np.float64]:
        """(F,) 1 where the family's own physics (:meth:`EffectFamily.fit_problems`) refuses
        the fold's fit of ``term`` at ``setting``, else 0; ``coefficients`` (F, q + p) are
        the base's and the term's, the term's last."""
        own = len(term.family.parameter_names(term.variant, setting))
        return np.array([1.0 if term.family.fit_problems(self.ctx, term.variant, setting,
                                                         fold[fold.size - own:]) else 0.0
                         for fold in coefficients])

    def _validation_errors(self, term: Term, stats: _BaseStatistics,
                           pairs: list[tuple[int, int, NDArray[np.float64]]]
                           ) -> NDArray[np.float64]:
        """(pairs, settings) squared error on block g of a fit on the blocks ``weights`` (each
        pair (f, g, weights over folds)), from the per-fold products alone."""
        q = stats.base.shape[1]
        weights = np.array([w for _, _, w in pairs], dtype=np.float64)
        target = np.array([g for _, g, _ in pairs])
        out = np.empty((len(pairs), len(term.settings)))
        for k, setting in enumerate(term.settings):
            gram, rhs, yy = self._products_of(stats, term, setting)
            train_gram = np.einsum("pf,fij->pij", weights, gram)
            coefficients = solve_normal(penalise(train_gram, q, gram.shape[1],
                                                 penalty_of(term, setting)), weights @ rhs)
            out[:, k] = yy[target] - 2.0 * np.einsum("pi,pi->p", coefficients, rhs[target]) + \
                np.einsum("pi,pij,pj->p", coefficients, gram[target], coefficients)
        return out

    def _choose_penalty(self, term: Term, stats: _BaseStatistics) -> list[dict]:
        """A penalised family's strength per fold, chosen **inside** the fold: validated on
        each other training block by a fit on the remaining training blocks (forward: each
        earlier block by a fit on the blocks before it). Never on the held-out block."""
        folds = self.folds
        pairs = self.cv.validation_pairs()
        middle = term.settings[len(term.settings) // 2]
        if not pairs:
            return [middle] * folds
        errors = self._validation_errors(term, stats, pairs)
        per_fold = np.zeros((folds, len(term.settings)))
        seen = np.zeros(folds, dtype=bool)
        for (f, _, _), row in zip(pairs, errors):
            per_fold[f] += row
            seen[f] = True
        return [term.settings[int(np.argmin(per_fold[f]))] if seen[f] else middle
                for f in range(folds)]

    def _choose_penalty_all(self, term: Term, base: NDArray[np.float64]) -> dict:
        """A penalised family's strength on all readings: the least out-of-fold error
        after ``base``."""
        stats = self.base_statistics(base)
        errors = self._validation_errors(term, stats, self.cv.held_out_pairs())
        return term.settings[int(np.argmin(errors.sum(axis=0)))]

    def choose_setting_all(self, term: Term, base: NDArray[np.float64]) -> dict:
        """The setting all readings choose (preselection or BIC).

        Parameters
        ----------
        term : Term
            The candidate.
        base : ndarray, shape (R, q)
            The current model's columns.

        Returns
        -------
        dict
            One of ``term.settings``, refined continuously where the family has a
            continuous setting (a period, a time constant: :meth:`refine_setting`).
        """
        setting = term.settings[0]
        if getattr(term.family, "penalty_setting", None) and len(term.settings) > 1:
            return self._choose_penalty_all(term, base)
        if len(term.settings) > 1:
            after_base = np.zeros(self.mask.size)
            coefficients, *_ = np.linalg.lstsq(base, self.y, rcond=None)
            after_base[self.rows] = self.y - base @ coefficients
            setting = term.family.preselect(self.ctx, term.variant, term.settings,
                                            after_base.reshape(-1, self.width)[:, :3],
                                            self.mask[:, :3], np.ones(self.n, dtype=bool))
            if setting is None:
                n = self.y.size
                best_key = (np.inf, np.inf)
                for candidate in term.settings:
                    x = np.column_stack([base, self.design_rows(term, candidate)])
                    coefficients, *_ = np.linalg.lstsq(x, self.y, rcond=None)
                    rss = float(np.sum((x @ coefficients - self.y) ** 2))
                    bic = n * np.log(max(rss, 1e-300) / n) + x.shape[1] * np.log(n)
                    # The folds' rule: a setting physics refuses only when all are.
                    key = (float(self._refused_in_folds(term, candidate,
                                                        coefficients[None, :])[0]), bic)
                    if key < best_key:
                        setting, best_key = candidate, key
        return self.refine_setting(term, base, setting)

    def refine_setting(self, term: Term, base: NDArray[np.float64], setting: dict) -> dict:
        """Polish a grid setting's continuous parameter between its grid neighbours.

        The residual sum of squares is minimised by variable projection (the linear
        coefficients solved for at each trial value; Brent's method).

        Parameters
        ----------
        term : Term
            The candidate.
        base : ndarray, shape (R, q)
            The current model's columns.
        setting : dict
            A grid setting of ``term``.

        Returns
        -------
        dict
            ``setting`` with its continuous value polished (unchanged when the family has
            none, the grid one point, or no value between the neighbours fits better).
        """
        key = term.family.continuous_setting
        if key is None or len(term.settings) < 2 or key not in setting:
            return setting
        grid = np.array([s[key] for s in term.settings], dtype=float)
        where = int(np.argmin(np.abs(grid - setting[key])))
        low = grid[max(0, where - 1)]
        high = grid[min(grid.size - 1, where + 1)]
        low, high = min(low, high), max(low, high)
        if not high > low:
            return setting

        def rss(value: float) -> float:
            design = self.ctx.measured_design(term.family, term.variant,
                                              dict(setting, **{key: value}))
            x = np.column_stack([base, design.reshape(-1, design.shape[2])[self.rows]])
            coefficients, *_ = np.linalg.lstsq(x, self.y, rcond=None)
            return float(np.sum((x @ coefficients - self.y) ** 2))

        start = rss(setting[key])
        value, best = minimise_bounded(rss, low, high, x_tolerance=(high - low) * 1e-6)
        if best >= start:
            return setting
        return dict(setting, **{key: float(value)})

    def fit_full(self, terms: list[tuple[Term, dict]]):
        """Joint least-squares fit of the offsets and ``terms`` on every reading.

        Parameters
        ----------
        terms : list of (Term, dict)
            The terms and their settings (a penalised one with its ridge).

        Returns
        -------
        coefficients : list of ndarray, each shape (P_i,)
            Per term (SI).
        standard_errors : list of ndarray, each shape (P_i,)
            Per term.
        residual : ndarray, shape (R,)
            What the fit leaves on the rows [m].
        """
        blocks = [self.design_rows(t, s) for t, s in terms]
        x = np.column_stack([self.offsets] + blocks)
        penalties, start = [], self.offsets.shape[1]
        for (term, setting), block in zip(terms, blocks):
            penalties.append((start, start + block.shape[1], penalty_of(term, setting)))
            start += block.shape[1]
        coefficients, standard, residual = penalised_fit(x, self.y, penalties)
        out_c, out_s, start = [], [], self.offsets.shape[1]
        for block in blocks:
            out_c.append(coefficients[start:start + block.shape[1]])
            out_s.append(standard[start:start + block.shape[1]])
            start += block.shape[1]
        return out_c, out_s, residual

    def _fit_products(self, gram, rhs, yy, penalty: tuple[int, float] = (0, 0.0)):
        """Coefficients and standard errors of the whole record's fit from per-fold
        products (what :meth:`fit_full` computes from the columns); ``penalty`` (first
        penalised column, strength) for a ridge candidate (:func:`.linalg.products_fit`)."""
        return products_fit(gram, rhs, yy, self.y.size, penalty)

    def _baseline(self):
        """The current model's columns, out-of-fold squared errors per sample, the number
        of measured components, their mean square, and what of it stands above noise."""
        stats = self.base_statistics(self.base_columns())
        base_sq, _ = self.out_of_fold(stats, None)
        count = int(np.sum(self.judged_mask))
        base_mse = float(base_sq.sum() / count)
        return stats, base_sq, count, base_mse, base_mse - self.noise_sigma ** 2

    def step(self, terms: list[Term]) -> Step:
        """One selection step over ``terms``: :meth:`score` each held out, :meth:`rank` them,
        :meth:`test` the first.

        Parameters
        ----------
        terms : list of Term
            The candidates (any of them already selected must not be among them).

        Returns
        -------
        Step
            The current model's out-of-fold RMSE [m], the ranking (best first), and the
            candidate added (None if the first did not pass).
        """
        stats, base_sq, count, base_mse, _ = self._baseline()
        ranking, plausible_best = self.rank(self.score(terms, stats, base_sq, count))
        added = self.test(ranking, plausible_best, terms, stats.base)
        # Per-reading errors are kept only where a pair look-ahead may need them (N floats
        # per candidate: GBs over a catalogue at 1e5 readings).
        for s in ranking[self.keep_errors:]:
            if s is not added:
                s.per_sample_sq = None
        return Step(float(np.sqrt(base_mse)), ranking, added)

    def score(self, terms: list[Term], stats: _BaseStatistics, base_sq: NDArray[np.float64],
              count: int) -> list[Scored]:
        """Each candidate's held-out score against the current model.

        Parameters
        ----------
        terms : list of Term
            The candidates.
        stats : _BaseStatistics
            The current model's per-fold products (:meth:`base_statistics`).
        base_sq : ndarray, shape (N, K)
            Its out-of-fold squared errors per reading and component [m^2].
        count : int
            The components judged (the mean squares' denominator).

        Returns
        -------
        list of Scored
            In the order of ``terms``: out-of-fold RMSE, reduction and share on the
            components each moves, its block test's p-value adjusted for every
            candidate tried (Westfall-Young max-T), its full-data fit and whether
            physics refuses it.
        """
        # Every candidate's fold fits and full-data fit first, their solves batched.
        plans = self.fold_fits(terms, stats)
        q = stats.base.shape[1]
        reported = [self._reported_setting(settings) for settings, _ in plans]
        problems = [(*self._products_of(stats, term, setting), (q, penalty_of(term, setting)))
                    for term, setting in zip(terms, reported)]
        full_fits = products_fits(problems, self.y.size)
        scored, gains = [], []
        for term, plan, setting, problem, full_fit in zip(terms, plans, reported, problems,
                                                          full_fits):
            candidate, gain = self._score_one(term, stats, base_sq, count, plan, setting,
                                              problem[0], full_fit)
            scored.append(candidate)
            gains.append(gain)
            if len(scored) % 8 == 0:
                self._release_errors(scored)
        # The best of many candidates is no chance winner: each p-value is adjusted for
        # every candidate tried, by the distribution of the *largest* t over them all
        # (Westfall-Young max-T, blocks' signs flipped together). Bonferroni assumed the
        # candidates independent; dozens of near-copies (thermal lags of one sensor, a
        # straightness and its periodic twin) made it far too strict (a 7 sigma
        # coefficient ranked first and was not named).
        if scored:
            for s, adjusted in zip(scored, max_t_adjusted(np.array(gains))):
                s.adjusted_p = float(adjusted)
        return scored

    @staticmethod
    def _reported_setting(settings: list[dict]) -> dict:
        """The setting a candidate reports: the most frequent of its folds' ``settings``."""
        keys = [tuple(sorted(s.items())) for s in settings]
        # Ties by the first fold to choose it: never by a set's (hash-seeded) order.
        return dict(max(dict.fromkeys(keys), key=keys.count))

    def _score_one(self, term: Term, stats: _BaseStatistics, base_sq: NDArray[np.float64],
                   count: int, fold_fits: tuple[list[dict], dict], setting: dict,
                   gram: NDArray[np.float64],
                   full_fit: tuple[NDArray[np.float64], NDArray[np.float64]]
                   ) -> tuple[Scored, NDArray[np.float64]]:
        """:meth:`score` of one candidate (its p-value not yet adjusted) and its gain per
        test block (B,), from its :meth:`fold_fits`, its reported ``setting``, that
        setting's per-fold X'X ``gram`` (F, q + p, q + p) and its full-data fit there
        (coefficients, standard errors) (q + p,) each."""
        q = stats.base.shape[1]
        per_sample, _ = self.out_of_fold(stats, term, fold_fits)
        mse = float(per_sample.sum() / count)
        # Tested on the components it moves (the others' errors are the base's).
        moved = self.components_of(term)
        own_count = int(self.judged_mask.sum(axis=0)[moved].sum())
        own_base = float(base_sq.sum(axis=0)[moved].sum()) / own_count
        own_mse = float(per_sample[:, moved].sum()) / own_count
        own_excess = own_base - self.noise_sigma ** 2
        gain = self._block_gains(base_sq[:, moved].sum(axis=1),
                                 per_sample[:, moved].sum(axis=1))
        share = (own_base - own_mse) / own_excess if own_excess > 0 else \
            (1.0 if own_mse < own_base else 0.0)
        candidate = Scored(term, float(np.sqrt(mse)),
                           1.0 - np.sqrt(own_mse / own_base) if own_base > 0 else 0.0,
                           gain_p_value(gain), 1.0, float(share), setting, per_sample,
                           components="".join(c for c, m in zip(self.components, moved) if m))
        # Every candidate carries its full-data fit, so that a user may add any of them
        # (judged by physics now, while its design is at hand).
        candidate.coefficients, candidate.standard_errors = (a[q:] for a in full_fit)
        candidate.parameter_names = term.family.parameter_names(term.variant, setting)
        own = candidate.coefficients
        own_square_sum = float(own @ gram[:, q:, q:].sum(axis=0) @ own)
        # What the named terms move beside it, where its spread needs judging at all.
        others = None if not self.shared_located or \
            self._spreads_within_allowances(own_square_sum) else \
            self._named_prediction(stats.base, full_fit[0][:q])
        candidate.refusal = self.physics_refusal(term, setting, own, own_square_sum, others)
        return candidate, gain

    def rank(self, scored: list[Scored]) -> tuple[list[Scored], Scored | None]:
        """The candidates best first: physics first, then by out-of-fold RMSE, the
        simplest of those the held-out data cannot tell apart first (Occam).

        Parameters
        ----------
        scored : list of Scored
            From :meth:`score`.

        Returns
        -------
        ranking : list of Scored
            The plausible (physics does not refuse them) by out-of-fold RMSE, the
            simplest of those within ``tie`` of the best (in mean square) moved first;
            then the refused.
        plausible_best : Scored or None
            The plausible candidate with the least out-of-fold RMSE (None if none is).
        """
        scored = sorted(scored, key=lambda s: s.cv_rmse)
        # Physics first: a fit it refuses is no explanation, however well it scores.
        plausible = [s for s in scored if not s.refusal]
        scored = plausible + [s for s in scored if s.refusal]
        if not plausible:
            return scored, None
        # Occam: among candidates the held-out data cannot tell apart from the best
        # (out-of-fold MSE within ``tie``), the simplest explanation is named first: the
        # fewest assumptions, then the fewest parameters.
        limit = scored[0].cv_rmse ** 2 * (1.0 + self.tie)
        tied = [s for s in plausible if s.cv_rmse ** 2 <= limit]
        # A rotary line of an axis that stood still is read as the line of one it carries
        # that turned (a still body moves what it carries rigidly): the turning line first.
        simplest = min(tied, key=lambda s: (still_rotary_axes(s, self.ctx), *simplicity(s),
                                            s.cv_rmse))
        scored.remove(simplest)
        scored.insert(0, simplest)
        return scored, plausible[0]

    def test(self, ranking: list[Scored], plausible_best: Scored | None, terms: list[Term],
             base: NDArray[np.float64]) -> Scored | None:
        """Fit the first of ``ranking`` on all readings and ask the acceptance rule.

        Parameters
        ----------
        ranking : list of Scored
            From :meth:`rank`; its first is refitted (setting chosen on all readings,
            jointly with the selected terms) and marked ``significant`` if it passes.
        plausible_best : Scored or None
            From :meth:`rank`: the first by out-of-fold RMSE may pass on its full-data
            coefficients instead of the block test.
        terms : list of Term
            Every candidate tried (the coefficients' test is adjusted for their settings).
        base : ndarray, shape (R, q)
            The current model's columns.

        Returns
        -------
        Scored or None
            The first candidate if it passes (:class:`.significance.PassRule`), else None.
        """
        if plausible_best is None:
            return None
        best = ranking[0]
        setting = self.choose_setting_all(best.term, base)
        coefficients, standard, _ = self.fit_full(self.selected + [(best.term, setting)])
        best.setting = setting
        best.coefficients, best.standard_errors = coefficients[-1], standard[-1]
        best.parameter_names = best.term.family.parameter_names(best.term.variant, setting)
        best.refusal = self.joint_refusals(self.selected + [(best.term, setting)], coefficients,
                                           [len(self.selected)])[0]
        # A weak effect spread evenly over the readings moves each block's error
        # too little for the blocks' t-test; the candidate the held-out data rank
        # first may then pass on its full-data coefficients instead, Bonferroni-
        # adjusted over every candidate *and* setting tried (a 7 sigma
        # straightness was named 7 times in 10). Its held-out reduction and share
        # must still be there. Not on a log validated forward: its residual is a slow
        # time series, whose full-data standard errors assume an independence the
        # readings do not have (there, only predicting later blocks counts).
        settings_tried = sum(max(1, len(t.settings)) for t in terms)
        best.coefficient_p = min(1.0, coefficient_p_value(
            coefficients[-1], standard[-1], self.y.size) * settings_tried)
        best.significant = self.rule.passes(
            best.evidence(on_coefficients=not self.forward and best is plausible_best))
        return best if best.significant else None

    def _release_errors(self, scored: list[Scored]) -> None:
        """Free the per-reading errors (N floats each) of candidates that can no longer be
        among the first ``keep_errors`` of the ranking nor its Occam choice: kept are the
        best ``keep_errors`` by out-of-fold error, overall and among the plausible, and the
        plausible ones within the tie of the best that no other beats in both simplicity
        and error (memory stays bounded over a catalogue at 1e5 readings)."""
        holding = [s for s in scored if s.per_sample_sq is not None]
        if len(holding) <= 2 * self.keep_errors:
            return
        by_error = sorted(holding, key=lambda s: s.cv_rmse)
        plausible = [s for s in by_error if not s.refusal]
        keep = {id(s) for s in by_error[:self.keep_errors]}
        keep |= {id(s) for s in plausible[:self.keep_errors]}
        if plausible:
            # The Occam choice is the simplest of those tied with the best: a candidate
            # another beats in both simplicity and error can never be it (whatever the
            # final best), so of the tied only the front of (complexity, error) is kept.
            limit = plausible[0].cv_rmse ** 2 * (1.0 + self.tie)
            lowest = float("inf")
            for c in sorted((s for s in plausible if s.cv_rmse ** 2 <= limit),
                            key=lambda s: (*simplicity(s), s.cv_rmse)):
                if c.cv_rmse < lowest:
                    keep.add(id(c))
                    lowest = c.cv_rmse
        for s in holding:
            if id(s) not in keep:
                s.per_sample_sq = None

    def _block_gains(self, base_sq: NDArray[np.float64], per_sample: NDArray[np.float64]
                     ) -> NDArray[np.float64]:
        """Per held-out block, the fraction of its error that ``per_sample`` removes from
        ``base_sq`` (:func:`.significance.block_gains`)."""
        return block_gains(self.block_of_sample, self.n_test_blocks, base_sq, per_sample)

    def _block_test(self, base_sq: NDArray[np.float64], per_sample: NDArray[np.float64]
                    ) -> float:
        """One-sided p-value (t-test over blocks) that ``per_sample`` errors are below
        ``base_sq`` (:meth:`_block_gains`)."""
        return gain_p_value(self._block_gains(base_sq, per_sample))

    def held_out_p_value(self, base_sq: NDArray[np.float64], per_sample: NDArray[np.float64]
                         ) -> float:
        """The block test a selected term passes, for any two predictions of the readings.

        Parameters
        ----------
        base_sq : ndarray, shape (N,)
            One prediction's out-of-fold squared errors per reading [m^2] (e.g. the live
            model's).
        per_sample : ndarray, shape (N,)
            The other's (e.g. a refit's).

        Returns
        -------
        float
            One-sided p-value that ``per_sample`` is below ``base_sq`` (t-test over the
            test blocks' gains).
        """
        return self._block_test(base_sq, per_sample)

    def above_noise(self) -> bool:
        """Could what the selected terms leave be the instrument's noise alone? (chi-square
        at 0.1 %, and a systematic part above half the noise)"""
        if self.noise_sigma <= 0:
            return True
        _, _, rest = self.fit_full(self.selected)
        mean_square = float(rest @ rest) / rest.size
        return bool(chi2_sf(mean_square * rest.size / self.noise_sigma ** 2, rest.size - 1) <
                    0.001 and mean_square - self.noise_sigma ** 2 > (0.5 * self.noise_sigma) ** 2)

    def pair_lookahead(self, step: Step, remaining: list[Term], beam: int
                       ) -> tuple[Scored, Scored] | None:
        """Two effects at once, when no single candidate passes.

        Each may leave the other's error in its held-out blocks: each of the ``beam``
        best is tried as a first term with the best second term after it; the first
        must pass the acceptance rule for the pair against the current model (block
        test Bonferroni over every pair tried, twice the share) and the second its own
        step.

        Parameters
        ----------
        step : Step
            The step where nothing passed.
        remaining : list of Term
            The candidates not selected.
        beam : int
            How many of its ranking are tried first.

        Returns
        -------
        (Scored, Scored) or None
            The first and second terms of the pair with the least out-of-fold error, or
            None when no pair passes.
        """
        stats, base_sq, count, base_mse, excess = self._baseline()
        pair_rule = replace(self.rule, min_share=2 * self.rule.min_share)
        options = []
        for first in step.ranking[:beam]:
            setting = self.choose_setting_all(first.term, stats.base)
            self.selected.append((first.term, setting))
            try:
                inner = self.step([t for t in remaining if t.name != first.term.name])
            finally:
                self.selected.pop()
            second = inner.added
            if second is None:
                continue
            mse = float(second.per_sample_sq.sum() / count)
            adjusted = min(1.0, self._block_test(base_sq.sum(axis=1),
                                                 second.per_sample_sq.sum(axis=1)) *
                           beam * max(1, len(remaining)))
            share = (base_mse - mse) / excess if excess > 0 else 1.0
            together = self.selected + [(first.term, setting), (second.term, second.setting)]
            coefficients, standard, _ = self.fit_full(together)
            # The first term of a pair passes the one rule, with twice the share.
            evidence = Evidence(self.joint_refusals(together, coefficients,
                                                    [len(together) - 2])[0],
                                adjusted, 1.0 - np.sqrt(mse / base_mse), share,
                                coefficients[-2], standard[-2])
            if pair_rule.passes(evidence):
                first.setting, first.adjusted_p = setting, adjusted
                first.parameter_names = first.term.family.parameter_names(first.term.variant,
                                                                          setting)
                first.significant = True
                first.paired_with = second.term.name
                options.append((mse, first, second))
        if not options:
            return None
        _, first, second = min(options, key=lambda o: o[0])
        return first, second

    def no_longer_needed(self, steps: list[Step], newest: Scored) -> list[Scored]:
        """The earlier terms ``newest`` explains, taken out.

        Each earlier term is re-tested held out, as if it were a candidate now, against
        the terms selected before it *and* ``newest``; one that no longer passes the
        selection's tests (its out-of-fold gain, block test, share and strength) is
        explained by ``newest`` and taken out of :attr:`selected` and its step (a product
        first named as a simpler stand-in keeps none of them once it is in). Only what
        the newest term explains is dropped: a term that several later ones explain
        together stays (they may be stand-ins of it).

        Parameters
        ----------
        steps : list of Step
            The steps so far (a dropped term's step is left with ``added`` None).
        newest : Scored
            The term just added.

        Returns
        -------
        list of Scored
            The terms dropped (also recorded in :attr:`dropped`).
        """
        dropped = []
        for step in steps:
            earlier = step.added
            if earlier is None or earlier is newest:
                continue
            names = [t.name for t, _ in self.selected]
            position = names.index(earlier.term.name)
            against = self.selected[:position] + [s for s in self.selected
                                                  if s[0].name == newest.term.name]
            kept = self.selected
            self.selected = against
            try:
                retest = self.step([earlier.term])
            finally:
                self.selected = kept
            without = [s for s in kept if s[0].name != earlier.term.name]
            if retest.added is None and self._may_drop(kept, without):
                self.selected = without
                step.added = None
                self.dropped.append((earlier, newest))
                dropped.append(earlier)
        return dropped

    def _out_of_fold_mse(self, selected: list[tuple[Term, dict]]) -> float:
        kept = self.selected
        self.selected = selected
        try:
            return self._baseline()[3]
        finally:
            self.selected = kept

    def _may_drop(self, kept: list[tuple[Term, dict]], without: list[tuple[Term, dict]]
                  ) -> bool:
        """A term the newest explains goes only if the model without it predicts the
        held-out readings as well (out-of-fold MSE within the Occam tie) and physics still
        accepts every remaining term in their joint fit (two correlated sensors may each
        carry half of a growth that one alone could not)."""
        if self._out_of_fold_mse(without) > self._out_of_fold_mse(kept) * (1.0 + self.tie):
            return False
        if not without:
            return True
        coefficients, _, _ = self.fit_full(without)
        return not any(self.joint_refusals(without, coefficients))

    def run(self, terms: list[Term], max_terms: int = 4, beam: int = 3) -> list[Step]:
        """The forward selection: steps until nothing passes or ``max_terms`` were added.

        A first step where no single term passes tries pairs (:meth:`pair_lookahead`);
        one where a simpler candidate passes too may begin from it instead
        (:meth:`_simpler_start`). After each addition every earlier term must still earn
        its place (:meth:`no_longer_needed`); one that does not is dropped (:attr:`dropped`),
        and at the end one the others together leave carrying nothing
        (:meth:`carrying_nothing`).
        Every added term is refit jointly at the end; one physics then refuses is taken
        out again, with the reason.

        Parameters
        ----------
        terms : list of Term
            The candidates.
        max_terms : int
            The most terms selected.
        beam : int
            Candidates tried as a pair's first term (0: no pairs).

        Returns
        -------
        list of Step
            In order; ``Scored.coefficients`` of the added ones are the joint fit.
        """
        self.keep_errors = max(1, beam)
        self.simpler_start = None
        steps = self._simpler_start(terms, max_terms, beam,
                                    self._forward(terms, max_terms, beam, []))
        refused = self._refit_jointly(steps)
        for _ in range(_RESUMED_SEARCHES):
            if not refused or len(self.selected) >= max_terms:
                break
            # What physics refused in the joint fit left the readings it stood for
            # unexplained: the search goes on from what remains, without it.
            unrefused = [t for t in terms if t.name not in refused]
            steps = self._forward(unrefused, max_terms, beam, steps)
            refused |= self._refit_jointly(steps)
        return steps

    def _forward(self, terms: list[Term], max_terms: int, beam: int, steps: list[Step]
                 ) -> list[Step]:
        """:meth:`run`'s greedy steps from ``steps`` (and :attr:`selected`) on."""
        chosen = {t.name for t, _ in self.selected}
        remaining = [t for t in terms if t.name not in chosen]
        while len(self.selected) < max_terms and remaining:
            step = self.step(remaining)
            steps.append(step)
            # Two effects hiding each other show at the start; later, what the named
            # effects leave is judged one effect at a time.
            if step.added is None and beam and not steps[:-1] and \
                    len(self.selected) + 2 <= max_terms and self.above_noise():
                pair = self.pair_lookahead(step, remaining, beam)
                if pair is not None:
                    step.added = pair[0]
                    self.selected.append((pair[0].term, pair[0].setting))
                    remaining = [t for t in remaining if t.name != pair[0].term.name]
                    step = Step(float(np.sqrt(pair[0].per_sample_sq.sum() /
                                              np.sum(self.judged_mask))),
                                [pair[1]],
                                pair[1])
                    steps.append(step)
            if step.added is None:
                break
            self.selected.append((step.added.term, step.added.setting))
            remaining = [t for t in remaining if t.name != step.added.term.name]
            if len(self.selected) > 1:
                self.no_longer_needed(steps, step.added)
        self.carrying_nothing(steps)
        return steps

    def carrying_nothing(self, steps: list[Step]) -> list[Scored]:
        """The named terms the others together leave carrying nothing, taken out.

        :meth:`no_longer_needed` drops only what one later term explains alone. Several
        later terms together can leave an earlier one with nothing to carry: a tilt's
        arm and its pivot's slope, named after a first guess of another axis' tilt,
        leave that guess's numbers at zero. A term goes when, in the joint fit of every
        named term, each of its coefficients lies within its expanded uncertainty
        (|c| <= 2 s, k = 2) - no number of it is told from zero - and the model without it
        predicts the held-out readings as well (:meth:`_may_drop`). Of several such terms
        the one whose absence costs the held-out error least goes first, then the rest
        are judged again.

        Parameters
        ----------
        steps : list of Step
            The selection's steps (a dropped term's step is left with ``added`` None).

        Returns
        -------
        list of Scored
            The terms taken out (also recorded in :attr:`dropped_jointly`).
        """
        gone = []
        while len(self.selected) > 1:
            coefficients, standard, _ = self.fit_full(self.selected)
            idle = [k for k, (c, s) in enumerate(zip(coefficients, standard))
                    if c.size and np.all(np.abs(c) <= COVERAGE * s)]
            options = []
            for k in idle:
                without = self.selected[:k] + self.selected[k + 1:]
                if self._may_drop(self.selected, without):
                    options.append((self._out_of_fold_mse(without), k, without))
            if not options:
                break
            _, k, without = min(options, key=lambda option: option[:2])
            name = self.selected[k][0].name
            step = next(s for s in steps if s.added is not None and s.added.term.name == name)
            self.dropped_jointly.append((step.added, [t.name for t, _ in without]))
            gone.append(step.added)
            step.added = None
            self.selected = without
        return gone

    def _simpler_start(self, terms: list[Term], max_terms: int, beam: int,
                       steps: list[Step]) -> list[Step]:
        """The search begun from a simpler first term, when it ends as well with fewer
        parameters.

        The first step takes the candidate with the least held-out error; a flexible one
        (a rotary axis' harmonics) may stand in there for two simple effects together (a
        squareness and the tool's located error), after which each of them trims too
        little to be named. Each plausible candidate among the first step's
        :data:`SIMPLER_START_RANKS` best that assumes less
        (:meth:`EffectFamily.variant_complexity`) and passes the acceptance rule on its own
        is taken first instead, and the search goes on from it; its selection replaces the
        first when it predicts the held-out readings as well (out-of-fold MSE within the
        Occam tie) with no more effects and fewer parameters - Occam's razor over whole
        selections, not only over one step's candidates.
        """
        first = steps[0] if steps else None
        if first is None or first.added is None or not beam:
            return steps

        def size() -> tuple[int, int]:
            coefficients, _, _ = self.fit_full(self.selected)
            return len(self.selected), sum(c.size for c in coefficients)

        best = (steps, list(self.selected), (list(self.dropped), list(self.dropped_jointly)),
                self._out_of_fold_mse(self.selected), size())
        mse0, size0 = best[3], best[4]
        def assumes(s: Scored) -> int:
            return s.term.family.variant_complexity(s.term.variant)

        # Of fewer assumptions: a family that fits fewer numbers to the same assumptions (a
        # rotary axis' harmonics against its line's offsets and tilts) is no simpler start.
        for alternative in [s for s in first.ranking[1:SIMPLER_START_RANKS]
                            if not s.refusal and assumes(s) < assumes(first.added)]:
            self.selected, self.dropped, self.dropped_jointly = [], [], []
            stats = self._baseline()[0]
            start = replace(alternative)
            # On the block test alone: its full-data coefficients were not ranked first.
            if self.test([start], first.added, terms, stats.base) is None:
                continue
            self.selected = [(start.term, start.setting)]
            ranking = [start if s is alternative else s for s in first.ranking]
            path = self._forward(terms, max_terms, beam,
                                 [Step(first.base_cv_rmse, ranking, start)])
            mse, (count, parameters) = self._out_of_fold_mse(self.selected), size()
            # No more effects and fewer numbers: one effect is never traded for two.
            if mse <= best[3] * (1.0 + self.tie) and count <= best[4][0] and \
                    parameters < best[4][1]:
                best = (path, list(self.selected),
                        (list(self.dropped), list(self.dropped_jointly)), mse,
                        (count, parameters))
                # The term begun from (a later one may have explained it and taken its
                # place: its step then holds no addition).
                started_from = start.term.name
        if best[0] is not steps:
            self.simpler_start = SimplerStart(started_from,
                                              first.added.term.name, best[4][1], size0[1],
                                              float(np.sqrt(best[3])), float(np.sqrt(mse0)))
        steps, self.selected, (self.dropped, self.dropped_jointly) = best[0], best[1], best[2]
        return steps

    def _refit_jointly(self, steps: list[Step]) -> set[str]:
        """Every added term refit jointly; one physics then refuses is taken out again,
        with the reason (:meth:`run`); the names of those taken out."""
        refused_names: set[str] = set()
        while True:
            added = [s.added for s in steps if s.added is not None]
            if not added:
                break
            coefficients, standard, _ = self.fit_full(self.selected)
            for scored, c, s in zip(added, coefficients, standard):
                scored.coefficients, scored.standard_errors = c, s
            # Jointly refit, a term physics refuses is taken out again (named, refused).
            reasons = self.joint_refusals(self.selected, coefficients)
            refused = next((k for k, reason in enumerate(reasons) if reason), None)
            if refused is None:
                break
            scored, reason = added[refused], reasons[refused]
            at = next(k for k, step in enumerate(steps) if step.added is scored)
            if self._later_break(steps, at, reason):
                refused_names.add(self.dropped_for_refusal[-1][0].term.name)
                continue
            scored.refusal = "in the joint fit: " + reason
            scored.significant = False
            self.selected = [(t, st) for t, st in self.selected if t.name != scored.term.name]
            steps[at].added = None
            refused_names.add(scored.term.name)
            self._without_refused(steps, at, scored.term.name)
        return refused_names

    def _later_break(self, steps: list[Step], at: int, reason: str) -> bool:
        """One term named after the one at ``steps[at]`` taken out instead of it, when that
        leaves a model physics accepts whole and predicts the held-out readings better than
        the model without the refused term: the later term broke its fit (a straightness of
        the same period cancelling part of a tilt's arm, say). Of several, the one whose
        absence costs least. False (nothing taken out) when no later term does so.
        """
        without_refused = [s for s in self.selected if s[0].name != steps[at].added.term.name]
        best_mse, best = self._out_of_fold_mse(without_refused), None
        for step in steps[at + 1:]:
            if step.added is None:
                continue
            kept = [s for s in self.selected if s[0].name != step.added.term.name]
            coefficients, _, _ = self.fit_full(kept)
            if any(self.joint_refusals(kept, coefficients)):
                continue
            mse = self._out_of_fold_mse(kept)
            if mse < best_mse:
                best_mse, best = mse, (step, kept)
        if best is None:
            return False
        step, kept = best
        self.dropped_for_refusal.append((step.added, steps[at].added.term.name, reason))
        step.added = None
        self.selected = kept
        return True

    def _without_refused(self, steps: list[Step], at: int, refused: str) -> None:
        """The terms named beside a term physics refused in the joint fit, taken out when
        they do not pass the acceptance rule against the terms that remain: each named
        after it (it was in the model they were judged against) and a pair's first term
        named only with it (:meth:`pair_lookahead`)."""
        for k, step in enumerate(steps):
            first = step.added
            if first is None or (k < at and first.paired_with != refused):
                continue
            others = [s for s in self.selected if s[0].name != first.term.name]
            kept = self.selected
            self.selected = others
            try:
                retest = self.step([first.term])
            finally:
                self.selected = kept
            if retest.added is None:
                self.selected = others
                step.added = None
                self.dropped_with_refused.append((first, refused))

    def remaining_residual(self) -> NDArray[np.float64]:
        """(N, K) residual after the offsets and the selected terms (in-sample)."""
        _, _, residual_rows = self.fit_full(self.selected)
        out = np.zeros(self.mask.size)
        out[self.rows] = residual_rows
        return out.reshape(-1, self.width)
