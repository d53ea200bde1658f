"""A plant of virtual machine tools, each recording a bag a day: data for ``mt-accuracy fleet``.

Every day of every machine is a scenario of its own (:func:`day_scenario`): the
machine's own seed (its geometry), that day's noise seed, the clock set to the day
(06:00 UTC), and the machine's effects, some of which may grow from day to day (a
guideway that wears: ``grows`` maps an effect's parameter to its increase per day).
Each day is simulated and written as a bag of reference readings and temperatures
(:func:`~.export.write_bag` with ``reference_period_s``), in ``OUT/<machine>/<date>/``:
the folder layout ``mt-accuracy fleet OUT`` reads.
"""
from __future__ import annotations

import copy
import datetime as dt
from dataclasses import dataclass, field
from pathlib import Path

from .export import write_bag
from .machine_tool import simulate
from .scenario import scenario_from_dict

#: The first day of :func:`write_fleet`'s plant (06:00 UTC).
FIRST_DAY = dt.datetime(2026, 11, 16, 6, 0, tzinfo=dt.timezone.utc)


@dataclass
class VirtualMachine:
    """One machine of the plant.

    Attributes
    ----------
    name : str
        Its name (the folder of its bags).
    seed : int
        Its geometry and scales (the scenario's ``seed``).
    effects : dict
        Scenario effects (:mod:`.effects`), as in a scenario file.
    grows : dict
        ``{(effect, parameter): increase per day}``: what wears.
    machine : str
        The bundled machine (or a machine YAML).
    """

    name: str
    seed: int
    effects: dict = field(default_factory=dict)
    grows: dict = field(default_factory=dict)
    machine: str = "kidani_hmc"


def day_scenario(machine: VirtualMachine, day: int, *, duration_s: float = 240.0,
                 sample_rate_hz: float = 200.0, first_day: dt.datetime = FIRST_DAY):
    """The scenario of ``machine`` on day ``day`` (0 = ``first_day``)."""
    effects = copy.deepcopy(machine.effects)
    for (effect, parameter), per_day in machine.grows.items():
        effects.setdefault(effect, {})
        effects[effect][parameter] = float(effects[effect].get(parameter, 0.0)) + per_day * day
    start = first_day + dt.timedelta(days=day)
    return scenario_from_dict({
        "description": f"{machine.name}, day {day}", "machine": machine.machine,
        "seed": machine.seed, "noise_seed": machine.seed * 1000 + day,
        "duration_s": duration_s, "sample_rate_hz": sample_rate_hz, "temperature_rate_hz": 1,
        "start_time_s": start.timestamp(),
        "program": {"type": "back_and_forth", "axes": ["X", "Y"], "feed_m_per_min": 6},
        "effects": effects}, f"{machine.name} day {day}")


def write_fleet(out: str | Path, machines: list[VirtualMachine], days: int | dict[str, int],
                *, reference_period_s: float = 1.0, **day_options) -> list[Path]:
    """A bag a day for every machine under ``out``; returns the bags written.

    ``days``: how many days each machine records (one number, or per machine name)."""
    out = Path(out)
    bags = []
    for machine in machines:
        count = days if isinstance(days, int) else days[machine.name]
        for day in range(count):
            scenario = day_scenario(machine, day, **day_options)
            date = dt.datetime.fromtimestamp(scenario.start_time_s, tz=dt.timezone.utc).date()
            bag = out / machine.name / date.isoformat()
            write_bag(simulate(scenario), bag, reference_period_s=reference_period_s,
                      scales=False)
            bags.append(bag)
    return bags
