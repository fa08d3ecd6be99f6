"""A planar double pendulum as an xval plug-in (the template for users' own systems)."""
