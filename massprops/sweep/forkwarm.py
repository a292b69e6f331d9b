"""Imported by a sweep's fork server (`run.SWEEP_PRELOAD`) and nowhere else: it initialises
numba's CPU target once there (`compiled.jit.start_numba_lean`, as the CLI does for its own
process), so that every worker the server forks inherits it and loads its kernels from the cache
in ~0.07 s instead of ~0.35 s (measured on this 2-core machine: the target's first
initialisation is the rest). The server is one thread running massprops alone when it imports
this: no user's numba code runs there, and forking after it is safe."""

from __future__ import annotations

from massprops.dynamics.compiled.jit import start_numba_lean

start_numba_lean()
