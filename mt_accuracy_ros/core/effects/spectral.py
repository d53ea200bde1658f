"""Periodograms of scattered readings in one position: exact, and fast on a frequency grid.

A periodic error of an axis (ball-screw pitch, rack, waviness) is found by the
weighted least-squares periodogram: for each frequency f, fit

    target ~ w (c0 + a cos 2 pi f q + b sin 2 pi f q)

(Lomb-Scargle with an offset; ``target`` = J . r, ``weight`` = |J|^2 per reading)
and take the sum of squares explained beyond the offset. Both routines here
return the same numbers; they differ in cost:

* :func:`periodogram` evaluates cos/sin at every (reading, frequency) pair, in
  blocks of frequencies so memory stays O(N) - for a handful of frequencies;
* :func:`grid_periodogram` evaluates a whole uniform grid f_k = k df at once. The
  normal equations need only the sums Z_a(f) = sum_n a_n exp(-2 pi i f q_n) of
  a = w and a = target at f and of w at 2f (cos^2 = (1 + cos 2x)/2, ...).
  For f on the grid these are a discrete Fourier transform of ``a`` spread onto
  a fine lattice of positions (linear "cloud-in-cell" weights, whose sinc^2
  transfer is divided out): O(N + L log L) for every frequency together,
  instead of O(N P). Positions are taken modulo 1/df - exact for grid
  frequencies, so readings outside the expected travel do no harm.

The grid's peak is then polished by :func:`periodogram` on its neighbours; a
setting's period is refined continuously afterwards by the workbench.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .lru import ByteBoundedCache

#: Periods the periodic families search [m]: 2-50 mm.
PERIOD_RANGE_M = (0.002, 0.05)
#: Lattice points per shortest period (of the harmonic, 2 f_max) of the grid periodogram:
#: the cloud-in-cell transfer there is > 0.98, and the periodogram agrees with the
#: exact one to ~1e-5 of its peak.
_LATTICE_PER_PERIOD = 20
#: Readings x frequencies up to which the sums are taken directly instead.
_DIRECT_MAX_PRODUCT = 400_000


def frequency_grid(span_m: float) -> NDArray[np.float64]:
    """Frequencies [1/m] for periods in :data:`PERIOD_RANGE_M`, a quarter cycle apart over
    ``span_m`` (so no peak falls between two of them), all multiples of 1/(4 span).

    Parameters
    ----------
    span_m : float
        Travel the readings cover [m], > 0.

    Returns
    -------
    ndarray, shape (P,)
        Ascending frequencies [1/m], multiples of 1 / (4 ``span_m``).
    """
    step = 1.0 / (4.0 * span_m)
    first = int(np.ceil(1.0 / PERIOD_RANGE_M[1] / step - 1e-9))
    last = int(np.floor(1.0 / PERIOD_RANGE_M[0] / step + 1e-9))
    return step * np.arange(first, last + 1)


def shortest_resolvable_period(q: NDArray[np.float64]) -> float:
    """The shortest period [m] readings at positions ``q`` can tell from its aliases.

    Readings on a few levels (a raster's lines, a grid of stops) fit any period much
    shorter than their spacing equally well - a periodogram then finds a "pitch" that
    is only aliasing. At least two distinct positions per cycle on average (Nyquist on
    the mean spacing) are asked for: 2 span / (distinct positions - 1). Random positions
    along the travel (hundreds of them) restrict nothing in :data:`PERIOD_RANGE_M`.

    Parameters
    ----------
    q : ndarray, shape (N,)
        Positions of the readings [m] (distinct to 1e-7 m).

    Returns
    -------
    float
        Period [m]; inf for fewer than 3 distinct positions.
    """
    distinct = np.unique(np.round(np.asarray(q, dtype=np.float64), 7))
    if distinct.size < 3:
        return float("inf")
    return 2.0 * float(distinct[-1] - distinct[0]) / (distinct.size - 1)


def resolvable(frequencies: NDArray[np.float64], q: NDArray[np.float64]
               ) -> NDArray[np.float64]:
    """``frequencies`` [1/m] whose periods :func:`shortest_resolvable_period` allows.

    Parameters
    ----------
    frequencies : ndarray, shape (P,)
        Frequencies [1/m].
    q : ndarray, shape (N,)
        Positions of the readings [m].

    Returns
    -------
    ndarray, shape (P',)
        The frequencies kept, in their order [1/m].
    """
    return frequencies[frequencies <= 1.0 / shortest_resolvable_period(q) + 1e-12]


def _solve(sum_w, zw1, zw2, sum_t, zt1):
    """Explained sum of squares and fundamental amplitude from the Fourier sums (batched)."""
    cw, sw = zw1.real, -zw1.imag
    c2, s2 = zw2.real, -zw2.imag
    normal = np.empty(cw.shape + (3, 3))
    normal[..., 0, 0] = sum_w
    normal[..., 0, 1] = normal[..., 1, 0] = cw
    normal[..., 0, 2] = normal[..., 2, 0] = sw
    normal[..., 1, 1] = 0.5 * (sum_w + c2)
    normal[..., 2, 2] = 0.5 * (sum_w - c2)
    normal[..., 1, 2] = normal[..., 2, 1] = 0.5 * s2
    # A degenerate frequency (the axis barely moved) must not be singular: a ridge far
    # below any real signal's normal-equation scale.
    trace = normal[..., 0, 0] + normal[..., 1, 1] + normal[..., 2, 2]
    normal += (1e-12 * trace + 1e-300)[..., None, None] * np.eye(3)
    rhs = np.stack([np.broadcast_to(sum_t, cw.shape), zt1.real, -zt1.imag], axis=-1)
    coefficients = np.linalg.solve(normal, rhs[..., None])[..., 0]
    explained = np.einsum("...i,...i->...", coefficients, rhs)
    explained = explained - sum_t ** 2 / max(float(sum_w), 1e-300)
    return explained, np.hypot(coefficients[..., 1], coefficients[..., 2])


def periodogram(q, target, weight, periods, *, block: int = 64):
    """Exact weighted periodogram at ``periods`` [m].

    Parameters
    ----------
    q, target, weight : array_like, shape (N,)
        Positions [m], weighted residual J . r [m], weights |J|^2 [-].
    periods : array_like, shape (P,)
        Periods [m].
    block : int, optional
        Frequencies evaluated together (memory O(N x block)).

    Returns
    -------
    explained : ndarray, shape (P,)
        Sum of squares explained beyond the offset [m^2].
    amplitude : ndarray, shape (P,)
        Amplitude of the fitted fundamental [m].
    """
    q = np.asarray(q, float)
    target = np.asarray(target, float)
    weight = np.asarray(weight, float)
    frequencies = 1.0 / np.asarray(periods, float)
    explained = np.empty(frequencies.size)
    amplitude = np.empty(frequencies.size)
    for start in range(0, frequencies.size, block):
        zw1, zw2, zt1 = _direct_sums(q, frequencies[start:start + block], weight, target)
        explained[start:start + block], amplitude[start:start + block] = _solve(
            float(weight.sum()), zw1, zw2, float(target.sum()), zt1)
    return explained, amplitude


def _direct_sums(q, frequencies, weight, target):
    """Z_w(f), Z_w(2f), Z_t(f) by explicit exponentials (P x N of them)."""
    zw1, zw2 = _exponential_sums(q, frequencies, weight, harmonic=True)
    (zt1,) = _exponential_sums(q, frequencies, target, harmonic=False)
    return zw1, zw2, zt1


def _exponential_sums(q, frequencies, values, harmonic: bool):
    """Z_v(f) - and Z_v(2f) when ``harmonic`` - by explicit exponentials (P x N)."""
    e1 = np.exp(-2j * np.pi * frequencies[:, None] * q[None, :])
    return (e1 @ values, (e1 * e1) @ values) if harmonic else (e1 @ values,)


def grid_transform(q, values, step: float, count: int):
    """sum_n values[n, j] exp(-2 pi i k step q_n) for k = 0 .. count - 1 and every column j.

    By linear spreading onto a lattice of positions modulo 1/step and one FFT; the
    spreading's transfer is divided out. ``values`` shape (N, M) -> (count, M) complex.

    Parameters
    ----------
    q : array_like, shape (N,)
        Positions [m].
    values : array_like, shape (N,) or (N, M)
        Values at the positions, any unit.
    step : float
        Frequency step [1/m].
    count : int
        Number of frequencies k = 0 .. count - 1.

    Returns
    -------
    ndarray of complex, shape (count, M)
        The sums, in the values' unit (M = 1 for 1-D values).
    """
    q = np.asarray(q, float)
    values = np.asarray(values, float).reshape(q.size, -1)
    f_max = step * (count - 1)
    length = 1 << int(np.ceil(np.log2(max(16, _LATTICE_PER_PERIOD * f_max / step))))
    spacing = 1.0 / (step * length)
    u = np.mod(q / spacing, length)
    cell = np.floor(u).astype(np.intp)
    frac = u - cell
    right = (cell + 1) % length
    columns = values.shape[1]
    lattice = np.empty((columns, length))
    for j in range(columns):
        lattice[j] = np.bincount(cell, values[:, j] * (1.0 - frac), minlength=length) + \
            np.bincount(right, values[:, j] * frac, minlength=length)
    spectrum = np.fft.rfft(lattice, axis=1)[:, :count].T
    k = np.arange(count)
    return spectrum / (np.sinc(k / length) ** 2)[:, None]


def _grid(frequencies) -> tuple[float, NDArray[np.intp], int]:
    """(step, k, count) of a frequency grid f = k step: the transform needs bins 0 .. count-1
    (up to 2 f_max, for the weights' second harmonic)."""
    step = float(frequencies[1] - frequencies[0]) if frequencies.size > 1 else \
        float(frequencies[0])
    k = np.rint(frequencies / step).astype(np.intp)
    return step, k, 2 * int(k[-1]) + 1


def direct_basis(q, frequencies) -> NDArray[np.complex128] | None:
    """exp(-2 pi i f q_n), shape (P, N), where :func:`grid_periodogram` takes the sums
    directly (few readings); None where it spreads them onto a lattice. A selection
    computes it once per axis and passes it to every later periodogram of that axis: the
    exponentials, not the products, are most of a direct periodogram's cost.

    Parameters
    ----------
    q : array_like, shape (N,)
        Positions [m].
    frequencies : array_like, shape (P,)
        Frequencies [1/m].

    Returns
    -------
    ndarray of complex, shape (P, N), or None
        The exponentials (dimensionless), or None when N x P > 400 000.
    """
    q = np.asarray(q, float)
    frequencies = np.asarray(frequencies, float)
    if q.size * frequencies.size > _DIRECT_MAX_PRODUCT:
        return None
    key = _basis_key(q, frequencies)
    basis = _BASES.get(key)
    if basis is None:
        basis = np.exp(-2j * np.pi * frequencies[:, None] * q[None, :])
        basis.flags.writeable = False
        _BASES.put(key, basis)
    return basis


#: The exponentials of :func:`direct_basis` by the positions' and frequencies' bytes, for
#: the whole process: a check's selection and both its localisations ask for the same
#: axis' exponentials, and at a few hundred readings making them (complex exponentials
#: of up to 400,000 phases) is a large part of a check. Bounded: seven of the largest
#: (6.4 MB each), enough for three axes' selection grids and their localisations'.
_BASES = ByteBoundedCache(max_bytes=45_000_000)


def _basis_key(q: NDArray[np.float64], frequencies: NDArray[np.float64]) -> tuple:
    """What an exponential basis depends on: the positions and frequencies, bit for bit."""
    return (np.ascontiguousarray(q, dtype=np.float64).tobytes(),
            np.ascontiguousarray(frequencies, dtype=np.float64).tobytes())


def _sums_at(q, values, frequencies, harmonic: bool, basis=None):
    """Z_v(f) (P, M) - and Z_v(2f) when ``harmonic`` - for every column of ``values`` (N, M):
    directly for few readings, else by :func:`grid_transform` (same lattice either way).
    ``basis``: :func:`direct_basis` of these readings and frequencies, if already made."""
    if basis is None:
        # Few readings: the sums directly (fewer operations than the lattice's FFT).
        basis = direct_basis(q, frequencies)
    if basis is not None:
        return (basis @ values, (basis * basis) @ values) if harmonic else (basis @ values,)
    step, k, count = _grid(frequencies)
    spectra = grid_transform(q, values, step, count)
    return (spectra[k], spectra[2 * k]) if harmonic else (spectra[k],)


def weight_sums(q, weight, frequencies, *, basis=None) -> tuple[NDArray, NDArray, NDArray]:
    """What :func:`grid_periodogram` needs of the weights alone - sum w (M,), Z_w(f) and
    Z_w(2f) (P, M) - to reuse while only the target changes (a selection's later steps).
    ``basis``: :func:`direct_basis` of ``q`` and ``frequencies``, if already made.

    Parameters
    ----------
    q : array_like, shape (N,)
        Positions [m].
    weight : array_like, shape (N,) or (N, M)
        Weights |J|^2, dimensionless.
    frequencies : ndarray, shape (P,)
        Multiples of one step [1/m], ascending.
    basis : ndarray of complex, shape (P, N), optional
        :func:`direct_basis` of ``q`` and ``frequencies``.

    Returns
    -------
    tuple of ndarray
        sum w, shape (M,); Z_w(f) and Z_w(2f), complex, shape (P, M); dimensionless.
    """
    q = np.asarray(q, float)
    weight2 = np.asarray(weight, float).reshape(q.size, -1)
    zw1, zw2 = _sums_at(q, weight2, frequencies, harmonic=True, basis=basis)
    return weight2.sum(axis=0), zw1, zw2


def grid_periodogram(q, target, weight, frequencies, *, weights=None, basis=None):
    """The weighted periodogram at ``frequencies`` = k * step (a :func:`frequency_grid`),
    for every column of ``target`` and ``weight`` at once.

    Parameters
    ----------
    q : array_like, shape (N,)
        Positions [m].
    target, weight : array_like, shape (N,) or (N, M)
        Weighted residual J . r [m] and weights |J|^2 [-], per column.
    frequencies : ndarray, shape (P,)
        Multiples of one step [1/m], ascending.
    weights : tuple, optional
        :func:`weight_sums` of ``weight`` at these readings and frequencies (then
        ``weight`` is not read again).
    basis : ndarray, optional
        :func:`direct_basis` of ``q`` and ``frequencies`` (the same numbers, sooner).

    Returns
    -------
    explained, amplitude : ndarray, shape (P,) or (P, M)
        Sum of squares explained beyond the offset [m^2] and amplitude of the fitted
        fundamental [m] (the shape of ``target``'s columns).
    """
    target = np.asarray(target, float)
    single = target.ndim == 1
    q = np.asarray(q, float)
    target2 = target.reshape(target.shape[0], -1)
    sum_w, zw1, zw2 = weights if weights is not None else weight_sums(q, weight, frequencies,
                                                                      basis=basis)
    (zt1,) = _sums_at(q, target2, frequencies, harmonic=False, basis=basis)
    m = target2.shape[1]
    out_e = np.empty((frequencies.size, m))
    out_a = np.empty((frequencies.size, m))
    for j in range(m):
        out_e[:, j], out_a[:, j] = _solve(float(sum_w[j]), zw1[:, j], zw2[:, j],
                                          float(target2[:, j].sum()), zt1[:, j])
    if single:
        return out_e[:, 0], out_a[:, 0]
    return out_e, out_a


def strongest_frequencies(q, target, frequencies, *, weights, basis=None
                          ) -> NDArray[np.intp]:
    """The index of each column's largest :func:`grid_periodogram` ``explained``, as
    ``np.argmax(grid_periodogram(...)[0], axis=0)`` gives it, at a fraction of its cost.

    The same Fourier sums, but every frequency's 3 x 3 normal equations solved in closed
    form (adjugate over determinant, for all columns at once) instead of by LAPACK one
    column at a time. That rounds differently, so each value carries a bound on how far
    either computation can be from the exact one (floating-point error of the solve,
    the target's sum and the offset's subtraction, with a 64-fold margin); a column
    whose largest value is not clear of every other by those bounds - a near tie, a
    degenerate frequency - is computed again as :func:`grid_periodogram` does. So the
    index returned is the one it returns.

    Parameters
    ----------
    q : array_like, shape (N,)
        Positions [m].
    target : array_like, shape (N, M)
        Weighted residual J . r [m] per column.
    frequencies : ndarray, shape (P,)
        Multiples of one step [1/m], ascending.
    weights : tuple
        :func:`weight_sums` of the weights at these readings and frequencies.
    basis : ndarray, optional
        :func:`direct_basis` of ``q`` and ``frequencies``.

    Returns
    -------
    ndarray of int, shape (M,)
        Index into ``frequencies`` of each column's strongest frequency.
    """
    q = np.asarray(q, float)
    target = np.asarray(target, float).reshape(q.size, -1)
    sum_w, zw1, zw2 = weights
    # The target's sums as grid_periodogram makes them: only the solve differs.
    (zt1,) = _sums_at(q, target, frequencies, harmonic=False, basis=basis)
    zt_re, zt_im = zt1.real, zt1.imag
    with np.errstate(divide="ignore", invalid="ignore"):
        # A column of no weight (a degenerate determinant) is left to the exact path.
        explained, bound = _closed_form_explained(sum_w, zw1, zw2, target, zt_re, zt_im)
    best = np.argmax(explained, axis=0)
    columns = np.arange(explained.shape[1])
    floor = explained[best, columns] - bound[best, columns]
    rival = explained + bound
    rival[best, columns] = -np.inf
    # A column of zeros explains nothing at any frequency: grid_periodogram's values are
    # all exactly zero there (zero sums, zero coefficients) and its argmax is the first.
    zero = ~target.any(axis=0)
    best[zero] = 0
    unclear = np.flatnonzero(~(floor > rival.max(axis=0)) & ~zero)
    if unclear.size:
        exact, _ = grid_periodogram(q, target[:, unclear], None, frequencies,
                                    weights=(sum_w[unclear], zw1[:, unclear], zw2[:, unclear]),
                                    basis=basis)
        best[unclear] = np.argmax(exact, axis=0)
    return best


def _closed_form_explained(sum_w, zw1, zw2, target, zt_re, zt_im):
    """:func:`_solve`'s explained sum of squares (P, M) by the adjugate of each 3 x 3 normal
    matrix, and a bound (P, M) on its distance from :func:`_solve`'s value."""
    eps = np.finfo(np.float64).eps
    n = target.shape[0]
    cw, sw = zw1.real, -zw1.imag
    c2, s2 = zw2.real, -zw2.imag
    a = np.broadcast_to(sum_w, cw.shape)
    d = 0.5 * (sum_w + c2)
    f = 0.5 * (sum_w - c2)
    e = 0.5 * s2
    # The same ridge as _solve's, on the same diagonal.
    ridge = 1e-12 * (a + d + f) + 1e-300
    a, d, f = a + ridge, d + ridge, f + ridge
    b, c = cw, sw
    sum_t = target.sum(axis=0)
    r0 = np.broadcast_to(sum_t, cw.shape)
    r1, r2 = zt_re, -zt_im
    # Adjugate of [[a b c] [b d e] [c e f]] (symmetric) and the determinant.
    adj00, adj11, adj22 = d * f - e * e, a * f - c * c, a * d - b * b
    adj01, adj02, adj12 = c * e - b * f, b * e - c * d, b * c - a * e
    det = a * adj00 + b * adj01 + c * adj02
    x0 = (adj00 * r0 + adj01 * r1 + adj02 * r2) / det
    x1 = (adj01 * r0 + adj11 * r1 + adj12 * r2) / det
    x2 = (adj02 * r0 + adj12 * r1 + adj22 * r2) / det
    quadratic = x0 * r0 + x1 * r1 + x2 * r2
    offset = sum_t ** 2 / np.maximum(sum_w, 1e-300)
    explained = quadratic - offset
    # What each computation's rounding scales with (Higham: a sum's error is under n eps
    # times the sum of its terms' magnitudes). LAPACK's solve: a backward error
    # eps |N| moves x' r by eps |x|' |N| |x|. The adjugate: each entry and the
    # determinant off by eps times their terms' magnitudes (``terms``, ``det_terms``).
    # The target's sum (r0) taken in another order: off by n eps sum |t|. The offset's
    # subtraction.
    ax0, ax1, ax2 = np.abs(x0), np.abs(x1), np.abs(x2)
    aa, ab, ac, ad, ae, af = np.abs(a), np.abs(b), np.abs(c), np.abs(d), np.abs(e), np.abs(f)
    solve_scale = (ax0 * (aa * ax0 + ab * ax1 + ac * ax2) +
                   ax1 * (ab * ax0 + ad * ax1 + ae * ax2) +
                   ax2 * (ac * ax0 + ae * ax1 + af * ax2))
    ar0, ar1, ar2 = np.abs(r0), np.abs(r1), np.abs(r2)
    terms = (ar0 * ar0 * (ad * af + ae * ae) + ar1 * ar1 * (aa * af + ac * ac) +
             ar2 * ar2 * (aa * ad + ab * ab) + 2.0 * ar0 * ar1 * (ac * ae + ab * af) +
             2.0 * ar0 * ar2 * (ab * ae + ac * ad) + 2.0 * ar1 * ar2 * (ab * ac + aa * ae))
    det_terms = (aa * (ad * af + ae * ae) + ab * (ac * ae + ab * af) +
                 ac * (ab * ae + ac * ad))
    sums_scale = n * np.abs(target).sum(axis=0) * (ax0 + ax1 + ax2)
    rhs_scale = ax0 * ar0 + ax1 * ar1 + ax2 * ar2
    bound = 64.0 * eps * (solve_scale + terms / np.abs(det) +
                          np.abs(quadratic) * (1.0 + det_terms / np.abs(det)) +
                          rhs_scale + sums_scale + offset)
    return explained, bound
