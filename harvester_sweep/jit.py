"""How every compiled function is compiled: one set of numba options for the models' and
the engine's (JIT), and plain IEEE arithmetic for the orbit solver's (SOLVER_JIT).

Bit-for-bit reproducible whichever lane, group or thread runs a point: no reassociation
(it would let a vector loop sum in another order than scalar code) and no approximate
functions. FMA contraction is allowed: LLVM fuses a multiply into an add of the same basic
block, so differently shaped code may round differently, but every lane runs the same
vector code and which steps run scalar code is decided by the point's own state
(tests/engine/test_reproducibility.py checks a point in several lanes, groups and thread
counts). No nnan/ninf either: the divergence check relies on isfinite. nsz and arcp let
LLVM vectorize the lane loop, which has no division, so that arcp cannot make a vector
lane differ from scalar code.
"""

from __future__ import annotations

FASTMATH = frozenset({"nsz", "arcp", "contract"})
JIT = dict(cache=True, fastmath=set(FASTMATH), error_model="numpy")

#: The orbit solver's compiled decisions (and the small dense algebra they use): plain
#: IEEE arithmetic, no contraction or reassociation, so that an expression rounds as
#: the same expression in numpy does.
SOLVER_JIT = dict(cache=True, error_model="numpy")
