"""A sweep's outputs over time (``sweep --plot``): per output component, the samples' median
and their 25-75 % and 5-95 % bands at each sample time (matplotlib, the ``plot`` extra)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from massprops.dynamics.plots import require_matplotlib, save_figure
from massprops.sweep.sample import Row

_AXES = ("x", "y", "z")


def plot_sweep(rows: Sequence[Row], outputs: Sequence[str], path: str | Path, *,
               force: bool = False, protect=()) -> None:
    """One panel per output of ``rows`` (those that ran and carry ``series``), each component
    a median line in its bands; a component that does not vary is left out."""
    require_matplotlib()
    import matplotlib.pyplot as plt  # deferred: the plot extra, checked just above
    ran = [(r.times, r.series) for r in rows
           if r.status == "ok" and r.series is not None and r.times is not None]
    names = [n for n in outputs if ran and n in ran[0][1]]
    fig, axes = plt.subplots(max(1, len(names)), 1, figsize=(8, 2.6 * max(1, len(names)) + 0.4),
                             sharex=True, constrained_layout=True, squeeze=False)
    for ax, name in zip(axes[:, 0], names):
        t = np.asarray(ran[0][0], dtype=float)
        n = min(len(times) for times, _ in ran)  # a run Ctrl-C cut short: the common part
        values = np.array([np.reshape(np.asarray(series[name][:n], dtype=float), (n, -1))
                           for _, series in ran])
        width = values.shape[2]
        for k in range(width):
            v = values[:, :, k]
            if np.ptp(v) == 0 and width > 1:
                continue
            q05, q25, q50, q75, q95 = np.nanquantile(v, (0.05, 0.25, 0.5, 0.75, 0.95), axis=0)
            shown = name.removeprefix("final.")
            label = shown if width == 1 else f"{shown}[{_AXES[k] if width == 3 else k}]"
            line, = ax.plot(t[:n], q50, label=label)
            ax.fill_between(t[:n], q05, q95, color=line.get_color(), alpha=0.15, lw=0)
            ax.fill_between(t[:n], q25, q75, color=line.get_color(), alpha=0.3, lw=0)
        ax.set_ylabel(name.removeprefix("final."), fontsize=8)
        ax.legend(loc="upper left", fontsize=7)
    axes[0, 0].set_title(f"{len(ran)} samples: median, 25-75 % and 5-95 % bands")
    axes[-1, 0].set_xlabel("time [s]")
    try:
        save_figure(fig, path, force=force, protect=protect)
    finally:
        plt.close(fig)
