"""The modal engine: a linear system with Hertz contact surfaces (any model in the form of
``harvester_sweep.models.beam``), integrated exactly between contacts and by RK4 in the
frame of the linear flow inside them (:mod:`.kernel`), many points in parallel.

Its machine code is cached apart from the lane engine's: its digest covers its own files,
the Hertz law, the Hermite interpolant, the atomic counter and the flags, so that editing
one engine never recompiles the other.
"""

from __future__ import annotations

from pathlib import Path

from ...models import hertz
from .. import cache, hermite
from . import kernel, layout
from .kernel import MAP, MAX_ORBIT, MEASURE, SAMPLES, SETTLE, record_samples, take_points
from .layout import (
    COMPLEX,
    HEAD,
    METRIC_HEAD,
    REAL,
    RealFields,
    complex_fields,
    metric_size,
    real_fields,
)

_HERE = Path(__file__).parent
SOURCE_DIGEST = cache.source_digest((_HERE, _HERE.parent / "hermite.py",
                                     _HERE.parent / "atomic.py",
                                     _HERE.parent.parent / "models" / "hertz.py",
                                     _HERE.parent.parent / "jit.py"))
cache.flush_if_changed(kernel.take_points, (kernel, layout), SOURCE_DIGEST)

__all__ = ["COMPLEX", "HEAD", "MAP", "MAX_ORBIT", "MEASURE", "METRIC_HEAD", "REAL", "SAMPLES",
           "SETTLE", "RealFields", "SOURCE_DIGEST", "complex_fields", "hermite", "hertz",
           "metric_size", "real_fields", "record_samples", "take_points"]
