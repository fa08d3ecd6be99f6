"""`regimes`, the map's batch path: many rotors as branches of one kinematic tree.

A tree of n rotors is n independent systems in one: its mass matrix is block diagonal, and the
dense LU of a block-diagonal matrix does, block by block, the arithmetic of each block alone
(the off-block entries are exact zeros), so each rotor's numbers are those of its `simulate`
run, bit for bit (tests); the loads of the whole tree are one compiled call per stage.
"""
import numpy as np

from compare.contract import LeafResult
from compare.physics import rotor as physics

from .chart import CHART_SWITCH, chart_motion, start
from .model import build, rotor, sim_settings, solve, stored
from .settings import SOLVERS, check_settings
from .time import fixed_step, grid_samples

TREE_SIZE = 8          # rotors per tree in `regimes` (measured in its note)
_TOGETHER = ("rk4", "rk67", "explicit_euler")   # fixed-step explicit: no system-wide decision


def _together(params_list, t_out, s):
    """Fixed-step runs of rotors with one gravity, all in one tree from 0 to t_end, as each
    would run alone in `simulate` (same step, same start, same arithmetic per rotor): rows
    (R, ω, work) on t_out per rotor. A rotor whose run would stop (a chart change, tilt π, a
    non-finite state: `simulate` goes on or ends there on its own) stops the whole tree; it
    is left out (None: `simulate` runs it alone) and, where it stopped the tree (any stop
    but a change of chart, which is read off the stored steps), the others run again from
    t = 0."""
    n_out = len(t_out)
    dto = float(t_out[1] - t_out[0])
    h = fixed_step(dto, float(s["dt"]))
    n_steps = max(1, int(round(t_out[-1] / h)))
    starts = [start(p) for p in params_list]
    out, todo = [None] * len(params_list), list(range(len(params_list)))
    while todo:
        model = build([rotor(params_list[i], q0=starts[i][2][0], qd0=starts[i][2][1],
                             torque=float(params_list[i]["torque"])) for i in todo],
                      chart_stop=False)
        ex = solve(model["mbs"], sim_settings(0.0, t_out[-1], n_steps, 0.0, s["integrator"],
                                              s["rtol"], s["spectral_radius"]),
                   SOLVERS[s["integrator"]])
        if ex is not None or model["flag"]["kind"] is not None:
            stopped = model["flag"]["rotor"]          # None: Exudyn's own error, unassigned
            todo = [i for j, i in enumerate(todo) if stopped is not None and j != stopped]
            continue
        tt, q, qd, w = stored(model)
        keep = tt > 0.0
        tt, q, qd, w = tt[keep], q[keep], qd[keep], w[keep]
        idx, on_grid = grid_samples(tt, t_out, 0)
        if not np.array_equal(idx[on_grid], np.arange(1, n_out)):
            break                                     # fell short: every rotor runs alone
        bad = ~(np.isfinite(q).all(axis=(0, 2)) & np.isfinite(qd).all(axis=(0, 2))
                & np.isfinite(w).all(axis=0))
        if bad.any():           # a last step gone non-finite (after the checks of its stages)
            todo = [i for j, i in enumerate(todo) if not bad[j]]
            continue
        # a step `simulate` would have ended for a change of chart: that rotor runs alone (the
        # others' runs stand: they never read it)
        charted = np.any(np.abs(np.cos(q[:, :, 1])) < CHART_SWITCH, axis=0)
        for j, i in enumerate(todo):
            if charted[j]:
                continue
            R, om = chart_motion(np.eye(3), q[on_grid, j], qd[on_grid, j])
            out[i] = (np.concatenate([starts[i][0][None], R]),
                      np.concatenate([starts[i][1][None], om]),
                      np.concatenate([[0.0], w[on_grid, j]]))
        break
    return out


def regimes(params_list, t_out, settings, channel, levels, window):
    """The map's batch path: the points run `TREE_SIZE` at a time in one kinematic tree
    (`_together`: each rotor's numbers are its `simulate` run's, bit for bit), reduced to the
    regime on |ω| by `physics.regime_summaries`; a rotor left out has code 1 (the caller runs
    it alone). None where runs cannot share a tree: another channel, an error-controlled or
    implicit integrator (their step or Newton decisions are system-wide), a step longer than
    the output step (`simulate` interpolates those). Measured (10 s spin-up, RK67 at 2 ms,
    2 busy cores, CPU time a rotor): 1, 4, 8, 16, 32 per tree 286, 132, 111, 113, 150 ms (the
    dense LU of the tree's mass matrix grows as n³) — against 61–79 ms for the tree's own C++
    without any Python call; the Python loads before 570–620 ms."""
    t_out = np.asarray(t_out, dtype=float)
    s = check_settings(settings, t_out)
    if channel != "omega_norm" or s["integrator"] not in _TOGETHER or len(t_out) < 2 or \
            float(s["dt"]) > (t_out[1] - t_out[0]) * (1 + 1e-9):
        return None
    by_gravity = {}
    for i, p in enumerate(params_list):
        by_gravity.setdefault(tuple(np.asarray(p["gravity"], float).tolist()), []).append(i)
    runs = [None] * len(params_list)
    for members in by_gravity.values():
        for c in range(0, len(members), TREE_SIZE):
            idx = members[c:c + TREE_SIZE]
            for i, rows in zip(idx, _together([params_list[i] for i in idx], t_out, s)):
                runs[i] = (LeafResult(channels={}, status="diverged", t_fail=float("nan"))
                           if rows is None else
                           LeafResult(channels=physics.channels(params_list[i], *rows)))
    levels = np.asarray(levels, float)
    return physics.regime_summaries(t_out, runs, levels[:, 0], levels[:, 1], window)
