"""Finite-element heat conduction with convection, and thermal modal analysis (Zhu ch. 3).

The semi-discrete heat equation (Zhu eq. 3.1), temperatures as rises over ambient,

    C dT/dt + K T = Q(t)

with C the heat capacity matrix and K the conductivity matrix plus the
convection to ambient. Its generalised eigenproblem (Zhu eq. 3.2)

    K Phi = C Phi Lambda,     Phi^T C Phi = I (3.6),  Phi^T K Phi = Lambda (3.7)

gives time constants tau_i = 1 / lambda_i (3.3) and decouples the system into
theta_i' + theta_i / tau_i = xi_i(t), xi = Phi^T Q (3.8, 3.9), with the step
response theta_i = xi_i tau_i (1 - exp(-t/tau_i)) (3.10). Mode weights are
w_i = |xi_i tau_i| (3.11); the dominant modes hold >= 90 % of the weight
(section 3.2.2).

Two element families:

* :func:`rod_model` - 1-D two-node elements with lateral convection (thermal
  elongation, Zhu Fig. 3.1(a));
* :func:`beam_model` - 2-D bilinear quadrilaterals through the beam's height
  with separate convection coefficients on the upper and lower faces (thermal
  bending, Fig. 3.1(b)); :meth:`ThermalFEModel.deformation` gives the free-end
  expansion epsilon, deflection delta and slope theta by beam theory.

Table 3.1 material (:data:`ZHU_TABLE_3_1`) is the default.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError, ParameterError


@dataclass(frozen=True)
class Material:
    """Zhu Table 3.1 symbols: k [W/m K], c_p [J/kg K], rho [kg/m^3], alpha [1/K]."""

    conductivity: float = 60.5
    specific_heat: float = 434.0
    density: float = 7.8e3
    expansion: float = 10.8e-6
    youngs_modulus: float = 120e9
    poisson: float = 0.25


#: Zhu Table 3.1: the simplified machine element (steel-like, L = 1 m, A = 0.0314 m^2).
ZHU_TABLE_3_1 = Material()
ZHU_LENGTH_M = 1.0
ZHU_AREA_M2 = 0.0314
ZHU_ELEMENTS = 22

#: Aluminium of Krulewich's test tube (set-up 1: 305 mm, heated wire at 8.75 in).
ALUMINIUM = Material(conductivity=167.0, specific_heat=896.0, density=2.70e3,
                     expansion=23.1e-6, youngs_modulus=69e9, poisson=0.33)


@dataclass
class ThermalFEModel:
    """Assembled C, K of one model; node coordinates (n, 2) [m] (y = 0 for rods).

    Parameters
    ----------
    capacity : ndarray or scipy.sparse matrix, shape (n, n)
        Heat capacity matrix C [J/K].
    conductivity : ndarray or scipy.sparse matrix, shape (n, n)
        Conduction plus convection matrix K [W/K].
    nodes : ndarray, shape (n, 2)
        Node coordinates x, y [m].
    material : Material
        The material.
    kind : {"rod", "beam"}
        The element type.
    length_m : float
        Length [m].
    height_m, width_m : float
        Section height and width [m] (beam; 0 for a rod).
    heat_nodes : ndarray of int, shape (h,)
        Nodes the heat input is shared by.
    """

    capacity: NDArray | scipy.sparse.spmatrix
    conductivity: NDArray | scipy.sparse.spmatrix
    nodes: NDArray[np.float64]
    material: Material
    kind: str
    length_m: float
    height_m: float = 0.0
    width_m: float = 0.0
    heat_nodes: NDArray[np.int64] = field(default_factory=lambda: np.zeros(1, dtype=np.int64))

    @property
    def n_nodes(self) -> int:
        return self.nodes.shape[0]

    def heat_vector(self, power_w: float = 1.0) -> NDArray[np.float64]:
        """Q for ``power_w`` watts shared by the heat-input nodes (the fixed end).

        Parameters
        ----------
        power_w : float, optional
            Heat input [W].

        Returns
        -------
        ndarray, shape (n,)
            Q per node [W].
        """
        q = np.zeros(self.n_nodes)
        q[self.heat_nodes] = power_w / self.heat_nodes.size
        return q

    def sensor_nodes(self, positions_m: ArrayLike, y_m: float = 0.0) -> NDArray[np.int64]:
        """Nearest node of each sensor position along the element [m].

        Raises :class:`InputDataError` for a sensor outside the body.

        Parameters
        ----------
        positions_m : array_like, shape (s,)
            Sensor positions x along the element [m].
        y_m : float, optional
            Height y of the sensors [m] (beam).

        Returns
        -------
        ndarray of int, shape (s,)
            Node indices.

        Raises
        ------
        InputDataError
            A sensor outside the body or not finite.
        """
        x = np.atleast_1d(np.asarray(positions_m, dtype=np.float64))
        outside = (x < -1e-9) | (x > self.length_m + 1e-9) | ~np.isfinite(x)
        if outside.any() or not (-1e-9 <= y_m <= max(self.height_m, 0.0) + 1e-9):
            bad = x[outside] if outside.any() else np.array([y_m])
            raise InputDataError(f"sensor position(s) {bad.tolist()} m outside the {self.kind} "
                                 f"(x in [0, {self.length_m}] m, y in [0, {self.height_m}] m)")
        distance = np.hypot(self.nodes[None, :, 0] - x[:, None], self.nodes[None, :, 1] - y_m)
        return np.argmin(distance, axis=1)

    def deformation(self, temperatures: ArrayLike) -> dict[str, NDArray[np.float64]]:
        """Free-end expansion epsilon [m], deflection delta [m], slope theta [rad].

        ``temperatures`` (..., n_nodes) rises [K]. epsilon = alpha int T_mean dx
        (Krulewich eq. 1); for the beam, the curvature kappa(x) =
        alpha int T (y - y_c) dA / I, theta = int kappa dx, delta = int kappa (L - x) dx.
        Positive delta bends towards +y (the hotter lower face pushes it up).

        Parameters
        ----------
        temperatures : array_like, shape (..., n)
            Node temperature rises [K].

        Returns
        -------
        dict of str to ndarray, shape (...)
            ``expansion`` [m], ``deflection`` [m] and ``slope`` [rad] (zeros for a rod).
        """
        t = np.asarray(temperatures, dtype=np.float64)
        alpha = self.material.expansion
        if self.kind == "rod":
            x = self.nodes[:, 0]
            expansion = alpha * np.trapezoid(t, x, axis=-1)
            zero = np.zeros_like(expansion)
            return {"expansion": expansion, "deflection": zero, "slope": zero}
        xs = np.unique(self.nodes[:, 0])
        ys = np.unique(self.nodes[:, 1])
        grid = t.reshape(t.shape[:-1] + (ys.size, xs.size))  # nodes ordered y-major
        mean = np.trapezoid(grid, ys, axis=-2) / self.height_m
        centre = 0.5 * self.height_m
        moment = np.trapezoid(grid * (ys[:, None] - centre), ys, axis=-2)
        inertia = self.height_m ** 3 / 12.0
        # Hotter at small y (lower face) expands the bottom: the beam bows to +y... sign
        # convention: kappa > 0 when the lower face is hotter.
        curvature = -alpha * moment / inertia
        expansion = alpha * np.trapezoid(mean, xs, axis=-1)
        slope = np.trapezoid(curvature, xs, axis=-1)
        deflection = np.trapezoid(curvature * (self.length_m - xs), xs, axis=-1)
        return {"expansion": expansion, "deflection": deflection, "slope": slope}


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not np.isfinite(value) or value <= 0:
            raise ParameterError(f"{name} must be finite and > 0, got {value!r}")


def rod_model(length_m: float = ZHU_LENGTH_M, area_m2: float = ZHU_AREA_M2,
              n_elements: int = ZHU_ELEMENTS, convection_w_m2k: float = 20.0,
              material: Material = ZHU_TABLE_3_1, *, perimeter_m: float | None = None,
              heat_at_m: float = 0.0, base_conductance_w_k: float = 0.0,
              end_convection_w_m2k: float | None = None,
              sparse: bool = False) -> ThermalFEModel:
    """1-D rod heated at x = 0 (fixed end), convection on its lateral surface and free end.

    Consistent element matrices: capacity rho c_p A le / 6 [[2, 1], [1, 2]],
    conduction k A / le [[1, -1], [-1, 1]], lateral convection h P le / 6 [[2, 1], [1, 2]];
    a round bar (P = 2 sqrt(pi A)) unless ``perimeter_m`` is given. ``heat_at_m``
    moves the heat input along the rod (Krulewich's heated wire at 8.75 in);
    ``base_conductance_w_k`` ties x = 0 to a heat sink (his granite block).

    Parameters
    ----------
    length_m : float, optional
        Rod length L [m].
    area_m2 : float, optional
        Cross-section A [m^2].
    n_elements : int, optional
        Linear elements along the rod.
    convection_w_m2k : float, optional
        Lateral convection coefficient h [W/m^2 K].
    material : Material, optional
        The material.
    perimeter_m : float, optional
        Section perimeter P [m] (default: a round bar's).
    heat_at_m : float, optional
        Where the heat enters [m], within [0, L].
    base_conductance_w_k : float, optional
        Conductance from x = 0 to a heat sink [W/K].
    end_convection_w_m2k : float, optional
        Convection on the free end face [W/m^2 K] (default: ``convection_w_m2k``).
    sparse : bool, optional
        Keep C and K as sparse matrices.

    Returns
    -------
    ThermalFEModel
        ``kind="rod"``, n_elements + 1 nodes.

    Raises
    ------
    ParameterError
        A length or area not positive, no element, a negative convection, or the
        heat input outside the rod.
    """
    _check_positive(length_m=length_m, area_m2=area_m2)
    if int(n_elements) < 1:
        raise ParameterError(f"n_elements must be >= 1, got {n_elements}")
    if not np.isfinite(convection_w_m2k) or convection_w_m2k < 0:
        raise ParameterError(f"convection_w_m2k must be finite and >= 0, got {convection_w_m2k}")
    perimeter = 2.0 * np.sqrt(np.pi * area_m2) if perimeter_m is None else float(perimeter_m)
    n = int(n_elements)
    le = length_m / n
    m = material
    cap = m.density * m.specific_heat * area_m2 * le / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    cond = m.conductivity * area_m2 / le * np.array([[1.0, -1.0], [-1.0, 1.0]]) + \
        convection_w_m2k * perimeter * le / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    rows, cols, c_vals, k_vals = [], [], [], []
    for e in range(n):
        for a in range(2):
            for b in range(2):
                rows.append(e + a)
                cols.append(e + b)
                c_vals.append(cap[a, b])
                k_vals.append(cond[a, b])
    rows.append(n)
    cols.append(n)
    c_vals.append(0.0)
    end_h = convection_w_m2k if end_convection_w_m2k is None else float(end_convection_w_m2k)
    k_vals.append(end_h * area_m2)  # free end face
    rows.append(0)
    cols.append(0)
    c_vals.append(0.0)
    k_vals.append(float(base_conductance_w_k))  # base to its heat sink
    shape = (n + 1, n + 1)
    capacity = scipy.sparse.coo_matrix((c_vals, (rows, cols)), shape=shape).tocsr()
    conductivity = scipy.sparse.coo_matrix((k_vals, (rows, cols)), shape=shape).tocsr()
    nodes = np.column_stack([np.linspace(0.0, length_m, n + 1), np.zeros(n + 1)])
    if not sparse:
        capacity, conductivity = capacity.toarray(), conductivity.toarray()
    if not 0.0 <= heat_at_m <= length_m:
        raise ParameterError(f"heat_at_m = {heat_at_m} is outside the rod [0, {length_m}] m")
    return ThermalFEModel(capacity, conductivity, nodes, material, "rod", length_m,
                          heat_nodes=np.array([int(round(heat_at_m / le))]))


def beam_model(length_m: float = ZHU_LENGTH_M, area_m2: float = ZHU_AREA_M2,
               n_elements: int = ZHU_ELEMENTS, n_layers: int = 4,
               upper_convection_w_m2k: float = 20.0, lower_convection_w_m2k: float = 100.0,
               end_convection_w_m2k: float = 20.0, material: Material = ZHU_TABLE_3_1,
               *, sparse: bool = False) -> ThermalFEModel:
    """2-D beam (square section of area A) heated over the fixed end x = 0 (Zhu Fig. 3.1(b)).

    Bilinear quadrilaterals, ``n_elements`` along x and ``n_layers`` through the
    height, per unit depth scaled by the width; convection h_up on y = H, h_low on
    y = 0 (Zhu: 20 and 100 W/m^2 K) and on the free end face.

    Parameters
    ----------
    length_m : float, optional
        Beam length L [m].
    area_m2 : float, optional
        Square cross-section A [m^2].
    n_elements, n_layers : int, optional
        Elements along x and through the height.
    upper_convection_w_m2k, lower_convection_w_m2k, end_convection_w_m2k : float, optional
        Convection on y = H, y = 0 and the free end [W/m^2 K].
    material : Material, optional
        The material.
    sparse : bool, optional
        Keep C and K as sparse matrices.

    Returns
    -------
    ThermalFEModel
        ``kind="beam"``, (n_elements + 1) (n_layers + 1) nodes, y-major.

    Raises
    ------
    ParameterError
        A length or area not positive, or no element.
    """
    _check_positive(length_m=length_m, area_m2=area_m2)
    if int(n_elements) < 1 or int(n_layers) < 1:
        raise ParameterError("n_elements and n_layers must be >= 1")
    width = height = float(np.sqrt(area_m2))
    nx, ny = int(n_elements), int(n_layers)
    xs = np.linspace(0.0, length_m, nx + 1)
    ys = np.linspace(0.0, height, ny + 1)
    node = lambda i, j: j * (nx + 1) + i  # noqa: E731 - y-major numbering
    a, b = length_m / nx, height / ny
    m = material
    # Bilinear element on a x b: exact conduction and consistent capacity matrices.
    gauss = np.array([-1.0, 1.0]) / np.sqrt(3.0)
    ke = np.zeros((4, 4))
    ce = np.zeros((4, 4))
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    for xi in gauss:
        for eta in gauss:
            shape = 0.25 * (1 + corners[:, 0] * xi) * (1 + corners[:, 1] * eta)
            dxi = 0.25 * corners[:, 0] * (1 + corners[:, 1] * eta)
            deta = 0.25 * corners[:, 1] * (1 + corners[:, 0] * xi)
            grad = np.vstack([dxi * 2 / a, deta * 2 / b])
            jac = a * b / 4.0
            ke += m.conductivity * width * (grad.T @ grad) * jac
            ce += m.density * m.specific_heat * width * np.outer(shape, shape) * jac
    edge = lambda h, length: h * width * length / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])  # noqa: E731
    rows, cols, c_vals, k_vals = [], [], [], []

    def add(indices, kmat, cmat=None):
        for p, gp in enumerate(indices):
            for q, gq in enumerate(indices):
                rows.append(gp)
                cols.append(gq)
                k_vals.append(kmat[p, q])
                c_vals.append(0.0 if cmat is None else cmat[p, q])

    for j in range(ny):
        for i in range(nx):
            add([node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)], ke, ce)
    for i in range(nx):
        add([node(i, 0), node(i + 1, 0)], edge(lower_convection_w_m2k, a))
        add([node(i, ny), node(i + 1, ny)], edge(upper_convection_w_m2k, a))
    for j in range(ny):
        add([node(nx, j), node(nx, j + 1)], edge(end_convection_w_m2k, b))
    size = (nx + 1) * (ny + 1)
    capacity = scipy.sparse.coo_matrix((c_vals, (rows, cols)), shape=(size, size)).tocsr()
    conductivity = scipy.sparse.coo_matrix((k_vals, (rows, cols)), shape=(size, size)).tocsr()
    grid_x, grid_y = np.meshgrid(xs, ys)
    nodes = np.column_stack([grid_x.ravel(), grid_y.ravel()])
    if not sparse:
        capacity, conductivity = capacity.toarray(), conductivity.toarray()
    return ThermalFEModel(capacity, conductivity, nodes, material, "beam", length_m,
                          height_m=height, width_m=width,
                          heat_nodes=np.array([node(0, j) for j in range(ny + 1)]))


@dataclass
class ThermalModes:
    """Eigen-solution of Zhu eq. 3.2: lambda (m,) [1/s], tau (m,) [s], shapes Phi (n, m).

    Parameters
    ----------
    eigenvalues : ndarray, shape (m,)
        lambda [1/s], ascending.
    shapes : ndarray, shape (n, m)
        Mode shapes Phi, normalised Phi^T C Phi = I (Zhu eq. 3.6).
    """

    eigenvalues: NDArray[np.float64]
    shapes: NDArray[np.float64]

    @property
    def time_constants_s(self) -> NDArray[np.float64]:
        return 1.0 / self.eigenvalues  # Zhu eq. 3.3

    def modal_load(self, heat: ArrayLike) -> NDArray[np.float64]:
        """xi = Phi^T Q (Zhu eq. 3.8); ``heat`` (..., n) -> (..., m).

        Parameters
        ----------
        heat : array_like, shape (..., n)
            Heat input per node Q [W].

        Returns
        -------
        ndarray, shape (..., m)
            Modal loads xi (xi tau is a modal temperature amplitude).
        """
        return np.asarray(heat, dtype=np.float64) @ self.shapes

    def weights(self, heat: ArrayLike) -> NDArray[np.float64]:
        """w_i = |xi_i tau_i| for a step heat input (Zhu eq. 3.11).

        Parameters
        ----------
        heat : array_like, shape (..., n)
            Heat input per node Q [W].

        Returns
        -------
        ndarray, shape (..., m)
            Mode weights.
        """
        return np.abs(self.modal_load(heat) * self.time_constants_s)

    def dominant(self, heat: ArrayLike, share: float = 0.9) -> NDArray[np.int64]:
        """Indices of the fewest modes holding >= ``share`` of the total weight (3.2.2).

        Parameters
        ----------
        heat : array_like, shape (n,)
            Heat input per node Q [W].
        share : float, optional
            Fraction of the total weight (dimensionless).

        Returns
        -------
        ndarray of int
            Mode indices, ascending.
        """
        w = self.weights(heat)
        order = np.argsort(w)[::-1]
        cumulative = np.cumsum(w[order]) / np.sum(w)
        count = int(np.searchsorted(cumulative, share - 1e-12) + 1)
        return np.sort(order[:count])

    def step_response(self, heat: ArrayLike, times_s: ArrayLike,
                      modes: ArrayLike | None = None) -> NDArray[np.float64]:
        """T(t) (len(t), n) for a constant ``heat`` from t = 0 (Zhu eqs. 3.4, 3.10).

        Parameters
        ----------
        heat : array_like, shape (n,)
            Constant heat input per node Q [W].
        times_s : array_like, shape (T,)
            Times [s].
        modes : array_like of int, optional
            Mode indices kept (default: all).

        Returns
        -------
        ndarray, shape (T, n)
            Node temperature rises [K].
        """
        t = np.asarray(times_s, dtype=np.float64)[:, None]
        selected = np.arange(self.eigenvalues.size) if modes is None else np.asarray(modes)
        xi = self.modal_load(heat)[selected]
        tau = self.time_constants_s[selected]
        theta = xi * tau * (1.0 - np.exp(-t / tau))
        return theta @ self.shapes[:, selected].T

    def response(self, heat_history: ArrayLike, dt_s: float,
                 modes: ArrayLike | None = None) -> NDArray[np.float64]:
        """T at the end of each step for piecewise-constant Q (steps, n) - exact per mode.

        theta_i(t + dt) = theta_i e^{-dt/tau_i} + xi_i tau_i (1 - e^{-dt/tau_i}) (Zhu eq. 3.9).

        Parameters
        ----------
        heat_history : array_like, shape (steps, n)
            Heat input per node during each step [W].
        dt_s : float
            Step length [s].
        modes : array_like of int, optional
            Mode indices kept (default: all).

        Returns
        -------
        ndarray, shape (steps, n)
            Node temperature rises [K], from zero at t = 0.
        """
        q = np.atleast_2d(np.asarray(heat_history, dtype=np.float64))
        selected = np.arange(self.eigenvalues.size) if modes is None else np.asarray(modes)
        xi = self.modal_load(q)[:, selected]
        tau = self.time_constants_s[selected]
        decay = np.exp(-dt_s / tau)
        theta = np.zeros(selected.size)
        out = np.empty((q.shape[0], selected.size))
        for step in range(q.shape[0]):
            theta = theta * decay + xi[step] * tau * (1.0 - decay)
            out[step] = theta
        return out @ self.shapes[:, selected].T


def thermal_modes(model: ThermalFEModel, n_modes: int | None = None) -> ThermalModes:
    """Solve Zhu eq. 3.2: dense ``eigh`` for small models, sparse shift-invert for large.

    ``n_modes`` None: all (dense). With sparse matrices or ``n_modes`` given for a
    model above 400 nodes, ARPACK ``eigsh`` (sigma = 0) finds the slowest modes.

    Parameters
    ----------
    model : ThermalFEModel
        The assembled model.
    n_modes : int, optional
        Slowest modes wanted (default: all).

    Returns
    -------
    ThermalModes
        Eigenvalues [1/s] and C-normalised shapes, each shape's largest entry positive.

    Raises
    ------
    InputDataError
        A non-positive eigenvalue (no heat loss, or a singular model).
    """
    capacity, conductivity = model.capacity, model.conductivity
    n = model.n_nodes
    use_sparse = scipy.sparse.issparse(capacity) and (n_modes is not None and n_modes < n - 1)
    if use_sparse:
        values, vectors = scipy.sparse.linalg.eigsh(
            scipy.sparse.csc_matrix(conductivity), k=int(n_modes),
            M=scipy.sparse.csc_matrix(capacity), sigma=0.0, which="LM")
        order = np.argsort(values)
        values, vectors = values[order], vectors[:, order]
        # Normalise Phi^T C Phi = I (Zhu eq. 3.6) explicitly: ARPACK's scaling is not guaranteed.
        norms = np.sqrt(np.einsum("ij,ij->j", vectors, capacity @ vectors))
        vectors = vectors / norms
    else:
        dense_c = capacity.toarray() if scipy.sparse.issparse(capacity) else capacity
        dense_k = conductivity.toarray() if scipy.sparse.issparse(conductivity) else conductivity
        values, vectors = scipy.linalg.eigh(dense_k, dense_c)
        if n_modes is not None:
            values, vectors = values[:n_modes], vectors[:, :n_modes]
    if np.any(values <= 1e-12 * np.abs(values).max()):
        raise InputDataError("non-positive eigenvalue: the model has no heat loss "
                             "(no convection) or is singular")
    # Sign convention: each mode shape's largest entry positive.
    signs = np.sign(vectors[np.argmax(np.abs(vectors), axis=0), np.arange(vectors.shape[1])])
    return ThermalModes(values, vectors * signs)


def integrate_directly(model: ThermalFEModel, heat_history: ArrayLike, dt_s: float,
                       substeps: int = 20) -> NDArray[np.float64]:
    """Zhu eq. 3.1 by Crank-Nicolson time stepping (independent of the modal solution).

    Returns T at the end of each of the ``steps`` (steps, n); Q piecewise constant.

    Parameters
    ----------
    model : ThermalFEModel
        The assembled model.
    heat_history : array_like, shape (steps, n)
        Heat input per node during each step [W].
    dt_s : float
        Step length [s].
    substeps : int, optional
        Crank-Nicolson steps per step.

    Returns
    -------
    ndarray, shape (steps, n)
        Node temperature rises [K], from zero at t = 0.
    """
    q = np.atleast_2d(np.asarray(heat_history, dtype=np.float64))
    capacity = model.capacity.toarray() if scipy.sparse.issparse(model.capacity) else model.capacity
    conductivity = model.conductivity.toarray() if scipy.sparse.issparse(model.conductivity) \
        else model.conductivity
    h = dt_s / substeps
    left = scipy.linalg.lu_factor(capacity / h + 0.5 * conductivity)
    right = capacity / h - 0.5 * conductivity
    t = np.zeros(model.n_nodes)
    out = np.empty((q.shape[0], model.n_nodes))
    for step in range(q.shape[0]):
        for _ in range(substeps):
            t = scipy.linalg.lu_solve(left, right @ t + q[step])
        out[step] = t
    return out


def place_sensors(modes: ThermalModes, candidates: ArrayLike, mode_indices: ArrayLike,
                  *, near_extreme: float = 0.8, max_sensors: int | None = None) -> list[int]:
    """One sensor per dominant mode, at an extreme of its shape (Zhu section 3.3.1).

    Rules of Zhu 3.3.1: (1) close to the extreme values of the mode's temperature
    field, never near its nodes, and - "the multicollinearity of the collected
    temperature is reduced" - sensors that tell the modes apart. For each mode
    in ``mode_indices`` (most important first), the candidates whose |phi| is
    at least ``near_extreme`` of the best candidate's are eligible; among them
    the one that maximises the smallest singular value of the mode-shape matrix
    Phi[chosen sensors, modes so far] is added (an effective-independence
    criterion). Zhu reuses one sensor for modes I and III of the rod; this rule
    adds a sensor per mode unless ``max_sensors`` stops it.

    Returns indices into ``candidates``.

    Parameters
    ----------
    modes : ThermalModes
        The modes.
    candidates : array_like of int, shape (c,)
        Node indices a sensor may sit at.
    mode_indices : array_like of int
        Dominant modes, most important first.
    near_extreme : float, optional
        Eligible fraction of the best |phi| (dimensionless).
    max_sensors : int, optional
        Most sensors placed.

    Returns
    -------
    list of int
        Indices into ``candidates``.
    """
    cand = np.asarray(candidates, dtype=np.int64)
    modes_so_far: list[int] = []
    chosen: list[int] = []
    for mode in np.asarray(mode_indices):
        if max_sensors is not None and len(chosen) >= max_sensors:
            break
        modes_so_far.append(int(mode))
        magnitude = np.abs(modes.shapes[cand, mode])
        eligible = [i for i in np.flatnonzero(magnitude >= near_extreme * magnitude.max())
                    if i not in chosen]
        if not eligible:
            continue
        def score(i: int) -> float:
            rows = modes.shapes[np.asarray(cand[chosen + [i]])][:, modes_so_far]
            return float(np.linalg.svd(rows, compute_uv=False).min())
        chosen.append(int(max(eligible, key=score)))
    return chosen
