"""Basins of attraction of the beam: where the motion goes from many initial states of
one point, grouped by the orbit it settles on.

The starting states lie in the plane of the first bending mode: the linear steady state
(the orbit without the stop, at phase 0) moved in that mode's coordinate and rate,
uniformly in a box of ``box`` times their linear amplitudes (a seeded generator: the same
seed, the same states).
Each runs the engine's transient to its own settle test, with no Newton step that could
carry it across a basin's edge; two end orbits are one attractor where one's strobe
matches one of the other's within ``match`` of each component's scale.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from . import modal_map
from ._engine.modal import HEAD
from .beam_packing import first_steps, pack_beam
from .beam_parameters import DEFAULT_BEAM_PRESET, resolve_beam_parameters
from .beam_runs import solve_beam, system_of
from .outputs import OUTPUTS
from .parameters import ParameterError, check_seed, is_number, whole_number
from .version import __version__

#: Two orbits are one attractor where their strobes agree within this fraction of each
#: component's scale [-].
MATCH = 1e-4
#: What each attractor reports beside its basin.
ATTRACTOR_OUTPUTS = ("power", "v_peak", "x_max", "x_min", "impacts_per_period",
                     "root_strain_max", "contact_force_max", "orbit_period")


def beam_basins(preset: str | None = DEFAULT_BEAM_PRESET, samples: int = 64, seed: int = 0,
                box: float = 2.0, **overrides) -> xr.Dataset:
    """The attractors of one beam point and the fraction of ``samples`` initial states
    that reach each (``box``: the half-width of the box of starts around the linear
    steady state, in units of the first mode's linear amplitude and rate [-]). Returns a
    CF dataset over ``attractor`` (and the starts over ``sample``)."""
    samples = whole_number("samples", samples, 1)
    if not (is_number(box) and math.isfinite(box) and box > 0):
        raise ParameterError(f"box [-] = {box!r}: must be a finite number > 0")
    seed = check_seed(seed)
    p = resolve_beam_parameters(preset, **overrides)
    bs = system_of(p)
    steps, sub = first_steps(p, bs)
    pk = pack_beam(p, bs, steps, sub)
    # the first mode's coordinate (0) and rate (its row after the displacements)
    rate = int(np.flatnonzero(bs.system.matrix[0])[0])
    size = np.abs(pk.particular[[0, rate]])
    rng = np.random.default_rng(seed)
    starts = np.repeat(pk.particular.imag[None, :], samples, axis=0)
    starts[:, [0, rate]] += box * size * rng.uniform(-1.0, 1.0, (samples, 2))
    metrics, ends, strobes = modal_map.run([pk] * samples, starts)
    label = np.full(samples, -1)
    members: list[list] = []
    scale = bs.scale
    for i in range(samples):
        if metrics[i, HEAD.status] != 0:
            continue
        period = max(int(metrics[i, HEAD.period]), 1)
        for a, first in enumerate(members):
            j = first[0]
            pj = max(int(metrics[j, HEAD.period]), 1)
            if pj == period and (np.abs(strobes[j, -pj:] - strobes[i, -1]) / scale).max(
                    axis=1).min() <= MATCH:
                label[i] = a
                first.append(i)
                break
        else:
            label[i] = len(members)
            members.append([i])
    fractions = np.array([len(m) / samples for m in members])
    data = {
        "basin_fraction": (("attractor",), fractions, OUTPUTS["basin_fraction"].attrs),
        "basin_fraction_error": (("attractor",), np.sqrt(fractions * (1 - fractions)
                                                         / samples),
                                 OUTPUTS["basin_fraction_error"].attrs),
        "fraction_not_settled": ((), float(np.mean(metrics[:, HEAD.status] == 1)),
                                 OUTPUTS["fraction_not_settled"].attrs),
        "fraction_diverged": ((), float(np.mean(metrics[:, HEAD.status] == 2)),
                              OUTPUTS["fraction_diverged"].attrs),
        "start_eta_1": (("sample",), starts[:, 0], {"units": "m kg0.5", "long_name":
                        "first bending mode's coordinate at the start"}),
        "start_eta_1_rate": (("sample",), starts[:, rate], {"units": "m kg0.5/s",
                             "long_name": "first bending mode's rate at the start"}),
        "sample_attractor": (("sample",), label, {"units": "1", "long_name":
                             "attractor the start reaches (-1: none settled)"}),
    }
    # each attractor measured as a sweep point is, from its first member's orbit: Newton on
    # the period map and the step halved to the accuracy asked (a start on the orbit
    # stays on it)
    solved = solve_beam([p] * len(members), [ends[m[0]] for m in members]) if members \
        else None
    for name in ATTRACTOR_OUTPUTS + ("error_estimate",):
        values = solved.values[name] if members else np.zeros(0)
        data[name] = (("attractor",), np.array(values, dtype=float), OUTPUTS[name].attrs)
    ds = xr.Dataset(data, coords={"attractor": ("attractor", np.arange(len(members)),
                                                 {"units": "1", "long_name": "attractor"})})
    ds.attrs.update({"Conventions": "CF-1.8", "model": "beam",
                     "title": "harvester_sweep basins of attraction of the beam model",
                     "source": f"harvester_sweep {__version__} modal engine",
                     "preset": preset or DEFAULT_BEAM_PRESET, "seed": seed, "box": box})
    for name, value in p.items():
        if value is not None:
            ds.attrs[f"parameter_{name}"] = value if not isinstance(value, (bool, tuple)) \
                else (int(value) if isinstance(value, bool) else list(value))
    return ds
