"""Physics every solver of a scene must compute alike — observables from a common kinematic
output, closed forms, load laws, payout — defined once. Numpy (and numba) only: leaves import
these modules, and nothing here imports orchestration (runner, CLI, recording, report)."""
