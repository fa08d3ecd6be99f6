"""Mode labels for the helicopter, from the shape vector every helicopter solver returns:
4 blades × 7 stations × [axial, lag, flap, twist·chord/2], then hub [u, θ] and fuselage [u, θ].

The blade family is the component with the largest share over the blades; the rotor pattern
is the multi-blade coordinate with the largest projection of the blades' tip amplitudes:
collective (1, 1, 1, 1), cyclic (1, 0, −1, 0)/(0, 1, 0, −1), differential (1, −1, 1, −1).
Modes whose blades carry less motion than hub and fuselage are 'fuselage'. Shared by
`mstmm` and `fem` (a labelling rule, not physics). An exactly repeated root (e.g. the two
reactionless torsion modes, twist pattern (1, 0, 1, 0) and (0, 1, 0, 1)) has no preferred
basis: each solver returns some pair spanning it, and the rotor-pattern word of those two
labels may differ between solvers and between machines, by round-off (measured: 19.868 Hz
'torsion differential' in mstmm, 'torsion collective' in fem on an Intel AVX-512 machine;
'torsion collective' in both on an AMD AVX2 one); frequencies and the spanned space agree,
and the comparison lists such modes as unpaired rather than dropping them."""
import numpy as np

FAMILY = ("axial", "lag", "flap", "torsion")
STATIONS = 7


def label_modes(shapes, omegas, L, spin):
    labels, counts = [], {}
    for sh in shapes:
        blades = sh[:4 * STATIONS * 4].reshape(4, STATIONS, 4)
        rigid = sh[4 * STATIONS * 4:]
        fam = int(np.argmax((blades**2).sum(axis=(0, 1))))
        if np.abs(blades).max() < np.abs(rigid).max():
            kind = "fuselage"
        else:
            tip = blades[:, -1, fam]
            proj = {"collective": abs(tip.sum()) / 2,
                    "cyclic": np.hypot(tip[0] - tip[2], tip[1] - tip[3]) / np.sqrt(2),
                    "differential": abs(tip[0] - tip[1] + tip[2] - tip[3]) / 2}
            kind = f"{FAMILY[fam]} {max(proj, key=proj.get)}"
        counts[kind] = counts.get(kind, 0) + 1
        labels.append(f"{kind} {counts[kind]}")
    return labels
