"""Figures of a simulation (matplotlib, an optional extra: pip install massprops[plot])."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from massprops.errors import UsageError, setting_ref


def require_matplotlib() -> None:
    """Fail at once (UsageError) when --plot cannot be served, before any long computation."""
    _pyplot()


def _pyplot():
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only; never needs a display
        import matplotlib.pyplot as plt
    except ImportError as exc:
        raise UsageError(f"{setting_ref('plot')} needs matplotlib: pip install 'massprops[plot]'"
                         ) from exc
    return plt


PLOT_EXTENSIONS: tuple[str, ...] = (".png",)
"""The format of every figure (``--plot``)."""


def plot_output():
    """The output rule's `OutputKind` for a figure (`massprops.io.atomic`)."""
    from massprops.io.atomic import OutputKind  # deferred: only when a figure is saved

    return OutputKind("a plot", PLOT_EXTENSIONS, "plot")


def save_figure(fig, path: str | Path, *, force: bool = False, protect=()) -> None:
    """Render ``fig`` as PNG and write it atomically under the output rule (a .png name, never
    over an input or, without force, an existing file)."""
    # deferred: file writing is needed only when a figure is saved
    import io

    from massprops.io.atomic import atomic_write_bytes, check_output

    path = check_output(path, plot_output(), force=force, protect=protect)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120)
    atomic_write_bytes(path, buf.getvalue(), force=force, protect=protect)


def plot_simulation(result, path: str | Path, *, force: bool = False, protect=()) -> None:
    """Stacked panels against time: angular velocity in the body frame, relative energy drift
    (if the scene conserves or only loses energy), relative angular-momentum drift, and for a
    body held by joints the reaction each joint applies to it (world frame)."""
    plt = _pyplot()
    tr = result.trajectory
    joints = getattr(tr, "joints", ())
    rows = 3 + (1 if joints else 0) + (1 if any(j.torque_world is not None for j in joints)
                                       else 0)
    fig, axes = plt.subplots(rows, 1, figsize=(8, 2.8 * rows + 0.1), sharex=True,
                             constrained_layout=True)
    for k, label in enumerate("xyz"):
        axes[0].plot(tr.t, tr.angular_velocity_body[:, k], label=f"ω_{label}")
    axes[0].set_ylabel("angular velocity,\nbody frame [rad/s]")
    axes[0].legend(loc="upper right", ncol=3)
    axes[0].set_title(f"{result.integrator}: {result.steps} steps, {result.wall_time_s:.3g} s")
    _drift(axes[1], tr.t, None if tr.energy is None else tr.energy - tr.energy[0],
           abs(tr.energy[0]) if tr.energy is not None else 1.0, "energy drift\n|E - E₀| / |E₀|")
    h = tr.angular_momentum
    _drift(axes[2], tr.t, None if joints else np.linalg.norm(h - h[0], axis=1),
           np.linalg.norm(h[0]), "angular momentum drift\n|H - H₀| / |H₀| (world)",
           "not conserved about the centre of mass: the joints' reaction has a moment about "
           "it\n(the diagnostics give the momenta about the joint this scene conserves)")
    if joints:
        _reactions(axes[3:], tr.t, joints)
    axes[-1].set_xlabel("time [s]")
    try:
        save_figure(fig, path, force=force, protect=protect)
    finally:
        plt.close(fig)


def _reactions(axes, t, joints) -> None:
    """The joints' reaction forces (and hinge torques) on the body, world components."""
    styles = ("-", "--", ":", "-.")
    for k, joint in enumerate(joints):
        for c, label in enumerate("xyz"):
            axes[0].plot(t, joint.force_world[:, c], styles[k % 4], color=f"C{c}",
                         label=f"joint {k}: F_{label}")
            if joint.torque_world is not None:
                axes[1].plot(t, joint.torque_world[:, c], styles[k % 4], color=f"C{c}",
                             label=f"joint {k}: τ_{label}")
    axes[0].set_ylabel("joint reaction force\non the body, world [N]")
    axes[0].legend(loc="upper right", ncol=3, fontsize="small")
    if len(axes) > 1:
        axes[1].set_ylabel("hinge reaction torque\n(across its axis), world [N·m]")
        axes[1].legend(loc="upper right", ncol=3, fontsize="small")
    for ax in axes:
        ax.grid(True, alpha=0.3)


def _drift(ax, t, delta, scale, label,
           why: str = "not conserved in this scene (external work)") -> None:
    ax.set_ylabel(label)
    if delta is None:
        ax.text(0.5, 0.5, why, ha="center", va="center", transform=ax.transAxes)
        return
    rel = np.abs(delta) / (scale if scale > 0 else 1.0)
    floor = np.finfo(float).eps / 4  # plot exact zeros at a visible floor on the log axis
    ax.semilogy(t, np.maximum(rel, floor))
    ax.grid(True, which="both", alpha=0.3)


def plot_precision(report, path: str | Path, *, title: str = "", force: bool = False,
                   protect=()) -> None:
    """Work-precision diagram: error (contract metric) against wall time, log-log, one line per
    integrator, the reference's own accuracy as a floor."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(8, 5.5), constrained_layout=True)
    names = sorted({r.integrator for r in report.runs})
    markers = "osD^vP*Xh<>"
    floor = report.reference.get("accuracy") or 0.0
    for i, name in enumerate(names):
        rows = [r for r in report.runs if r.integrator == name and r.error is not None]
        if not rows:
            continue
        ax.loglog([r.wall_time_s for r in rows], [max(r.error, 1e-17) for r in rows],
                  marker=markers[i % len(markers)], label=name)
    if floor > 0:
        ax.axhline(floor, color="grey", linestyle=":", label="reference accuracy")
    ax.set_xlabel("wall time per run [s]")
    ax.set_ylabel("error (max of position/size, angle [rad], v/v_scale, ω/ω_scale)")
    ref = report.reference
    how = "exact solution" if ref["kind"] == "exact" else \
        f"reference: {ref['integrator']} {ref['setting']:.3g}"
    ax.set_title(f"{title}  ({how})" if title else how)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    try:
        save_figure(fig, path, force=force, protect=protect)
    finally:
        plt.close(fig)
