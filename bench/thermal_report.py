"""Figures and numbers for docs/thermal.md (issue 5).

``python -m bench.thermal_report`` writes docs/figures/thermal_*.png and prints
the numbers: Table 3.1 time constants and placements, robustness, placement
comparison over seeds, and the held-out errors on data/fl_thermal.
"""
from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from tqdm import tqdm  # noqa: E402

from studies import thermal_fe as studies  # noqa: E402
from studies.thermal_data import load_thermal_csv, study  # noqa: E402
from mt_accuracy_ros.core.thermal.fem import beam_model, rod_model, thermal_modes  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ROOT / "docs" / "figures"
DATA = ROOT / "data"


def main() -> int:
    FIGURES.mkdir(parents=True, exist_ok=True)
    out: dict = {}
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.5))
    for ax, (name, model) in zip(axes, (("rod (elongation)", rod_model()),
                                        ("beam (bending), lower face", beam_model()))):
        modes = thermal_modes(model)
        q = model.heat_vector(1.0)
        weights = modes.weights(q)
        dominant = modes.dominant(q)
        rows = model.nodes[:, 1] == 0
        for i in range(4):
            ax.plot(model.nodes[rows, 0], modes.shapes[rows, i],
                    label=f"mode {i + 1}: τ = {modes.time_constants_s[i] / 60:.1f} min, "
                          f"w = {100 * weights[i] / weights.sum():.0f} %")
        ax.set(title=name, xlabel="x [m]", ylabel="mode shape (C-normalised)")
        ax.legend(fontsize=7)
        out[name] = {"tau_min": (modes.time_constants_s[:5] / 60).round(2).tolist(),
                     "weight_share": (weights[:5] / weights.sum()).round(3).tolist(),
                     "dominant_modes": (dominant + 1).tolist()}
    fig.tight_layout()
    fig.savefig(FIGURES / "thermal_modes.png", dpi=110)
    plt.close(fig)
    model = rod_model()
    modes = thermal_modes(model)
    out["rod modal sensors (node, x m)"] = [(int(n), float(model.nodes[n, 0]))
                                            for n in studies.modal_sensors(model, modes)]
    extrapolation = studies.robustness_extrapolation()
    frequency = studies.robustness_frequency()
    out["robustness"] = {"second_hour_rmse_um": extrapolation.test_rmse_m["second_hour"] * 1e6,
                         "second_hour_peak_um": extrapolation.peak_error_m["second_hour"] * 1e6,
                         "10_min_rmse_um": frequency.test_rmse_m["10_min"] * 1e6,
                         "40_min_rmse_um": frequency.test_rmse_m["40_min"] * 1e6,
                         "train_20_min_rmse_um": frequency.train_rmse_m * 1e6}
    sweep = []
    for seed in tqdm(range(10), desc="placement seeds"):
        p = studies.placement_comparison(seed=seed)
        sweep.append({"full": p.mse_um2["full"], "reduced": p.mse_um2["reduced"],
                      "changed": not np.array_equal(p.sensors["statistical_full"],
                                                    p.sensors["statistical_reduced"])})
    out["placement"] = {
        "full_median_um2": {m: float(np.median([s["full"][m] for s in sweep]))
                            for m in ("modal", "gaussian", "statistical")},
        "reduced_median_um2": {m: float(np.median([s["reduced"][m] for s in sweep]))
                               for m in ("modal", "gaussian", "statistical")},
        "statistical_pick_changed_share": float(np.mean([s["changed"] for s in sweep]))}
    record = load_thermal_csv(DATA / "fl_thermal" / "fl_thermal.csv")
    result = study(record)
    out["fl_thermal_held_out_rmse_um"] = {m: {c: round(v, 2) for c, v in r.items()}
                                          for m, r in result.held_out_rmse_um.items()}
    out["fl_thermal_selected"] = result.selected_sensors
    out["fl_thermal_time_constants_min"] = (result.time_constants_s / 60).round(1).tolist()
    split = record.time_s.size // 2
    fig, axes = plt.subplots(5, 1, figsize=(10, 11), sharex=True)
    hours = record.time_s / 3600
    for c, ax in enumerate(axes):
        channel = record.channel_names[c]
        ax.plot(hours, record.displacements_um[:, c], "k-", lw=0.8, label="measured")
        for model_name, style in (("all16", "b-"), ("all16_ridge", "r-"), ("selected+lag", "g-")):
            ax.plot(hours[split:], result.predictions[model_name][channel], style, lw=0.8,
                    label=f"{model_name} ({result.held_out_rmse_um[model_name][channel]:.1f} µm)")
        ax.axvline(hours[split], color="0.5", ls="--")
        ax.set_ylabel(f"{channel} [µm]")
        ax.legend(fontsize=7, loc="upper left")
    axes[-1].set_xlabel("time [h] (trained left of the dashed line, judged right)")
    fig.tight_layout()
    fig.savefig(FIGURES / "thermal_fl_held_out.png", dpi=100)
    plt.close(fig)
    print(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
