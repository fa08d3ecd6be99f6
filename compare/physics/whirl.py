"""One whirling mode seen from the ground (fixed frame) and from the shaft (rotating frame).

Write the lateral deflection as r = x + iy in the fixed frame and ρ in the frame turning with
the shaft at Ω (counter-clockwise about the spin axis): r = ρ e^{iΩt}. A mode whose rotating-
frame whirl is ρ ∝ e^{iνt} — ν = s·ω signed, s = +1 turning with the spin — is r ∝ e^{i(ν+Ω)t}
seen from the ground: the signed whirl rates of the two frames differ by the spin,

    ν_fixed = ν_rot + Ω.

The mode whirls forward (ROSS: "forward") where ν_fixed > 0, backward where ν_fixed < 0; its
frequency in a frame is |ν| of that frame. With f = |ν|/2π, s the sense and F = Ω/2π:

    forward:   f_fixed = s·f_rot + F   (the signed rotating-frame line s·f_rot = f_fixed − F)
    backward:  f_fixed = f_rot − F     (s = −1 for Ω > 0: f_rot = f_fixed + F)

The isotropic Euler–Bernoulli shaft has f_fixed = λ²ω₀/2π for both whirls at every speed (no
gyroscopic term): in the rotating frame the forward line falls as λ² − Ω* to 0 at Ω* = λ² and
rises again beyond it (s = −1 there), the backward line rises as λ² + Ω*. A rotating-frame leaf
therefore reports the sense of each mode (`extra["whirl_sense"]`): the frequency alone cannot
tell s·f_rot from −s·f_rot. An anisotropic shaft's rotating-frame mode is elliptic, a forward
and a backward circle at once; `sense` is that of the larger circle (sign ∫U·V), and the fixed
frame sees its two circles at |ν ± Ω|: the mapping follows the larger.
"""
from __future__ import annotations

import numpy as np

FRAMES = ("fixed", "rotating")


def signed_in_frame(signed_hz, spin_hz, src: str, dst: str):
    """Signed whirl rates [Hz] of `src` as seen in `dst` (ν_fixed = ν_rot + Ω)."""
    if src not in FRAMES or dst not in FRAMES:
        raise ValueError(f"frame must be one of {FRAMES}: {src!r} → {dst!r}")
    shift = {("rotating", "fixed"): 1.0, ("fixed", "rotating"): -1.0}.get((src, dst), 0.0)
    return np.asarray(signed_hz, float) + shift * spin_hz


def whirl_direction(signed_fixed_hz, spin_hz) -> list:
    """ROSS's words per mode from its signed fixed-frame rate: "forward" turning with the spin,
    "backward" against it, None at rest (no spin, no direction)."""
    if spin_hz == 0:
        return [None] * len(np.atleast_1d(signed_fixed_hz))
    return ["forward" if v * spin_hz > 0 else "backward" for v in np.atleast_1d(signed_fixed_hz)]


def whirl_labels(rot_hz, sense, spin_hz) -> list[str]:
    """Labels of a rotating-frame leaf's modes, in the order given: "forward whirl k" /
    "backward whirl k" numbered per direction by fixed-frame frequency — a physical order, the
    same at every speed (numbered by rotating-frame frequency, the forward lines falling to 0
    and rising again would swap numbers where they cross: Ω* = (λ₁² + λ₂²)/2 = 12.78 on the
    isotropic shaft) — and "whirl k" in frequency order at rest, where the planes decouple."""
    rot_hz = np.asarray(rot_hz, float)
    if spin_hz == 0:
        return [f"whirl {k + 1}" for k in range(len(rot_hz))]
    fixed = signed_in_frame(np.asarray(sense) * rot_hz, spin_hz, "rotating", "fixed")
    kinds = ["forward whirl" if d == "forward" else "backward whirl"
             for d in whirl_direction(fixed, spin_hz)]
    labels = [""] * len(rot_hz)
    for kind in set(kinds):
        idx = [i for i, k in enumerate(kinds) if k == kind]
        for n, i in enumerate(sorted(idx, key=lambda i: abs(fixed[i])), start=1):
            labels[i] = f"{kind} {n}"
    return labels


def order_seen(order: int, src: str, dst: str, whirl) -> int:
    """The order at which a mode whirling `whirl` meets an order-n excitation line of `src`,
    as seen in `dst` (ν_fixed = ν_rot + Ω at the crossing): fixed → rotating, forward |n − 1|
    (unbalance meets the forward line where it reaches 0), backward n + 1; rotating → fixed,
    forward n + 1, backward |n − 1|."""
    if src == dst:
        return order
    if (src == "fixed") == (whirl == "forward"):
        return abs(order - 1)
    return order + 1


def shown_label(label: str, whirl: str | None) -> str:
    """A mode's label as printed: without "forward"/"backward" where the mode has no whirl
    sense ("—": at rest, where the pair is degenerate)."""
    if whirl != "—":
        return label
    for sense in ("forward ", "backward "):
        if label.startswith(sense):
            return label[len(sense):]
    return label
