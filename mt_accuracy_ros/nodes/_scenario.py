"""What the virtual-machine nodes share: the scenario, its clock, chunked simulation."""
from __future__ import annotations

from pathlib import Path

from ..core.errors import ScenarioError
from ..sim.scenario import Scenario, load_scenario

BUNDLED = Path(__file__).resolve().parents[1] / "scenarios"


def resolve_scenario(name_or_path: str) -> Scenario:
    """A bundled scenario name (``demo``) or a path to a scenario YAML."""
    candidate = Path(name_or_path)
    if candidate.suffix in (".yaml", ".yml") or candidate.exists():
        return load_scenario(candidate)
    bundled = BUNDLED / f"{name_or_path}.yaml"
    if not bundled.is_file():
        known = ", ".join(sorted(p.stem for p in BUNDLED.glob("*.yaml")))
        raise ScenarioError(f"no scenario {name_or_path!r} (bundled: {known}; or give a path)")
    return load_scenario(bundled)


class ScenarioClock:
    """Sim time of a scenario streamed in real time x ``rate_factor`` from ``start_ns``.

    Sample i of the run is stamped ``start_ns + i / sample_rate`` (sim seconds); it
    is due when the node clock reaches ``start_ns + (i / sample_rate) / rate_factor``.
    """

    def __init__(self, start_ns: int, rate_factor: float) -> None:
        self.start_ns = int(start_ns)
        self.rate_factor = float(rate_factor)

    def sim_time_s(self, now_ns: int) -> float:
        return max(0.0, (now_ns - self.start_ns) / 1e9 * self.rate_factor)

    def stamp_ns(self, sim_time_s: float) -> int:
        return self.start_ns + int(round(sim_time_s * 1e9))
