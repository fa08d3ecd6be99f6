"""The MSTMM scenes' `mode_shape_3d` hooks: one mode row of a solver → the structure's line
strips (metres) and the mode's displacement on them (complex: the motion is
Re(displacement·e^{iωt})). The row layouts are the leaves' (their docstrings):

- blade, `mstmm`/`fem`: stations × [axial, lag, flap, twist·chord/2] at equal stations root→tip;
  `exudyn`/`mujoco` (reference_models/beam_chain_common.py): [Re, Im] of [flap z, lag y,
  twist·chord/2] at x_k = k·L/n, k = 1..n (the clamped root is not sampled);
- shaft, `mstmm`/`fem`: [U, V] at equal stations, u = U cos ωt, v = V sin ωt (at rest the
  planes are standing modes, u = U, v = V in phase); engines: [Re, Im] of [u, v] at k·L/n;
- helicopter (both solvers): 4 blades × stations × [axial, lag, flap, twist·chord/2] in the
  blade frames, then hub [u, θ] at its centre and fuselage [u, θ] at its centre of mass.

Everything is drawn in the rotating frame the leaves solve in. Twist shows as the chord line
at each station (chord in the rotor plane; its edges move ±twist·chord/2 out of the plane).
"""
import numpy as np

from ..physics.mstmm import helicopter_layout

ENGINES = ("exudyn", "mujoco")      # the rigid-segment chains: [Re, Im] rows, root not sampled
Strips = list[tuple[np.ndarray, np.ndarray]]


def _engine_rows(shape, n_fields, L):
    """Stations (root included, at rest) and [n, n_fields] complex rows of an engine row."""
    n = len(shape) // (2 * n_fields)
    c = np.asarray(shape[:n_fields * n]) + 1j * np.asarray(shape[n_fields * n:])
    rows = np.vstack([np.zeros(n_fields), c.reshape(n_fields, n).T])
    return L * np.arange(n + 1) / n, rows


def blade_strips(root, frame, xs, chord, rows) -> Strips:
    """The blade's axis and its chord line at each station. frame: columns radial, lag
    (chord, in the rotor plane), flap; rows: [axial, lag, flap, twist·chord/2] per station."""
    rows = np.asarray(rows, complex)
    axis = root + np.outer(xs, frame[:, 0])
    d_axis = rows[:, :3] @ frame.T
    half = 0.5 * chord * frame[:, 1]
    twist = np.outer(rows[:, 3], frame[:, 2])          # leading edge up, trailing edge down
    strips = [(axis, d_axis)]
    strips += [(np.array([p - half, p + half]), np.array([d - t, d + t]))
               for p, d, t in zip(axis, d_axis, twist)]
    return strips


def rotating_beam(params, solver, shape) -> Strips:
    L = params["L"]
    if solver in ENGINES:
        xs, zyt = _engine_rows(shape, 3, L)
        rows = np.column_stack([np.zeros(len(xs)), zyt[:, 1], zyt[:, 0], zyt[:, 2]])
    else:
        rows = np.reshape(shape, (-1, 4))
        xs = np.linspace(0.0, L, len(rows))
    return blade_strips(np.array([params["hub_radius"], 0.0, 0.0]), np.eye(3), xs,
                        params["chord"], rows)


def spinning_shaft(params, solver, shape) -> Strips:
    """The shaft's axis along z (spin axis), u along x, v along y."""
    L = params["L"]
    if solver in ENGINES:
        xs, uv = _engine_rows(shape, 2, L)
    else:
        U, V = np.reshape(shape, (2, -1))
        xs = np.linspace(0.0, L, len(U))
        uv = np.column_stack([U, V if params["spin_ratio"] == 0 else -1j * V])
    pts = np.column_stack([np.zeros((len(xs), 2)), xs])
    return [(pts, np.column_stack([uv, np.zeros(len(xs))]))]


def _rigid(u, theta, ref, pts):
    """Displacement of points of a rigid body moving (u, θ) about `ref` (small rotation)."""
    return u + np.cross(theta, np.asarray(pts) - ref)


def box_edges(centre, size) -> list:
    """The 12 edges of an axis-aligned box as 2-point strips."""
    c = np.array([[i, j, k] for i in (-.5, .5) for j in (-.5, .5) for k in (-.5, .5)])
    corners = centre + c * size
    return [corners[[a, b]] for a in range(8) for b in range(a + 1, 8)
            if np.sum(c[a] != c[b]) == 1]


def helicopter(params, solver, shape, clamped) -> Strips:
    """4 blades on the hub (drawn as the cross between the blade roots), the drive shaft, the
    fuselage box and the tail boom. The row samples no point inside the shaft or the tail:
    both are drawn straight between their ends (hub / fuselage motion, the clamped end at
    rest); when hovering the free tail end is drawn moving with the fuselage."""
    lay = helicopter_layout(params)
    shape = np.asarray(shape)
    n_st = (len(shape) - 12) // 16
    blades = shape[:16 * n_st].reshape(4, n_st, 4)
    hub_u, hub_t = shape[-12:-9], shape[-9:-6]
    fus_u, fus_t = shape[-6:-3], shape[-3:]
    b, sh, fu, tail = lay["blade"], lay["shaft"], lay["fuselage"], lay["tail"]
    xs = np.linspace(0.0, b["L"], n_st)
    strips = []
    for k in range(4):
        a = k * np.pi / 2
        frame = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0],
                          [0.0, 0.0, 1.0]])
        strips += blade_strips(lay["roots"][k], frame, xs, b["chord"], blades[k])

    def hub(pts):
        return np.array(pts, float), _rigid(hub_u, hub_t, np.zeros(3), pts)

    def fuselage(pts):
        return np.array(pts, float), _rigid(fus_u, fus_t, fu["cm"], pts)

    r = lay["roots"]
    strips += [hub([r[0], r[2]]), hub([r[1], r[3]]), hub([np.zeros(3), sh["top"]])]
    top = hub([sh["top"]])[1][0]
    bottom = fuselage([sh["bottom"]])[1][0]
    strips.append((np.array([sh["top"], sh["bottom"]]), np.array([top, bottom])))
    size = np.array([params["fuselage_length"], params["fuselage_width"],
                     params["fuselage_height"]])
    strips += [fuselage(e) for e in box_edges(fu["cm"], size)]
    strips.append(fuselage([sh["bottom"], fu["cm"], tail["root"]]))
    root_d = fuselage([tail["root"]])[1][0]
    end_d = np.zeros(3) if clamped else fuselage([tail["end"]])[1][0]
    strips.append((np.array([tail["root"], tail["end"]]), np.array([root_d, end_d])))
    return strips


def helicopter_clamped(params, solver, shape) -> Strips:
    return helicopter(params, solver, shape, clamped=True)


def helicopter_hover(params, solver, shape) -> Strips:
    return helicopter(params, solver, shape, clamped=False)
