"""A model's state, declared as components: name, unit, how its scale is taken, meaning.

Every row that carries a state (the engine's state rows and stroboscopic samples, the
period map's deviations, the basins' box of starting states) is laid out from a model's
components, and every size is their number.
"""

from __future__ import annotations

from collections import namedtuple

#: One component of a state. ``scale`` says how the component's scale on an orbit of
#: displacement amplitude X [m] is taken (the Newton and settle tests measure each
#: component against it): "displacement" X, "velocity" w X, "voltage" the larger of the
#: orbit's peak voltage and the voltage an amplitude X induces.
Component = namedtuple("Component", ("name", "unit", "scale", "meaning"))


def describe(components) -> tuple:
    """(name, "meaning [unit]") of each component, as a layout's fields."""
    return tuple((c.name, f"{c.meaning} [{c.unit}]") for c in components)
