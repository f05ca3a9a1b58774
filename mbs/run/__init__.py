"""A run's machinery: the Model and Data (:mod:`mbs.run.model`), the equations of motion, the
stages of a Moreau step with the body stage and their kernels, contact detection at run
time (fused detections, the bounding spheres of the planned broad phase, residual
flexibility at closed contacts), the planner and the static initial state."""
