"""Multibody core: FFR bodies, rigid bodies, links, System, integrators.

Planned (issues 3, 4, 6): ``FlexibleBodyFFR`` built from the body files of
:mod:`preprocess`, Moreau time-stepping, the report's modal step-load solvers.
"""
