"""The selection's linear algebra: normal equations, penalised fits, standard errors.

Every fit of the workbench is solved from its normal equations X'X c = X'y, the
columns equilibrated first and the directions the readings do not determine dropped
(the minimum-norm solution, as ``lstsq`` gives), so a fold's fit can be assembled
from per-fold products (:mod:`.folds`) instead of refitting its rows.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Directions of a scaled normal matrix with eigenvalue below this fraction of its largest
#: are dropped (minimum-norm solution, as ``lstsq`` gives): a Gram matrix's eigenvalues
#: are accurate to ~1e-15 of the largest, so a kept direction is known to 0.1 %.
NORMAL_RCOND = 1e-12


#: The most bytes of normal matrices decomposed in one batched call: a step's candidates
#: are batched for speed, but their stacked copies (and the decomposition's temporaries,
#: several times that) must not add to a check's peak memory.
BATCH_BYTES = 2 * 2 ** 20


def same_shape_batches(shapes: list[tuple[int, ...]], limit_bytes: int | None = None
                       ) -> list[list[int]]:
    """Indices of arrays of one shape, in batches of at most ``limit_bytes`` of float64.

    Parameters
    ----------
    shapes : list of tuple of int
        Each array's shape.
    limit_bytes : int, optional
        The most bytes of arrays in a batch (a batch holds at least one); default
        :data:`BATCH_BYTES`.

    Returns
    -------
    list of list of int
        Every index once, each batch of one shape, in the order first met.
    """
    limit_bytes = BATCH_BYTES if limit_bytes is None else limit_bytes
    groups: dict[tuple[int, ...], list[int]] = {}
    for i, shape in enumerate(shapes):
        groups.setdefault(tuple(shape), []).append(i)
    batches = []
    for shape, members in groups.items():
        per_batch = max(1, limit_bytes // max(8 * int(np.prod(shape)), 1))
        batches += [members[k:k + per_batch] for k in range(0, len(members), per_batch)]
    return batches


def _equilibrated_eigen(gram: NDArray[np.float64]):
    """(scale, eigenvectors, inverse eigenvalues) of X'X with unit-diagonal columns; the
    directions below :data:`NORMAL_RCOND` get inverse 0. Batched over leading axes."""
    diagonal = np.sqrt(np.clip(np.einsum("...ii->...i", gram), 0.0, None))
    scale = np.divide(1.0, diagonal, out=np.zeros_like(diagonal), where=diagonal > 0)
    values, vectors = np.linalg.eigh(gram * scale[..., :, None] * scale[..., None, :])
    keep = values > NORMAL_RCOND * np.maximum(values[..., -1:], 1e-300)
    return scale, vectors, np.divide(1.0, values, out=np.zeros_like(values), where=keep)


def solve_normal(gram: NDArray[np.float64], rhs: NDArray[np.float64]) -> NDArray[np.float64]:
    """Minimum-norm least-squares coefficients from normal equations, batched.

    Parameters
    ----------
    gram : ndarray, shape (..., p, p)
        X'X (symmetric, positive semi-definite).
    rhs : ndarray, shape (..., p)
        X'y.

    Returns
    -------
    ndarray, shape (..., p)
        Columns are equilibrated first (a zero column gets coefficient 0), so the
        cut-off does not depend on the columns' units.
    """
    return _solve_with(_equilibrated_eigen(gram), rhs)


def _solve_with(eigen, rhs: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`solve_normal` from X'X's :func:`_equilibrated_eigen` (made once for a fit
    that also needs :func:`normal_inverse` of the same matrix)."""
    scale, vectors, inverse = eigen
    projected = np.einsum("...ji,...j->...i", vectors, rhs * scale)
    return scale * np.einsum("...ij,...j->...i", vectors, inverse * projected)


def solve_normal_grouped(grams: list[NDArray[np.float64]], rhs: list[NDArray[np.float64]]
                         ) -> list[NDArray[np.float64]]:
    """:func:`solve_normal` of each pair, the pairs of one shape in one batched call.

    A candidate's settings are solved with one eigendecomposition call instead of one
    per setting; each result is its own call's, bit for bit.

    Parameters
    ----------
    grams : list of ndarray, each shape (..., p, p)
        X'X of each fit (p may differ between fits).
    rhs : list of ndarray, each shape (..., p)
        X'y of each fit.

    Returns
    -------
    list of ndarray, each shape (..., p)
        The coefficients of each fit, in the order given.
    """
    out: list[NDArray[np.float64] | None] = [None] * len(grams)
    for members in same_shape_batches([gram.shape for gram in grams]):
        if len(members) == 1:
            out[members[0]] = solve_normal(grams[members[0]], rhs[members[0]])
            continue
        solved = solve_normal(np.stack([grams[i] for i in members]),
                              np.stack([rhs[i] for i in members]))
        for k, i in enumerate(members):
            out[i] = solved[k]
    return out


def normal_inverse(gram: NDArray[np.float64]) -> NDArray[np.float64]:
    """(X'X)^-1 with the cut-off of :func:`solve_normal`.

    Parameters
    ----------
    gram : ndarray, shape (p, p)
        X'X.

    Returns
    -------
    ndarray, shape (p, p)
        The coefficients' covariance per unit variance [1 / (column unit)^2]; the
        directions :func:`solve_normal` drops get zero variance.
    """
    return _inverse_with(_equilibrated_eigen(gram))


def _inverse_with(eigen) -> NDArray[np.float64]:
    """:func:`normal_inverse` from X'X's :func:`_equilibrated_eigen`."""
    scale, vectors, inverse = eigen
    return scale[:, None] * ((vectors * inverse) @ vectors.T) * scale[None, :]


def penalise(gram: NDArray[np.float64], start: int, stop: int, strength: float
             ) -> NDArray[np.float64]:
    """X'X with a scale-free ridge on columns start:stop, batched.

    Parameters
    ----------
    gram : ndarray, shape (..., p, p)
        X'X.
    start, stop : int
        The penalised columns, start:stop.
    strength : float
        lambda, relative to each column's own sum of squares (dimensionless): the
        diagonal of those columns is multiplied by 1 + lambda.

    Returns
    -------
    ndarray, shape (..., p, p)
        The penalised X'X (``gram`` itself, not a copy, when ``strength`` <= 0).
    """
    if strength <= 0:
        return gram
    out = np.array(gram, dtype=np.float64, copy=True)
    index = np.arange(start, stop)
    out[..., index, index] *= 1.0 + strength
    return out


def ridge_standard_errors(gram: NDArray[np.float64], penalised: NDArray[np.float64],
                          sigma2: float, inverse: NDArray[np.float64] | None = None
                          ) -> NDArray[np.float64]:
    """Standard errors of A^-1 X'y, A the penalised X'X (the sandwich).

    Parameters
    ----------
    gram : ndarray, shape (p, p)
        X'X.
    penalised : ndarray, shape (p, p)
        A, X'X with its ridge (:func:`penalise`).
    sigma2 : float
        The residual variance [unit of y squared].
    inverse : ndarray, shape (p, p), optional
        :func:`normal_inverse` of ``penalised``, when already made.

    Returns
    -------
    ndarray, shape (p,)
        sqrt(sigma^2 diag(A^-1 X'X A^-1)) [unit of y / column unit]; equal to least
        squares' when nothing is penalised.
    """
    if inverse is None:
        inverse = normal_inverse(penalised)
    return np.sqrt(sigma2 * np.clip(np.einsum("ij,jk,ki->i", inverse, gram, inverse), 0.0, None))


def penalised_fit(x: NDArray[np.float64], y: NDArray[np.float64],
                  penalties: list[tuple[int, int, float]]
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Least squares y ~ x (minimum norm, :func:`solve_normal`) with ridge penalties.

    Parameters
    ----------
    x : ndarray, shape (R, p)
        The design.
    y : ndarray, shape (R,)
        The readings.
    penalties : list of (start, stop, strength)
        Ridge strengths of column ranges (:func:`penalise`).

    Returns
    -------
    coefficients : ndarray, shape (p,)
    standard_errors : ndarray, shape (p,)
        The sandwich (:func:`ridge_standard_errors`) where anything is penalised.
    residual : ndarray, shape (R,)
        y - x @ coefficients.
    """
    gram = x.T @ x
    penalised = gram
    for start, stop, strength in penalties:
        penalised = penalise(penalised, start, stop, strength)
    eigen = _equilibrated_eigen(penalised)
    coefficients = _solve_with(eigen, x.T @ y)
    residual = y - x @ coefficients
    sigma2 = float(residual @ residual) / max(1, y.size - x.shape[1])
    inverse = _inverse_with(eigen)
    standard = ridge_standard_errors(gram, penalised, sigma2, inverse) \
        if penalised is not gram else np.sqrt(sigma2 * np.clip(np.diag(inverse), 0.0, None))
    return coefficients, standard, residual


def products_fit(gram: NDArray[np.float64], rhs: NDArray[np.float64], yy: NDArray[np.float64],
                 readings: int, penalty: tuple[int, float] = (0, 0.0)
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`penalised_fit`'s coefficients and standard errors from per-fold products.

    Parameters
    ----------
    gram : ndarray, shape (F, p, p)
        Each fold's X'X.
    rhs : ndarray, shape (F, p)
        Each fold's X'y.
    yy : ndarray, shape (F,)
        Each fold's y'y.
    readings : int
        R, the rows of the whole record (the residual's degrees of freedom are R - p).
    penalty : (int, float)
        (first penalised column, ridge strength) of a penalised candidate: the columns
        from there to the last.

    Returns
    -------
    coefficients : ndarray, shape (p,)
    standard_errors : ndarray, shape (p,)
        Of the whole record's fit (the sum over the folds' products).
    """
    return products_fits([(gram, rhs, yy, penalty)], readings)[0]


def products_fits(problems: list[tuple[NDArray[np.float64], NDArray[np.float64],
                                       NDArray[np.float64], tuple[int, float]]],
                  readings: int) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
    """:func:`products_fit` of each problem, the decompositions of one size in one call.

    A step's candidates are fitted on the whole record together: their normal matrices
    of one size are decomposed by batched eigendecompositions (:func:`same_shape_batches`;
    each matrix's result is its own call's, bit for bit) and solved by batched products.

    Parameters
    ----------
    problems : list of (gram, rhs, yy, penalty)
        Per fit: each fold's X'X (F, p, p), X'y (F, p) and y'y (F,), and (first penalised
        column, ridge strength) as :func:`products_fit` takes them; p may differ.
    readings : int
        R, the rows of the whole record.

    Returns
    -------
    list of (coefficients (p,), standard_errors (p,))
        In the order given.
    """
    summed = []
    for gram, rhs, yy, (start, strength) in problems:
        gram = gram.sum(axis=0)
        summed.append((gram, rhs.sum(axis=0), float(yy.sum()),
                       penalise(gram, start, gram.shape[0], strength)))
    out: list = [None] * len(problems)
    for members in same_shape_batches([gram.shape for gram, *_ in summed]):
        # The coefficients and their covariance from one decomposition of each matrix.
        scale, vectors, inverse = _equilibrated_eigen(np.stack([summed[i][3] for i in members]))
        solved = _solve_with((scale, vectors, inverse), np.stack([summed[i][1] for i in members]))
        for k, i in enumerate(members):
            gram, rhs, yy, penalised = summed[i]
            out[i] = _fit_from_eigen(gram, rhs, yy, penalised, (scale[k], vectors[k], inverse[k]),
                                     solved[k], readings)
    return out


def _fit_from_eigen(gram, rhs, yy: float, penalised, eigen, coefficients, readings: int
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The standard errors of the whole record's ``coefficients`` (p,), solved from
    ``penalised``'s :func:`_equilibrated_eigen` ``eigen``; ``gram`` (p, p), ``rhs`` (p,) and
    ``yy`` its unpenalised products."""
    dof = max(1, readings - gram.shape[0])
    # yy - 2 c'r + c'Gc: the residual sum of squares of any coefficients.
    rss = yy - 2.0 * float(coefficients @ rhs) + float(coefficients @ gram @ coefficients)
    sigma2 = max(rss, 0.0) / dof
    inverse = _inverse_with(eigen)
    standard = ridge_standard_errors(gram, penalised, sigma2, inverse) \
        if penalised is not gram else np.sqrt(sigma2 * np.clip(np.diag(inverse), 0.0, None))
    return coefficients, standard
