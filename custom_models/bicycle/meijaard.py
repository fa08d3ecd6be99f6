"""The benchmark bicycle by the paper's own linearised equations (the `meijaard` solver):
M q̈ + v C1 q̇ + (g K0 + v² K2) q = 0 for q = (lean φ, steer δ), M, C1, K0, K2 from the 25
design parameters by Appendix A (compare.physics.bicycle), the roots the eigenvalues of the
4×4 first-order system at the scene's `speed`.

Modes are the oscillating roots (one per conjugate pair: the weave above ~0.7 m/s); every root,
real ones included, is in extra["eigenvalues"] as [Re, Im] in 1/s, with a round-off bound
per root (compare.physics.eigen) in extra["eigenvalue_error_per_s"].
"""
import numpy as np

from compare.contract import LeafModes, merge_settings
from compare.physics import bicycle, eigen

MODES_SETTINGS: dict = {}


def modes(params: dict, settings: dict) -> LeafModes:
    s = merge_settings(settings, MODES_SETTINGS, ())
    v = float(params["speed"])
    mats = bicycle.matrices(params)
    A = bicycle.state_matrix(params, v, mats)
    lam = bicycle.eigenvalues(params, v, mats)
    # LAPACK returns a real root with Im exactly 0 and pairs as exact conjugates
    err = eigen.root_errors(A, lam)
    labels = bicycle.root_labels(lam)
    osc = [i for i in np.argsort(lam.imag) if lam[i].imag > 0]
    w = lam[osc].imag
    return LeafModes(frequencies_hz=w / (2 * np.pi), labels=[labels[i] for i in osc],
                     damping=-lam[osc].real / np.abs(lam[osc]), settings=s,
                     notes=[bicycle.roots_text(lam, labels)],
                     extra={"eigenvalues": np.column_stack([lam.real, lam.imag]),
                            "eigenvalue_labels": labels,
                            "eigenvalue_error_per_s": err,
                            "frequency_error_hz": err[osc] / (2 * np.pi),
                            "damping_error": eigen.zeta_error(err[osc], lam[osc]),
                            "max_re_per_s": float(np.max(lam.real))})
