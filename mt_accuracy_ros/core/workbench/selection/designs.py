"""Designs, sensitivities and per-fold products of the candidates at the readings.

A candidate (:class:`Term`: a family's variant and its grid of settings) acts on the
residual through its design, (rows, P) at the measured rows. A separable design (one
sensitivity per row times scalar columns per reading) lives on the readings instead.
The selection scores every candidate from per-fold products of its design with the
current model's columns and the residual (:meth:`ReadingDesigns.base_statistics`,
:meth:`ReadingDesigns._products_of`), kept on the context so that every selector over
the same readings shares them (:class:`_ReadingCaches`).
"""
from __future__ import annotations

import hashlib
import itertools
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ...effects.base import Context, EffectFamily
from ...effects.lru import ByteBoundedCache
from .folds import Folds


@dataclass
class Term:
    """One candidate: a family's variant with its grid of settings."""

    family: EffectFamily
    variant: str
    settings: list[dict]

    @property
    def name(self) -> str:
        return f"{self.family.name}:{self.variant}" if self.variant else self.family.name



def penalty_of(term: "Term", setting: dict) -> float:
    """The ridge strength ``setting`` gives ``term``.

    Parameters
    ----------
    term : Term
        The candidate.
    setting : dict
        One of its settings.

    Returns
    -------
    float
        lambda, relative to each column's sum of squares (:func:`.linalg.penalise`); 0 for
        a family without one.
    """
    key = getattr(term.family, "penalty_setting", None)
    return float(setting.get(key, 0.0)) if key else 0.0


def design_setting(term: "Term", setting: dict) -> tuple:
    """The part of ``setting`` that makes the design (a penalty does not): a cache key.

    Parameters
    ----------
    term : Term
        The candidate.
    setting : dict
        One of its settings.

    Returns
    -------
    tuple
        Its (name, value) pairs but the penalty's, sorted, lists made tuples (hashable).
    """
    key = getattr(term.family, "penalty_setting", None)
    # (Asked for several times per candidate and step: no closure made per call.)
    return tuple(sorted((k, _frozen(v) if isinstance(v, (list, tuple)) else v)
                        for k, v in setting.items() if k != key))


def _frozen(sequence: list | tuple) -> tuple:
    """``sequence`` with every list or tuple in it, nested, made a tuple (hashable)."""
    return tuple(_frozen(v) if isinstance(v, (list, tuple)) else v for v in sequence)


@dataclass
class _BaseStatistics:
    """The selected model's columns and per-fold products of [columns, y] with themselves."""

    base: NDArray[np.float64]
    products: NDArray[np.float64]   # (folds, q + 1, q + 1)
    with_y: NDArray[np.float64]     # (rows, q + 1): [base, y]
    #: Per-fold products of each candidate (term, setting) with these columns.
    candidates: dict = field(default_factory=dict)
    #: (training sets (folds, N), each fold's residual after its base fit (folds, N, 3)):
    #: what every preselecting candidate's in-fold search starts from.
    after_base: tuple | None = None
    #: Unique per statistics a selector computed: the key of what is cached against them.
    serial: int = 0


#: Designs kept for reuse (every candidate's columns at every setting would hold GBs for
#: 1e5 readings); the least recently used beyond this are computed again when needed.
#: Measured (docs/benchmarks.md, A/B on one core): 96 MB and 48 MB for the sensitivities
#: were no faster than 32 and 16 MB at 1e4 or 1e5 readings - a design is cheap to make
#: again beside the page faults and heap growth of holding it - and held 150-180 MB more
#: at 1e5 (635-641 MB peak against 456-481 MB).
DESIGN_CACHE_BYTES = 32 * 2 ** 20
#: The separable terms' sensitivities, bounded alike.
SENSITIVITY_CACHE_BYTES = 16 * 2 ** 20


class _ReadingCaches:
    """What a selector derives from its context and rows alone - designs, scalar bases,
    sensitivities, where each term acts, and (per cut into folds) each design's products
    with itself - kept on the context, so that every selector over the same readings
    shares them: the look after the named effects are added (``check --auto``) scores
    the same candidates' designs against another residual."""

    def __init__(self) -> None:
        self.designs = ByteBoundedCache(DESIGN_CACHE_BYTES)
        self.sensitivities = ByteBoundedCache(SENSITIVITY_CACHE_BYTES)
        self.components: dict[str, NDArray[np.bool_]] = {}
        #: fold bounds -> {(term name, setting): per-fold X'X (folds, p, p)}.
        self.own_products: dict[tuple, dict] = {}


def _reading_caches(ctx: Context, mask: NDArray[np.bool_]) -> _ReadingCaches:
    """The caches of the selectors over ``ctx`` fitting the rows ``mask`` (N, K) selects."""
    key = ("selector caches", mask.shape, hashlib.sha1(np.packbits(mask)).digest())
    caches = ctx.cache.get(key)
    if caches is None:
        caches = ctx.cache[key] = _ReadingCaches()
    return caches


#: Serial numbers of base statistics, unique in the process: selectors sharing a cache
#: (:class:`_ReadingCaches`) must never key two bases alike.
_SERIALS = itertools.count(1)


def _largest_magnitude_per_row(design: NDArray[np.float64]) -> NDArray[np.float64]:
    """max_j |design[:, j]| (R,), column by column (numpy's reduction along a short last
    axis is several times slower than these passes)."""
    largest = np.abs(design[:, 0])
    for column in range(1, design.shape[1]):
        np.maximum(largest, np.abs(design[:, column]), out=largest)
    return largest


def per_target(offsets: NDArray[np.float64], groups: NDArray[np.intp] | None,
               sample_of_row: NDArray[np.intp]) -> NDArray[np.float64]:
    """The instrument's offsets split by target: one zero per located target.

    Parameters
    ----------
    offsets : ndarray, shape (R, 3)
        One free offset per position component (1 on the rows of that component).
    groups : ndarray of int, shape (N,), or None
        Each reading's target (:attr:`Context.target_groups`); None: one target.
    sample_of_row : ndarray of int, shape (R,)
        Each row's reading.

    Returns
    -------
    ndarray, shape (R, 3 G)
        The offsets' columns per target (``offsets`` itself when ``groups`` is None).
    """
    if groups is None:
        return offsets
    group = groups[sample_of_row]
    count = int(groups.max()) + 1
    return np.concatenate([offsets * (group == g)[:, None] for g in range(count)], axis=1)


#: Names of the measured components of a reading: the TCP position's, then (when the
#: instrument measured the tool's direction) the direction's, about x, y and z.
COMPONENT_NAMES = "xyzabc"



class ReadingDesigns:
    """The readings a selector fits and its candidates' designs and products there.

    A mixin of :class:`~.selector.Selector`: :meth:`_set_readings` lays out the rows
    (every measured component of every reading, in time order), the folds and the
    caches; the methods make a term's design, its sensitivity and its per-fold products
    with the current model.
    """

    def _set_readings(self, ctx: Context, residual: NDArray[np.float64],
                      mask: NDArray[np.bool_], fold_of_sample: NDArray[np.intp],
                      folds: int, forward: bool = False) -> None:
        """Lay out the rows ``mask`` (N, K) selects of ``residual`` (N, K) [m] at ``ctx``'s
        readings, each reading in its fold ``fold_of_sample`` (N,) (non-decreasing,
        0..``folds`` - 1; ``forward``: each fold trained on the earlier ones only)."""
        n, width = residual.shape
        self.ctx = ctx
        self.width = width
        self.components = COMPONENT_NAMES[:width]
        self.mask = mask
        self._measured_components = mask.any(axis=0)
        self._rows_per_component = mask.sum(axis=0)
        self.rows = np.flatnonzero(mask.ravel())
        self.sample_of_row = self.rows // width
        self.y = residual.ravel()[self.rows]
        self.n = n
        offsets = np.zeros((mask.size, width))
        offsets[np.arange(mask.size), np.tile(np.arange(width), n)] = 1.0
        # An instrument measures the TCP position from a zero of its own: a free offset
        # per position component (per target, when each of several spheres was located on
        # its own). The tool's direction it measures absolutely (an R-test's spheres lie
        # on the tool axis; its nest is aligned to the table): a constant tilt is the
        # machine's, not the instrument's.
        self.offsets = per_target(offsets[self.rows][:, :3], ctx.target_groups,
                                  self.sample_of_row)
        self.residual = residual
        self.component_of_row = self.rows % width
        self._ones = np.ones(n)
        self.fold_of_sample = fold_of_sample
        self.fold_of_row = self.fold_of_sample[self.sample_of_row]
        self.folds = folds
        #: The time-blocked cross-validation (:class:`.folds.Folds`): rows are in time
        #: order and folds contiguous, so each fold is one slice of rows.
        self.cv = Folds(self.fold_of_row, folds, forward)
        self.fold_bounds = self.cv.bounds
        # Separable designs (one sensitivity x scalar columns) live on the readings that
        # measured anything, one value each, instead of on the rows.
        self.present = np.unique(self.sample_of_row)
        self.present_of_row = np.searchsorted(self.present, self.sample_of_row)
        self.row_starts = np.searchsorted(self.sample_of_row, self.present)
        self.all_rows = self.rows.size == mask.size
        self.present_bounds = [(int(self.present_of_row[a]), int(self.present_of_row[b - 1]) + 1)
                               for a, b in self.fold_bounds]
        #: Per separable term: its sensitivity at each measured row and, after them, its
        #: square summed per reading - bounded like the designs (at 1e5 readings each is
        #: megabytes, and a catalogue has a hundred separable terms).
        caches = _reading_caches(ctx, mask)
        self._sensitivities = caches.sensitivities
        self._designs = caches.designs
        self._components = caches.components
        self._own_products = caches.own_products.setdefault(tuple(self.fold_bounds), {})

    def design_rows(self, term: Term, setting: dict) -> NDArray[np.float64]:
        """``term``'s design at ``setting`` on the rows fitted, from the cache or made.

        Parameters
        ----------
        term : Term
            The candidate.
        setting : dict
            One of its settings (a smaller setting nested in its largest is a view of
            the largest's columns).

        Returns
        -------
        ndarray, shape (R, P)
            Its columns [m per unit parameter] at the measured rows, in time order.
        """
        key = (term.name, design_setting(term, setting))
        design = self._designs.get(key)
        if design is None:
            columns = self._nested_columns(term, setting)
            if columns is not None:
                # Columns of the largest setting's design (the first ones: a view).
                largest = self.design_rows(term, term.settings[-1])
                return largest[:, :len(columns)] if columns[-1] == len(columns) - 1 else \
                    largest[:, columns]
            design = self.ctx.measured_design(term.family, term.variant, setting)
            design = design.reshape(-1, design.shape[2])
            if self.rows.size != design.shape[0]:
                design = design[self.rows]
            self._designs.put(key, design)
        return design

    @staticmethod
    def _nested_columns(term: Term, setting: dict) -> list[int] | None:
        """The columns of ``term``'s largest setting that are ``setting``'s (None when
        ``setting`` is the largest, or no part of it)."""
        if setting == term.settings[-1]:
            return None
        return term.family.nested_columns(term.variant, setting, term.settings[-1])

    def basis_rows(self, term: Term, setting: dict) -> NDArray[np.float64] | None:
        """The scalar columns of a separable design at the readings that measured anything.

        Parameters
        ----------
        term : Term
            The candidate.
        setting : dict
            One of its settings.

        Returns
        -------
        ndarray, shape (S, P), or None
            The columns (the design is these times :meth:`sensitivity` along each row);
            None when the family's design is not separable.
        """
        key = ("basis", term.name, design_setting(term, setting))
        basis = self._designs.get(key)
        if basis is None:
            columns = self._nested_columns(term, setting)
            if columns is not None:
                largest = self.basis_rows(term, term.settings[-1])
                if largest is None:
                    return None
                return largest[:, :len(columns)] if columns[-1] == len(columns) - 1 else \
                    largest[:, columns]
            separable = self.ctx.measured_separable(term.family, term.variant, setting)
            if separable is None:
                return None
            sensitivity, basis = separable
            if self._sensitivities.get(term.name) is None:
                self._sensitivities.put(term.name, self._sensitivity_rows(sensitivity))
            basis = np.ascontiguousarray(basis if self.all_rows else basis[self.present])
            self._designs.put(key, basis)
        return basis

    def _sensitivity_rows(self, sensitivity: NDArray[np.float64]) -> NDArray[np.float64]:
        """(R + S,): the sensitivity at each measured row (R = the rows fitted), then its
        square summed per reading (S) - one array, for the bounded cache."""
        if self.all_rows:
            flat = sensitivity.reshape(-1)
            return np.concatenate([flat, np.einsum("nc,nc->n", sensitivity, sensitivity)])
        flat = sensitivity.reshape(-1)[self.rows]
        return np.concatenate([flat, np.add.reduceat(flat * flat, self.row_starts)])

    def sensitivity(self, term: Term) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """A separable ``term``'s sensitivity, from the cache or made again.

        Parameters
        ----------
        term : Term
            A candidate whose design is separable (its sensitivity is the same at every
            setting).

        Returns
        -------
        along_rows : ndarray, shape (R,)
            Its sensitivity along each measured row [dimensionless].
        squared : ndarray, shape (S,)
            Its square summed per reading that measured anything.
        """
        both = self._sensitivities.get(term.name)
        if both is None:
            # Made again after the store let it go: from a setting whose design is separable
            # (a located tilt's last settings are not).
            separable = (self.ctx.measured_separable(term.family, term.variant, setting)
                         for setting in reversed(term.settings))
            sensitivity, _ = next(pair for pair in separable if pair is not None)
            both = self._sensitivity_rows(sensitivity)
            self._sensitivities.put(term.name, both)
        return both[:self.y.size], both[self.y.size:]

    def _separable_prediction(self, term: Term, basis: NDArray[np.float64],
                              coefficients: NDArray[np.float64], a: int = 0,
                              b: int | None = None) -> NDArray[np.float64]:
        """X @ coefficients over rows a:b of a separable design."""
        b = self.y.size if b is None else b
        along_rows = self.sensitivity(term)[0][a:b]
        start, stop = (self.present_of_row[a], self.present_of_row[b - 1] + 1) if b > a \
            else (0, 0)
        values = basis[start:stop] @ coefficients
        if self.all_rows:
            return along_rows * np.repeat(values, self.width)
        return along_rows * values[self.present_of_row[a:b] - start]

    def full_design(self, term: Term, setting: dict) -> NDArray[np.float64]:
        """``term``'s design at ``setting`` at every reading and component.

        Parameters
        ----------
        term : Term
            The candidate.
        setting : dict
            One of its settings.

        Returns
        -------
        ndarray, shape (N, K, P)
            Its columns [m per unit parameter], measured or not.
        """
        return self.ctx.measured_design(term.family, term.variant, setting)

    def base_columns(self) -> NDArray[np.float64]:
        """(R, q) the current model's columns: the offsets, then each selected term's."""
        columns = [self.offsets] + [self.design_rows(t, s) for t, s in self.selected]
        return np.column_stack(columns)

    def components_of(self, term: Term) -> NDArray[np.bool_]:
        """The measured components ``term``'s design moves (its largest setting's).

        A candidate changes the held-out prediction only where its columns are non-zero,
        so its error there is the base model's: pooling those components into its test
        dilutes an effect that lives in one component - it is judged on the
        components it moves.

        Parameters
        ----------
        term : Term
            The candidate.

        Returns
        -------
        ndarray of bool, shape (K,)
            Per component (x, y, z, then a, b, c): measured and moved (all measured ones
            when it moves none).
        """
        # Three booleans per term: kept apart from the designs' cache, whose evictions
        # would otherwise make a design again only to know where it acts.
        known = self._components.get(term.name)
        if known is None:
            setting = term.settings[-1]
            if self.basis_rows(term, setting) is not None:
                size = np.abs(self.sensitivity(term)[0])
            else:
                size = _largest_magnitude_per_row(self.design_rows(term, setting))
            # Rounding (a lever's cross product) is not a component the effect moves.
            size = size / max(float(np.max(size, initial=0.0)), 1e-300)
            largest = np.zeros(self.width)
            np.maximum.at(largest, self.component_of_row, size)
            known = (largest > 1e-9) & self._measured_components
            if not known.any():
                known = self._measured_components.copy()
            self._components[term.name] = known
        return known

    def _block_products(self, left: NDArray[np.float64], right: NDArray[np.float64]
                        ) -> NDArray[np.float64]:
        """(folds, a, b): left_f^T right_f over each fold's rows."""
        return self.cv.block_products(left, right)

    def base_statistics(self, base: NDArray[np.float64]) -> _BaseStatistics:
        """The selected model's per-fold products (its columns with themselves and y).

        Parameters
        ----------
        base : ndarray, shape (R, q)
            The model's columns (:meth:`base_columns`).

        Returns
        -------
        _BaseStatistics
            [base, y]'s products per fold, (F, q + 1, q + 1), and the columns.
        """
        with_y = np.column_stack([base, self.y])
        products = self._block_products(with_y, with_y)
        # The columns once (at 1e5 readings a model of a few terms is tens of MB): the
        # base is a view of [base, y].
        return _BaseStatistics(with_y[:, :-1], products, with_y, serial=next(_SERIALS))

    def _candidate_products(self, stats: _BaseStatistics, design: NDArray[np.float64],
                            key: tuple | None = None):
        """Per-fold normal equations of base + ``design``: X_f'X_f (folds, q+p, q+p), X_f'y_f
        (folds, q+p) and y_f'y_f (folds,); :func:`.folds.training_sums` turns them into the training
        blocks', a sum over folds into the whole record's. ``key`` (term name, setting):
        the design's products with itself are kept under it (they hold for any base)."""
        q = stats.base.shape[1]
        with_base = self._block_products(design, stats.with_y)     # (folds, p, q + 1)
        own = None if key is None else self._own_products.get(key)
        if own is None:
            own = self._block_products(design, design)             # (folds, p, p)
            if key is not None:
                self._own_products[key] = own
        return self._assemble_products(stats, q, with_base, own)

    def _assemble_products(self, stats: _BaseStatistics, q: int, with_base, own):
        """[base, design]'s per-fold products from the design's with [base, y] and itself."""
        products = stats.products
        size = q + own.shape[1]
        gram = np.empty((self.folds, size, size))
        gram[:, :q, :q] = products[:, :q, :q]
        gram[:, q:, :q] = with_base[:, :, :q]
        gram[:, q:, q:] = own
        gram[:, :q, q:] = np.swapaxes(with_base[:, :, :q], 1, 2)
        rhs = np.concatenate([products[:, :q, q], with_base[:, :, q]], axis=1)
        return gram, rhs, products[:, q, q]

    def _separable_products(self, stats: _BaseStatistics, term: Term,
                            basis: NDArray[np.float64], own_key: tuple | None = None):
        """:meth:`_candidate_products` of a separable design, on one value per reading: X'W
        = B'(sum over components of sensitivity x W) and X'X = B' diag(|sensitivity|^2) B."""
        # Kept in the design cache (bounded: at 1e5 readings one is megabytes per variant).
        # Per candidate (family and variant): a family's sensitivity is its own to say.
        key = ("contracted", term.name, stats.serial)
        along_rows, squared = self.sensitivity(term)
        contracted = self._designs.get(key)
        if contracted is None:
            if self.all_rows:
                width = stats.with_y.shape[1]
                contracted = np.einsum("nc,ncm->nm", along_rows.reshape(-1, self.width),
                                       stats.with_y.reshape(-1, self.width, width))
            else:
                contracted = np.add.reduceat(along_rows[:, None] * stats.with_y,
                                             self.row_starts, axis=0)
            self._designs.put(key, contracted)
        q = stats.base.shape[1]
        with_base = np.stack([basis[a:b].T @ contracted[a:b] for a, b in self.present_bounds])
        own = None if own_key is None else self._own_products.get(own_key)
        if own is None:
            own = np.stack(
                [basis[a:b].T @ (squared[a:b, None] * basis[a:b]) for a, b in self.present_bounds])
            if own_key is not None:
                self._own_products[own_key] = own
        return self._assemble_products(stats, q, with_base, own)

    def _products_of(self, stats: _BaseStatistics, term: Term, setting: dict):
        """:meth:`_candidate_products` of ``term`` at ``setting``, kept with ``stats`` (the
        full-data fit of the candidate reuses them)."""
        key = (term.name, design_setting(term, setting))
        cache = stats.candidates
        if key not in cache:
            columns = self._nested_columns(term, setting)
            if columns is not None:
                gram, rhs, yy = self._products_of(stats, term, term.settings[-1])
                q = stats.base.shape[1]
                if columns[-1] == len(columns) - 1:
                    size = q + len(columns)
                    cache[key] = (gram[:, :size, :size], rhs[:, :size], yy)
                else:
                    index = np.concatenate([np.arange(q), q + np.asarray(columns)])
                    cache[key] = (gram[:, index[:, None], index], rhs[:, index], yy)
            else:
                basis = self.basis_rows(term, setting)
                cache[key] = self._candidate_products(stats, self.design_rows(term, setting),
                                                      key) \
                    if basis is None else self._separable_products(stats, term, basis, key)
        return cache[key]

