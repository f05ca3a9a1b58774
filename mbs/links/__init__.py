"""The links between bodies: force elements and bilateral constraints (:mod:`mbs.links.link`),
ideal joints, spring-dampers, applied loads (forces, torques, distributed and nodal
loads, force files, a force moving along a contour) and the time axis of tabulated loads."""
