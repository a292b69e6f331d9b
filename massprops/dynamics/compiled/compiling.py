"""Getting the compiled kernels of a run ready: loaded from numba's on-disk cache, or compiled once
for this machine with one notice, and on a machine with a spare core the independent ones
compiled side by side.

numba keeps every compiled kernel in its cache (``massprops.dynamics`` keys the folder by a hash
of the package's sources); a kernel the cache lacks is compiled on its first call, a few seconds
of one core. `prepare` gets the kernels of the integrators a command will use ready before any
run starts, so that compiling never happens inside a timed run or on a helper thread, and so that
the caller hears about it while it happens:

- the notice is honest: it is given when numba actually starts compiling (its "numba:compile"
  event fires only on a cache miss, never for a kernel loaded from the cache), once per
  `prepare`, on the calling thread, never by printing (the CLI passes a function that writes the
  line to stderr);
- in a process that runs massprops alone (the CLI calls `whole_process`; a library import
  keeps numba as it is and everything in its own process), numba is started lean
  (``jit.start_numba_lean``), and the first compile starts one helper process that compiles
  the batch's other kernels into the same cache on the second core; the caller waits for it
  before loading them (a helper that fails costs nothing but the time: the kernels are then
  compiled here).

The closed form (``exact``) needs no compiled kernel: it is evaluated with numpy.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from typing import cast

import numpy as np

SYSTEM_ENTRIES = ("dop853", "fixed", "outputs", "rhs")
"""The systems engine's compiled entries (`systems_kernel.WARM_UPS`): the two step loops (the
registry's ``kernel`` of each time-stepping method), the samples' outputs (and the stiffness
probe's right-hand sides), and one right-hand side callable from Python, which no run loads
(the tests compare it with the numpy model). Each compiles and caches on its own."""

COMPILE_SECONDS = {"splitting": 10.0, "dop853": 35.0, "fixed": 45.0, "outputs": 27.0,
                   "rhs": 22.0}
"""About how long (s, one idle core) compiling each kernel takes in a fresh process from an
empty cache (benchmarks/bench_compile.py; docs/performance.md, "Compiling and loading"); a
second systems entry in the same process costs less, the code they share being compiled
already. Only for the notice's estimate and for sharing the work between two processes."""

HELPER_TIMEOUT_S = 600.0
"""The longest the caller waits for the helper process before compiling the rest itself."""

_whole_process = False

_ready: set[str] = set()
"""Kernels warmed up in this process: numba's dispatchers keep them, so `prepare` skips them
(a warm-up costs ~0.4 ms, twice in every one-body `simulate` call before this)."""


def whole_process(alone: bool = True) -> None:
    """Declare that this process runs massprops alone (the CLI): `prepare` then starts numba lean
    and may compile independent kernels in a helper process. Never call it where users' own
    numba code runs."""
    global _whole_process
    _whole_process = alone


def compiled_names(names: Sequence[str]) -> list[str]:
    """The distinct compiled kernels behind ``names`` (integrator names, or kernel names such as
    `SYSTEM_ENTRIES`), in order: an integrator's is its registry ``kernel`` (a registered one
    without: its own name); the closed form has none; kernels shared by several methods are
    named once."""
    # deferred: the registry imports the kernels' modules; needed only when preparing them
    from massprops.dynamics.integrators import INTEGRATORS

    out: list[str] = []
    for name in names:
        if name in SYSTEM_ENTRIES:
            kernel: str | None = name
        else:
            spec = INTEGRATORS[name]
            kernel = spec.kernel or (None if spec.kind == "exact" else name)
        if kernel is not None and kernel not in out:
            out.append(kernel)
    return out


def prepare(names: Sequence[str], notice: Callable[[str], None] | None = None) -> float:
    """Load or compile the kernels of the integrators ``names``; returns the seconds spent.

    ``notice(text)`` is called once, on this thread, when numba starts compiling (a cache miss)
    with one line saying what is compiled and about how long it takes; never when everything
    comes from the cache.
    """
    kernels = [k for k in compiled_names(names) if k not in _ready]
    if not kernels:
        return 0.0
    start = time.perf_counter()
    from numba.core import event

    if _whole_process:
        # deferred: the registry imports the kernels' modules; needed only when preparing them
        from massprops.dynamics.compiled.jit import start_numba_lean

        start_numba_lean()

    watch = _Watch(kernels, notice)

    class Listener(event.Listener):
        def on_start(self, ev) -> None:
            watch.on_start()

        def on_end(self, ev) -> None:
            """Nothing to do: the notice is given when a compile starts."""

    with event.install_listener("numba:compile", Listener()):
        try:
            pending = list(kernels)
            while pending:
                name = pending.pop(0)
                if name in watch.helper_kernels:
                    if any(k not in watch.helper_kernels for k in pending):
                        pending.append(name)  # ours first, the helper's once it is done
                        continue
                    watch.wait_for_helper()
                warm_up(name)
                watch.done.append(name)
                _ready.add(name)
        finally:
            watch.stop_helper()
    return time.perf_counter() - start


def warm_up(name: str) -> None:
    """Run integrator ``name`` for one tiny step on a stand-in problem whose arguments have the
    types of every real run (so the call loads or compiles the very kernel the runs use)."""
    if name in SYSTEM_ENTRIES:
        # deferred: the systems' kernels, needed only when preparing them
        from massprops.dynamics.compiled.systems_kernel import WARM_UPS

        WARM_UPS[name]()
        return
    # deferred: the registry imports the kernels' modules; needed only when preparing them
    from massprops.dynamics.forces import GRAVITY, NPAR
    from massprops.dynamics.integrators import INTEGRATORS

    spec = INTEGRATORS[name]
    y = np.zeros(13)
    y[6] = 1.0
    arrays = (np.ones(1, dtype=np.bool_), np.array([GRAVITY], dtype=np.int64),
              np.zeros((1, NPAR)), 1.0, np.array([1.0, 2.0, 3.0]))
    # a one-body kernel's (the systems' entries are warmed above): it has one
    run_segment = cast(Callable[..., tuple], spec.run_segment)
    run_segment(y, 0.0, 1e-9, 1e-9, arrays, False, np.empty(0), np.empty((0, 13)),
                     np.zeros(5, dtype=np.int64))


def _estimate(kernels: Sequence[str]) -> float:
    return sum(COMPILE_SECONDS.get(k, 5.0) for k in kernels)


class _Watch:
    """numba "numba:compile" listener: the notice on the first compile, and the helper process."""

    def __init__(self, kernels: list[str], notice: Callable[[str], None] | None) -> None:
        self.kernels, self.notice = kernels, notice
        self.done: list[str] = []
        self.started = False
        self.helper: subprocess.Popen | None = None
        self.helper_kernels: list[str] = []

    def on_start(self) -> None:
        """numba started compiling something (a cache miss)."""
        if self.started:
            return
        self.started = True
        rest = [k for k in self.kernels if k not in self.done]
        if _whole_process and len(rest) > 1:
            self.helper_kernels = _second_share(rest)
            self.helper = _spawn(self.helper_kernels)
        if self.notice is not None:
            names = ", ".join(rest)
            self.notice(f"compiling the {names} kernel{'s' if len(rest) > 1 else ''} once for "
                        f"this machine (~{_wall_estimate(rest, self.helper_kernels):.0f} s); "
                        f"later runs load {'them' if len(rest) > 1 else 'it'} from the cache")

    def wait_for_helper(self) -> None:
        """Block until the helper has finished (its kernels are then in the cache)."""
        if self.helper is None:
            return
        with contextlib.suppress(subprocess.TimeoutExpired):  # then stopped, its rest done here
            self.helper.wait(timeout=HELPER_TIMEOUT_S)
        self.stop_helper()

    def stop_helper(self) -> None:
        helper, self.helper = self.helper, None
        if helper is not None and helper.poll() is None:
            helper.kill()
            helper.wait()


def balanced(kernels: Sequence[str], jobs: int) -> list[list[str]]:
    """``kernels`` split into ``jobs`` shares of about equal compile time (largest first, each
    to the share with least to do), for compiling side by side."""
    shares: list[list[str]] = [[] for _ in range(jobs)]
    for name in sorted(kernels, key=lambda k: -COMPILE_SECONDS.get(k, 5.0)):
        min(shares, key=_estimate).append(name)
    return shares


def _second_share(kernels: list[str]) -> list[str]:
    """The kernels the helper compiles: the first stays here (it is compiling already); the rest
    go, largest first, to whichever side has less to do."""
    here: list[str] = [kernels[0]]
    there: list[str] = []
    for name in sorted(kernels[1:], key=lambda k: -COMPILE_SECONDS.get(k, 5.0)):
        (there if _estimate(there) < _estimate(here) else here).append(name)
    return there


def _wall_estimate(kernels: list[str], helper: list[str]) -> float:
    if not helper:
        return _estimate(kernels)
    return max(_estimate([k for k in kernels if k not in helper]), _estimate(helper))


def _helper_command(kernels: Sequence[str]) -> list[str]:
    code = ("import sys; from massprops.dynamics.compiled.compiling import helper_main; "
            "helper_main(sys.argv[1:])")
    return [sys.executable, "-c", code, *kernels]


def _spawn(kernels: list[str]) -> subprocess.Popen | None:
    """A helper process compiling ``kernels`` into the same cache (None if it cannot start)."""
    try:
        return subprocess.Popen(_helper_command(kernels), env=os.environ.copy(),
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
    except OSError:
        return None


def helper_main(kernels: list[str]) -> None:
    """The helper process: load or compile ``kernels`` into the shared cache, then print how many
    functions numba compiled (0: everything came from the cache) and exit."""
    # deferred: the registry imports the kernels' modules; needed only when preparing them
    from numba.core import event

    from massprops.dynamics.compiled.jit import start_numba_lean

    start_numba_lean()
    compiled = 0

    class Counter(event.Listener):
        def on_start(self, ev) -> None:
            nonlocal compiled
            compiled += 1

        def on_end(self, ev) -> None:
            """Counted at the start."""

    with event.install_listener("numba:compile", Counter()):
        for name in kernels:
            warm_up(name)
    print(compiled)


def ready_side_by_side(names: Sequence[str] | None = None, jobs: int = 2,
                       timeout: float = 1800.0, env: dict | None = None) -> int:
    """Load or compile the kernels of the integrators ``names`` (default: every one, and every
    systems entry) into the cache, in ``jobs`` fresh processes side by side (one kernel is
    one process's work); returns the number of functions numba compiled (0: all were cached).
    The build step and the test suite's start use it; a run uses `prepare`.
    Raises RuntimeError when a process fails or takes longer than ``timeout`` seconds."""
    # deferred: the registry imports the kernels' modules; needed only when preparing them
    from massprops.dynamics.integrators import INTEGRATORS

    kernels = compiled_names(names or [*INTEGRATORS, *SYSTEM_ENTRIES])
    procs = [subprocess.Popen(_helper_command(share), env=env, stdin=subprocess.DEVNULL,
                              stdout=subprocess.PIPE, text=True)
             for share in balanced(kernels, jobs) if share]
    try:
        outs = [proc.communicate(timeout=timeout)[0] for proc in procs]
    except subprocess.TimeoutExpired as exc:
        raise RuntimeError(f"compiling the kernels took over {timeout:.0f} s") from exc
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    if any(proc.returncode != 0 for proc in procs):
        raise RuntimeError("compiling a kernel failed (its error is above)")
    return sum(int(out.split()[-1]) for out in outs)
