"""The response's peak, Q and half-power ζ located on the model (`xval response`), against
closed forms worked out here: the peak is the stationary point of |a|², a ratio of quadratics
in x = Ω², whose derivative's numerator is linear in x; the half-power points are the roots of
a quadratic in x."""
import numpy as np
import pytest

from compare.analysis import response as resp
from compare.scenes import get_scene
from compare.workflows import response as workflow
from compare.workflows.plan import plan

REL = 1e-9


def _half_power(F, peak):
    """Roots Ω₁ < Ω₂ of F(x) = F*/2, F(x) = (p x − q)² / ((K − M x)² + c² x), as (p, q, K, M, c)."""
    p, q, K, M, c = F
    h = peak / 2
    x = np.roots([p**2 - h * M**2, -2 * p * q - h * (c**2 - 2 * K * M), q**2 - h * K**2])
    return np.sqrt(np.sort(x.real))


def _peak(F):
    """x* where dF/dx = 0: 2p[(K − Mx)² + c²x] = (px − q)(c² − 2M(K − Mx)), linear in x."""
    p, q, K, M, c = F
    x = (2 * p * K**2 + q * c**2 - 2 * M * K * q) / (2 * p * K * M - p * c**2 - 2 * M**2 * q)
    F_x = (p * x - q) ** 2 / ((K - M * x) ** 2 + c**2 * x)
    return np.sqrt(x), F_x


def _check(pk, F, scale):
    top, F_top = _peak(F)
    w1, w2 = _half_power(F, F_top)
    assert pk["peak_rad_s"] == pytest.approx(top, rel=REL)
    assert pk["peak_amplitude"] == pytest.approx(scale * np.sqrt(F_top), rel=REL)
    assert pk["half_power_rad_s"] == pytest.approx([w1, w2], rel=REL)
    assert pk["Q"] == pytest.approx(top / (w2 - w1), rel=REL)
    assert pk["zeta_half_power"] == pytest.approx((w2 - w1) / (2 * top), rel=REL)


def test_peak_on_the_model_of_a_rotating_unbalance_oscillator():
    """a = Ω²/(ω_n² − Ω² + 2iζω_nΩ): |a| peaks at ω_n/√(1 − 2ζ²) with 1/(2ζ√(1 − ζ²)) —
    located on the formula within 1e-9 (the 24-point spline: 6.8e-8 off in speed)."""
    wn, z = 40.0, 0.05
    w = resp.speeds(wn, z, 24)

    def exact(x):
        x = np.asarray(x, float)
        return x**2 / (wn**2 - x**2 + 2j * z * wn * x)
    pk = resp.peak_on_model(exact, w, exact(w))
    assert pk["located"] == "model"
    assert pk["peak_rad_s"] == pytest.approx(wn / np.sqrt(1 - 2 * z**2), rel=REL)
    assert pk["peak_amplitude"] == pytest.approx(1 / (2 * z * np.sqrt(1 - z**2)), rel=REL)
    _check(pk, (1.0, 0.0, wn**2, 1.0, 2 * z * wn), 1.0)


@pytest.mark.parametrize("name", ["closed-form", "euler-vector"])
def test_xval_response_peak_is_the_rotors_closed_form_peak(name):
    """rotor-whirl: a = −m e (lΩ² − g_z) / (k_eff − (I_t − I_p)Ω² + i c_e Ω) (I_t = mR²/4 +
    ml², I_p = mR²/2, k_eff = k + m l g_z, written here from the scene's numbers): the peak
    `xval response` reports, its Q and half-power ζ, each within 1e-9 of the closed form.
    Measured: ≤ 8.7e-13 relative for all four frequency solvers (the spline over the 24
    speeds it reported before: −7.8e-8 in peak speed, 5e-7 in Q and ζ)."""
    scene = get_scene("rotor-whirl")
    params = plan(scene, dict(scene.response.set)).params
    m, R, l, k = params["m"], params["R"], params["l"], params["k"]
    gz, c = float(np.asarray(params["gravity"])[2]), params["c_ext"]
    It, Ip = m * R**2 / 4 + m * l**2, m * R**2 / 2
    F = (l, gz, k + m * l * gz, It - Ip, c)
    critical, zeta = scene.response.critical(params)
    spins = resp.speeds(critical, zeta, 24)
    data = {"speeds_rad_s": spins.tolist(), "peaks": {}, "time": {},
            "frequency": {name: workflow._frequency(scene, name, params, spins)}}
    workflow._peaks(scene, data, params, [name], [])
    pk = data["peaks"][name]
    assert pk["located"] == "model"
    _check(pk, F, m * params["eccentricity"])

