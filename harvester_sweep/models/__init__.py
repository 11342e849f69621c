"""The models the engine runs, each declared once in a module of its own.

A model module declares its state (:class:`.state.Component` rows: names, units, scales),
its right-hand side and RK4 step, its contact surfaces (through the one Hertz law of
:mod:`.hertz`), its contact-free step as a linear map, its linear system (from which the
closed-form response and the time scales of the step choice come) and the energy bound of
the no-contact proof. The layers above derive layouts, sizes and references from it.

Compiled functions only (numba, numpy): this is the package's lowest layer, below the
engine, and imports nothing from above.
"""

from . import hertz, tip_mass

#: Every model, by name.
MODELS = {"tip_mass": tip_mass}

__all__ = ["MODELS", "hertz", "tip_mass"]
