"""Campbell diagrams a reviewer can follow: where to sample a sweep, and which modes form one
line. Nothing here runs a solver — `sample` calls the function it is given.

Sampling (`sample`): the scene's grid, then bisection of the steps where the picture is
uncertain for any solver — a mode without a partner of MAC ≥ 0.9 at the next point, two lines
that swap order (a crossing or a veering to resolve), labels that change — widest steps first,
down to `min_step`, at most `extra` added points. A veering narrower than `min_step` cannot be
told from a crossing and is reported as one.

Tracking (`track_lines`): from one sample to the next a mode continues the line of the mode it
correlates with best (MAC, optimal assignment) when MAC ≥ 0.9. Modes left over whose shapes
only mix among themselves (one side's shapes lie in the span of the other's to MAC ≥ 0.9) continue
by frequency order: the lines do not cross there, and the step is marked (`veering` for two
modes, `degenerate` where their frequencies are equal to 1e-3 at either end — a repeated root
or its splitting — `mixing` for more). MAC differences under 0.01 are settled by the nearer
frequency. A mode that
correlates with nothing ends its line (it left the computed set, or the solver missed it at
the next point) and a new line begins. Solvers without shapes are tracked by unique labels,
else by nearest frequency (no MAC, no veering told).

Frames (`in_frame`, `Diagram.lines_of`): the lines are tracked in the frame the solvers
report (compare/scenes: `Campbell.frame`), where shapes and frequencies move smoothly; where the
modes whirl, each sample's modes are re-expressed in the other frame (signed whirl rates,
ν_fixed = ν_rot + Ω: compare.physics.whirl) and the same lines read there.

Events (`Diagram.events`): a `crossing` where two lines swap order over a step while both keep
their shapes (MAC ≥ 0.9); a `veering` where two lines adjacent in frequency come closest at a
sample and hand their shapes over around it (the lower line's shape before is the upper
line's after), or where the hand-over happens within one step (above).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import linear_sum_assignment

from ..physics.whirl import signed_in_frame, whirl_direction
from .trajectory import Modes

MAC_KEEP = 0.9            # a line continues on MAC ≥ this (the acceptance threshold)
MAC_OVERLAP = 0.1         # shapes that share less than this are unrelated
DEGENERATE = 1e-3         # relative frequency gap below which a pair is one repeated root
TIE = 0.01                # MAC differences below this are settled by frequency


def mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Modal assurance criterion between the rows of a and b (complex shapes allowed)."""
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    num = np.abs(np.conj(a) @ b.T) ** 2
    den = np.outer(np.sum(np.abs(a) ** 2, 1), np.sum(np.abs(b) ** 2, 1))
    return num / np.maximum(den, 1e-300)


def subspace_mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """For each row of a, the share of it that lies in the span of b's rows (1: inside)."""
    q, _ = np.linalg.qr(np.atleast_2d(b).T)
    a = np.atleast_2d(a)
    proj = np.conj(a) @ q
    return np.sum(np.abs(proj) ** 2, 1) / np.maximum(np.sum(np.abs(a) ** 2, 1), 1e-300)


def signed_hz(m: Modes, frame: str) -> np.ndarray | None:
    """The modes' signed whirl rates [Hz] in the solver's `frame`: the sense a leaf reports
    (extra["whirl_sense"], +1 with the spin), else in the fixed frame the direction its labels
    name (forward +, backward −); None where the modes do not whirl."""
    f = np.asarray(m.frequencies_hz, float)
    if "whirl_sense" in m.extra:
        return np.asarray(m.extra["whirl_sense"], float)[:len(f)] * f
    if frame == "fixed" and m.labels and all("forward" in lb or "backward" in lb
                                             for lb in m.labels):
        return np.array([1.0 if "forward" in lb else -1.0 for lb in m.labels]) * f
    return None


def in_frame(m: Modes, spin_hz: float, src: str, dst: str) -> Modes:
    """The solver's modes (reported in `src`) as seen in `dst`: frequency |ν| and sense of
    ν_dst, labels and shapes unchanged. Raises ValueError where the modes carry no whirl."""
    if src == dst or spin_hz == 0 or not _ok(m):        # at rest the frames coincide
        return m
    nu = signed_hz(m, src)
    if nu is None:
        raise ValueError(f"{m.solver}: modes without a whirl sense cannot be seen from the "
                         f"{dst} frame")
    nu = signed_in_frame(nu, spin_hz, src, dst)
    return replace(m, frequencies_hz=np.abs(nu),
                   extra={**m.extra, "whirl_sense": np.where(nu < 0, -1.0, 1.0)})


def whirl(m: Modes, frame: str, spin_hz: float) -> list:
    """ROSS's whirl direction per mode ("forward", "backward"; None without whirl or spin)."""
    nu = signed_hz(m, frame)
    if nu is None:
        return [None] * len(m.frequencies_hz)
    return whirl_direction(signed_in_frame(nu, spin_hz, frame, "fixed"), spin_hz)


def _ok(m: Modes) -> bool:
    return m.status == "ok" and len(m.frequencies_hz) > 0


def _unique(labels) -> bool:
    return all(labels) and len(set(labels)) == len(labels)


def _has_shapes(a: Modes, b: Modes) -> bool:
    return a.shapes is not None and b.shapes is not None and \
        np.shape(a.shapes)[1:] == np.shape(b.shapes)[1:]


def _pairs(a: Modes, b: Modes) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Mode i of a ↔ mode j of b: by MAC (optimal assignment) where both have shapes, else by
    unique labels, else by nearest frequency; the MAC of each pair (None without shapes)."""
    if _has_shapes(a, b):
        m = mac(a.shapes, b.shapes)
        # MAC decides; between modes of one shape (a spinning shaft's forward and backward
        # whirl of one order share [U, V] in the rotating frame) the nearer frequency does
        df = np.abs(a.frequencies_hz[:, None] - b.frequencies_hz[None, :])
        scale = max(np.max(np.abs(a.frequencies_hz)), np.max(np.abs(b.frequencies_hz)), 1e-300)
        rows, cols = linear_sum_assignment(-m + TIE * np.minimum(df / scale, 1.0))
        return rows, cols, m[rows, cols]
    if _unique(a.labels) and _unique(b.labels):
        common = [lb for lb in a.labels if lb in b.labels]
        return (np.array([a.labels.index(lb) for lb in common], int),
                np.array([b.labels.index(lb) for lb in common], int), None)
    cost = np.abs(a.frequencies_hz[:, None] - b.frequencies_hz[None, :])
    rows, cols = linear_sum_assignment(cost)
    return rows, cols, None


def _window(a: Modes, b: Modes) -> float:
    """Modes above the lower of the two highest computed frequencies may have left the set."""
    return min(a.frequencies_hz.max(), b.frequencies_hz.max())


def needs_refining(a: Modes, b: Modes) -> bool:
    """Is the step a → b uncertain: a mode (inside both computed windows) without a partner of
    MAC ≥ 0.9, two paired modes that swap frequency order (a crossing, or a veering narrower
    than the step; not a repeated root), or labels that change where a solver has no shapes?"""
    if not (_ok(a) and _ok(b)):
        return False
    rows, cols, m = _pairs(a, b)
    top = _window(a, b)
    inside = (a.frequencies_hz[rows] <= top) & (b.frequencies_hz[cols] <= top)
    if m is not None and np.any(m[inside] < MAC_KEEP):
        return True
    if m is None and _unique(a.labels) and _unique(b.labels) and a.labels != b.labels:
        return True
    kept = np.ones(len(rows), bool) if m is None else m >= MAC_KEEP
    fa, fb = a.frequencies_hz[rows][kept], b.frequencies_hz[cols][kept]
    da, db = fa[:, None] - fa[None, :], fb[:, None] - fb[None, :]
    scale = np.maximum(np.abs(fa)[:, None], np.abs(fa)[None, :])
    distinct = (np.abs(da) > DEGENERATE * scale) | (np.abs(db) > DEGENERATE * scale)
    return bool(np.any((da * db < 0) & distinct))


def sample(at, base: np.ndarray, extra: int, min_step: float) -> tuple[np.ndarray, list]:
    """The base grid plus at most `extra` points, each the midpoint of a step no narrower than
    2·min_step that is uncertain for any solver (widest first, round by round). `at(value)`
    returns one Modes per solver; every solver is sampled on the same points, so that their
    lines compare at the same values. Returns the values and, per value, at's tuple."""
    pts = {float(v): tuple(at(float(v))) for v in base}
    while extra > 0:
        xs = sorted(pts)
        steps = [(b - a, a, b) for a, b in zip(xs, xs[1:]) if b - a >= 2 * min_step
                 and any(needs_refining(ma, mb) for ma, mb in zip(pts[a], pts[b]))]
        if not steps:
            break
        for _, a, b in sorted(steps, reverse=True)[:extra]:
            pts[0.5 * (a + b)] = tuple(at(0.5 * (a + b)))
            extra -= 1
    xs = sorted(pts)
    return np.array(xs), [pts[x] for x in xs]


@dataclass
class Event:
    kind: str                 # crossing | veering | degenerate | mixing
    lines: tuple              # the line keys involved
    lo: float                 # the step (or stretch) of the sweep where it happens
    hi: float
    at: float                 # crossing: linear estimate; veering: the sample of least gap
    gap_hz: float             # least sampled frequency gap between the lines (0: crossing)

    def as_dict(self):
        return {"kind": self.kind, "lines": list(self.lines), "lo": self.lo, "hi": self.hi,
                "at": self.at, "gap_hz": self.gap_hz}


@dataclass
class Diagram:
    values: np.ndarray                          # every sampled value of the sweep
    lines: dict = field(default_factory=dict)   # key → Hz at each value (nan: not on the line)
    mac: dict = field(default_factory=dict)     # key → MAC of each step (nan: no shapes / gap)
    events: list = field(default_factory=list)
    index: dict = field(default_factory=dict)   # key → the mode's index at each value (−1: none)

    def lines_of(self, results: list[Modes]) -> dict:
        """The same lines read from `results` (the tracked samples re-expressed, e.g. in the
        other frame: `in_frame`)."""
        return {k: np.array([r.frequencies_hz[j] if j >= 0 else np.nan
                             for r, j in zip(results, idx)]) for k, idx in self.index.items()}

    def min_mac_unmarked(self) -> float:
        """The least MAC between consecutive samples of a line over steps no event marks."""
        marked = [(e.lines, e.lo, e.hi) for e in self.events if e.kind != "crossing"]
        worst = 1.0
        for key, m in self.mac.items():
            for i, v in enumerate(m):
                a, b = self.values[i], self.values[i + 1]
                if np.isfinite(v) and not any(key in ks and lo <= a and b <= hi
                                              for ks, lo, hi in marked):
                    worst = min(worst, float(v))
        return worst


def _groups(left, right, m):
    """Components of the bipartite graph 'shares MAC ≥ MAC_OVERLAP' over the left-over modes."""
    seen_l, seen_r, out = set(), set(), []
    for i0 in left:
        if i0 in seen_l:
            continue
        gl, gr, todo = {i0}, set(), [("l", i0)]
        while todo:
            side, i = todo.pop()
            for j in (right if side == "l" else left):
                w = m[i, j] if side == "l" else m[j, i]
                other = gr if side == "l" else gl
                if w >= MAC_OVERLAP and j not in other:
                    other.add(j)
                    todo.append(("r" if side == "l" else "l", j))
        seen_l |= gl
        seen_r |= gr
        out.append((sorted(gl), sorted(gr)))
    return out


def track_lines(values: np.ndarray, results: list[Modes]) -> Diagram:
    """Mode lines over the sampled sweep (see the module's docstring); failed samples end the
    lines that cross them."""
    n = len(values)
    open_: dict[int, int] = {}            # mode index at the current sample → line id
    freq, macs, index, last_label, events_raw = [], [], [], [], []

    def new_line():
        freq.append(np.full(n, np.nan))
        macs.append(np.full(max(n - 1, 0), np.nan))
        index.append(np.full(n, -1))
        last_label.append("")
        return len(freq) - 1

    for k, r in enumerate(results):
        if not _ok(r):
            open_ = {}
            continue
        nxt: dict[int, int] = {}
        prev = results[k - 1] if k else None
        if open_ and prev is not None and _ok(prev):
            rows, cols, m = _pairs(prev, r)
            full = mac(prev.shapes, r.shapes) if m is not None else None
            left = []
            for i, j, w in zip(rows, cols, m if m is not None else [None] * len(rows)):
                if i not in open_:
                    continue
                if w is None or w >= MAC_KEEP:
                    nxt[j] = open_[i]
                    if w is not None:
                        macs[open_[i]][k - 1] = w
                else:
                    left.append(i)
            if full is not None and left:
                right = [j for j in range(len(r.frequencies_hz)) if j not in nxt]
                for gl, gr in _groups(left, right, full):
                    # one side inside the other's span: a solver may return one shape twice
                    # for a repeated root (the spinning shaft's pairs at rest)
                    kept = len(gl) == len(gr) > 1 and (
                        np.all(subspace_mac(prev.shapes[gl], r.shapes[gr]) >= MAC_KEEP)
                        or np.all(subspace_mac(r.shapes[gr], prev.shapes[gl]) >= MAC_KEEP))
                    if not kept:
                        continue
                    gl = sorted(gl, key=lambda i: prev.frequencies_hz[i])
                    gr = sorted(gr, key=lambda j: r.frequencies_hz[j])
                    for i, j in zip(gl, gr):
                        nxt[j] = open_[i]
                        macs[open_[i]][k - 1] = full[i, j]
                    fl, fr = prev.frequencies_hz[gl], r.frequencies_hz[gr]
                    gap = float(np.min(np.diff(np.sort(fr))))
                    same = min(np.ptp(fl), np.ptp(fr)) <= DEGENERATE * np.max(np.abs(fl))
                    kind = "degenerate" if same else "veering" if len(gl) == 2 else "mixing"
                    events_raw.append((kind, [open_[i] for i in gl], k - 1, k, gap))
        for j in range(len(r.frequencies_hz)):
            line = nxt[j] if j in nxt else new_line()
            freq[line][k] = r.frequencies_hz[j]
            index[line][k] = j
            last_label[line] = r.labels[j] if j < len(r.labels) else ""
            nxt[j] = line
        open_ = nxt

    keys = []
    for i, lb in enumerate(last_label):
        key = lb or f"mode {i + 1}"
        keys.append(key if key not in keys else f"{key} #{keys.count(key) + 1}")
    d = Diagram(values=np.asarray(values, float), lines=dict(zip(keys, freq)),
                mac=dict(zip(keys, macs)), index=dict(zip(keys, index)))
    for kind, ids, k0, k1, gap in events_raw:
        d.events.append(Event(kind, tuple(keys[i] for i in ids), float(values[k0]),
                              float(values[k1]), float(values[k1]), gap))
    d.events = _merged(d.events + _veerings(d, results)) + _crossings(d)
    d.events.sort(key=lambda e: (e.lo, e.kind))
    return d


def _merged(events: list[Event]) -> list[Event]:
    """One event per hand-over: those of the same lines whose stretches touch become one (the
    least gap, the stretch joined, the most specific kind)."""
    out: list[Event] = []
    rank = {"veering": 0, "degenerate": 1, "mixing": 2}
    for e in sorted(events, key=lambda e: (sorted(e.lines), e.lo)):
        last = out[-1] if out else None
        if last and set(last.lines) == set(e.lines) and e.lo <= last.hi:
            best = last if last.gap_hz <= e.gap_hz else e
            out[-1] = Event(min(last.kind, e.kind, key=rank.get), best.lines, last.lo,
                            max(last.hi, e.hi), best.at, best.gap_hz)
        else:
            out.append(e)
    return out


def _crossings(d: Diagram) -> list[Event]:
    """Two lines that swap order over a step while both keep their shapes."""
    out, keys, v = [], list(d.lines), d.values
    for a in range(len(keys)):
        for b in range(a + 1, len(keys)):
            fa, fb = d.lines[keys[a]], d.lines[keys[b]]
            g = fa - fb
            for k in np.nonzero(np.isfinite(g[:-1]) & np.isfinite(g[1:])
                                & (g[:-1] * g[1:] < 0))[0]:
                ma, mb = d.mac[keys[a]][k], d.mac[keys[b]][k]
                if not (ma >= MAC_KEEP or np.isnan(ma)) or not (mb >= MAC_KEEP or np.isnan(mb)):
                    continue
                x = v[k] - g[k] * (v[k + 1] - v[k]) / (g[k + 1] - g[k])
                out.append(Event("crossing", (keys[a], keys[b]), float(v[k]), float(v[k + 1]),
                                 float(x), 0.0))
    return out


def _veerings(d: Diagram, results: list[Modes]) -> list[Event]:
    """Two lines whose gap has a local minimum at a sample, with the shapes handed over around
    it: over the stretch where the gap grows monotonically to below 4× its least value (one
    sample more each side, where it must be ≥ 1.5× that value), the lower line's first shape
    correlates with the upper line's last (MAC ≥ 0.5) and not with its own (< 0.5)."""
    out, keys, v = [], list(d.lines), d.values
    where = {}                        # (line key, sample) → mode index, to read shapes back
    for k, r in enumerate(results):
        if not _ok(r) or r.shapes is None:
            continue
        for key in keys:
            f = d.lines[key][k]
            if np.isfinite(f):
                where[key, k] = int(np.argmin(np.abs(r.frequencies_hz - f)))
    for a in range(len(keys)):
        for b in range(a + 1, len(keys)):
            fa, fb = d.lines[keys[a]], d.lines[keys[b]]
            g = np.abs(fa - fb)
            for k in range(1, len(v) - 1):
                sign = np.sign(fa[k - 1:k + 2] - fb[k - 1:k + 2])
                if not (np.isfinite(g[k - 1:k + 2]).all() and g[k] < g[k - 1]
                        and g[k] <= g[k + 1] and abs(sign.sum()) == 3):   # no crossing
                    continue
                lo, hi = k, k
                while lo > 0 and np.isfinite(g[lo - 1]) and g[lo - 1] < 4 * g[k] \
                        and g[lo - 1] > g[lo]:
                    lo -= 1
                while hi < len(v) - 1 and np.isfinite(g[hi + 1]) and g[hi + 1] < 4 * g[k] \
                        and g[hi + 1] > g[hi]:
                    hi += 1
                lo, hi = max(lo - 1, 0), min(hi + 1, len(v) - 1)
                if min(g[lo], g[hi]) < 1.5 * g[k]:       # no clear approach (parallel lines)
                    continue
                low, up = (keys[a], keys[b]) if fa[k] < fb[k] else (keys[b], keys[a])
                try:
                    s0 = results[lo].shapes[where[low, lo]]
                    s_own = results[hi].shapes[where[low, hi]]
                    s_other = results[hi].shapes[where[up, hi]]
                except KeyError:
                    continue
                if mac(s0, s_other)[0, 0] >= 0.5 > mac(s0, s_own)[0, 0]:
                    out.append(Event("veering", (low, up), float(v[lo]), float(v[hi]),
                                     float(v[k]), float(g[k])))
    return out


def growing_onsets(values, zeta_lines: dict, floor: float = 0.0,
                   error_lines: dict | None = None) -> list[dict]:
    """Where each line's root starts to grow: its ζ (tracked like the frequencies) goes below
    −(`floor` + its error estimate on `error_lines`, tracked alike): the scene's ζ allowance
    and the solver's own error bar, round-off is not growth. Per line whose root grows
    somewhere: the speed where ζ crosses zero (linear between the samples that bracket it;
    the sweep's start where it grows from there), the bracket, and the least ζ on the sweep."""
    v = np.asarray(values, float)
    out = []
    for key, z in zeta_lines.items():
        z = np.asarray(z, float)
        e = np.nan_to_num(np.asarray((error_lines or {}).get(key, 0.0), float))
        grows = np.isfinite(z) & (z < -(floor + e))
        if not grows.any():
            continue
        i = int(np.argmax(grows))
        if i == 0 or not np.isfinite(z[i - 1]):
            at, lo = float(v[i]), float(v[i])
        else:
            lo = float(v[i - 1])
            at = lo + (v[i] - lo) * z[i - 1] / (z[i - 1] - z[i]) if z[i - 1] > 0 else lo
        out.append({"line": key, "from": float(at), "lo": lo, "hi": float(v[i]),
                    "least_zeta": float(np.nanmin(z))})
    return out
