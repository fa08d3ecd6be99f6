"""Exudyn reference models of the MSTMM beams: the rotating cantilever blade (`rotating-beam`,
this module's `modes`) and the spinning cantilever shaft (`spinning-shaft`, `shaft_modes`,
registered through `reference_models/exudyn/shaft_modes.py`).

Both are chains of rigid segments in one `ObjectKinematicTree` (the rigid-finite-element
layout of `reference_models/beam_chain_common.py`: hinges at the segment mid-points, joint
springs EI/Δl and GJ/Δl as the tree's P-control), hung from a hub joint about z that spins at
the rotor speed Ω. Exudyn's `ComputeLinearizedSystem` linearises the tree about the straight
chain spinning steadily (q = 0, q̇_hub = Ω): M, the stiffness K — which then holds the
centrifugal tension stiffening of flap, the −Ω²m̄ softening of lag, the torsion 'propeller'
term — and D = −∂f/∂q̇ with the Coriolis/gyroscopic coupling. Nothing rotating-frame is added
by hand: it all comes from the tree's rigid-body dynamics in the inertial frame.

Constant rotor speed: the hub row and column are deleted from M, K, D (the hub angle's
perturbation is held at zero), then the quadratic eigenproblem M s² + D s + K = 0 is solved
densely (numpy). The frequencies are those seen in the rotating frame, as in Tables 1 and 2.

Why not ANCF cable elements (the Exudyn notes' choice for bending): `ObjectANCFCable` has no
torsion and a single (isotropic) bending stiffness, so it can model neither the blade's torsion
nor an anisotropic shaft, and in the rotating frame it needs the centrifugal and Coriolis
matrices added by hand. The chain converges at second order in 1/N (measured, see
`MODES_SETTINGS`); the default extrapolates N and N/2 (Richardson), which removes the 1/N² term,
and reports the spread against the N/4–N/2 extrapolate as an error bound (with a note to
raise n_segments where it exceeds 5e-3: the blade above ~230 rad/s at N = 40).

Physics differences to the paper's Euler–Bernoulli model (all from the rigid section, see
`beam_chain_common.blade_chain`): lag n carries the section rotary inertia ρI_lag (lag 1
−1.34e-3, lag 2 −0.93 %, lag 3 −2.2 %), flap n the tiny ρI_flap (flap 1–3 ≤ 1.5e-4 against
the custom mstmm; higher flap modes add the N = 40 discretisation: flap 8 −7.9e-4), torsion's
Ω² term is ρ(I_lag − I_flap) instead of I_α (−6.4e-4 at 40 rad/s); the chain is
inextensible, so the blade's axial modes (the first at 192 Hz) are absent.

Wall time per `modes` call (defaults, N = 40 and 20): 0.1–0.3 s with OPENBLAS_NUM_THREADS=1;
under load OpenBLAS threading can make the 240×240 eigen solve 10× slower.
"""
from __future__ import annotations

import exudyn as exu
import numpy as np
from exudyn.itemInterface import NodeGenericODE2, ObjectKinematicTree

from compare.contract import LeafModes, merge_settings
from reference_models import beam_chain_common as bc

# Convergence study (max relative error over the first five modes; second order checked in
# tests/engines/test_beam_engines.py):
#   blade at rest, Euler–Bernoulli segments vs closed forms: N = 10/20/40/80 plain 1.3e-2,
#   3.3e-3, 8.2e-4, 2.0e-4 (order 2); Richardson N/N/2: 4.2e-4, 1.3e-5, 7.9e-7, 5.0e-8;
#   blade at 40 rad/s vs Richardson 160/80: plain 3.9e-2, 1.0e-2, 2.6e-3, 6.4e-4; Richardson
#   4.7e-3, 6.3e-4, 5.4e-5, 3.5e-6; shaft at Ω* = 4 vs λ² ± Ω*: Richardson 4.5e-4, 1.5e-5,
#   9.1e-7, 4.8e-7. Default N = 40 extrapolated: ≤ 5.4e-5 (below the scene's 1e-4 window) in
#   0.1–0.3 s; N = 80 buys 3.5e-6 for ~4× the time.
MODES_SETTINGS = {"n_segments": 40, "extrapolate": True, "rotary_inertia": True}
SHAFT_MODES_SETTINGS = {"n_segments": 40, "extrapolate": True}

_AXES = (exu.JointType.RevoluteX, exu.JointType.RevoluteY, exu.JointType.RevoluteZ)


def _linearised(chain: dict, fd_scales=(1.0,)) -> list:
    """M, K, D of the chain about steady spin, hub coordinate removed, one (M, K, D) per factor
    in `fd_scales` on Exudyn's finite-difference step (D = −∂f/∂q̇ is numerical: another
    step's change is the linearisation's error)."""
    a = chain["axis"]
    e_a = np.eye(3)[a]
    js = chain["joints"]
    jt, parents, offs, inert, coms, masses, P = [_AXES[2]], [-1], [[0.0] * 3], [np.eye(3)], \
        [[0.0] * 3], [1.0], [0.0]                       # link 0: the hub, spinning about z
    prev, prev_x = 0, -chain["root"]
    for i, x in enumerate(chain["hinges"]):
        for j, (_, axis, k) in enumerate(js):
            last = j == len(js) - 1
            jt.append(_AXES[axis])
            parents.append(prev if j == 0 else len(jt) - 2)
            offs.append(list((x - prev_x) * e_a) if j == 0 else [0.0] * 3)
            inert.append(np.diag(chain["inertia"][i]) if last else np.zeros((3, 3)))
            coms.append(list(0.5 * chain["lengths"][i] * e_a) if last else [0.0] * 3)
            masses.append(float(chain["masses"][i]) if last else 0.0)
            P.append(float(k[i]))                       # per hinge
        prev, prev_x = len(jt) - 1, x
    nq = len(jt)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    qd0 = [0.0] * nq
    qd0[0] = float(chain["spin"])
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0] * nq,
                                       initialCoordinates=[0.0] * nq, initialCoordinates_t=qd0,
                                       numberOfODE2Coordinates=nq))
    mbs.AddObject(ObjectKinematicTree(
        nodeNumber=node, jointTypes=jt, linkParents=parents,
        jointTransformations=exu.Matrix3DList([np.eye(3)] * nq),
        jointOffsets=exu.Vector3DList(offs), linkInertiasCOM=exu.Matrix3DList(inert),
        linkCOMs=exu.Vector3DList(coms), linkMasses=masses,
        jointPControlVector=P, jointDControlVector=[0.0] * nq,
        jointPositionOffsetVector=[0.0] * nq, jointVelocityOffsetVector=[0.0] * nq))
    mbs.Assemble()
    out = []
    for scale in fd_scales:
        ss = exu.SimulationSettings()
        ss.staticSolver.newton.numericalDifferentiation.relativeEpsilon *= scale
        out.append(tuple(np.asarray(x, float)[1:, 1:]
                         for x in mbs.ComputeLinearizedSystem(ss)[:3]))
    return out


_package = bc.package


def modes(params: dict, settings: dict | None = None) -> LeafModes:
    """Rotating blade: flap/lag/torsion frequencies (Hz, rotating frame) at params['speed']."""
    return bc.blade_result(params, merge_settings(settings, MODES_SETTINGS, ()), _linearised,
                           _package, "rigid-segment chain (ObjectKinematicTree), linearised "
                           "about steady spin, hub speed held; lag modes carry the section's "
                           "rotary inertia ρI_lag")


def shaft_modes(params: dict, settings: dict | None = None) -> LeafModes:
    """Spinning shaft: whirl frequencies (Hz, co-rotating frame) at Ω = spin_ratio·ω₀;
    extra['omega_star'] = ω/ω₀ (Table 2)."""
    return bc.shaft_result(params, merge_settings(settings, SHAFT_MODES_SETTINGS, ()),
                           _linearised, _package, "rigid-segment chain (ObjectKinematicTree) "
                           "spinning about its axis, linearised about steady spin")
