"""Transfer matrix method for multibody systems (MSTMM, "Rui method", seed 002).

elements.py: transfer matrices of one element (12-component state [X, Y, Z, Θx, Θy, Θz,
Mx, My, Mz, Qx, Qy, Qz]); roots.py: the characteristic-function root finder; blade.py,
shaft.py, helicopter.py: the leaves (modes(params, settings)).
"""
