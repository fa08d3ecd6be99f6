"""The explicit Runge–Kutta tableaus, scipy's numbers without importing scipy.integrate: its
package imports scipy.optimize, scipy.special and the sparse solvers, 0.68 s of every process
that ran a custom time solver (each map pool worker, each `xval run`) for three small tables.

DOP853 (Hairer, Nørsett and Wanner's coefficients, with the dense output's extra stages): scipy's
own coefficient file, `scipy/integrate/_ivp/dop853_coefficients.py` (numpy only), loaded alone.
RK23 (Bogacki and Shampine, 1989) and RK45 (Dormand and Prince, 1980, with Shampine's 1986
quartic interpolant at the optimum c₆) written out as the papers give them.
tests/physics/test_dense_integrators.py holds every array equal to scipy.integrate's public one."""
import importlib.util
from pathlib import Path
from types import SimpleNamespace

import numpy as np


def _dop853_coefficients():
    scipy_dir = Path(importlib.util.find_spec("scipy").origin).parent
    spec = importlib.util.spec_from_file_location(
        "_xval_dop853_coefficients", scipy_dir / "integrate" / "_ivp" / "dop853_coefficients.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_c = _dop853_coefficients()
_n = _c.N_STAGES
DOP853 = SimpleNamespace(A=_c.A[:_n, :_n], B=_c.B, C=_c.C[:_n], E3=_c.E3, E5=_c.E5, D=_c.D,
                         A_EXTRA=_c.A[_n + 1:], C_EXTRA=_c.C[_n + 1:])

RK23 = SimpleNamespace(
    C=np.array([0, 1/2, 3/4]),
    A=np.array([[0, 0, 0], [1/2, 0, 0], [0, 3/4, 0]]),
    B=np.array([2/9, 1/3, 4/9]),
    E=np.array([5/72, -1/12, -1/9, 1/8]),
    P=np.array([[1, -4/3, 5/9], [0, 1, -2/3], [0, 4/3, -8/9], [0, -1, 1]]))

RK45 = SimpleNamespace(
    C=np.array([0, 1/5, 3/10, 4/5, 8/9, 1]),
    A=np.array([[0, 0, 0, 0, 0],
                [1/5, 0, 0, 0, 0],
                [3/40, 9/40, 0, 0, 0],
                [44/45, -56/15, 32/9, 0, 0],
                [19372/6561, -25360/2187, 64448/6561, -212/729, 0],
                [9017/3168, -355/33, 46732/5247, 49/176, -5103/18656]]),
    B=np.array([35/384, 0, 500/1113, 125/192, -2187/6784, 11/84]),
    E=np.array([-71/57600, 0, 71/16695, -71/1920, 17253/339200, -22/525, 1/40]),
    P=np.array([[1, -8048581381/2820520608, 8663915743/2820520608, -12715105075/11282082432],
                [0, 0, 0, 0],
                [0, 131558114200/32700410799, -68118460800/10900136933,
                 87487479700/32700410799],
                [0, -1754552775/470086768, 14199869525/1410260304, -10690763975/1880347072],
                [0, 127303824393/49829197408, -318862633887/49829197408,
                 701980252875/199316789632],
                [0, -282668133/205662961, 2019193451/616988883, -1453857185/822651844],
                [0, 40617522/29380423, -110615467/29380423, 69997945/29380423]]))
