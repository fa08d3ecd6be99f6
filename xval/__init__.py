"""xval from Python: `import xval; r = xval.run("rotor-spinup", torque=3.2, t_end=5)`.

The distribution's name as an import: the same operations as the `xval` command, each from its
command's module (compare/commands/, the registry), and the Result types they return, as
compare.api gathers them. See docs/python-api.md.
"""
from compare import api as _api

globals().update({name: getattr(_api, name) for name in _api.__all__})
__all__ = list(_api.__all__)
