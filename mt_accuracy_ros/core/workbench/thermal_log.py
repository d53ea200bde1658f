"""A thermal log on the survey engine: one displacement column, temperatures, a spindle.

A thermal log (a displacement sensor at the spindle nose against time, the
structure's thermocouples, the spindle speed - e.g. the FL_THERMAL data) is
a reference survey of a machine that does not move: its readings become
:class:`~.diagnosis.Observations` of one measured component at a standing
position, and the catalogue's thermal families - ``structural_thermal_drift``
(a sensor, Zhu eq. 3.12), ``thermal_gradient`` (a difference, Zhu Table 4.2),
``thermal_lag`` (a sensor through a time constant, Zhu eqs. 3.9-3.10),
``heat_source`` (the spindle through a lag) and ``all_sensors_ridge`` (many weak
sensors at once) - are selected, tested, tie-broken and judged as for any survey
(:func:`~.diagnosis.diagnose`), with **forward validation**: each block is
predicted by a fit on the blocks before it only, the way the model will be used.

The log's later rows (after ``train_fraction``) are never seen by the selection:
each model version is judged on them (:func:`held_out_rmse`), and a term that
raises that error is not added (:func:`~mt_accuracy_ros.commands.check`).
"""
from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from ..compensation.error_model import ErrorModel
from ..errors import InputDataError, InsufficientDataError
# One rule for a signal's noise, shared with the sensors' judge (re-exported here).
from ..inputs.sensor_health import noise_from_differences  # noqa: F401
from ..kinematics.machine import generic_cartesian
from .diagnosis import Observations
from .log_runs import run_starts, stitched_time

#: Structure between a log's sensors and its displacement sensor when the user does
#: not say [m]: a machine tool's column and spindle head. It bounds what physics
#: allows a thermal gain (:mod:`..effects.physics`: 30 um/m/K over it).
DEFAULT_STRUCTURE_LENGTH_M = 1.0

#: Fewest rows a log needs (forward validation cuts the training rows in 6 blocks).
MIN_LOG_ROWS = 30


def log_machine(structure_length_m: float = DEFAULT_STRUCTURE_LENGTH_M):
    """The machine of a thermal log: three standing axes, ``structure_length_m`` of
    structure for the physics bounds.

    Parameters
    ----------
    structure_length_m : float, optional
        Structure between the sensors and the displacement sensor [m], > 0.

    Returns
    -------
    MachineDescription
        ``thermal_log``: X, Y, Z with zero strokes.

    Raises
    ------
    InputDataError
        A length that is not finite and > 0.
    """
    if not (np.isfinite(structure_length_m) and structure_length_m > 0):
        raise InputDataError(f"structure length {structure_length_m!r} m: give a length > 0")
    machine = generic_cartesian({a: (0.0, 0.0) for a in "XYZ"}, name="thermal_log")
    return dataclasses.replace(machine, structure_length_m=float(structure_length_m))


def complete_log_rows(time_s: NDArray[np.float64], target_m: NDArray[np.float64],
                      temperatures: dict[str, NDArray[np.float64]],
                      spindle_speed_rad_s: NDArray[np.float64] | None = None
                      ) -> NDArray[np.bool_]:
    """The rows a log's observations keep: time, target, every temperature and the speed
    finite (:func:`log_observations` keeps these, in order).

    Parameters
    ----------
    time_s, target_m : ndarray, shape (N,)
        Time [s] and target [m].
    temperatures : dict of str to ndarray, shape (N,)
        Input temperatures [degC].
    spindle_speed_rad_s : ndarray, shape (N,), optional
        The spindle speed [rad/s].

    Returns
    -------
    ndarray of bool, shape (N,)
        True where every value of the row is finite.
    """
    good = np.isfinite(np.asarray(time_s, dtype=np.float64)) & \
        np.isfinite(np.asarray(target_m, dtype=np.float64))
    for values in list(temperatures.values()) + ([spindle_speed_rad_s]
                                                  if spindle_speed_rad_s is not None else []):
        good &= np.isfinite(np.asarray(values, dtype=np.float64))
    return good


def kept_data_rows(data_rows: NDArray[np.intp] | None, kept: NDArray[np.bool_]
                   ) -> NDArray[np.intp]:
    """The data rows (1-based, the header not counted) of the rows ``kept``.

    Parameters
    ----------
    data_rows : ndarray of int, shape (N,), optional
        Each row's data row in the file (None: 1..N).
    kept : ndarray of bool, shape (N,)
        The rows kept (:func:`complete_log_rows`).

    Returns
    -------
    ndarray of int, shape (K,)
        The kept rows' data rows, in order.
    """
    rows = np.arange(1, kept.size + 1) if data_rows is None else np.asarray(data_rows)
    return rows[kept]


def log_observations(time_s: NDArray[np.float64], target_m: NDArray[np.float64],
                     temperatures: dict[str, NDArray[np.float64]], *,
                     spindle_speed_rad_s: NDArray[np.float64] | None = None,
                     component: str = "z", uncertainty_m: float | None = None,
                     run_of_row: NDArray[np.intp] | None = None,
                     run_names: list[str] | None = None, zeroed_runs: bool = False,
                     data_rows: NDArray[np.intp] | None = None) -> Observations:
    """A thermal log as reference readings of one component at a standing position.

    Rows with a non-finite time, target, temperature or speed are left out (the
    caller counts them); fewer than :data:`MIN_LOG_ROWS` left is an error.

    Parameters
    ----------
    time_s : ndarray, shape (N,)
        Strictly increasing [s].
    target_m : ndarray, shape (N,)
        The measured displacement [m].
    temperatures : dict of str to ndarray, shape (N,)
        Structure temperatures [degC].
    spindle_speed_rad_s : ndarray, shape (N,), optional
        The spindle speed [rad/s] (the heat source's driver).
    component : {"x", "y", "z"}
        The direction the displacement sensor measures.
    uncertainty_m : float, optional
        The sensor's k = 2 uncertainty [m]; default twice the noise read off the
        target's successive differences (:func:`noise_from_differences`).
    run_of_row : ndarray, shape (N,), optional
        The run of each row (:func:`~.log_runs.run_labels`): time restarts or jumps
        between runs, lags restart at each run's first reading, and ``time_s`` becomes
        the runs laid end to end (:func:`~.log_runs.stitched_time`).
    run_names : list of str, optional
        The runs' names, for the errors.
    zeroed_runs : bool
        The instrument was zeroed at each run's start: each run's readings are referred
        to its first (so are the model's, :meth:`~.diagnosis.Observations.zeroed`).
    data_rows : ndarray, shape (N,), optional
        Each row's number in the file, for the errors.

    Returns
    -------
    Observations
        The complete rows at a standing position (X, Y, Z at 0 [m]), ``component``
        measured [m], time from 0 [s], temperatures [degC], the uncertainty (k = 2) [m].

    Raises
    ------
    InputDataError
        A component not x, y or z, a time that goes back, a run left with one row, or
        zeroed runs without a run column.
    InsufficientDataError
        Fewer than :data:`MIN_LOG_ROWS` complete rows.
    """
    if component not in ("x", "y", "z"):
        raise InputDataError(f"component {component!r}: one of x, y, z")
    t = np.asarray(time_s, dtype=np.float64)
    y = np.asarray(target_m, dtype=np.float64)
    good = complete_log_rows(t, y, temperatures, spindle_speed_rad_s)
    if int(good.sum()) < MIN_LOG_ROWS:
        raise InsufficientDataError(f"only {int(good.sum())} complete rows; a thermal log "
                                    f"needs >= {MIN_LOG_ROWS}")
    file_rows = kept_data_rows(data_rows, good)
    t, y = t[good], y[good]
    runs = None
    if run_of_row is not None:
        runs = np.asarray(run_of_row, dtype=np.intp)[good]
        names = run_names or [str(k) for k in range(int(runs.max()) + 1)]
        # A run's rows dropped away entirely leaves a hole in the numbering: renumber.
        runs = np.concatenate(([0], np.cumsum(np.diff(runs) != 0))).astype(np.intp)
        names = [names[k] for k in np.asarray(run_of_row)[good][run_starts(runs)]]
        counts = np.bincount(runs)
        if np.any(counts < 2):
            k = int(np.flatnonzero(counts < 2)[0])
            raise InputDataError(f"run {names[k]!r} keeps {int(counts[k])} complete row "
                                 "(the others had a missing value): a run needs at least 2")
        t = stitched_time(t, runs, names, file_rows)
        if zeroed_runs:
            y = y - y[run_starts(runs)][runs]
    else:
        if zeroed_runs:
            raise InputDataError("zeroed runs need a run column (--run COLUMN)")
        # Equal stamps are a logger's resolution (0.1 s, a second), not an error: the lags
        # hold still over them. Only a stamp that goes back is refused, by its row.
        back = np.flatnonzero(np.diff(t) < 0)
        if back.size:
            k = int(back[0]) + 1
            raise InputDataError(f"the time goes back at data row {int(file_rows[k])}: "
                                 f"{t[k]:g} s after {t[k - 1]:g} s (sort the file or fix the "
                                 "stamps; a log of many runs: --run COLUMN)")
    n = t.size
    measured = np.zeros((n, 3))
    mask = np.zeros((n, 3), dtype=bool)
    c = "xyz".index(component)
    measured[:, c] = y
    mask[:, c] = True
    if uncertainty_m is None:
        uncertainty_m = 2.0 * noise_from_differences(y)
    if not (np.isfinite(uncertainty_m) and uncertainty_m > 0):
        # A quantised, perfectly smooth target: one part in 1e6 of its range.
        uncertainty_m = max(float(np.ptp(y)) * 1e-6, 1e-12)
    return Observations(
        positions={a: np.zeros(n) for a in "XYZ"}, measured_m=measured, measured_mask=mask,
        time_s=t - t[0], velocities={a: np.zeros(n) for a in "XYZ"},
        temperatures={k: np.asarray(v, dtype=np.float64)[good] for k, v in temperatures.items()},
        uncertainty_m=float(uncertainty_m),
        spindle_speed_rad_s=None if spindle_speed_rad_s is None else
        np.asarray(spindle_speed_rad_s, dtype=np.float64)[good],
        run_of_row=runs, zeroed_runs=bool(zeroed_runs and runs is not None))


def log_model(obs: Observations, structure_length_m: float = DEFAULT_STRUCTURE_LENGTH_M
              ) -> ErrorModel:
    """The empty model of a log: its machine, every temperature referenced to its first row.

    Parameters
    ----------
    obs : Observations
        The log's N readings (:func:`log_observations`).
    structure_length_m : float, optional
        Structure for the physics bounds [m].

    Returns
    -------
    ErrorModel
        No effects; each sensor's reference its first reading [degC].

    Raises
    ------
    InputDataError
        A length that is not finite and > 0.
    """
    model = ErrorModel(log_machine(structure_length_m), {})
    for sensor, values in obs.temperatures.items():
        model.reference_temperatures_c[sensor] = float(values[0])
    return model


def log_prediction(model: ErrorModel, obs: Observations) -> NDArray[np.float64]:
    """The model's displacement (N,) [m] in the measured component at every row (lags run
    from the first row).

    Parameters
    ----------
    model : ErrorModel
        The model (its thermal effects).
    obs : Observations
        The log's N readings (:func:`log_observations`).

    Returns
    -------
    ndarray, shape (N,)
        Displacement [m], zeroed per run when the runs were zeroed.
    """
    c = int(np.flatnonzero(obs.measured_mask[0])[0])
    return obs.zeroed(model.tcp_error(obs.positions, **obs.model_inputs(), fresh=True)[0][:, c])


def held_out_residual(model: ErrorModel, obs: Observations, train: NDArray[np.bool_]
                      ) -> NDArray[np.float64]:
    """measured - model (N,) [m], its zero (a displacement sensor's own) set on the
    training rows only: the later rows judge the model as it would have predicted them.
    Zeroed runs have their zero at each run's start already: none is set.

    Parameters
    ----------
    model : ErrorModel
        The model (its thermal effects).
    obs : Observations
        The log's N readings (:func:`log_observations`).
    train : ndarray of bool, shape (N,)
        The training rows.

    Returns
    -------
    ndarray, shape (N,)
        Residual [m].
    """
    c = int(np.flatnonzero(obs.measured_mask[0])[0])
    residual = obs.measured_m[:, c] - log_prediction(model, obs)
    return residual if obs.zeroed_runs else residual - float(np.mean(residual[train]))


def held_out_rmse(model: ErrorModel, obs: Observations, train: NDArray[np.bool_]) -> float:
    """RMS of :func:`held_out_residual` over the rows after training [m].

    Parameters
    ----------
    model : ErrorModel
        The model (its thermal effects).
    obs : Observations
        The log's N readings (:func:`log_observations`).
    train : ndarray of bool, shape (N,)
        The training rows.

    Returns
    -------
    float
        RMS [m] (nan when every row is a training row).
    """
    residual = held_out_residual(model, obs, train)[~train]
    return float(np.sqrt(np.mean(residual ** 2)))


def all_inputs_least_squares(obs: Observations, train: NDArray[np.bool_]) -> float:
    """The plain baseline a user tries first: least squares on every temperature at once,
    fitted on the training rows, its held-out RMSE [m] (nan without temperatures).

    Parameters
    ----------
    obs : Observations
        The log's N readings (:func:`log_observations`).
    train : ndarray of bool, shape (N,)
        The training rows.

    Returns
    -------
    float
        Held-out RMSE [m], or nan.
    """
    if not obs.temperatures:
        return float("nan")
    rest = all_inputs_least_squares_residual(obs, train)
    return float(np.sqrt(np.mean(rest[~train] ** 2)))


def all_inputs_least_squares_residual(obs: Observations, train: NDArray[np.bool_]
                                      ) -> NDArray[np.float64]:
    """measured - least squares on every temperature (N,) [m], fitted on the training rows
    (an offset too, unless the runs were zeroed: their zero is known).

    Parameters
    ----------
    obs : Observations
        The log's N readings (:func:`log_observations`).
    train : ndarray of bool, shape (N,)
        The training rows.

    Returns
    -------
    ndarray, shape (N,)
        Residual [m] (gains [m/K] on the rises over each sensor's first reading).
    """
    c = int(np.flatnonzero(obs.measured_mask[0])[0])
    x = np.column_stack([v - v[0] for v in obs.temperatures.values()])
    x = obs.zeroed(x) if obs.zeroed_runs else np.column_stack([np.ones(obs.n), x])
    coefficients, *_ = np.linalg.lstsq(x[train], obs.measured_m[train, c], rcond=None)
    return obs.measured_m[:, c] - x @ coefficients
