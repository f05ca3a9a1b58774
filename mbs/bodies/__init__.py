"""The bodies: what every body offers the System and its frames (:mod:`mbs.bodies.body`), the
floating frame of reference and its rotation parametrizations, FFR bodies with their
shape integrals and geometric stiffening, rigid bodies and point masses, their numba
kernels, and the monitors of linear FFR's validity."""
