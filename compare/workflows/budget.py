"""The size of the work, estimated before anything runs (and before anything is allocated).

`output_dt = 1e-9` over 10 s asks for 1e10 samples per channel per solver: 74.5 GiB for the
time grid alone, which `Scene.resolve` would try to allocate. The estimate here reads only
`t_end` and `output_dt` (each validated on its own) and the settings, so an oversized request
stops with one line and exit 2 in milliseconds.
"""
from ..errors import BadInput

MAX_OUTPUT_GIB = 2.0      # samples × (channels + time) × solvers × 8 bytes, per run or case
MAX_STEPS = 1e9           # integrator steps per solver run (fixed-step methods: t_end / dt)


def _value(scene, overrides, name):
    if name in overrides:
        return scene.param(name).parse(overrides[name])
    return scene.param(name).default


def n_samples(scene, overrides):
    """Output samples per channel of a time scene, from the two grid parameters only."""
    t_end, dt = _value(scene, overrides, "t_end"), _value(scene, overrides, "output_dt")
    return t_end / dt + 1


def _gib(n_bytes):
    for unit, size in (("TiB", 2 ** 40), ("GiB", 2 ** 30), ("MiB", 2 ** 20)):
        if n_bytes >= size:
            return f"{n_bytes / size:.3g} {unit}"
    return f"{n_bytes / 1024:.3g} KiB"


def check_output(scene, overrides, n_solvers, max_gib=None, where=""):
    """BadInput when the output of `n_solvers` runs would exceed the budget. Call it before
    `scene.resolve` (which builds the grid)."""
    if not scene.has_output_grid:
        return
    max_gib = MAX_OUTPUT_GIB if max_gib is None else max_gib
    n = n_samples(scene, overrides)
    n_bytes = n * (len(scene.channels) + 1) * n_solvers * 8
    if n_bytes > max_gib * 2 ** 30:
        raise BadInput(f"{where}output of {n:.3g} samples × {len(scene.channels) + 1} channels "
                       f"× {n_solvers} solvers ≈ {_gib(n_bytes)} exceeds the budget of "
                       f"{max_gib:g} GiB: raise output_dt, shorten t_end or pass "
                       f"--max-output-gib")


def check_steps(solver_name, info, params, settings, max_steps=None, where=""):
    """BadInput when one run's fixed steps (`LeafInfo.steps`: t_end / dt, the leaf's `AUTO_DT`
    for "auto"; an error-controlled method's are not known in advance) exceed the budget."""
    max_steps = MAX_STEPS if max_steps is None else max_steps
    est = info.steps(settings, params["t_end"])
    if est is not None and est[0] > max_steps:
        n, dt = est
        raise BadInput(f"{where}{solver_name}: {n:.3g} steps of dt = {dt:g} s over "
                       f"t_end = {params['t_end']:g} s exceed the budget of {max_steps:.3g} "
                       f"steps: raise --dt or pass --max-steps")


def check_dt(params, dt, max_steps=None, where=""):
    """A requested fixed step checked before any solver is loaded (t_end / dt steps)."""
    max_steps = MAX_STEPS if max_steps is None else max_steps
    if dt and params["t_end"] / dt > max_steps:
        raise BadInput(f"{where}--dt {dt:g}: {params['t_end'] / dt:.3g} steps over t_end = "
                       f"{params['t_end']:g} s exceed the budget of {max_steps:.3g} steps: "
                       f"raise --dt or pass --max-steps")
