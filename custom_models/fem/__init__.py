"""Independent finite-element models for the MSTMM scenes (seed 002): Hermite cubic beam
elements with centrifugal geometric stiffness, quadratic elements for torsion and extension,
gyroscopic matrices for the spinning shaft, rigid bodies as lumped masses/inertias."""
