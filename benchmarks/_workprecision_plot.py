"""Work-precision figure of one scene: error against wall time, massprops solid, scipy dashed.

The same algorithm shares a colour across the two families (massprops dop853 and scipy DOP853;
massprops implicit, a Radau IIA, and scipy Radau), so the pairs can be read side by side.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402

COLOURS = {
    "dop853": "tab:blue", "DOP853": "tab:blue",
    "implicit": "tab:orange", "Radau": "tab:orange",
    "rk4": "tab:green", "RK45": "tab:red", "LSODA": "tab:brown",
    "midpoint": "tab:purple", "splitting": "tab:pink", "splitting4": "tab:olive",
    "splitting6": "tab:cyan", "exact": "black",
}


def plot_scene(curves, reference: dict, title: str, path: Path, budgets_s, target: float
               ) -> None:
    """Write ``path`` (PNG): one line per curve (label, family, method, points (wall s, error)
    in ladder order, note), through its rungs from loose to tight."""
    fig, ax = plt.subplots(figsize=(10.5, 6.2), layout="constrained")
    for c in curves:
        if not c.points:  # a ladder with no run at all still shows up, saying so
            why = c.note.split(":")[0] or "no runs"
            ax.plot([], [], " ", label=f"{c.label}: {why} (see table)")
            continue
        x, y = [p[0] for p in c.points], [p[1] for p in c.points]  # ladder order
        colour = COLOURS.get(c.method, "grey")
        if c.method == "exact":
            ax.plot(x, y, "*", ms=16, color=colour, label=c.label, zorder=5)
        elif c.family == "massprops":
            ax.plot(x, y, "-o", ms=5, lw=2, color=colour, label=c.label)
        else:
            ax.plot(x, y, "--s", ms=5, lw=1.6, color=colour, mfc="white", label=c.label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    floor = reference["accuracy"]
    ax.axhline(floor, color="grey", ls=":", lw=1.2)
    ax.annotate(f"reference accuracy {floor:.0e}", (0.01, floor), xycoords=("axes fraction",
                "data"), va="bottom", fontsize=8, color="grey")
    ax.axhline(target, color="lightgrey", lw=1, zorder=0)
    ax.annotate(f"target {target:.0e}", (0.99, target), xycoords=("axes fraction", "data"),
                ha="right", va="bottom", fontsize=8, color="grey")
    for b in budgets_s:
        ax.axvline(b, color="lightgrey", lw=1, zorder=0)
        ax.annotate(f"{b * 1e3:g} ms", (b, 0.99), xycoords=("data", "axes fraction"),
                    ha="left", va="top", fontsize=8, color="grey", rotation=90)
    ax.grid(True, which="major", alpha=0.3)
    ax.set_xlabel("wall time per run [s] (best of repeats; compile time excluded)")
    ax.set_ylabel("error (max of |Δr|/size, angle [rad], |Δv|/v-scale, |Δω|/ω-scale)")
    ax.set_title(title, fontsize=10)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9,
              title="solid: massprops\ndashed: scipy solve_ivp", title_fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)
