"""Rigid shaft in two spring–damper bearings with a local defect at journal a, spun up by a DC
motor (seed 001; spec scene-bearing-rotor.md). The force laws and observables live once in
compare/physics/bearing_rotor.py."""
import numpy as np

from ..errors import BadInput
from ..params import Param, positive
from .base import Scene

SOURCE = ("seed 001 (001_d37db2f6f0246403.txt): shaft in Rodrigues–Hamilton parameters in the "
          "fixed frame, journals a/b with state-dependent bearing forces, DC motor, defect at a")


def check(values):
    """A rigid body's central inertias obey the triangle inequality: J_p ≤ 2 J_t."""
    if values["J_p"] > 2.0 * values["J_t"]:
        raise BadInput(f"J_p: {values['J_p']:g} kg·m² exceeds 2·J_t = {2 * values['J_t']:g} "
                       "kg·m² (no rigid body has such inertias)")


BEARING_ROTOR = Scene(
    name="bearing-rotor",
    title="Two-bearing rotor with a bearing defect, spun up by a DC motor",
    source=SOURCE,
    kind="time",
    leaves={"quaternion": "custom_models.bearing_rotor"},
    params=(
        positive("m", 6.0, "kg", "shaft mass"),
        positive("l", 0.6, "m", "distance between the journals a (+l/2) and b (−l/2)"),
        positive("J_t", 0.1806, "kg·m²", "transverse central inertia"),
        positive("J_p", 0.0012, "kg·m²", "polar central inertia (about the shaft axis)"),
        positive("k_b", 1.0e6, "N/m", "radial bearing stiffness (each bearing)"),
        Param("c_b", 300.0, "N·s/m", "radial bearing damping (each bearing); 0 allowed",
              lo=0.0, hi=1e9),
        positive("k_axial", 1.0e6, "N/m", "axial spring on journal a's z"),
        Param("gravity", np.array([0.0, -9.81, 0.0]), "m/s²",
              "gravity vector; default −y (horizontal shaft)", kind="vector", lo=-1e3, hi=1e3),
        Param("defect_height", 20e-6, "m", "height H of the bump on journal a", lo=0.0, hi=0.1),
        positive("defect_width", 0.1, "rad", "half width w of the bump (h = 0 for |x| ≥ w)",
                 hi=np.pi),
        Param("defect_angle", 0.0, "rad", "body angle of the bump about the shaft axis",
              lo=-2 * np.pi, hi=2 * np.pi),
        Param("motor_stall_torque", 1.0, "N·m", "DC motor torque at rest", lo=0.0, hi=1e4),
        positive("motor_no_load_speed", 80.0, "rad/s", "DC motor speed at zero torque", hi=1e5),
        Param("bearing_drag", 1.0e-3, "N·m·s", "viscous drag moment coefficient", lo=0.0,
              hi=1e4),
        Param("mu", 0.05, "", "journal friction coefficient", lo=0.0, hi=10.0),
        positive("r_j", 0.02, "m", "journal radius (friction arm)"),
        positive("t_end", 3.0, "s", "horizon", hi=1e5),
        positive("output_dt", 0.0005, "s", "common output grid step"),
    ),
    # `kinetic`, `potential` (gravity + bearing springs), `motor_work`, `dissipated` (dampers,
    # friction and the work of the prescribed defect lift) make up the energy balance
    channels=("spin_rate", "spin_angle", "journal_a_x", "journal_a_y", "journal_b_x",
              "journal_b_y", "energy_balance", "kinetic", "potential", "motor_work",
              "dissipated"),
    tolerances={"spin_rate": 1e-4, "spin_angle": 1e-4, "journal_a_x": 1e-3,
                "journal_a_y": 1e-3, "journal_b_x": 1e-3, "journal_b_y": 1e-3,
                "kinetic": 1e-4, "motor_work": 1e-4},
    key_channel="spin_rate",
    energy_scale_channels=("kinetic", "motor_work"),
    reference_solvers=("quaternion",),
    check=check,
    notes="Force laws, spin angle (swing–twist about the shaft axis) and every observable are "
          "computed by compare/physics/bearing_rotor.py for all solvers; all start at the "
          "defect-free static sag, unrotated, at rest.",
)
