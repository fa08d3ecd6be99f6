"""`fem` leaf for `helicopter-clamped` / `helicopter-hover`: the helicopter of seed 002 by
finite elements, independent of the transfer matrices (shared: helicopter_layout and the
physics of each element, see custom_models/mstmm/helicopter.py).

Beams (4 blades, drive shaft, tail boom) are 3-D Hermite members: per node the 6 shared dofs
(u, v, w, θx, θy, θz in the member frame, θz = v', θy = −w') plus 2 member-own dofs (u', θx')
so that extension and torsion are Hermite cubic too. Blades: centrifugal geometric stiffness
∫T(v'² + w'²), lag and extension softening −Ω²m̄, torsion +Ω²I_α (and ∫T k_A² φ'² with the
tension–torsion term). Shaft: spin softening and
the gyroscopic matrix G (v, w blocks ∓2Ω M_b). Hub and fuselage: rigid bodies (lumped mass and
inertia at the centre of mass); blade roots, shaft ends and tail root are tied to them by rigid
links. Eigenproblem M q̈ + G q̇ + K q = 0 (complex, sparse shift-invert, each root then refined to
the matrices' own accuracy: eigen.refine_gyroscopic); convergence: blades meshed
with n and 2n elements, the frequencies extrapolated (h⁴) and the change reported.
"""
import numpy as np
from scipy import sparse

from compare.contract import LeafModes, merge_settings
from compare.physics.eigen import refine_gyroscopic
from compare.physics.mstmm import (
    AXIAL,
    AXIAL_RIGID,
    axial_shift,
    helicopter_layout,
    root_tension_wavenumber,
)
from compare.physics.rotation import skew

from .beam import bending

MODES_SETTINGS = {"blade_elements": 12, "shaft_elements": 2, "tail_elements": 6,
                  "richardson": True}
BLADE_STATIONS = 7
RIGID_BODY_HZ = 0.01
OSCILLATORY_RE = 1e-4
UNREFINED_RE = 1e-2


def blade_frame(k):
    c, s = np.cos(k * np.pi / 2), np.sin(k * np.pi / 2)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


SHAFT_FRAME = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


class Model:
    """Independent dofs: masters (hub, fuselage: 6 each), free beam nodes (6), member-own
    dofs (2 per beam node). E maps them to every member's field dofs."""

    def __init__(self):
        self.n = 0
        self.blocks = []            # (field K, G, M, E rows)

    def new(self, k):
        idx = np.arange(self.n, self.n + k)
        self.n += k
        return idx


def member_fields(nodes, EA, m, EI_v, EI_w, GJ, I_alpha, tension=None, k_A2=0.0):
    """Field matrices (8 dofs per node: u, u', v, v', w, w', φ, φ') K, M and the bending mass
    M_b (per plane), in member coordinates; torsion stiffness GJ + T(x)·k_A² (the
    tension–torsion term, k_A2 = 0 when off)."""
    _, Ku, Mu = bending(nodes, 0.0, m, lambda x: EA)        # ∫EA u'², the "tension" form
    Kv, KTv, Mv = bending(nodes, EI_v, m, tension)
    Kw, KTw, Mw = bending(nodes, EI_w, m, tension)
    _, Kt, Mt = bending(nodes, 0.0, I_alpha,
                        lambda x: GJ + (k_A2 * tension(x) if k_A2 else 0.0))
    return {"u": (Ku, Mu), "v": (Kv + KTv, Mv), "w": (Kw + KTw, Mw), "t": (Kt, Mt)}


def build(L, spin, n_blade, n_shaft, n_tail, clamped):
    """Global K, G, M over the independent dofs, and samplers for the shape vector."""
    mdl = Model()
    hub = mdl.new(6)
    fus = mdl.new(6)
    # rigid link: shared dofs of a node at offset r from a master = Tl @ master
    def link(r):
        T = np.eye(6)
        T[0:3, 3:6] = -skew(r)
        return T

    members = []

    def add_member(R, nodes, fields, ends, extra=None):
        """ends: for first/last node either ('link', master_idx, r) or None (free) or
        'fixed'. Returns per node (shared map 6 x n, own idx)."""
        nn = len(nodes)
        shared = []
        for i in range(nn):
            spec = ends.get(i)
            if spec is None:
                idx = mdl.new(6)
                S = ("free", idx)
            elif spec == "fixed":
                S = ("fixed", None)
            else:
                S = ("link", spec[0], link(spec[1]))
            shared.append(S)
        own = [mdl.new(2) for _ in range(nn)]
        members.append((R, nodes, fields, shared, own, extra))
        return shared, own

    b = L["blade"]
    Lb = b["L"]
    blade_nodes = np.linspace(0.0, Lb, n_blade + 1)
    T = lambda x: b["m"] * spin**2 * (np.linalg.norm(L["roots"][0]) * (Lb - x)
                                        + 0.5 * (Lb**2 - x**2))
    blade_members = []
    for k in range(4):
        f = member_fields(blade_nodes, b["EA"], b["m"], b["EI_lag"], b["EI_flap"], b["GJ"],
                          b["I_alpha"], T, b["k_A2"])
        f["u"] = (f["u"][0] - spin**2 * f["u"][1], f["u"][1])
        f["v"] = (f["v"][0] - spin**2 * f["v"][1], f["v"][1])
        f["t"] = (f["t"][0] + spin**2 * f["t"][1], f["t"][1])
        blade_members.append(add_member(blade_frame(k), blade_nodes, f,
                                        {0: (hub, L["roots"][k])}))
    s = L["shaft"]
    shaft_nodes = np.linspace(0.0, s["L"], n_shaft + 1)      # x_l = z, from the bottom
    f = member_fields(shaft_nodes, s["EA"], s["m"], s["EI"], s["EI"], s["GJ"], s["I_p"])
    Mb = f["v"][1]
    f["v"] = (f["v"][0] - spin**2 * Mb, Mb)
    f["w"] = (f["w"][0] - spin**2 * Mb, Mb)
    fu = L["fuselage"]
    add_member(SHAFT_FRAME, shaft_nodes, f,
               {0: (fus, s["bottom"] - fu["cm"]), n_shaft: (hub, s["top"])},
               extra={"gyro": 2 * spin * Mb})
    t = L["tail"]
    tail_nodes = np.linspace(0.0, t["L"], n_tail + 1)        # x_l = +x, from the tail end
    f = member_fields(tail_nodes, t["EA"], t["m"], t["EI_lag"], t["EI_flap"], t["GJ"],
                      t["I_alpha"])
    add_member(np.eye(3), tail_nodes, f,
               {0: "fixed" if clamped else None, n_tail: (fus, t["root"] - fu["cm"])})

    n = mdl.n
    # rigid bodies
    h = L["hub"]
    diag = np.zeros(n)
    diag[hub] = np.concatenate([[h["m"]] * 3, h["I"]])
    diag[fus] = np.concatenate([[fu["m"]] * 3, fu["I"]])
    K = G = sparse.csr_matrix((n, n))
    M = sparse.diags(diag, format="csr")
    samplers = []
    for R, nodes, fields, shared, own, extra in members:
        E = field_map(R, shared, own, n)
        for name, off in (("u", 0), ("v", 2), ("w", 4), ("t", 6)):
            Kf, Mf = fields[name]
            Ef = E[[8 * i + off + j for i in range(len(nodes)) for j in range(2)]]
            K = K + _congruent(Ef, Kf)
            M = M + _congruent(Ef, Mf)
        if extra and "gyro" in extra:
            Ev = E[[8 * i + 2 + j for i in range(len(nodes)) for j in range(2)]]
            Ew = E[[8 * i + 4 + j for i in range(len(nodes)) for j in range(2)]]
            Gb = extra["gyro"]
            G = G + (_congruent(Ev, -Gb, Ew) + _congruent(Ew, Gb, Ev))
        samplers.append((nodes, E))
    # drop dofs nobody uses (the clamped tail-end node has none)
    used = np.where(np.asarray(abs(M).sum(axis=0) + abs(K).sum(axis=0)).ravel() > 0)[0]
    K, G, M = (_canonical(X[used][:, used]) for X in (K, G, M))
    return K, G, M, samplers[:4], hub, fus, used, n


# The field map and the products below are sparse: a member's field dofs touch a handful of
# the aircraft's, and the dense products cost O(n²) per member (28 s of a 33 s run on 84- and
# 168-element blades, profiled; the run takes 3.4 s sparse). Each entry's terms are summed in
# the order the dense products add them (ascending inner index, zeros skipped), so K, G and M
# are those of the dense assembly bit for bit (checked at eight parameter sets, refined meshes
# included).
_FIELD_ROWS = ((0, 0, 1.0), (2, 1, 1.0), (3, 5, 1.0), (4, 2, 1.0), (5, 4, -1.0), (6, 3, 1.0))


def field_map(R, shared, own, n):
    """E: a member's field dofs (8 per node: u, u', v, v', w, w', φ, φ'; v' = θz, w' = −θy)
    from the aircraft's independent dofs, through the node's own 6 dofs, its master's rigid
    link, or nothing (fixed), turned into member axes by R."""
    Rb = np.zeros((6, 6))
    Rb[0:3, 0:3] = R.T
    Rb[3:6, 3:6] = R.T
    rows, cols, vals = [], [], []
    for i, (kind, *spec) in enumerate(shared):
        r = 8 * i
        if kind != "fixed":
            Sl = Rb @ (np.eye(6) if kind == "free" else spec[1])   # local u, v, w, θx, θy, θz
            for row, src, sign in _FIELD_ROWS:
                rows += [r + row] * 6
                cols += list(spec[0])
                vals += list(sign * Sl[src])
        rows += [r + 1, r + 7]
        cols += [own[i][0], own[i][1]]
        vals += [1.0, 1.0]
    return _canonical(sparse.csr_matrix((vals, (rows, cols)), shape=(8 * len(shared), n)))


def _canonical(X):
    X = X.tocsr()
    X.eliminate_zeros()
    X.sort_indices()
    return X


def _congruent(A, F, B=None):
    """Aᵀ F B (B = A by default) for sparse field maps A, B and a dense member matrix F."""
    return _canonical(_canonical(A.T @ _canonical(sparse.csr_matrix(F))) @ (A if B is None else B))


def solve(L, spin, mesh, clamped, count):
    """The `count` eigenvalues of M λ² + G λ + K = 0 nearest to a small shift (the lowest
    modes), by sparse shift-invert on the first-order form B z' = A z,
    A = [[0, I], [−K, −G]], B = [[I, 0], [0, M]]."""
    from scipy.sparse.linalg import eigs
    K, G, M, samplers, hub, fus, used, n = build(L, spin, *mesh, clamped)
    K, G, M = (X.tocsc() for X in (K, G, M))      # once: the refinement uses them
    N = K.shape[0]
    I = sparse.identity(N, format="csc")
    A = sparse.bmat([[None, I], [-K, -G]], format="csc")
    B = sparse.bmat([[I, None], [None, M]], format="csc")
    # shift off the axis: the hovering aircraft has (defective) rigid-body modes at λ = 0. A
    # fixed start vector: ARPACK's random one picked a different basis of a near-degenerate pair
    # on each run (the hovering fuselage pair's labels, and so its critical speeds, moved by
    # 4e-5 between identical runs)
    v0 = np.linspace(1.0, 2.0, 2 * N)
    lam, V = eigs(A, k=min(count, 2 * N - 2), M=B, sigma=-1.0, which="LM", tol=1e-14, v0=v0)
    return lam, V[:N], (K, G, M), samplers, hub, fus, used, n


def shape_vector(x, samplers, hub, fus, used, n, chord):
    """Blades (7 stations × [axial, lag, flap, twist·chord/2]) + hub and fuselage motion."""
    full = np.zeros(n, dtype=complex)
    full[used] = x
    parts = []
    for nodes, E in samplers:
        fld = E @ full
        step = (len(nodes) - 1) // (BLADE_STATIONS - 1)
        for i in range(0, len(nodes), step):
            r = 8 * i
            parts.append([fld[r], fld[r + 2], fld[r + 4], fld[r + 6] * chord / 2])
    v = np.concatenate([np.ravel(parts), full[hub], full[fus]])
    k = np.argmax(np.abs(v))
    v = v / v[k]
    return v.real


def frequencies(L, spin, mesh, clamped, n_modes):
    lam, V, KGM, samplers, hub, fus, used, n = solve(L, spin, mesh, clamped, 2 * n_modes + 40)
    scale = np.abs(lam).max()
    # oscillatory: Re λ is the shift-invert's round-off, up to 3.2e-6 |λ| next to the free
    # aircraft's near-defective rigid-body cluster (helicopter-hover's second calibration set at
    # rest, ×2 mesh); at 1e-6 that mode was dropped and Richardson paired the next one with it.
    # ARPACK's Re λ can be far larger before refinement (helicopter-clamped, `xval calibrate
    # --seed 777` set 4 at 57 rad/s, ×2 mesh: lag modes at 1e-4–4e-3 |λ|, dropped, so the
    # meshes' modes were paired out of order, torsion 2 % off), so every candidate up to
    # UNREFINED_RE is refined first (a conservative gyroscopic root refines onto the imaginary
    # axis) and judged after, ascending, until n_modes are kept; below 0.01 Hz the free
    # aircraft's rigid-body modes (mstmm's search starts at 0.05 Hz)
    cand = sorted((i for i in range(len(lam)) if lam[i].imag > max(1e-6 * scale ** 0.5,
                                                                  RIGID_BODY_HZ * 2 * np.pi)
                   and abs(lam[i].real) < UNREFINED_RE * abs(lam[i])), key=lambda i: lam[i].imag)
    osc, bound = [], []
    for i in cand:
        if len(osc) == n_modes:
            break
        raw = lam[i]
        lam[i], V[:, i], b = refine_gyroscopic(*KGM, lam[i], V[:, i])
        # a candidate that moved onto a root already kept is that root again (a degenerate
        # pair's two start together: both stay)
        if abs(lam[i].real) >= OSCILLATORY_RE * abs(lam[i]) or any(
                abs(lam[i] - lam[j]) < 1e-9 * abs(lam[j]) and abs(raw - lam[j]) > 1e-6 * abs(lam[j])
                for j in osc):
            continue
        osc.append(i)
        bound.append(b)
    unstable = [float(lam[i].real) for i in range(len(lam))
                if lam[i].real > 1e-6 * max(1.0, abs(lam[i])) and abs(lam[i]) > 1e-2]
    osc.sort(key=lambda i: lam[i].imag)
    shapes = [shape_vector(V[:, i], samplers, hub, fus, used, n, L["blade"]["chord"])
              for i in osc]
    return np.array([lam[i].imag for i in osc]), shapes, unstable, np.array(bound)


# The blade's elements span ≤ TENSION_SPAN of its tension length √(EI_flap/T_root) at the
# default mesh: the h⁴ Richardson estimate holds only there. helicopter-clamped, the
# extrapolate's true error (against mstmm) over its estimate, worst mode, against
# h·√(T/EI) of the coarse mesh: 0.22 at 1.55 (the defaults), 0.28 at 1.80, 0.54 at 2.40, 1.41
# at 3.61 (the first calibration set at 12 elements: a miss).
TENSION_SPAN = 2.0


def blade_refinement(L, spin, hub_radius):
    """The factor on every blade mesh: ⌈√(T_root/EI_flap)·L / (TENSION_SPAN · default
    elements)⌉, T_root = m̄Ω²(r_H L + L²/2) (1 at the defaults: 18.7 / 24)."""
    b = L["blade"]
    span = root_tension_wavenumber(b["m"], b["EI_flap"], b["L"], spin, hub_radius) * b["L"]
    return max(1, int(np.ceil(span / (TENSION_SPAN * MODES_SETTINGS["blade_elements"]))))


def check_settings(settings: dict | None, t_out=None) -> dict:
    """The settings over MODES_SETTINGS; ValueError (one line) for a mesh the mode-shape
    stations cannot sit on (a bench's mesh ladder stops there)."""
    s = merge_settings(settings, MODES_SETTINGS, ())
    mesh = (s["blade_elements"], s["shaft_elements"], s["tail_elements"])
    if not all(isinstance(m, int) and m >= 1 for m in mesh) or mesh[0] % (BLADE_STATIONS - 1):
        raise ValueError(f"blade_elements must be a positive multiple of {BLADE_STATIONS - 1} "
                         f"(the mode-shape stations sit on nodes), shaft_elements and "
                         f"tail_elements positive integers; got {mesh}")
    return s


def modes_for(params, settings, clamped):
    s = check_settings(settings)
    L = helicopter_layout(params)
    spin, n_modes = params["speed"], params["n_modes"]
    mesh = (s["blade_elements"], s["shaft_elements"], s["tail_elements"])
    refine = blade_refinement(L, spin, params["hub_radius"])
    mesh = (mesh[0] * refine, *mesh[1:])
    w, shapes, unstable, rounding = frequencies(L, spin, mesh, clamped, n_modes)
    first = w
    notes, extra = [], {"unstable": unstable}
    if refine > 1:
        notes.append(f"blade mesh ×{refine} (elements within {TENSION_SPAN:g} tension lengths)")
    if s["richardson"]:
        w2, shapes, unstable, rounding2 = frequencies(L, spin, tuple(2 * m for m in mesh),
                                                      clamped, n_modes)
        k = min(len(w), len(w2))
        ext = w2[:k] + (w2[:k] - w[:k]) / 15.0
        notes.append(f"meshes {mesh} and twice; Richardson change "
                     f"{np.max(np.abs(ext - w2[:k]) / ext):.1e}")
        w, shapes = ext, shapes[:k]
        # the mesh change, and the extrapolate's share of each mesh's eigen rounding
        extra["frequency_error_hz"] = (np.abs(ext - w2[:k]) + 16 / 15 * rounding2[:k]
                                       + rounding[:k] / 15) / (2 * np.pi)
    if unstable:
        notes.append(f"divergent (real) eigenvalues {np.round(unstable, 4).tolist()} 1/s")
    extra["unstable"] = unstable
    if spin == 0:          # what the engines' axially rigid chains lack, where they are compared
        rigid = frequencies(helicopter_layout(params, AXIAL_RIGID), spin, mesh, clamped,
                            n_modes)[0]                     # like for like, on the first mesh
        extra["model_differences"] = {AXIAL: axial_shift(first[:len(w)], rigid)}
    from custom_models.mstmm.labels import label_modes
    labels = label_modes(np.array(shapes), w, L, spin)
    return LeafModes(frequencies_hz=w / (2 * np.pi), labels=labels, shapes=np.array(shapes),
                       settings=s, notes=notes, extra=extra)


def modes(params: dict, settings: dict) -> LeafModes:
    """Dispatches on the scene: `helicopter-clamped` has a `clamped` tail (n_modes default
    13), `helicopter-hover` not; the leaf modules below fix it."""
    return modes_for(params, settings, True)
