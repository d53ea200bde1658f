"""Reproduce Kidani's headline results on the simulator; figures for docs/results.md.

``python -m bench.thesis_results`` writes ``docs/figures/result_[abcd].png``
and prints the numbers (the seeds the tests use, then a sweep over seeds).
"""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from tqdm import tqdm  # noqa: E402

from studies import thesis  # noqa: E402

FIGURES = Path(__file__).resolve().parents[1] / "docs" / "figures"


def _save(fig, ax, name: str, xlabel: str, ylabel: str, title: str) -> None:
    ax.set(xlabel=xlabel, ylabel=ylabel, title=title)
    ax.legend()
    fig.tight_layout()
    fig.savefig(FIGURES / name, dpi=110)
    plt.close(fig)


def figure_a(r) -> None:
    fig, ax = plt.subplots(figsize=(6, 3.5))
    y = r.positions_m * 1e3
    ax.fill_between(y, (r.scale_yaw_rad - r.band_2u_rad) * 1e6,
                    (r.scale_yaw_rad + r.band_2u_rad) * 1e6, color="r", alpha=0.15, label="2u")
    ax.plot(y, r.scale_yaw_rad * 1e6, "ro-", label="scales (eq. 3.9)")
    ax.plot(y, r.laser_yaw_rad * 1e6, "bs-", label="laser (XM60-like)")
    _save(fig, ax, "result_a.png", "Y position [mm]", "E_CY [µrad]",
          f"(a) yaw: {r.count_inside} of 11 positions inside 2u")


def figure_b(r) -> None:
    fig, ax = plt.subplots(figsize=(6, 3.5))
    end = -1
    ax.plot(r.hours, np.max(np.abs(r.raw_change_rad), axis=1) * 1e6, "k.-",
            label="scales - laser, raw")
    ax.plot(r.hours, np.max(np.abs(r.compensated_change_rad), axis=1) * 1e6, "r.-",
            label="with thermal compensation (eq. 3.17)")
    _save(fig, ax, "result_b.png", "warm-up time [h]", "max |apparent yaw change| [µrad]",
          f"(b) 20 h warm-up: {100 * r.removed_fraction:.1f} % removed "
          f"(scale rises {r.scale_rise_k[end, 0]:.2f} / {r.scale_rise_k[end, 1]:.2f} K)")


def figure_c(r) -> None:
    fig, ax = plt.subplots(figsize=(6, 3.5))
    y = r.positions_m * 1e3
    ax.plot(y, r.tcp_change_true_m * 1e6, "k--", label="T2 - T1 (no compensation)")
    ax.plot(y, r.residual_m * 1e6, "r-", label="T3 - T1 (y_MOD = y - Δe)")
    ax.fill_between(y, 0, 1, where=r.flagged, color="orange", alpha=0.2,
                    transform=ax.get_xaxis_transform(), label="flagged |ΔE| ≥ tol")
    _save(fig, ax, "result_c.png", "Y position [mm]", "TCP change Δe_y [µm]",
          f"(c) deterioration: {100 * r.removed_fraction:.1f} % removed")


def figure_d(r) -> None:
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(r.positions_m * 1e3, r.values_rad * 1e6, ",", color="0.6", label="yaw samples")
    grid = np.linspace(r.positions_m.min(), r.positions_m.max(), r.systematic_rad.size)
    ax.plot(grid * 1e3, r.systematic_rad * 1e6, "r-", label=f"kNN systematic, k = {r.k}")
    _save(fig, ax, "result_d.png", "X position [mm]", "E_CX [µrad]",
          f"(d) CV RMSE {r.cv_rmse_rad * 1e6:.4f} vs new data "
          f"{r.new_data_rmse_rad * 1e6:.4f} µrad ({100 * r.relative_difference:.2f} %)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seeds", type=int, default=10, help="seeds in the sweep")
    args = parser.parse_args()
    FIGURES.mkdir(parents=True, exist_ok=True)
    a, b = thesis.yaw_vs_laser(), thesis.warmup_compensation()
    c, d = thesis.deterioration_compensation(), thesis.knn_cv_vs_new_data()
    figure_a(a), figure_b(b), figure_c(c), figure_d(d)
    out = {"test_seeds": {
        "a_inside_of_11": a.count_inside, "b_removed": b.removed_fraction,
        "c_removed": c.removed_fraction,
        "c_true_change_um": float(np.abs(c.tcp_change_true_m).max() * 1e6),
        "c_residual_um": float(np.abs(c.residual_m).max() * 1e6),
        "d_k": d.k, "d_cv_rmse_urad": d.cv_rmse_rad * 1e6,
        "d_new_rmse_urad": d.new_data_rmse_rad * 1e6,
        "d_relative_difference": d.relative_difference}}
    sweep = {"a_inside_of_11": [], "c_removed": [], "d_relative_difference": []}
    for seed in tqdm(range(100, 100 + args.seeds), desc="seed sweep"):
        sweep["a_inside_of_11"].append(thesis.yaw_vs_laser(seed).count_inside)
        sweep["c_removed"].append(thesis.deterioration_compensation(seed).removed_fraction)
        sweep["d_relative_difference"].append(thesis.knn_cv_vs_new_data(seed).relative_difference)
    out["sweep"] = {k: {"min": float(np.min(v)), "median": float(np.median(v)),
                        "max": float(np.max(v))} for k, v in sweep.items()}
    out["sweep"]["d_share_within_1.4%"] = float(
        np.mean(np.array(sweep["d_relative_difference"]) <= 0.014))
    out["sweep"]["a_share_ge_10"] = float(np.mean(np.array(sweep["a_inside_of_11"]) >= 10))
    out["sweep"]["c_share_ge_86%"] = float(np.mean(np.array(sweep["c_removed"]) >= 0.86))
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
